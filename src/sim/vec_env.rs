//! A batch of `LocomotionEnv`s stepped in parallel with rayon, auto-resetting
//! the ones that finish, and the ones whose physics blew up (a non-finite
//! state or a rapier failure costs that env its episode, not the run).
//!
//! Determinism: each env owns its world and its own ChaCha stream seeded
//! from (seed, env index), and results are gathered by index, so the same
//! seed gives bit-identical numbers whatever the number of rayon threads.
//! Buffers are row-major: observations (num_envs, OBS_DIM), privileged
//! observations (num_envs, PRIV_OBS_DIM), histories (num_envs, HISTORY_LEN * OBS_DIM).
//!
//! A batch may instead step and reset its envs one after another on the calling
//! thread ([`VecEnv::set_on_calling_thread`]): the same numbers, without handing
//! each call to a rayon worker and waiting for it (about 75 µs a call, which is
//! most of a one-env step from Python).

use super::env::{EpisodeReplay, LocomotionEnv};
use super::episode::{EpisodeSummary, PhysicsBlowUp, Step};
use super::obs::{ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_OBS_DIM};
use super::robot::RobotModel;
use super::tasks::Perturbation;
use crate::config::EnvConfig;
use crate::util::{derive_seed, Stream};
use anyhow::bail;
use rayon::prelude::*;
use std::sync::Arc;

/// What a step of a batch of environments returns: the simulator's
/// [`VecEnv::step`], and every `rl::TrainEnv`'s.
#[derive(Debug, Clone, Default)]
pub struct VecStep {
    /// (num_envs,)
    pub reward: Vec<f32>,
    /// Fell (trunk contact / tilt): no bootstrap. (num_envs,)
    pub terminated: Vec<bool>,
    /// Time-out: PPO bootstraps. (num_envs,)
    pub truncated: Vec<bool>,
    /// (num_envs, OBS_DIM): the observation reached by this step, before any auto-reset.
    pub next_obs_before_reset: Vec<f32>,
    /// Episodes that ended in this step, in env order.
    pub finished: Vec<EpisodeSummary>,
    /// Envs whose physics blew up in this step, with what happened: each was
    /// reset (its row reads terminated, reward 0, the new episode's first
    /// observation) and its cut-short episode is not among `finished`.
    pub physics_resets: Vec<(usize, String)>,
}

/// What one env's step came to.
enum StepOutcome {
    /// A step, with the observation it reached (before any auto-reset).
    Stepped(Step, [f32; OBS_DIM]),
    /// The physics blew up (what happened) and the env was reset (its first observation).
    Reset(String, [f32; OBS_DIM]),
}

/// A batch of environments.
pub struct VecEnv {
    envs: Vec<LocomotionEnv>,
    obs: Vec<f32>,
    priv_obs: Vec<f32>,
    histories: Vec<f32>,
    /// Step and reset the envs in order on the calling thread, not on rayon's pool.
    on_calling_thread: bool,
}

impl VecEnv {
    /// `num_envs` envs with the same task, env i reset with `derive_seed(seed, Stream::Env(i))`.
    pub fn new(
        cfg: &EnvConfig,
        robot: &RobotModel,
        task: &Perturbation,
        num_envs: usize,
        seed: u64,
    ) -> anyhow::Result<Self> {
        crate::config::ppo::check_env_count("the batch's env count", num_envs)?;
        let robot = Arc::new(robot.clone());
        let envs = (0..num_envs)
            .into_par_iter()
            .map(|i| {
                let mut env = LocomotionEnv::with_shared_robot(cfg, robot.clone(), task, i)?;
                env.reset(derive_seed(seed, Stream::Env(i)))?;
                Ok(env)
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let mut v = Self {
            obs: vec![0.0; num_envs * OBS_DIM],
            priv_obs: vec![0.0; num_envs * PRIV_OBS_DIM],
            histories: vec![0.0; num_envs * HISTORY_LEN * OBS_DIM],
            envs,
            on_calling_thread: false,
        };
        v.gather();
        Ok(v)
    }

    /// Attaches `observer` to env `env` (it hears that env's episode starts and steps).
    pub fn observe(&mut self, env: usize, observer: Box<dyn super::observe::StepObserver>) -> anyhow::Result<()> {
        let n = self.envs.len();
        let e = self.envs.get_mut(env).ok_or_else(|| anyhow::anyhow!("no env {env}: the batch has {n}"))?;
        e.observe(observer);
        e.announce();
        Ok(())
    }

    /// Pushes env `env` now: adds `dv` (world x, y, m/s) to its trunk's velocity.
    pub fn push(&mut self, env: usize, dv: [f32; 2]) -> anyhow::Result<()> {
        let n = self.envs.len();
        self.envs.get_mut(env).ok_or_else(|| anyhow::anyhow!("no env {env}: the batch has {n}"))?.push(dv);
        Ok(())
    }

    /// Number of envs.
    pub fn num_envs(&self) -> usize {
        self.envs.len()
    }

    /// (num_envs, OBS_DIM): current observations (after auto-reset).
    pub fn observations(&self) -> &[f32] {
        &self.obs
    }

    /// (num_envs, PRIV_OBS_DIM)
    pub fn privileged_observations(&self) -> &[f32] {
        &self.priv_obs
    }

    /// (num_envs, HISTORY_LEN * OBS_DIM), oldest first.
    pub fn obs_histories(&self) -> &[f32] {
        &self.histories
    }

    /// The envs, for inspection.
    pub fn envs(&self) -> &[LocomotionEnv] {
        &self.envs
    }

    /// Changes every env's task (takes effect at the next step).
    pub fn set_task(&mut self, task: &Perturbation) {
        for env in &mut self.envs {
            env.set_task(task);
        }
    }

    /// `true`: [`Self::step`], [`Self::reset`] and [`Self::restore`] run the envs in order on the calling thread
    /// (one thread's worth of work without a pool's hand-off); `false` (the default): on rayon's
    /// pool, the one the caller runs in. The numbers are the same either way.
    pub fn set_on_calling_thread(&mut self, on: bool) {
        self.on_calling_thread = on;
    }

    /// Reseeds and resets every env (env i with `derive_seed(seed, Stream::Env(i))`).
    pub fn reset(&mut self, seed: u64) -> anyhow::Result<()> {
        let reset = |(i, env): (usize, &mut LocomotionEnv)| env.reset(derive_seed(seed, Stream::Env(i)));
        if self.on_calling_thread {
            self.envs.iter_mut().enumerate().try_for_each(reset)?;
        } else {
            self.envs.par_iter_mut().enumerate().try_for_each(reset)?;
        }
        self.gather();
        Ok(())
    }

    /// From now on every env keeps what [`Self::replays`] needs (before the first step).
    pub fn keep_replays(&mut self) -> anyhow::Result<()> {
        self.envs.iter_mut().try_for_each(LocomotionEnv::keep_replay)
    }

    /// Every env's exact state, as a replay of its current episode (see `sim::EpisodeReplay`).
    pub fn replays(&self) -> anyhow::Result<Vec<EpisodeReplay>> {
        self.envs.iter().map(LocomotionEnv::replay).collect()
    }

    /// Puts every env in the state of its replay (the envs in parallel) and keeps replays from then on.
    pub fn restore(&mut self, replays: &[EpisodeReplay]) -> anyhow::Result<()> {
        anyhow::ensure!(
            replays.len() == self.envs.len(),
            "{} env replays for a batch of {} envs",
            replays.len(),
            self.envs.len()
        );
        let restore = |(env, replay): (&mut LocomotionEnv, &EpisodeReplay)| env.restore(replay);
        if self.on_calling_thread {
            self.envs.iter_mut().zip(replays).try_for_each(restore)?;
        } else {
            self.envs.par_iter_mut().zip(replays).try_for_each(restore)?;
        }
        self.gather();
        Ok(())
    }

    /// Steps every env with its row of `actions` (num_envs, ACT_DIM); finished envs are reset.
    pub fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep> {
        let n = self.envs.len();
        if actions.len() != n * ACT_DIM {
            bail!("VecEnv::step: {} actions for {n} envs, expected {} ({n} x {ACT_DIM})", actions.len(), n * ACT_DIM);
        }
        let step = |(env, action): (&mut LocomotionEnv, &[f32])| -> anyhow::Result<StepOutcome> {
            match env.step(action) {
                Ok(step) => {
                    let next_obs = *env.observation();
                    if step.terminated || step.truncated {
                        env.reset_episode()?;
                    }
                    Ok(StepOutcome::Stepped(step, next_obs))
                }
                Err(e) => match e.downcast_ref::<PhysicsBlowUp>() {
                    Some(_) => {
                        env.reset_episode()?;
                        Ok(StepOutcome::Reset(format!("{e:#}"), *env.observation()))
                    }
                    None => Err(e),
                },
            }
        };
        let results: Vec<anyhow::Result<StepOutcome>> = if self.on_calling_thread {
            self.envs.iter_mut().zip(actions.chunks(ACT_DIM)).map(step).collect()
        } else {
            self.envs.par_iter_mut().zip(actions.par_chunks(ACT_DIM)).map(step).collect()
        };
        let mut out = VecStep {
            reward: Vec::with_capacity(n),
            terminated: Vec::with_capacity(n),
            truncated: Vec::with_capacity(n),
            next_obs_before_reset: Vec::with_capacity(n * OBS_DIM),
            finished: Vec::new(),
            physics_resets: Vec::new(),
        };
        for (i, r) in results.into_iter().enumerate() {
            match r? {
                StepOutcome::Stepped(step, next_obs) => {
                    out.reward.push(step.reward);
                    out.terminated.push(step.terminated);
                    out.truncated.push(step.truncated);
                    out.next_obs_before_reset.extend_from_slice(&next_obs);
                    out.finished.extend(step.finished);
                }
                StepOutcome::Reset(what, first_obs) => {
                    tracing::warn!("{what}; the env was reset");
                    out.reward.push(0.0);
                    out.terminated.push(true);
                    out.truncated.push(false);
                    out.next_obs_before_reset.extend_from_slice(&first_obs);
                    out.physics_resets.push((i, what));
                }
            }
        }
        self.gather();
        Ok(out)
    }

    fn gather(&mut self) {
        for (i, env) in self.envs.iter().enumerate() {
            self.obs[i * OBS_DIM..(i + 1) * OBS_DIM].copy_from_slice(env.observation());
            self.priv_obs[i * PRIV_OBS_DIM..(i + 1) * PRIV_OBS_DIM].copy_from_slice(env.privileged_observation());
            let h = HISTORY_LEN * OBS_DIM;
            self.histories[i * h..(i + 1) * h].copy_from_slice(env.obs_history());
        }
    }
}
