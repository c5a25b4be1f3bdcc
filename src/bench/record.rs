//! Recording's cost for `quadcl bench`: control steps per second of the
//! shipped base policy walking in one env (policy forward included), without
//! a recorder and while recording to `.mcap` (JSON messages, zstd chunks).
//!
//! Keys: `record_control_steps_per_s_off`, `record_control_steps_per_s_mcap`,
//! `record_mcap_cost` (1 - with / without), and the same for the bare simulator
//! (zero actions, no policy: the strictest ratio) as `record_sim_steps_per_s_off`,
//! `record_sim_steps_per_s_mcap`, `record_sim_mcap_cost`. Skipped (null) without
//! `policies/base-a1-flat`.

use quadcl::record::McapRecorder;
use quadcl::rl::RobotViewer;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

fn rate(viewer: &mut RobotViewer, seconds: f64) -> anyhow::Result<f64> {
    let start = Instant::now();
    let mut steps = 0u64;
    while start.elapsed().as_secs_f64() < seconds {
        viewer.step()?;
        steps += 1;
    }
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}

/// Adds the recording figures to `report`.
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let policy = Path::new("policies/base-a1-flat");
    if !policy.exists() {
        report.insert("record_control_steps_per_s_off".into(), json!(null));
        return Ok(());
    }
    let mut viewer = RobotViewer::new(policy, "none", 0, Some([0.5, 0.0, 0.0]))?;
    rate(&mut viewer, 0.2)?;
    let off = rate(&mut viewer, seconds)?;
    let file = std::env::temp_dir().join(format!("quadcl-bench-{}.mcap", std::process::id()));
    viewer.observe(Box::new(McapRecorder::create(&file, viewer.env().robot())?));
    let mcap = rate(&mut viewer, seconds)?;
    if let Some(mut r) = viewer.take_observer() {
        r.finish()?;
    }
    let _ = std::fs::remove_file(&file);
    let cfg = quadcl::config::EnvConfig::default();
    let robot = quadcl::sim::RobotModel::for_config(&cfg)?;
    let mut env = quadcl::sim::LocomotionEnv::new(&cfg, &robot, &quadcl::sim::Perturbation::none())?;
    let sim_rate = |env: &mut quadcl::sim::LocomotionEnv| -> anyhow::Result<f64> {
        let (start, mut steps) = (Instant::now(), 0u64);
        while start.elapsed().as_secs_f64() < seconds {
            let s = env.step(&[0.0; quadcl::sim::ACT_DIM])?;
            if s.terminated || s.truncated {
                env.reset_episode()?;
            }
            steps += 1;
        }
        Ok(steps as f64 / start.elapsed().as_secs_f64())
    };
    let sim_off = sim_rate(&mut env)?;
    env.observe(Box::new(McapRecorder::create(&file, &robot)?));
    let sim_mcap = sim_rate(&mut env)?;
    if let Some(mut r) = env.take_observer() {
        r.finish()?;
    }
    let _ = std::fs::remove_file(&file);
    report.insert("record_sim_steps_per_s_off".into(), json!(sim_off.round()));
    report.insert("record_sim_steps_per_s_mcap".into(), json!(sim_mcap.round()));
    report.insert("record_sim_mcap_cost".into(), json!(((1.0 - sim_mcap / sim_off) * 1000.0).round() / 1000.0));
    report.insert("record_control_steps_per_s_off".into(), json!(off.round()));
    report.insert("record_control_steps_per_s_mcap".into(), json!(mcap.round()));
    report.insert("record_mcap_cost".into(), json!(((1.0 - mcap / off) * 1000.0).round() / 1000.0));
    Ok(())
}
