//! `quadcl record` into MCAP, read back with the `mcap` crate: the channels
//! and their schemas, one message per control step per channel (the link
//! shapes once), and the joint angles and trunk height the simulator reported
//! at each step (a second, identical simulation observed directly).

mod record_common;

use quadcl::record::{record_episodes, RecordOptions, TOPICS};
use quadcl::sim::{StepInfo, StepObserver};
use record_common::{base, options, walk_seen};
use std::sync::{Arc, Mutex};

#[test]
fn an_mcap_recording_has_every_channel_one_message_per_step_and_the_simulators_numbers() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("walk.mcap");
    let summary = record_episodes(&base(), "none", &out, &options(2.0)).unwrap();
    assert_eq!(summary.control_steps, 100, "2 s at 0.02 s per control step");
    assert!(!tmp.path().join("walk.mcap.partial").exists());

    // The same simulation, observed directly.
    let seen = walk_seen(100);
    assert_eq!(seen.len(), 101, "the start and every step");

    let bytes = std::fs::read(&out).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let mut schemas: Vec<(String, String)> = summary
        .channels
        .values()
        .map(|c| (c.topic.clone(), c.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default()))
        .collect();
    schemas.sort();
    let mut expected: Vec<(String, String)> = TOPICS
        .iter()
        .zip([
            "foxglove.FrameTransforms",
            "foxglove.SceneUpdate",
            "quadcl.JointStates",
            "quadcl.Command",
            "quadcl.RewardTerms",
            "quadcl.Contacts",
        ])
        .map(|(t, s)| (t.to_string(), s.to_string()))
        .collect();
    expected.sort();
    assert_eq!(schemas, expected);
    for c in summary.channels.values() {
        assert_eq!(c.message_encoding, "json");
        assert_eq!(c.schema.as_ref().unwrap().encoding, "jsonschema");
    }

    let mut per_topic: std::collections::BTreeMap<String, Vec<(u64, serde_json::Value)>> = Default::default();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        per_topic
            .entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, serde_json::from_slice(&m.data).unwrap()));
    }
    assert_eq!(per_topic["/scene"].len(), 1);
    for topic in ["/tf", "/joint_states", "/command", "/reward_terms", "/contacts"] {
        assert_eq!(per_topic[topic].len(), 101, "{topic}: the start and one message per step");
    }
    let tf = &per_topic["/tf"];
    let joints = &per_topic["/joint_states"];
    for (k, (time, q, height)) in seen.iter().enumerate() {
        let ns = (time * 1e9).round() as u64;
        assert_eq!(tf[k].0, ns, "log time is simulation time");
        let trunk = &tf[k].1["transforms"][0];
        assert_eq!(trunk["child_frame_id"], "trunk");
        assert_eq!(trunk["translation"]["z"].as_f64().unwrap() as f32, *height, "trunk height at step {k}");
        let position: Vec<f32> = serde_json::from_value(joints[k].1["position"].clone()).unwrap();
        assert_eq!(position, q.to_vec(), "joint angles at step {k}");
        assert_eq!(tf[k].1["transforms"].as_array().unwrap().len(), 13, "the trunk and the 12 leg links");
    }
    let terms = &per_topic["/reward_terms"][10].1["terms"];
    assert_eq!(terms.as_object().unwrap().len(), quadcl::sim::reward::TERM_NAMES.len());
    assert_eq!(per_topic["/command"][10].1["vx"], 0.5);
    let scene = &per_topic["/scene"][0].1["entities"];
    assert!(scene.as_array().unwrap().iter().any(|e| e["id"] == "trunk" && e["cubes"].as_array().unwrap().len() == 1));
}

#[test]
fn a_recording_refuses_to_overwrite_an_unknown_format_and_an_unwritable_place() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("a.mcap");
    std::fs::write(&out, b"keep me").unwrap();
    let err = format!("{:#}", record_episodes(&base(), "none", &out, &options(0.2)).unwrap_err());
    assert!(err.contains("exists") && err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"keep me", "nothing was written");
    record_episodes(&base(), "none", &out, &RecordOptions { force: true, ..options(0.2) }).unwrap();
    assert!(mcap::Summary::read(&std::fs::read(&out).unwrap()).unwrap().is_some());

    let err = format!("{:#}", record_episodes(&base(), "none", &tmp.path().join("a.bag"), &options(0.2)).unwrap_err());
    assert!(err.contains("a.bag") && err.contains(".mcap") && err.contains(".rrd"), "{err}");
    let err = format!(
        "{:#}",
        record_episodes(&base(), "none", &tmp.path().join("no/such/dir/a.mcap"), &options(0.2)).unwrap_err()
    );
    assert!(err.contains("no/such/dir"), "{err}");
    let err = format!("{:#}", record_episodes(&base(), "none", &tmp.path().join("b.mcap"), &options(1e9)).unwrap_err());
    assert!(err.contains("--seconds"), "{err}");
    let err =
        format!("{:#}", record_episodes(&base(), "wobble:FL", &tmp.path().join("c.mcap"), &options(1.0)).unwrap_err());
    assert!(err.contains("wobble"), "{err}");
}

/// Counts what it hears.
struct Count(Arc<Mutex<(usize, usize)>>);

impl StepObserver for Count {
    fn on_reset(&mut self, _: &StepInfo) {
        self.0.lock().unwrap().0 += 1;
    }
    fn on_step(&mut self, _: &StepInfo) {
        self.0.lock().unwrap().1 += 1;
    }
}

#[test]
fn an_observer_attaches_to_one_env_of_a_learners_batch() {
    use quadcl::rl::{SimTrainEnv, TrainEnv};
    let cfg = quadcl::config::EnvConfig { episode_s: 0.2, ..Default::default() };
    let mut batch = SimTrainEnv::new(&cfg, &quadcl::sim::Perturbation::none(), 3, 1).unwrap();
    let heard = Arc::new(Mutex::new((0, 0)));
    batch.observe(1, Box::new(Count(heard.clone()))).unwrap();
    for _ in 0..25 {
        batch.step(&[0.0; 3 * quadcl::sim::ACT_DIM]).unwrap();
    }
    // 0.2 s episodes at 0.02 s: ten steps each, so two auto-resets in 25 steps, plus the start it was attached at.
    assert_eq!(*heard.lock().unwrap(), (3, 25));
    let err = format!("{:#}", batch.observe(3, Box::new(Count(heard.clone()))).unwrap_err());
    assert!(err.contains("no env 3"), "{err}");
}
