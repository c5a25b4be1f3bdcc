//! The reward: the paper's Table 1, one pure function per term on a plain
//! input struct ([`RewardInput`]); [`compute`] weights each term by its
//! named weight (`EnvConfig::rewards`) and the policy dt (legged_gym
//! convention). Velocities are in the trunk frame, as in legged_gym.

use crate::config::env::{EnvConfig, RewardWeights};

/// Everything the reward terms read, for one env at one policy step.
#[derive(Debug, Clone, Default)]
pub struct RewardInput {
    /// Trunk linear velocity in the trunk frame, m/s.
    pub base_lin_vel: [f32; 3],
    /// Trunk angular velocity in the trunk frame, rad/s.
    pub base_ang_vel: [f32; 3],
    /// Gravity direction in the trunk frame (unit vector).
    pub projected_gravity: [f32; 3],
    /// Command (vx, vy, wz).
    pub command: [f32; 3],
    /// Joint positions, rad.
    pub q: [f32; 12],
    /// Soft lower / upper joint limits, rad.
    pub soft_lower: [f32; 12],
    pub soft_upper: [f32; 12],
    /// Joint torques, N m.
    pub torques: [f32; 12],
    /// Joint accelerations, rad/s^2.
    pub qdd: [f32; 12],
    /// Trunk height above the ground, m.
    pub base_height: f32,
    /// Foot heights above the ground, m.
    pub foot_height: [f32; 4],
    /// Foot horizontal speeds, m/s.
    pub foot_speed_xy: [f32; 4],
    /// Number of thigh/calf colliders touching the ground.
    pub limb_contacts: u32,
    /// This step's and the previous step's actions.
    pub action: [f32; 12],
    pub last_action: [f32; 12],
}

/// Number of reward terms.
pub const NUM_TERMS: usize = 12;

/// Term names, in the order of [`RewardTerms::values`] (also the config keys).
pub const TERM_NAMES: [&str; NUM_TERMS] = [
    "lin_vel_tracking",
    "ang_vel_tracking",
    "lin_vel_z",
    "ang_vel_xy",
    "orientation",
    "joint_limits",
    "torques",
    "joint_acc",
    "body_height",
    "feet_clearance",
    "collision",
    "action_rate",
];

/// Each term's contribution to this step's reward (weight * value * dt).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RewardTerms {
    pub values: [f32; NUM_TERMS],
}

impl RewardTerms {
    /// The step reward: the sum of the terms.
    pub fn total(&self) -> f32 {
        self.values.iter().sum()
    }
}

fn sq(x: f32) -> f32 {
    x * x
}

/// exp(-|v_xy - v_xy_cmd|^2 / sigma)
pub fn lin_vel_tracking(r: &RewardInput, sigma: f32) -> f32 {
    (-(sq(r.base_lin_vel[0] - r.command[0]) + sq(r.base_lin_vel[1] - r.command[1])) / sigma).exp()
}

/// exp(-(w_z - w_z_cmd)^2 / sigma)
pub fn ang_vel_tracking(r: &RewardInput, sigma: f32) -> f32 {
    (-sq(r.base_ang_vel[2] - r.command[2]) / sigma).exp()
}

/// v_z^2
pub fn lin_vel_z(r: &RewardInput) -> f32 {
    sq(r.base_lin_vel[2])
}

/// |w_xy|^2
pub fn ang_vel_xy(r: &RewardInput) -> f32 {
    sq(r.base_ang_vel[0]) + sq(r.base_ang_vel[1])
}

/// |g_xy|^2
pub fn orientation(r: &RewardInput) -> f32 {
    sq(r.projected_gravity[0]) + sq(r.projected_gravity[1])
}

/// Sum over joints of the distance outside the soft limits.
pub fn joint_limits(r: &RewardInput) -> f32 {
    (0..12).map(|i| (r.soft_lower[i] - r.q[i]).max(0.0) + (r.q[i] - r.soft_upper[i]).max(0.0)).sum()
}

/// |tau|^2
pub fn torques(r: &RewardInput) -> f32 {
    r.torques.iter().map(|t| t * t).sum()
}

/// |qdd|^2
pub fn joint_acc(r: &RewardInput) -> f32 {
    r.qdd.iter().map(|a| a * a).sum()
}

/// (h - h_target)^2
pub fn body_height(r: &RewardInput, target: f32) -> f32 {
    sq(r.base_height - target)
}

/// Sum over feet of (p_z - p_target)^2 * |v_foot_xy|
pub fn feet_clearance(r: &RewardInput, target: f32) -> f32 {
    (0..4).map(|f| sq(r.foot_height[f] - target) * r.foot_speed_xy[f]).sum()
}

/// Count of thigh/calf contacts with the ground.
pub fn collision(r: &RewardInput) -> f32 {
    r.limb_contacts as f32
}

/// |a_(t-1) - a_t|^2
pub fn action_rate(r: &RewardInput) -> f32 {
    (0..12).map(|i| sq(r.last_action[i] - r.action[i])).sum()
}

/// Every term, weighted and times the policy dt.
pub fn compute(r: &RewardInput, cfg: &EnvConfig) -> RewardTerms {
    let w: &RewardWeights = &cfg.rewards;
    let raw = [
        (w.lin_vel_tracking, lin_vel_tracking(r, cfg.tracking_sigma)),
        (w.ang_vel_tracking, ang_vel_tracking(r, cfg.tracking_sigma)),
        (w.lin_vel_z, lin_vel_z(r)),
        (w.ang_vel_xy, ang_vel_xy(r)),
        (w.orientation, orientation(r)),
        (w.joint_limits, joint_limits(r)),
        (w.torques, torques(r)),
        (w.joint_acc, joint_acc(r)),
        (w.body_height, body_height(r, cfg.height_target)),
        (w.feet_clearance, feet_clearance(r, cfg.feet_height_target)),
        (w.collision, collision(r)),
        (w.action_rate, action_rate(r)),
    ];
    let dt = cfg.policy_dt();
    RewardTerms { values: raw.map(|(weight, value)| weight * value * dt) }
}
