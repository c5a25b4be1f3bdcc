//! One task's training run, start to end: the loop behind `quadcl train`.
//!
//! Writes into the output directory:
//! - `config.toml`: the full configuration of the run;
//! - `metrics.jsonl`: one JSON object per iteration with the namespaced
//!   metrics (`charts/episodic_return`, `losses/approx_kl`, `charts/SPS`, ...);
//! - `policy/`: the trained policy (see [`super::policy_dir`]), saved when
//!   the task ends (final masks chosen, observation statistics frozen: they
//!   belong to the task). The base policy is task 0 of the masked learner.
//! - `checkpoint/`: every `ppo.checkpoint_every` iterations, the run in
//!   progress (networks with their soft scores, log-std, normaliser
//!   statistics, `trainer.json`: iterations done, learning rate, env steps,
//!   and `training_state.safetensors`: Adam's moments, the random streams,
//!   full-precision statistics and every env's state, see
//!   [`super::training_state`]). The folder is replaced as a whole (written
//!   beside, then renamed), so an interruption leaves the previous checkpoint intact.
//!
//! `--resume` goes on from `checkpoint/` (with `--iterations` equal to the
//! checkpoint's, it only ends the task and writes `policy/`); metrics rows
//! after the checkpoint are dropped. The run then goes on bit for bit as if
//! it had never stopped: the same policy and the same metrics, timing fields
//! aside (each env re-runs its current episode from its stream to reach its
//! state; see `sim::EpisodeReplay`). A checkpoint without
//! `training_state.safetensors` (written before it existed, or by an
//! environment that keeps no replays) resumes as before: networks,
//! statistics, learning rate and iteration count restored, Adam's moments
//! and the environments afresh from seeds derived from (seed, iteration):
//! deterministic, not bit-identical.

use super::agent::Agent;
use super::env::TrainEnv;
use super::metrics::Metrics;
use super::metrics_log::MetricsLog;
use super::policy_dir::{load_training_checkpoint, save_policy, PolicyInfo};
use super::ppo::PpoLearner;
use super::progress::{iteration_summary, progress_bar, TrainingClock};
use super::training_state::{TrainingState, TRAINING_STATE_FILE};
use crate::config::Config;
use crate::log::ScalarLog;
use crate::util::{derive_seed, replace_dir, write_atomic, Stream};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::Path;

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

/// What `checkpoint/trainer.json` holds besides the policy.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrainerState {
    /// Iterations completed when the checkpoint was written.
    pub iteration: usize,
    /// The adaptive learning rate at that moment.
    pub learning_rate: f64,
    /// Environment control steps taken so far (all envs).
    pub env_steps: usize,
    /// Wall-clock seconds of training so far.
    pub wall_s: f64,
    /// SHA-256 of `training_state.safetensors` (absent in checkpoints from before it existed):
    /// a damaged or edited state is refused, not resumed into a different run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub training_state_sha256: Option<String>,
}

/// Where `--resume` goes on from: the agent, where the run was, and (in checkpoints
/// that have it) the rest of the run's state, which makes the resume exact.
#[derive(Debug)]
pub struct ResumePoint {
    pub agent: Agent,
    pub state: TrainerState,
    pub training: Option<TrainingState>,
}

impl ResumePoint {
    /// Whether the run goes on bit for bit (the environments' state included).
    pub fn is_exact(&self) -> bool {
        self.training.as_ref().is_some_and(TrainingState::has_envs)
    }
}

/// Trains a fresh agent on `env` for `config.ppo.iterations` iterations and
/// writes the results into `out` (TensorBoard events and CSV in `out/tb/` too). `progress`:
/// show a progress bar on stderr.
pub fn train(
    config: &Config,
    task: &str,
    env: &mut dyn TrainEnv,
    out: &Path,
    progress: bool,
) -> anyhow::Result<TrainSummary> {
    train_from(config, task, env, out, progress, true, None)
}

/// Reads `out/checkpoint/` for `--resume`: the agent and where the run was.
/// The checkpoint must belong to the same task and configuration, apart
/// from `ppo.iterations` (which may grow) and the mask settings that do not act
/// while a task is in progress ([`crate::config::net::MaskConfig::with_end_of_task`]:
/// METHOD.md 2.4, and where the next task's bias starts), so a finished run can be
/// ended again with other ones; errors name the folder.
pub fn load_resume_point(config: &Config, task: &str, out: &Path) -> anyhow::Result<ResumePoint> {
    let dir = out.join("checkpoint");
    crate::util::recover_replaced_dir(&dir)?;
    anyhow::ensure!(dir.is_dir(), "{}: no checkpoint to resume from (is `ppo.checkpoint_every` 0?)", dir.display());
    let loaded = load_training_checkpoint(&dir)?;
    anyhow::ensure!(
        loaded.tasks.get(loaded.agent.task).map(String::as_str) == Some(task),
        "{}: the checkpoint trains task {:?}, not {task:?}",
        dir.display(),
        loaded.tasks.get(loaded.agent.task)
    );
    let mut saved = loaded.info.config.clone();
    saved.ppo.iterations = config.ppo.iterations;
    // What acts only at the end of the task may change: training up to the end does not read it.
    saved.net.mask = saved.net.mask.with_end_of_task(&config.net.mask);
    anyhow::ensure!(
        &saved == config,
        "{}: the checkpoint was trained with another configuration than the one given (compare {} with the config file)",
        dir.display(),
        out.join("config.toml").display()
    );
    let path = dir.join("trainer.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let state: TrainerState =
        serde_json::from_str(&text).with_context(|| format!("{}: not a trainer state", path.display()))?;
    anyhow::ensure!(
        state.iteration <= config.ppo.iterations,
        "{}: the checkpoint is at iteration {}, past the {} iterations asked for",
        path.display(),
        state.iteration,
        config.ppo.iterations
    );
    let mut agent = loaded.agent;
    agent.set_end_of_task(&config.net.mask)?;
    let path = dir.join(TRAINING_STATE_FILE);
    let training = match (path.exists(), &state.training_state_sha256) {
        (false, None) => None,
        (false, Some(_)) => anyhow::bail!("{}: missing, though trainer.json names its digest", path.display()),
        (true, None) => anyhow::bail!("{}: trainer.json names no digest for it", path.display()),
        (true, Some(digest)) => {
            let bytes = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
            anyhow::ensure!(
                &crate::util::sha256_hex(&bytes) == digest,
                "{}: its content does not match the digest in trainer.json (damaged or edited)",
                path.display()
            );
            Some(TrainingState::from_bytes(&path, &bytes)?)
        }
    };
    Ok(ResumePoint { agent, state, training })
}

/// Writes `checkpoint/` as a whole (see [`replace_dir`]), so a crash leaves
/// the previous checkpoint intact.
fn save_checkpoint(
    learner: &PpoLearner,
    env: &dyn TrainEnv,
    task: &str,
    info: &PolicyInfo,
    state: &TrainerState,
    out: &Path,
) -> anyhow::Result<()> {
    let training = TrainingState::of(learner, env)?.to_bytes()?;
    let state = TrainerState { training_state_sha256: Some(crate::util::sha256_hex(&training)), ..state.clone() };
    replace_dir(&out.join("checkpoint"), |dir| {
        save_policy(&learner.agent, &[task.to_string()], info, dir)?;
        crate::nn::checkpoint::write_provenance(dir, &crate::util::Provenance::of_this_build(None))?;
        write_atomic(&dir.join(TRAINING_STATE_FILE), &training)?;
        write_atomic(&dir.join("trainer.json"), serde_json::to_string_pretty(&state)?.as_bytes())
    })
}

/// [`train`], or with `resume` (from [`load_resume_point`]) the same run
/// continued from its checkpoint; with `tensorboard`, every iteration's metrics also go
/// to `out/tb/` as TensorBoard events and CSV ([`crate::log::ScalarLog`], step = the
/// iteration, from 1, as `charts/iteration` counts); `env` must be fresh (not stepped yet), and
/// for a checkpoint that is not exact ([`ResumePoint::is_exact`]) seeded with
/// `derive_seed(config.seed, Stream::Trainer(iteration))`.
pub fn train_from(
    config: &Config,
    task: &str,
    env: &mut dyn TrainEnv,
    out: &Path,
    progress: bool,
    tensorboard: bool,
    resume: Option<ResumePoint>,
) -> anyhow::Result<TrainSummary> {
    let cfg = &config.ppo;
    cfg.validate()?;
    // Checkpoints keep each env's episode so far, so that a resume is exact.
    if cfg.checkpoint_every > 0 {
        env.keep_replays()?;
    }
    write_atomic(&out.join("config.toml"), config.to_toml_string().as_bytes())?;
    let metrics_path = out.join("metrics.jsonl");
    let (mut learner, done, mut log, kept) = match resume {
        None => {
            let mut agent = Agent::new(env.dims(), config, config.seed)?;
            // The one task's settings: E resolved for its budget (a share of it unless a count is set).
            agent.set_mask_config(&config.net.mask.for_budget(cfg.iterations))?;
            agent.begin_task(0, &[])?;
            (
                PpoLearner::new(cfg.clone(), agent, env.num_envs(), derive_seed(config.seed, Stream::Trainer(0)))?,
                None,
                MetricsLog::create(&metrics_path)?,
                Vec::new(),
            )
        }
        Some(ResumePoint { agent, state, training }) => {
            let mut learner = PpoLearner::new(
                cfg.clone(),
                agent,
                env.num_envs(),
                derive_seed(config.seed, Stream::Trainer(state.iteration)),
            )?;
            learner.iteration = state.iteration;
            learner.optimizer.set_learning_rate(state.learning_rate);
            match training {
                Some(training) => {
                    let (exact, steps) = (training.has_envs(), training.replay_steps());
                    let dir = out.join("checkpoint");
                    training.restore(&mut learner, env).with_context(|| format!("{}: resuming", dir.display()))?;
                    if exact {
                        tracing::info!("resumed exactly at iteration {} ({steps} env steps replayed)", state.iteration);
                    } else {
                        tracing::warn!("{}: these environments keep no state; they start afresh", dir.display());
                    }
                }
                None => tracing::warn!(
                    "{}: no {TRAINING_STATE_FILE} (an older checkpoint): Adam and the environments start afresh, so the run is deterministic but not bit-identical to one that never stopped",
                    out.join("checkpoint").display()
                ),
            }
            // Rows after the checkpoint go (also when a resume has nothing left to train).
            let (log, kept) = MetricsLog::resume(&metrics_path, state.iteration)?;
            (learner, Some(state), log, kept)
        }
    };
    let first = done.as_ref().map_or(0, |s| s.iteration);
    let tb_dir = out.join("tb");
    let mut tb = if tensorboard { Some(ScalarLog::after(&tb_dir, first)?) } else { None };

    let bar = progress_bar(cfg.iterations, progress);
    bar.set_prefix(task.to_string());
    bar.set_position(first as u64);
    let mut clock =
        TrainingClock::new(done.as_ref().map_or(0, |s| s.env_steps), done.as_ref().map_or(0.0, |s| s.wall_s));
    // A resumed run's time splits start from the kept rows, so the summary covers the whole run.
    let kept_time = |key: &str| -> f64 { kept.iter().filter_map(|m| m.get(key).copied()).sum() };
    let mut summary = TrainSummary {
        iterations: 0,
        env_steps: 0,
        wall_s: 0.0,
        env_s: kept_time("time/env_s"),
        policy_s: kept_time("time/policy_s"),
        update_s: kept_time("time/update_s"),
        last: Metrics::new(),
    };
    let dims = env.dims();
    let info_at = |iterations: usize| PolicyInfo { config: config.clone(), dims, iterations };
    for it in first..cfg.iterations {
        let mut m = learner.train_iteration(env)?;
        clock.stamp(&mut m, cfg.steps_per_env * env.num_envs());
        summary.env_s += m.get("time/env_s").copied().unwrap_or(0.0);
        summary.policy_s += m.get("time/policy_s").copied().unwrap_or(0.0);
        summary.update_s += m.get("time/update_s").copied().unwrap_or(0.0);
        log.append(&m)?;
        if let Some(tb) = &mut tb {
            tb.write(it as i64 + 1, m.iter().map(|(k, v)| (k.as_str(), *v)))?;
        }
        let last = it + 1 == cfg.iterations;
        // The last iteration is checkpointed too (before the task ends), so a
        // finished run can be resumed with a larger `--iterations`.
        let checkpoint = cfg.checkpoint_every > 0 && ((it + 1) % cfg.checkpoint_every == 0 || last);
        if checkpoint {
            log.sync()?;
            tb.as_mut().map(ScalarLog::flush).transpose()?;
            let state = TrainerState {
                iteration: it + 1,
                learning_rate: learner.optimizer.learning_rate(),
                env_steps: clock.env_steps(),
                wall_s: clock.wall_s(),
                training_state_sha256: None,
            };
            save_checkpoint(&learner, env, task, &info_at(it + 1), &state, out)?;
        }
        if cfg.log_every > 0 && (it % cfg.log_every == 0 || last) {
            bar.set_message(iteration_summary(&m));
        }
        bar.inc(1);
        summary.last = m;
    }
    bar.finish();
    log.sync()?;
    tb.as_mut().map(ScalarLog::flush).transpose()?;
    learner.end_task()?;
    save_policy(&learner.agent, &[task.to_string()], &info_at(cfg.iterations), &out.join("policy"))?;
    crate::nn::checkpoint::write_provenance(&out.join("policy"), &crate::util::Provenance::of_this_build(None))?;
    summary.iterations = cfg.iterations;
    summary.env_steps = clock.env_steps();
    summary.wall_s = clock.wall_s();
    Ok(summary)
}
