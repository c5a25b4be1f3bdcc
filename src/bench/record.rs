//! Recording's cost for `quadcl bench`: control steps per second of the
//! shipped base policy walking in one env (policy forward included), without
//! a recorder, while recording to `.mcap` (JSON messages, zstd chunks) and
//! while recording to `.rrd` (Rerun: the URDF once, 13 transforms and the
//! scalars every step).
//!
//! Keys: `record_control_steps_per_s_off`, `record_control_steps_per_s_mcap`,
//! `record_control_steps_per_s_rrd`, `record_mcap_cost` and `record_rrd_cost`
//! (1 - with / without), and the same for the bare simulator (zero actions, no
//! policy: the strictest ratio) as `record_sim_steps_per_s_*` and
//! `record_sim_*_cost`. Skipped (null) without `policies/base-a1-flat`. And what
//! TensorBoard logging costs per training iteration (`tb_write_us_per_iteration`).

use quadcl::record::{Recorder, RerunScene, RerunSink};
use quadcl::rl::RobotViewer;
use quadcl::sim::{LocomotionEnv, RobotModel};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn rate(seconds: f64, mut step: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    let start = Instant::now();
    let mut steps = 0u64;
    while start.elapsed().as_secs_f64() < seconds {
        step()?;
        steps += 1;
    }
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}

fn temp_file(ext: &str) -> PathBuf {
    std::env::temp_dir().join(format!("quadcl-bench-{}.{ext}", std::process::id()))
}

/// A recorder of `ext` into `file`.
fn recorder(ext: &str, file: &Path, robot: &RobotModel, scene: &RerunScene) -> anyhow::Result<Recorder> {
    match ext {
        "mcap" => Recorder::mcap(file, robot),
        _ => Recorder::rerun(&[RerunSink::Save(file.to_path_buf())], robot, scene),
    }
}

fn cost(with: f64, without: f64) -> serde_json::Value {
    json!(((1.0 - with / without) * 1000.0).round() / 1000.0)
}

/// What writing one iteration's metrics to TensorBoard and CSV costs (`quadcl train` and
/// `quadcl run` do it every iteration): microseconds per iteration for the first row of the
/// shipped base run's `metrics.jsonl` (every metric a PPO iteration logs), flushed every 25
/// iterations as at checkpoints. Keys `tb_write_us_per_iteration`, `tb_scalars_per_iteration`.
fn tensorboard_cost(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let rows = Path::new("policies/base-a1-flat-run/metrics.jsonl");
    let Some(row) = std::fs::read_to_string(rows).ok().and_then(|t| t.lines().next().map(str::to_string)) else {
        report.insert("tb_write_us_per_iteration".into(), json!(null));
        return Ok(());
    };
    let metrics: quadcl::rl::Metrics = serde_json::from_str(&row)?;
    let dir = std::env::temp_dir().join(format!("quadcl-bench-tb-{}", std::process::id()));
    let mut log = quadcl::log::ScalarLog::create(&dir)?;
    let mut step = 0i64;
    let per_s = rate(seconds.min(2.0), || {
        step += 1;
        log.write(step, metrics.iter().map(|(k, v)| (k.as_str(), *v)))?;
        if step % 25 == 0 {
            log.flush()?;
        }
        Ok(())
    })?;
    drop(log);
    let _ = std::fs::remove_dir_all(&dir);
    report.insert("tb_write_us_per_iteration".into(), json!((1e7 / per_s).round() / 10.0));
    report.insert("tb_scalars_per_iteration".into(), json!(metrics.len()));
    Ok(())
}

/// Adds the recording figures to `report`.
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    tensorboard_cost(seconds, report)?;
    let policy = Path::new("policies/base-a1-flat");
    if !policy.exists() {
        report.insert("record_control_steps_per_s_off".into(), json!(null));
        return Ok(());
    }
    let mut viewer = RobotViewer::new(policy, "none", 0, Some([0.5, 0.0, 0.0]))?;
    let scene = RerunScene { task: "none".into(), policy: policy.display().to_string(), masks: viewer.mask_views() };
    rate(0.2, || viewer.step().map(drop))?;
    let off = rate(seconds, || viewer.step().map(drop))?;
    report.insert("record_control_steps_per_s_off".into(), json!(off.round()));
    for ext in ["mcap", "rrd"] {
        let file = temp_file(ext);
        let robot = viewer.env().robot().clone();
        viewer.observe(Box::new(recorder(ext, &file, &robot, &scene)?));
        let with = rate(seconds, || viewer.step().map(drop))?;
        if let Some(mut r) = viewer.take_observer() {
            r.finish()?;
        }
        let _ = std::fs::remove_file(&file);
        report.insert(format!("record_control_steps_per_s_{ext}"), json!(with.round()));
        report.insert(format!("record_{ext}_cost"), cost(with, off));
    }
    let cfg = quadcl::config::EnvConfig::default();
    let robot = RobotModel::for_config(&cfg)?;
    let mut env = LocomotionEnv::new(&cfg, &robot, &quadcl::sim::Perturbation::none())?;
    let sim_step = |env: &mut LocomotionEnv| -> anyhow::Result<()> {
        let s = env.step(&[0.0; quadcl::sim::ACT_DIM])?;
        if s.terminated || s.truncated {
            env.reset_episode()?;
        }
        Ok(())
    };
    let sim_off = rate(seconds, || sim_step(&mut env))?;
    report.insert("record_sim_steps_per_s_off".into(), json!(sim_off.round()));
    let bare = RerunScene { masks: Vec::new(), ..scene };
    for ext in ["mcap", "rrd"] {
        let file = temp_file(ext);
        env.observe(Box::new(recorder(ext, &file, &robot, &bare)?));
        let with = rate(seconds, || sim_step(&mut env))?;
        if let Some(mut r) = env.take_observer() {
            r.finish()?;
        }
        let _ = std::fs::remove_file(&file);
        report.insert(format!("record_sim_steps_per_s_{ext}"), json!(with.round()));
        report.insert(format!("record_sim_{ext}_cost"), cost(with, sim_off));
    }
    Ok(())
}
