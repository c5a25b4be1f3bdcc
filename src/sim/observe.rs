//! Watching one environment from outside: a [`StepObserver`] attached to a
//! `LocomotionEnv` ([`LocomotionEnv::observe`](super::LocomotionEnv::observe))
//! hears every episode start and every control step, with the step's reward
//! terms, which a batch or a learner otherwise drops. Recorders (`record/`)
//! implement it; the simulator knows nothing of them. An env without an
//! observer pays nothing.

use super::physics::RawState;
use super::reward::RewardTerms;

/// One link's world pose: translation (m) and rotation quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkPose {
    pub translation: [f32; 3],
    pub rotation: [f32; 4],
}

/// The env at an episode start or after a control step.
#[derive(Debug, Clone, Copy)]
pub struct StepInfo<'a> {
    /// Index of the env in its batch.
    pub env: usize,
    /// Simulated seconds since the env was built (across episodes).
    pub sim_time: f64,
    /// Control steps into the episode (0 at its start).
    pub episode_step: usize,
    /// Trunk pose and velocities, joint angles and speeds, foot points.
    pub state: &'a RawState,
    /// World pose of the trunk (first) and of the link each leg joint moves, in leg-joint order.
    pub links: &'a [LinkPose; 13],
    /// The velocity command (vx, vy, wz).
    pub command: [f32; 3],
    /// PD targets, rad.
    pub targets: &'a [f32; 12],
    /// Joint torques of the last physics step, N m.
    pub torques: &'a [f32; 12],
    /// The step's reward and its terms (None at an episode start).
    pub reward: Option<(f32, &'a RewardTerms)>,
    /// Feet touching the ground (FL, FR, RL, RR).
    pub contacts: [bool; 4],
    /// A push applied during this step (world x, y velocity change).
    pub push: Option<[f32; 2]>,
    pub terminated: bool,
    pub truncated: bool,
}

/// Hears an env's episode starts and control steps.
pub trait StepObserver: Send {
    /// A new episode started (after the reset).
    fn on_reset(&mut self, info: &StepInfo);
    /// A control step ended.
    fn on_step(&mut self, info: &StepInfo);
    /// The recording is over: flush and close what it writes; reports the first error it met.
    fn finish(&mut self) -> anyhow::Result<()> {
        Ok(())
    }
}
