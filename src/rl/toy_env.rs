//! A tiny environment that implements [`TrainEnv`] in microseconds, so the
//! learner's loop can be tested end to end without the physics: a point on a
//! line must move at a commanded velocity.
//!
//! State: position x, commanded velocity c ~ U(-1, 1) per episode, previous
//! action. Action a (1): the velocity, x += a * dt. Reward `exp(-(a - c)^2 /
//! 0.25) * dt`. Episodes last `episode_steps` steps (a time-out), and end
//! early with a "fall" when |x| > 2. Observation (3): [c, a_prev, 0];
//! privileged (6): obs + [a_prev, 0, 0] (the "base velocity" at offset 3);
//! history: the last 2 observations. The position stays out of the policy's
//! and critic observations on purpose: it is a proxy of the (unobserved) time in the
//! episode, and a critic that learns it biases GAE towards standing still.

use super::env::{EnvDims, EpisodeSummary, TrainEnv, VecStep};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const DT: f32 = 0.1;
const HISTORY: usize = 2;

/// A batch of point-mass velocity-tracking environments.
#[derive(Debug, Clone)]
pub struct ToyEnv {
    episode_steps: usize,
    x: Vec<f32>,
    command: Vec<f32>,
    prev_action: Vec<f32>,
    steps: Vec<usize>,
    episode_return: Vec<f64>,
    episode_err: Vec<f64>,
    history: Vec<f32>,
    obs: Vec<f32>,
    privileged: Vec<f32>,
    rng: ChaCha8Rng,
}

impl ToyEnv {
    pub fn new(num_envs: usize, episode_steps: usize, seed: u64) -> Self {
        let mut env = Self {
            episode_steps,
            x: vec![0.0; num_envs],
            command: vec![0.0; num_envs],
            prev_action: vec![0.0; num_envs],
            steps: vec![0; num_envs],
            episode_return: vec![0.0; num_envs],
            episode_err: vec![0.0; num_envs],
            history: vec![0.0; num_envs * HISTORY * 3],
            obs: vec![0.0; num_envs * 3],
            privileged: vec![0.0; num_envs * 6],
            rng: ChaCha8Rng::seed_from_u64(seed),
        };
        for e in 0..num_envs {
            env.reset(e);
        }
        env.refresh();
        env
    }

    fn reset(&mut self, e: usize) {
        self.x[e] = 0.0;
        self.command[e] = self.rng.gen_range(-1.0..1.0);
        self.prev_action[e] = 0.0;
        self.steps[e] = 0;
        self.episode_return[e] = 0.0;
        self.episode_err[e] = 0.0;
        let o = [self.command[e], 0.0, 0.0];
        for h in 0..HISTORY {
            self.history[(e * HISTORY + h) * 3..(e * HISTORY + h + 1) * 3].copy_from_slice(&o);
        }
    }

    fn observation(&self, e: usize) -> [f32; 3] {
        [self.command[e], self.prev_action[e], 0.0]
    }

    /// Rebuilds obs and privileged obs from the state.
    fn refresh(&mut self) {
        for e in 0..self.x.len() {
            let o = self.observation(e);
            self.obs[e * 3..e * 3 + 3].copy_from_slice(&o);
            self.privileged[e * 6..e * 6 + 6].copy_from_slice(&[o[0], o[1], o[2], self.prev_action[e], 0.0, 0.0]);
        }
    }

    fn push_history(&mut self, e: usize) {
        let row = &mut self.history[e * HISTORY * 3..(e + 1) * HISTORY * 3];
        row.copy_within(3.., 0);
        let o = [self.command[e], self.prev_action[e], 0.0];
        row[(HISTORY - 1) * 3..].copy_from_slice(&o);
    }
}

impl TrainEnv for ToyEnv {
    fn dims(&self) -> EnvDims {
        EnvDims {
            obs: 3,
            privileged_obs: 6,
            history_len: HISTORY,
            act: 1,
            base_velocity_offset: 3,
            control_dt: f64::from(DT),
        }
    }
    fn num_envs(&self) -> usize {
        self.x.len()
    }
    fn observations(&self) -> &[f32] {
        &self.obs
    }
    fn privileged_observations(&self) -> &[f32] {
        &self.privileged
    }
    fn obs_histories(&self) -> &[f32] {
        &self.history
    }

    fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep> {
        let n = self.num_envs();
        anyhow::ensure!(actions.len() == n, "toy env: expected {n} actions, got {}", actions.len());
        let mut out = VecStep {
            reward: vec![0.0; n],
            terminated: vec![false; n],
            truncated: vec![false; n],
            next_obs_before_reset: vec![0.0; n * 3],
            finished: Vec::new(),
            physics_resets: Vec::new(),
        };
        for (e, &action) in actions.iter().enumerate() {
            let a = action.clamp(-3.0, 3.0);
            self.x[e] += a * DT;
            self.prev_action[e] = a;
            self.steps[e] += 1;
            let err = a - self.command[e];
            let reward = (-(err * err) / 0.25).exp() * DT;
            out.reward[e] = reward;
            self.episode_return[e] += f64::from(reward);
            self.episode_err[e] += f64::from(err.abs());
            self.push_history(e);
            out.next_obs_before_reset[e * 3..e * 3 + 3].copy_from_slice(&self.observation(e));
            out.terminated[e] = self.x[e].abs() > 2.0;
            out.truncated[e] = self.steps[e] >= self.episode_steps;
            if out.terminated[e] || out.truncated[e] {
                out.finished.push(EpisodeSummary {
                    env: e,
                    episode_return: self.episode_return[e] as f32,
                    length_s: self.steps[e] as f32 * DT,
                    lin_vel_err: (self.episode_err[e] / self.steps[e] as f64) as f32,
                    ang_vel_err: 0.0,
                    fell: out.terminated[e],
                    term_sums: Default::default(),
                });
                self.reset(e);
            }
        }
        self.refresh();
        Ok(out)
    }
}
