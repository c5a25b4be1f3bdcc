//! One task's training run, start to end: the loop behind `quadcl train`.
//!
//! Writes into the output directory:
//! - `config.toml`: the full configuration of the run;
//! - `metrics.jsonl`: one JSON object per iteration with the namespaced
//!   metrics (`charts/episodic_return`, `losses/approx_kl`, `charts/SPS`, ...);
//! - `policy/`: the trained policy (see [`super::policy_dir`]), saved when
//!   the task ends (final masks chosen, observation statistics frozen: they
//!   belong to the task). The base policy is task 0 of the masked learner.

use super::agent::Agent;
use super::env::TrainEnv;
use super::policy_dir::{save_policy, PolicyInfo};
use super::ppo::{Metrics, PpoLearner};
use crate::config::Config;
use crate::util::write_atomic;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;
use std::time::Instant;

/// Rewrite `metrics.jsonl` at least every this many iterations.
const METRICS_FLUSH_EVERY: usize = 10;

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct TrainSummary {
    pub iterations: usize,
    /// Environment control steps taken (all envs).
    pub env_steps: usize,
    pub wall_s: f64,
    /// Seconds in `env.step` (physics), policy/critic forward passes during rollouts, and updates.
    pub env_s: f64,
    pub policy_s: f64,
    pub update_s: f64,
    /// The last iteration's metrics.
    pub last: Metrics,
}

/// The learner's random stream is derived from the master seed, apart from
/// the network initialisers and the environment's.
pub fn learner_seed(master: u64) -> u64 {
    master ^ 0x5eed_1ea7_0000_0001
}

/// Trains a fresh agent on `env` for `config.ppo.iterations` iterations and
/// writes the results into `out`. `progress`: show a progress bar on stderr.
pub fn train(config: &Config, task: &str, env: &mut dyn TrainEnv, out: &Path, progress: bool) -> anyhow::Result<TrainSummary> {
    let cfg = &config.ppo;
    cfg.validate()?;
    write_atomic(&out.join("config.toml"), config.to_toml_string().as_bytes())?;
    let mut agent = Agent::new(env.dims(), config, config.seed)?;
    agent.begin_task(0, &[])?;
    let mut learner = PpoLearner::new(cfg.clone(), agent, env.num_envs(), learner_seed(config.seed))?;

    let bar = if progress { ProgressBar::new(cfg.iterations as u64) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} it  eta {eta}  {msg}")
            .expect("a valid progress template")
            .progress_chars("=> "),
    );
    let start = Instant::now();
    let mut log = String::new();
    let mut summary = TrainSummary { iterations: 0, env_steps: 0, wall_s: 0.0, env_s: 0.0, policy_s: 0.0, update_s: 0.0, last: Metrics::new() };
    for it in 0..cfg.iterations {
        let mut m = learner.train_iteration(env)?;
        summary.env_steps += cfg.steps_per_env * env.num_envs();
        m.insert("charts/env_steps".into(), summary.env_steps as f64);
        m.insert("time/wall_s".into(), start.elapsed().as_secs_f64());
        summary.env_s += m.get("time/env_s").copied().unwrap_or(0.0);
        summary.policy_s += m.get("time/policy_s").copied().unwrap_or(0.0);
        summary.update_s += m.get("time/update_s").copied().unwrap_or(0.0);
        log.push_str(&serde_json::to_string(&m)?);
        log.push('\n');
        let last = it + 1 == cfg.iterations;
        if last || (it + 1) % METRICS_FLUSH_EVERY == 0 {
            write_atomic(&out.join("metrics.jsonl"), log.as_bytes())?;
        }
        if cfg.log_every > 0 && (it % cfg.log_every == 0 || last) {
            let get = |k: &str| m.get(k).copied().unwrap_or(f64::NAN);
            bar.set_message(format!(
                "return {:.2}  lin_err {:.2}  fall {:.2}  SPS {:.0}",
                get("charts/episodic_return"),
                get("charts/lin_vel_err"),
                get("charts/fall_rate"),
                get("charts/SPS")
            ));
        }
        bar.inc(1);
        summary.last = m;
    }
    bar.finish();
    learner.end_task()?;
    let info = PolicyInfo { config: config.clone(), dims: env.dims().into(), iterations: cfg.iterations };
    save_policy(&learner.agent, &[task.to_string()], &info, &out.join("policy"))?;
    summary.iterations = cfg.iterations;
    summary.wall_s = start.elapsed().as_secs_f64();
    Ok(summary)
}
