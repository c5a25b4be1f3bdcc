//! The CPU renderer (`quadcl::render`): a frame of a known pose (the A1 standing at its start,
//! its front-left leg perturbed) matches the committed reference image within a small per-pixel
//! tolerance, text lands on a frame, and sizes are checked. To look at a change of the renderer
//! on purpose, run with `QUADCL_BLESS=1` to rewrite the reference, and look at it.

use quadcl::config::EnvConfig;
use quadcl::render::{frame_of, Camera, Frame};
use quadcl::sim::{LocomotionEnv, Perturbation, RobotModel};
use std::path::Path;
use std::str::FromStr;

fn standing(task: &str) -> LocomotionEnv {
    let cfg = EnvConfig::default();
    let robot = RobotModel::for_config(&cfg).unwrap();
    let mut env = LocomotionEnv::new(&cfg, &robot, &Perturbation::from_str(task).unwrap()).unwrap();
    env.reset(3).unwrap();
    env.set_command([0.0, 0.0, 0.0]);
    for _ in 0..25 {
        env.step(&[0.0; 12]).unwrap();
    }
    env
}

fn decode(bytes: &[u8]) -> Frame {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgb).unwrap();
    rgb.truncate(info.buffer_size());
    Frame { width: info.width as usize, height: info.height as usize, rgb }
}

#[test]
fn a_standing_robot_renders_as_its_reference_image() {
    let env = standing("crash:FL");
    let frame = frame_of(&env, &Camera::default(), 320, 240).unwrap();
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/render_reference/a1-standing-crash-FL.png");
    if std::env::var_os("QUADCL_BLESS").is_some() {
        std::fs::write(&reference, frame.png().unwrap()).unwrap();
    }
    let expected = decode(&std::fs::read(&reference).unwrap());
    assert_eq!((frame.width, frame.height), (expected.width, expected.height));
    // Physics and shading in f32 may differ in the last bits across machines: a few levels per
    // channel, on few pixels (silhouette edges).
    let off: Vec<usize> = (0..frame.rgb.len()).filter(|&i| frame.rgb[i].abs_diff(expected.rgb[i]) > 8).collect();
    assert!(off.len() < frame.rgb.len() / 200, "{} of {} channels differ by more than 8", off.len(), frame.rgb.len());
}

#[test]
fn the_robot_is_in_the_middle_of_the_frame_with_the_perturbed_leg_in_red_and_a_sky_above() {
    let env = standing("crash:FL");
    let frame = frame_of(&env, &Camera::default(), 160, 120).unwrap();
    let sky = frame.pixel(80, 2);
    assert!(sky[2] > sky[0] && sky[2] > 150, "blue sky at the top: {sky:?}");
    // Some pixels are the red of the perturbed leg, none at the frame's edges.
    let red = |p: [u8; 3]| p[0] > 150 && p[1] < 110 && p[2] < 110;
    let reds: Vec<(usize, usize)> =
        (0..120).flat_map(|y| (0..160).map(move |x| (x, y))).filter(|&(x, y)| red(frame.pixel(x, y))).collect();
    assert!(reds.len() > 20, "the front-left leg is drawn in red ({} pixels)", reds.len());
    assert!(reds.iter().all(|&(x, y)| (20..140).contains(&x) && (10..110).contains(&y)), "{reds:?}");
    // The same pose without a perturbed leg has no red.
    let healthy = frame_of(&standing("none"), &Camera::default(), 160, 120).unwrap();
    assert!((0..120).all(|y| (0..160).all(|x| !red(healthy.pixel(x, y)))));
}

#[test]
fn text_drawn_on_a_frame_changes_its_top_left_corner_only() {
    let env = standing("none");
    let plain = frame_of(&env, &Camera::default(), 320, 240).unwrap();
    let mut labelled = plain.clone();
    labelled.write_lines(&["crash:FL  vx 0.50".to_string()], 14.0).unwrap();
    let changed: Vec<usize> =
        (0..plain.rgb.len() / 3).filter(|&i| plain.rgb[3 * i..3 * i + 3] != labelled.rgb[3 * i..3 * i + 3]).collect();
    assert!(changed.len() > 50, "the text drew {} pixels", changed.len());
    assert!(changed.iter().all(|&i| i % 320 < 200 && i / 320 < 30), "text outside the top-left corner");
}

#[test]
fn a_frame_of_no_pixels_or_too_many_is_an_error_naming_its_size() {
    let env = standing("none");
    for (w, h) in [(0, 240), (320, 0), (100_000, 100_000)] {
        let err = format!("{:#}", frame_of(&env, &Camera::default(), w, h).unwrap_err());
        assert!(err.contains(&format!("{w} x {h}")), "{err}");
    }
}
