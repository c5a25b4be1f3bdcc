//! `quadcl record` into Rerun's `.rrd`, read back with Rerun's own decoder:
//! the URDF's links (through Rerun's URDF importer), a transform per leg joint
//! and the floating base at every step, the scalars with the simulator's own
//! joint angles and trunk height, the mask images; and `view --connect` to an
//! address where no viewer listens fails fast, saying what to do instead.

mod record_common;

use quadcl::record::{record_episodes, view_policy, RerunSink, TIMELINE};
use re_log_encoding::DecoderApp;
use record_common::{base, options, walk_seen};
use rerun::log::{Chunk, LogMsg};
use rerun::{Scalars, SegmentationImage, Transform3D};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::time::{Duration, Instant};

/// Every chunk of an `.rrd` file's recording (not its blueprint).
fn chunks(path: &Path) -> Vec<Chunk> {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    DecoderApp::decode_lazy(file)
        .map(|msg| msg.unwrap())
        .filter_map(|msg| match msg {
            LogMsg::ArrowMsg(store, arrow) if store.kind() == rerun::StoreKind::Recording => {
                Some(Chunk::from_arrow_msg(&arrow).unwrap())
            }
            _ => None,
        })
        .collect()
}

/// The (sim time in ns, values) of every row of `entity`'s `component` of f64 slices.
fn scalar_rows(chunks: &[Chunk], entity: &str) -> Vec<(i64, Vec<f64>)> {
    let component = Scalars::descriptor_scalars().component;
    let mut rows: Vec<(i64, Vec<f64>)> = chunks
        .iter()
        .filter(|c| c.entity_path().to_string() == format!("/{entity}"))
        .flat_map(|c| {
            let times = c.timelines().get(&TIMELINE.into()).map(|t| t.times_raw().to_vec()).unwrap_or_default();
            let values: Vec<Vec<f64>> = c.iter_slices::<f64>(component).map(|s| s.to_vec()).collect();
            times.into_iter().zip(values).collect::<Vec<_>>()
        })
        .collect();
    rows.sort_by_key(|r| r.0);
    rows
}

#[test]
fn an_rrd_recording_has_the_urdf_links_a_transform_per_joint_per_step_the_scalars_and_the_masks() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("walk.rrd");
    let summary = record_episodes(&base(), "none", &out, &options(2.0)).unwrap();
    assert_eq!(summary.control_steps, 100, "2 s at 0.02 s per control step");
    assert!(!tmp.path().join("walk.rrd.partial").exists(), "renamed when complete");
    let seen = walk_seen(100);
    assert_eq!(seen.len(), 101, "the start and every step");
    let chunks = chunks(&out);
    let entities: BTreeSet<String> = chunks.iter().map(|c| c.entity_path().to_string()).collect();

    // The URDF through Rerun's importer: the shapes of every link that has any (every link is a
    // frame the transforms below move), and the joints' static transforms.
    let robot = quadcl::sim::RobotModel::a1().unwrap();
    let file = rerun::external::urdf_rs::read_file(&robot.path).unwrap();
    let shaped: Vec<_> = file.links.iter().filter(|l| !l.collision.is_empty() || !l.visual.is_empty()).collect();
    assert!(shaped.len() >= 9, "the trunk, thighs and calves have shapes");
    for link in shaped {
        assert!(
            entities.iter().any(|e| e.starts_with("/robot/a1/") && e.contains(&format!("/{}/", link.name))),
            "no entity of link {}: {entities:?}",
            link.name
        );
    }
    assert!(entities.contains("/tf_static"), "{entities:?}");

    // Per step (and at the start): the floating base, then one transform per leg joint.
    let child = Transform3D::descriptor_child_frame().component;
    let translation = Transform3D::descriptor_translation().component;
    let mut per_time: BTreeMap<i64, Vec<String>> = BTreeMap::new();
    let mut trunk_height: BTreeMap<i64, f32> = BTreeMap::new();
    for c in chunks.iter().filter(|c| c.entity_path().to_string() == "/transforms") {
        let times = c.timelines()[&TIMELINE.into()].times_raw().to_vec();
        let frames: Vec<Vec<String>> =
            c.iter_slices::<String>(child).map(|s| s.iter().map(|f| f.to_string()).collect()).collect();
        let translations: Vec<Vec<[f32; 3]>> = c.iter_slices::<[f32; 3]>(translation).map(|s| s.to_vec()).collect();
        for ((t, frame), xyz) in times.iter().zip(frames).zip(translations) {
            if frame.first().map(String::as_str) == Some("trunk") {
                trunk_height.insert(*t, xyz[0][2]);
            }
            per_time.entry(*t).or_default().extend(frame);
        }
    }
    assert_eq!(per_time.len(), 101, "a time per step and the start");
    let mut expected: Vec<String> = std::iter::once("trunk".to_string())
        .chain(robot.joints.iter().map(|j| robot.urdf.links[j.child_link].name.clone()))
        .collect();
    expected.sort();
    for (t, frames) in &per_time {
        let mut frames = frames.clone();
        frames.sort();
        assert_eq!(frames, expected, "the transforms at {t} ns");
    }

    // The scalars on the sim_time timeline carry the simulator's numbers.
    let positions = scalar_rows(&chunks, "joints/position");
    assert_eq!(positions.len(), 101);
    for (k, ((t, q), (seen_t, seen_q, height))) in positions.iter().zip(&seen).enumerate() {
        assert_eq!(*t, (seen_t * 1e9).round() as i64, "time of step {k}");
        assert_eq!(q, &seen_q.map(f64::from).to_vec(), "joint angles at step {k}");
        assert_eq!(trunk_height[t], *height, "trunk height at step {k}");
    }
    let terms = scalar_rows(&chunks, "reward/terms");
    assert_eq!(terms.len(), 100, "a reward per step (none at the start)");
    assert!(terms.iter().all(|(_, v)| v.len() == quadcl::sim::reward::TERM_NAMES.len()));
    assert_eq!(scalar_rows(&chunks, "joints/torque").len(), 101);
    let errors = scalar_rows(&chunks, "tracking/lin_vel_err");
    let mean = errors[50..].iter().map(|(_, v)| v[0]).sum::<f64>() / 51.0;
    assert!(mean < 0.3, "the walking policy tracks 0.5 m/s: mean error {mean}");
    assert!(scalar_rows(&chunks, "command").iter().all(|(_, v)| v == &vec![0.5, 0.0, 0.0]));

    // The base task's masks, one image per layer, with the element views' annotation context.
    let views = quadcl::rl::RobotViewer::new(&base(), "none", 3, None).unwrap().mask_views();
    assert!(!views.is_empty());
    let buffer = SegmentationImage::descriptor_buffer().component;
    for view in &views {
        let entity = format!("/masks/{}", view.layer.replace('.', "_"));
        let image = chunks.iter().find(|c| c.entity_path().to_string() == entity).unwrap_or_else(|| panic!("{entity}"));
        let bytes: Vec<u8> =
            image.iter_slices::<&[u8]>(buffer).next().unwrap().iter().flat_map(|b| b.as_slice().to_vec()).collect();
        assert_eq!(bytes, view.codes, "{entity}");
    }
    assert!(entities.contains("/masks"), "the annotation context");
}

#[test]
fn view_connect_to_an_address_where_nothing_listens_fails_within_seconds_naming_the_alternatives() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let url = format!("rerun+http://127.0.0.1:{port}/proxy");
    let start = Instant::now();
    let err = view_policy(&base(), "none", &[RerunSink::Connect(url.clone())], &options(5.0)).unwrap_err();
    let took = start.elapsed();
    let err = format!("{err:#}");
    assert!(took < Duration::from_secs(10), "took {took:?}");
    assert!(err.contains(&url) && err.contains("--save") && err.contains("--spawn"), "{err}");
    let err = format!(
        "{:#}",
        view_policy(&base(), "none", &[RerunSink::Connect("nonsense".into())], &options(1.0)).unwrap_err()
    );
    assert!(err.contains("nonsense"), "{err}");
}

#[test]
fn an_rrd_recording_into_an_unwritable_place_is_an_error_naming_it_and_an_existing_file_is_kept() {
    let tmp = tempfile::tempdir().unwrap();
    let err = format!(
        "{:#}",
        record_episodes(&base(), "none", &tmp.path().join("no/such/dir/a.rrd"), &options(0.2)).unwrap_err()
    );
    assert!(err.contains("no/such/dir"), "{err}");
    let out = tmp.path().join("keep.rrd");
    std::fs::write(&out, b"keep me").unwrap();
    let err =
        format!("{:#}", view_policy(&base(), "none", &[RerunSink::Save(out.clone())], &options(0.2)).unwrap_err());
    assert!(err.contains("exists") && err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"keep me");
}
