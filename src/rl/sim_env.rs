//! The simulated quadruped as a [`TrainEnv`]: a thin adapter over
//! `sim::VecEnv` (the batch stepped in parallel with rayon).

use super::env::{EnvDims, EnvStep, FinishedEpisode, TrainEnv};
use crate::config::EnvConfig;
use crate::sim::{Perturbation, RobotModel, VecEnv, ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_BASE_LIN_VEL, PRIV_OBS_DIM};
use std::path::{Path, PathBuf};

/// A batch of `LocomotionEnv`s on one task.
pub struct SimTrainEnv {
    inner: VecEnv,
    control_dt: f64,
}

/// The robot description named by the config: as given (absolute or from
/// the working directory), else relative to the crate root.
pub fn load_robot(cfg: &EnvConfig) -> anyhow::Result<RobotModel> {
    let given = PathBuf::from(&cfg.urdf);
    let path = if given.is_absolute() || given.exists() {
        given
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(&cfg.urdf)
    };
    RobotModel::load(&path)
}

impl SimTrainEnv {
    /// `num_envs` environments on `task`, seeded from `seed`.
    pub fn new(cfg: &EnvConfig, task: &Perturbation, num_envs: usize, seed: u64) -> anyhow::Result<Self> {
        let robot = load_robot(cfg)?;
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

    fn step(&mut self, actions: &[f32]) -> anyhow::Result<EnvStep> {
        let step = self.inner.step(actions)?;
        // `finished` lists the ended episodes in env order.
        let ended: Vec<usize> = (0..step.reward.len()).filter(|&i| step.terminated[i] || step.truncated[i]).collect();
        anyhow::ensure!(
            ended.len() == step.finished.len(),
            "VecEnv reported {} finished episodes for {} ended envs",
            step.finished.len(),
            ended.len()
        );
        let finished = ended
            .into_iter()
            .zip(step.finished)
            .map(|(env_index, e)| FinishedEpisode {
                env_index,
                episode_return: f64::from(e.episode_return),
                length_s: f64::from(e.length_s),
                lin_vel_err: f64::from(e.lin_vel_err),
                ang_vel_err: f64::from(e.ang_vel_err),
                fell: e.fell,
            })
            .collect();
        Ok(EnvStep {
            reward: step.reward,
            terminated: step.terminated,
            truncated: step.truncated,
            next_obs_before_reset: step.next_obs_before_reset,
            finished,
        })
    }
}
