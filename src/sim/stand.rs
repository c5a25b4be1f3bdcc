//! Whether a robot stands: dropped from its start height, held by the PD
//! motors at its default pose (zero actions) on flat ground for a while, with
//! nominal physics and no pushes. `quadcl robot` prints it; the robot tests
//! use it for every URDF they write.
//!
//! It stood when the episode did not end (no trunk contact, tilt under
//! `env.max_tilt_rad`), the trunk is upright within 0.2 rad at the end, all
//! four feet touch the ground, and the trunk is at least half of
//! `env.height_target` high.

use super::env::LocomotionEnv;
use super::robot::{RobotModel, NUM_LEGS};
use super::tasks::Perturbation;
use crate::config::EnvConfig;
use serde::Serialize;

/// The robot after settling, world frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StandReport {
    /// Simulated seconds settled.
    pub seconds: f32,
    /// Trunk (root link frame) height at the end, metres.
    pub trunk_height: f32,
    /// The run file's body height target, metres.
    pub height_target: f32,
    /// Angle of the trunk's up axis from vertical at the end, rad.
    pub tilt_rad: f32,
    /// Feet on the ground at the end, FL, FR, RL, RR.
    pub feet_in_contact: [bool; NUM_LEGS],
    /// The largest |PD torque| of the last step over the leg joints, N m.
    pub max_torque: f32,
    /// The episode ended (trunk contact or tilt) before the time was up.
    pub fell: bool,
    /// Stood (see the module header).
    pub stood: bool,
}

/// Settles the robot for `seconds` at its default pose; errors from the physics are returned.
pub fn stand_test(cfg: &EnvConfig, robot: &RobotModel, seconds: f32) -> anyhow::Result<StandReport> {
    let cfg = EnvConfig { randomize: false, push_interval_s: 0.0, episode_s: seconds + 1.0, ..cfg.clone() };
    let mut env = LocomotionEnv::new(&cfg, robot, &Perturbation::none())?;
    env.set_command([0.0; 3]);
    let steps = (seconds / cfg.policy_dt()).round().max(1.0) as usize;
    let mut fell = false;
    for _ in 0..steps {
        if env.step(&[0.0; 12])?.terminated {
            fell = true;
            break;
        }
    }
    let pose = env.pose();
    let up_z = pose.trunk_rotation[2][2].clamp(-1.0, 1.0);
    let tilt_rad = up_z.acos();
    let feet_in_contact = pose.legs.map(|l| l.contact);
    let trunk_height = env.raw_state().base_pos[2];
    let max_torque = env.torques().iter().fold(0.0f32, |m, t| m.max(t.abs()));
    let stood = !fell && tilt_rad < 0.2 && feet_in_contact.iter().all(|&c| c) && trunk_height > 0.5 * cfg.height_target;
    Ok(StandReport {
        seconds,
        trunk_height,
        height_target: cfg.height_target,
        tilt_rad,
        feet_in_contact,
        max_torque,
        fell,
        stood,
    })
}
