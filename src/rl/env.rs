//! What the learner needs from a batch of environments: the [`TrainEnv`]
//! trait. `sim::VecEnv` implements it (in `rl/sim_env.rs`); tests implement
//! it with tiny environments so the whole training loop can be tested in
//! milliseconds.
//!
//! A step returns the simulator's own [`VecStep`] (rewards, terminations,
//! time-outs, the observations before auto-reset, finished episodes' summaries).
//!
//! Shapes (N = `num_envs`): observations (N, obs), privileged (N, priv),
//! histories (N, history_len * obs, oldest first), actions (N, act).

pub use crate::sim::{EpisodeReplay, EpisodeSummary, VecStep};

/// Widths of an environment's vectors (also stored in a policy's manifest).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnvDims {
    /// Actor observation width.
    pub obs: usize,
    /// Privileged (critic) observation width.
    pub privileged_obs: usize,
    /// Observations in the CENet's history.
    pub history_len: usize,
    /// Action width.
    pub act: usize,
    /// Offset of the 3 base-velocity entries (the CENet's target) in the privileged observation.
    pub base_velocity_offset: usize,
    /// Seconds of simulated time per control step.
    pub control_dt: f64,
}

/// A batch of environments that auto-resets finished members.
pub trait TrainEnv {
    fn dims(&self) -> EnvDims;
    fn num_envs(&self) -> usize;
    /// (N, obs), after auto-reset.
    fn observations(&self) -> &[f32];
    /// (N, priv).
    fn privileged_observations(&self) -> &[f32];
    /// (N, history_len * obs), oldest first.
    fn obs_histories(&self) -> &[f32];
    /// Steps every environment with `actions` (N, act).
    fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep>;
    /// Attaches a step observer (a recorder) to environment `env`; environments that are not
    /// simulated (the toy ones) cannot take one.
    fn observe(&mut self, env: usize, observer: Box<dyn crate::sim::StepObserver>) -> anyhow::Result<()> {
        let _ = (env, observer);
        anyhow::bail!("this environment is not simulated: there is nothing to observe")
    }
    /// From now on keep what [`Self::replays`] needs (call before the first step); false
    /// for environments that cannot (a checkpoint then restarts them afresh).
    fn keep_replays(&mut self) -> anyhow::Result<bool> {
        Ok(false)
    }
    /// Every environment's exact state as a replay of its current episode
    /// ([`EpisodeReplay`]), for a checkpoint; None when none is kept.
    fn replays(&self) -> anyhow::Result<Option<Vec<EpisodeReplay>>> {
        Ok(None)
    }
    /// Puts every environment in the state of its replay (and keeps replays from then on).
    fn restore(&mut self, replays: &[EpisodeReplay]) -> anyhow::Result<()> {
        let _ = replays;
        anyhow::bail!("this environment cannot be restored from a checkpoint")
    }
}
