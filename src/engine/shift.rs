//! An environment shift for sim-to-real fine-tuning (METHOD.md 2.7): other
//! friction, added mass, motor strength and action latency than the task was
//! trained with, read from a TOML file.
//!
//! ```toml
//! friction = [0.3, 0.5]        # friction coefficient range
//! added_mass = [1.0, 2.0]      # kg added to the trunk
//! motor_strength = [0.8, 0.9]  # factor on the motor torques
//! latency_s = 0.04             # action delay, rounded to whole control steps
//! iterations = 100             # fine-tuning iterations
//! ```
//!
//! Latency is applied by [`DelayedActions`], a wrapper around any
//! [`TrainEnv`]: the motors get the action chosen `latency_steps` control
//! steps earlier (zeros at the start of an episode).

use crate::config::bounds::{self, Interval, NON_NEGATIVE, POSITIVE};
use crate::config::ppo::MAX_ITERATIONS;
use crate::config::EnvConfig;
use crate::rl::{EnvDims, TrainEnv, VecStep};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use std::path::Path;

/// The longest action latency a shift may ask for, seconds: each delayed step
/// holds every env's actions, and no robot waits this long.
pub const MAX_LATENCY_S: f32 = 10.0;

/// A shifted environment (every field optional; unset ones keep the policy's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Shift {
    /// Friction coefficient range [low, high].
    pub friction: Option<[f32; 2]>,
    /// Added trunk mass range [low, high], kg.
    pub added_mass: Option<[f32; 2]>,
    /// Motor strength factor range [low, high].
    pub motor_strength: Option<[f32; 2]>,
    /// Action latency in seconds (rounded to whole control steps).
    pub latency_s: f32,
    /// Fine-tuning iterations.
    pub iterations: usize,
}

impl Default for Shift {
    fn default() -> Self {
        Self { friction: None, added_mass: None, motor_strength: None, latency_s: 0.0, iterations: 100 }
    }
}

impl Shift {
    /// Reads a shift file; errors name the file and the key.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading shift file {}", path.display()))?;
        let shift: Shift = toml::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("in shift file {}", path.display()))?;
        shift.validate().with_context(|| format!("in shift file {}", path.display()))?;
        Ok(shift)
    }

    /// Checks the ranges (with the same bounds as `[env]`'s ranges) and the budget.
    pub fn validate(&self) -> anyhow::Result<()> {
        for (key, range, interval) in [
            ("friction", self.friction, NON_NEGATIVE),
            ("added_mass", self.added_mass, Interval::Finite),
            ("motor_strength", self.motor_strength, POSITIVE),
        ] {
            if let Some(range) = range {
                bounds::check_range(key, range, interval)?;
            }
        }
        bounds::check("latency_s", self.latency_s, Interval::Closed(0.0, MAX_LATENCY_S.into()))?;
        bounds::check_count("iterations", self.iterations, 1, MAX_ITERATIONS)
    }

    /// `env` with the shift's ranges (randomisation switched on when a range is given).
    pub fn apply(&self, env: &EnvConfig) -> EnvConfig {
        let mut e = env.clone();
        if let Some(r) = self.friction {
            e.friction_range = r;
        }
        if let Some(r) = self.added_mass {
            e.added_mass_range = r;
        }
        if let Some(r) = self.motor_strength {
            e.motor_strength_range = r;
        }
        if self.friction.is_some() || self.added_mass.is_some() || self.motor_strength.is_some() {
            e.randomize = true;
        }
        e
    }

    /// The latency in whole control steps of `env`.
    pub fn latency_steps(&self, env: &EnvConfig) -> usize {
        (f64::from(self.latency_s) / f64::from(env.policy_dt())).round() as usize
    }
}

/// Delays every action by a fixed number of control steps.
pub struct DelayedActions {
    inner: Box<dyn TrainEnv + Send>,
    /// Oldest first; `delay` entries of (N, act).
    queue: VecDeque<Vec<f32>>,
}

impl DelayedActions {
    /// Wraps `inner` with a delay of `delay` control steps (0 = no delay).
    pub fn new(inner: Box<dyn TrainEnv + Send>, delay: usize) -> Self {
        let width = inner.num_envs() * inner.dims().act;
        Self { queue: (0..delay).map(|_| vec![0.0; width]).collect(), inner }
    }
}

impl TrainEnv for DelayedActions {
    fn dims(&self) -> EnvDims {
        self.inner.dims()
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
        if self.queue.is_empty() {
            return self.inner.step(actions);
        }
        self.queue.push_back(actions.to_vec());
        let applied = self.queue.pop_front().expect("a non-empty queue");
        let step = self.inner.step(&applied)?;
        let act = self.inner.dims().act;
        for e in &step.finished {
            for queued in &mut self.queue {
                queued[e.env * act..(e.env + 1) * act].fill(0.0);
            }
        }
        Ok(step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two envs, one action each; records what reached the motors; env 1 ends an episode at step 2.
    struct Recorder {
        applied: std::sync::Arc<std::sync::Mutex<Vec<Vec<f32>>>>,
        steps: usize,
        obs: Vec<f32>,
    }

    impl TrainEnv for Recorder {
        fn dims(&self) -> EnvDims {
            EnvDims { obs: 1, privileged_obs: 1, history_len: 1, act: 1, base_velocity_offset: 0, control_dt: 0.02 }
        }
        fn num_envs(&self) -> usize {
            2
        }
        fn observations(&self) -> &[f32] {
            &self.obs
        }
        fn privileged_observations(&self) -> &[f32] {
            &self.obs
        }
        fn obs_histories(&self) -> &[f32] {
            &self.obs
        }
        fn step(&mut self, actions: &[f32]) -> anyhow::Result<VecStep> {
            self.applied.lock().unwrap().push(actions.to_vec());
            self.steps += 1;
            let finished = if self.steps == 2 {
                vec![crate::sim::EpisodeSummary { env: 1, length_s: 0.04, fell: true, ..Default::default() }]
            } else {
                Vec::new()
            };
            Ok(VecStep {
                reward: vec![0.0; 2],
                terminated: vec![false; 2],
                truncated: vec![false; 2],
                next_obs_before_reset: self.obs.clone(),
                finished,
                physics_resets: Vec::new(),
            })
        }
    }

    #[test]
    fn actions_arrive_late_by_the_latency_and_a_new_episode_starts_without_stale_ones() {
        let applied = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let inner = Recorder { applied: applied.clone(), steps: 0, obs: vec![0.0; 2] };
        let mut env = DelayedActions::new(Box::new(inner), 2);
        for t in 1..=4 {
            env.step(&[t as f32, 10.0 * t as f32]).unwrap();
        }
        let got = applied.lock().unwrap().clone();
        // Env 1's episode ended at step 2: its actions of steps 1-2 never reach the next episode.
        assert_eq!(got, vec![vec![0.0, 0.0], vec![0.0, 0.0], vec![1.0, 0.0], vec![2.0, 0.0]]);
    }

    #[test]
    fn latency_rounds_to_control_steps_and_ranges_switch_randomisation_on() {
        let env = EnvConfig { randomize: false, ..EnvConfig::default() };
        let shift = Shift { latency_s: 0.041, friction: Some([0.2, 0.3]), ..Shift::default() };
        assert_eq!(shift.latency_steps(&env), (0.041 / f64::from(env.policy_dt())).round() as usize);
        let shifted = shift.apply(&env);
        assert!(shifted.randomize);
        assert_eq!(shifted.friction_range, [0.2, 0.3]);
        assert_eq!(shifted.added_mass_range, env.added_mass_range);
        assert!(Shift { friction: Some([0.5, 0.2]), ..Shift::default() }.validate().is_err());
    }
}
