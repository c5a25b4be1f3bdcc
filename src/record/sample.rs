//! One control step as a recorder's writer thread needs it: an owned copy of
//! [`StepInfo`]'s numbers (about 1 KB), so the simulation thread only copies
//! and every encoding happens off it.

use crate::sim::reward::NUM_TERMS;
use crate::sim::{LinkPose, StepInfo, NUM_LEGS};

/// An owned copy of one [`StepInfo`].
pub(crate) struct Sample {
    /// Simulated seconds since the env was built.
    pub t: f64,
    pub episode_step: usize,
    /// World pose of the trunk, then of each leg joint's child link.
    pub links: [LinkPose; 13],
    pub q: [f32; 12],
    pub qd: [f32; 12],
    pub torques: [f32; 12],
    /// Trunk velocity, world frame (m/s) and angular velocity, world frame (rad/s).
    /// (The trunk's velocity and pose are drawn by the Rerun recorder only.)
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub base_lin_vel: [f32; 3],
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub base_ang_vel: [f32; 3],
    /// Trunk orientation (x, y, z, w).
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub base_quat: [f32; 4],
    /// The velocity command (vx, vy, wz), trunk frame.
    pub command: [f32; 3],
    pub reward: Option<(f32, [f32; NUM_TERMS])>,
    pub contacts: [bool; NUM_LEGS],
    pub foot_pos: [[f32; 3]; NUM_LEGS],
    pub push: Option<[f32; 2]>,
}

impl Sample {
    pub fn of(info: &StepInfo) -> Self {
        let s = info.state;
        Self {
            t: info.sim_time,
            episode_step: info.episode_step,
            links: *info.links,
            q: s.q,
            qd: s.qd,
            torques: *info.torques,
            base_lin_vel: s.base_lin_vel,
            base_ang_vel: s.base_ang_vel,
            base_quat: s.base_quat,
            command: info.command,
            reward: info.reward.map(|(r, terms)| (r, terms.values)),
            contacts: info.contacts,
            foot_pos: s.foot_pos,
            push: info.push,
        }
    }

    /// The trunk's velocity in its own frame: forward vx, lateral vy (m/s), yaw rate wz (rad/s).
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub fn base_velocity(&self) -> [f32; 3] {
        let lin = crate::sim::obs::rotate_into_frame(self.base_quat, self.base_lin_vel);
        let ang = crate::sim::obs::rotate_into_frame(self.base_quat, self.base_ang_vel);
        [lin[0], lin[1], ang[2]]
    }

    /// The tracking errors of the step: |command (vx, vy) - trunk (vx, vy)| (m/s) and
    /// |command wz - trunk wz| (rad/s).
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub fn tracking_errors(&self) -> [f32; 2] {
        let [vx, vy, wz] = self.base_velocity();
        let [cx, cy, cw] = self.command;
        [((cx - vx).powi(2) + (cy - vy).powi(2)).sqrt(), (cw - wz).abs()]
    }
}
