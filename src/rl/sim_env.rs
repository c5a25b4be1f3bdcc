//! The simulated quadruped as a [`TrainEnv`]: a thin adapter over
//! `sim::VecEnv` (the batch stepped in parallel with rayon).

use super::env::{EnvDims, TrainEnv, VecStep};
use crate::config::EnvConfig;
use crate::sim::{Perturbation, RobotModel, VecEnv, ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_BASE_LIN_VEL, PRIV_OBS_DIM};

/// A batch of `LocomotionEnv`s on one task.
pub struct SimTrainEnv {
    inner: VecEnv,
    control_dt: f64,
}

impl SimTrainEnv {
    /// `num_envs` environments on `task`, seeded from `seed`.
    pub fn new(cfg: &EnvConfig, task: &Perturbation, num_envs: usize, seed: u64) -> anyhow::Result<Self> {
        let robot = RobotModel::for_config(cfg)?;
        Ok(Self { inner: VecEnv::new(cfg, &robot, task, num_envs, seed)?, control_dt: f64::from(cfg.policy_dt()) })
    }

    /// The wrapped batch (for viewers and recorders).
    pub fn vec_env(&self) -> &VecEnv {
        &self.inner
    }
}

impl TrainEnv for SimTrainEnv {
    fn dims(&self) -> EnvDims {
        EnvDims {
            obs: OBS_DIM,
            privileged_obs: PRIV_OBS_DIM,
            history_len: HISTORY_LEN,
            act: ACT_DIM,
            base_velocity_offset: PRIV_BASE_LIN_VEL,
            control_dt: self.control_dt,
        }
    }
    fn num_envs(&self) -> usize {
        self.inner.num_envs()
    }
    fn observations(&self) -> &[f32] {
        self.inner.observations()
    }
    fn privileged_observations(&self) -> &[f32] {
        self.inner.privileged_observations()
    }
    fn obs_histories(&self) -> &[f32] {
        self.inner.obs_histories()
    }

    fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep> {
        self.inner.step(actions)
    }

    fn observe(&mut self, env: usize, observer: Box<dyn crate::sim::StepObserver>) -> anyhow::Result<()> {
        self.inner.observe(env, observer)
    }

    fn keep_replays(&mut self) -> anyhow::Result<bool> {
        self.inner.keep_replays()?;
        Ok(true)
    }

    fn replays(&self) -> anyhow::Result<Option<Vec<crate::sim::EpisodeReplay>>> {
        self.inner.replays().map(Some)
    }

    fn restore(&mut self, replays: &[crate::sim::EpisodeReplay]) -> anyhow::Result<()> {
        self.inner.restore(replays)
    }
}
