//! What a policy step returns, and the per-episode bookkeeping behind the
//! `EpisodeSummary` of a finished episode (return, length, tracking errors,
//! fall, reward-term sums).

use super::reward::{RewardTerms, NUM_TERMS};

/// What one policy step returns.
#[derive(Debug, Clone)]
pub struct Step {
    /// Sum of the reward terms.
    pub reward: f32,
    /// Each term's contribution.
    pub terms: RewardTerms,
    /// Fell (trunk contact or tilt): no bootstrap.
    pub terminated: bool,
    /// Episode time-out: bootstrap.
    pub truncated: bool,
    /// The finished episode's summary when terminated or truncated.
    pub finished: Option<EpisodeSummary>,
}

/// Summary of one finished episode: what the simulator reports, and what
/// every learner (`rl::TrainEnv`, the toy environments too) and evaluation reads.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EpisodeSummary {
    /// Index of the env in its batch (0 for a lone env).
    pub env: usize,
    /// Sum of step rewards.
    pub episode_return: f32,
    /// Simulated seconds.
    pub length_s: f32,
    /// Mean |v_xy - v_xy_cmd| over the steps, m/s.
    pub lin_vel_err: f32,
    /// Mean |w_z - w_z_cmd| over the steps, rad/s.
    pub ang_vel_err: f32,
    /// Whether it ended by falling.
    pub fell: bool,
    /// Sum of each reward term over the episode, in `reward::TERM_NAMES` order.
    pub term_sums: [f32; NUM_TERMS],
}

/// Running sums over the current episode.
#[derive(Debug, Clone, Default)]
pub struct EpisodeStats {
    episode_return: f32,
    lin_vel_err: f32,
    ang_vel_err: f32,
    term_sums: [f32; NUM_TERMS],
}

impl EpisodeStats {
    /// Adds one step: its reward terms and the trunk-frame velocities against the command.
    pub fn add(&mut self, terms: &RewardTerms, lin_vel: [f32; 3], ang_vel: [f32; 3], command: [f32; 3]) {
        self.episode_return += terms.total();
        for (sum, v) in self.term_sums.iter_mut().zip(terms.values) {
            *sum += v;
        }
        self.lin_vel_err += ((lin_vel[0] - command[0]).powi(2) + (lin_vel[1] - command[1]).powi(2)).sqrt();
        self.ang_vel_err += (ang_vel[2] - command[2]).abs();
    }

    /// The summary of an episode of `steps` policy steps of `dt` seconds.
    pub fn summary(&self, env: usize, steps: usize, dt: f32, fell: bool) -> EpisodeSummary {
        let n = steps.max(1) as f32;
        EpisodeSummary {
            env,
            episode_return: self.episode_return,
            length_s: steps as f32 * dt,
            lin_vel_err: self.lin_vel_err / n,
            ang_vel_err: self.ang_vel_err / n,
            fell,
            term_sums: self.term_sums,
        }
    }
}

/// A physics step that blew up: the state went non-finite, or rapier failed
/// inside the step. The env that returns it is in no state to continue and
/// must be reset; [`VecEnv`](super::VecEnv) does so and counts it
/// (`VecStep::physics_resets`) instead of ending the run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PhysicsBlowUp(pub String);

impl std::fmt::Display for PhysicsBlowUp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PhysicsBlowUp {}
