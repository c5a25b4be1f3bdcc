//! End-to-end PPO throughput for `quadcl bench`: whole training iterations
//! (rollout of every env, then the update) of a run file's learner on the
//! simulator, as `quadcl train` runs them, timed after warm-up.
//!
//! Configuration (compiled in, so the bench runs from any folder):
//! `scenes/train-base.toml`, the full method (masked actor and critic,
//! CENet), keys `ppo_*`; `scenes/train-dense.toml`, like for like with a lean
//! Python PPO (dense actor and critic, no CENet, 4 minibatches), keys
//! `ppo_dense_*` and the headline `ppo_env_steps_per_s_dense`.
//!
//! Keys per configuration: `env_steps_per_s` (env steps of the measured
//! iterations over their wall time), `iteration_ms` (mean), the split per
//! iteration into `physics_ms` (env.step), `policy_ms` (policy and critic
//! forwards of the rollout, observation normalisation), `update_ms` (the
//! epochs x minibatches update) and `other_ms` (GAE, bookkeeping; of it
//! `masks_ms` drawing the iteration's masks and `plasticity_ms` the probes), and
//! `iterations` measured. On a machine shared with other work, also
//! `fastest_iteration_ms` (the least loaded iteration: compare binaries by it
//! when the means drift) and `cores_busy` (the process's CPU time over the wall
//! time of the measured iterations, from /proc/self/stat; absent where there
//! is none): 2.0 means both cores worked throughout.

use quadcl::config::Config;
use quadcl::rl::{Agent, PpoLearner, SimTrainEnv, TrainEnv};
use quadcl::sim::Perturbation;
use serde_json::json;
use std::time::Instant;

const WARM_UP: usize = 2;
const MIN_ITERATIONS: usize = 10;

/// The configurations measured: (key prefix, headline key, run file text, its name).
const CONFIGS: [(&str, &str, &str, &str); 2] = [
    ("ppo", "ppo_env_steps_per_s", include_str!("../../scenes/train-base.toml"), "scenes/train-base.toml"),
    (
        "ppo_dense",
        "ppo_env_steps_per_s_dense",
        include_str!("../../scenes/train-dense.toml"),
        "scenes/train-dense.toml",
    ),
];

/// Mean milliseconds per iteration of the per-iteration seconds under `key`.
fn mean_ms(rows: &[quadcl::rl::Metrics], key: &str) -> f64 {
    rows.iter().filter_map(|m| m.get(key)).sum::<f64>() * 1000.0 / rows.len().max(1) as f64
}

/// Measures one configuration for at least `MIN_ITERATIONS` iterations and `seconds`.
fn measure_config(
    prefix: &str,
    headline: &str,
    text: &str,
    name: &str,
    seconds: f64,
    report: &mut serde_json::Map<String, serde_json::Value>,
) -> anyhow::Result<()> {
    let config = Config::from_toml_str(text).map_err(|e| anyhow::anyhow!("{name}: {e:#}"))?;
    let task: Perturbation = "none".parse()?;
    let mut env = SimTrainEnv::new(&config.env, &task, config.ppo.num_envs, config.seed)?;
    let mut agent = Agent::new(env.dims(), &config, config.seed)?;
    agent.begin_task(0, &[])?;
    let mut learner = PpoLearner::new(config.ppo.clone(), agent, env.num_envs(), config.seed)?;
    for _ in 0..WARM_UP {
        learner.train_iteration(&mut env)?;
    }
    let mut rows = Vec::new();
    let cpu_start = process_cpu_seconds();
    let start = Instant::now();
    while rows.len() < MIN_ITERATIONS || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        let mut m = learner.train_iteration(&mut env)?;
        m.insert("bench/iteration_s".into(), t.elapsed().as_secs_f64());
        rows.push(m);
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = process_cpu_seconds().zip(cpu_start).map(|(end, start)| end - start);
    let fastest_ms =
        rows.iter().filter_map(|m| m.get("bench/iteration_s")).fold(f64::INFINITY, |a, &b| a.min(b)) * 1000.0;
    let steps = rows.len() * config.ppo.num_envs * config.ppo.steps_per_env;
    let iteration_ms = mean_ms(&rows, "bench/iteration_s");
    let physics_ms = mean_ms(&rows, "time/env_s");
    let policy_ms = mean_ms(&rows, "time/policy_s");
    let update_ms = mean_ms(&rows, "time/update_s");
    let round = |v: f64| (v * 10.0).round() / 10.0;
    report.insert(headline.into(), json!((steps as f64 / wall).round()));
    report.insert(format!("{prefix}_iteration_ms"), json!(round(iteration_ms)));
    report.insert(format!("{prefix}_physics_ms"), json!(round(physics_ms)));
    report.insert(format!("{prefix}_policy_ms"), json!(round(policy_ms)));
    report.insert(format!("{prefix}_update_ms"), json!(round(update_ms)));
    report.insert(format!("{prefix}_other_ms"), json!(round(iteration_ms - physics_ms - policy_ms - update_ms)));
    // Parts of `other`: drawing the iteration's masks, and the plasticity probes.
    report.insert(format!("{prefix}_masks_ms"), json!(round(mean_ms(&rows, "time/masks_s"))));
    report.insert(format!("{prefix}_plasticity_ms"), json!(round(mean_ms(&rows, "time/plasticity_s"))));
    report.insert(format!("{prefix}_iterations"), json!(rows.len()));
    report.insert(format!("{prefix}_fastest_iteration_ms"), json!(round(fastest_ms)));
    if let Some(cpu) = cpu {
        report.insert(format!("{prefix}_cores_busy"), json!((cpu / wall * 100.0).round() / 100.0));
    }
    Ok(())
}

/// Adds the `ppo*` keys for every configuration (only those named in `which`, when given).
pub fn measure(
    seconds: f64,
    which: Option<&str>,
    report: &mut serde_json::Map<String, serde_json::Value>,
) -> anyhow::Result<()> {
    for (prefix, headline, text, name) in CONFIGS {
        if which.is_none_or(|w| w == prefix) {
            measure_config(prefix, headline, text, name, seconds, report)?;
        }
    }
    report.insert("ppo_threads".into(), json!(rayon::current_num_threads()));
    Ok(())
}

/// The process's CPU time so far (user + system, all threads), seconds (Linux; None elsewhere).
fn process_cpu_seconds() -> Option<f64> {
    super::cpu_seconds("/proc/self/stat")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(target_os = "linux")]
    #[test]
    fn process_cpu_time_grows_with_busy_work() {
        let before = process_cpu_seconds().expect("/proc/self/stat is readable on Linux");
        let start = Instant::now();
        let mut x = 0u64;
        // Busy until the CPU time has moved by 5 ticks, for at most 10 s of wall time.
        while process_cpu_seconds().unwrap() < before + 0.05 && start.elapsed().as_secs() < 10 {
            for i in 0..100_000u64 {
                x = std::hint::black_box(x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(i));
            }
        }
        let after = process_cpu_seconds().unwrap();
        assert!(after >= before + 0.05, "CPU time {before} -> {after} s after busy work");
        assert!(after - before <= start.elapsed().as_secs_f64() * 64.0 + 0.02, "more CPU time than threads could give");
    }
}
