//! What the learner needs from a batch of environments: the [`TrainEnv`]
//! trait. `sim::VecEnv` implements it (in `rl/sim_env.rs`); tests implement
//! it with tiny environments so the whole training loop can be tested in
//! milliseconds.
//!
//! Shapes (N = `num_envs`): observations (N, obs), privileged (N, priv),
//! histories (N, history_len * obs, oldest first), actions (N, act).

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

/// An episode that ended during a step.
#[derive(Debug, Clone, PartialEq)]
pub struct FinishedEpisode {
    /// Which member of the batch it was.
    pub env_index: usize,
    /// Sum of the (dt-scaled) rewards.
    pub episode_return: f64,
    /// Simulated seconds survived.
    pub length_s: f64,
    /// Mean |v_xy - v_cmd| over the episode, m/s.
    pub lin_vel_err: f64,
    /// Mean |w_z - w_cmd| over the episode, rad/s.
    pub ang_vel_err: f64,
    /// Ended by a fall (termination), not by the time limit.
    pub fell: bool,
}

/// The outcome of one step of every environment.
#[derive(Debug, Clone, Default)]
pub struct EnvStep {
    /// (N,)
    pub reward: Vec<f32>,
    /// (N,) fell: no bootstrap.
    pub terminated: Vec<bool>,
    /// (N,) time limit: bootstrapped.
    pub truncated: Vec<bool>,
    /// (N, obs): the observation the step reached, before any auto-reset.
    pub next_obs_before_reset: Vec<f32>,
    /// Episodes that ended in this step.
    pub finished: Vec<FinishedEpisode>,
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
    fn step(&mut self, actions: &[f32]) -> anyhow::Result<EnvStep>;
}
