//! The CPU renderer's cost for `quadcl bench --only render`: milliseconds per frame of the A1
//! standing on flat ground at 320 x 240 and 640 x 480 on one thread (a pool of one), and at
//! 320 x 240 on every core; and the share of real time a 50 fps video takes to render at
//! 320 x 240 on one core (below 1: faster than real time).
//!
//! Keys: `render_ms_per_frame_320x240_1thread`, `render_ms_per_frame_640x480_1thread`,
//! `render_ms_per_frame_320x240_all_threads`, `render_real_time_share_320x240_1thread`.

use quadcl::config::EnvConfig;
use quadcl::render::{render, Camera, Scene};
use quadcl::sim::{LocomotionEnv, Perturbation, RobotModel};
use serde_json::json;
use std::time::Instant;

fn ms_per_frame(scene: &Scene, width: usize, height: usize, seconds: f64) -> anyhow::Result<f64> {
    let camera = Camera::default();
    let start = Instant::now();
    let mut frames = 0u32;
    while frames < 3 || start.elapsed().as_secs_f64() < seconds {
        render(scene, &camera, width, height)?;
        frames += 1;
    }
    Ok(start.elapsed().as_secs_f64() * 1e3 / f64::from(frames))
}

/// Adds the renderer's figures to `report`.
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let cfg = EnvConfig::default();
    let robot = RobotModel::for_config(&cfg)?;
    let mut env = LocomotionEnv::new(&cfg, &robot, &Perturbation::none())?;
    env.reset(0)?;
    for _ in 0..25 {
        env.step(&[0.0; 12])?;
    }
    let scene = Scene::of_env(&env);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let (small, large) = one.install(|| {
        Ok::<_, anyhow::Error>((ms_per_frame(&scene, 320, 240, seconds)?, ms_per_frame(&scene, 640, 480, seconds)?))
    })?;
    let all = ms_per_frame(&scene, 320, 240, seconds)?;
    let round = |v: f64| (v * 100.0).round() / 100.0;
    report.insert("render_ms_per_frame_320x240_1thread".into(), json!(round(small)));
    report.insert("render_ms_per_frame_640x480_1thread".into(), json!(round(large)));
    report.insert("render_ms_per_frame_320x240_all_threads".into(), json!(round(all)));
    // A 50 fps video: 20 ms of real time a frame.
    report.insert("render_real_time_share_320x240_1thread".into(), json!(round(small / 20.0)));
    Ok(())
}
