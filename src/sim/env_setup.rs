//! The pieces of a `LocomotionEnv` that are plain functions of its config and
//! robot: the standing pose, the soft joint limits, a uniform draw, the world,
//! and the check that the physics gave a finite state.

use super::physics::{PhysicsParams, RawState, RobotSim};
use super::robot::RobotModel;
use crate::config::EnvConfig;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

pub(super) fn uniform(rng: &mut ChaCha8Rng, range: [f32; 2]) -> f32 {
    if range[0] == range[1] {
        range[0]
    } else {
        rng.gen_range(range[0]..range[1])
    }
}

/// The standing pose from the config, in leg-joint order.
pub(super) fn default_pose(cfg: &EnvConfig, robot: &RobotModel) -> [f32; 12] {
    let _ = robot;
    let mut q = [0.0; 12];
    for leg in super::robot::Leg::ALL {
        let l = leg.index();
        q[3 * l] = if leg.is_left() { cfg.default_hip_left } else { cfg.default_hip_right };
        q[3 * l + 1] = if leg.is_front() { cfg.default_thigh_front } else { cfg.default_thigh_rear };
        q[3 * l + 2] = cfg.default_calf;
    }
    q
}

pub(super) fn soft_limit(robot: &RobotModel, cfg: &EnvConfig, i: usize) -> (f32, f32) {
    let j = &robot.joints[i];
    let mid = 0.5 * (j.lower + j.upper);
    let half = 0.5 * (j.upper - j.lower) * cfg.soft_limit_fraction;
    (mid - half, mid + half)
}

pub(super) fn build_sim(
    cfg: &EnvConfig,
    robot: &RobotModel,
    params: PhysicsParams,
    q0: &[f32; 12],
) -> anyhow::Result<RobotSim> {
    RobotSim::new(robot, cfg, params, q0)
}

/// The first non-finite quantity of `s`: (what, component, value).
pub(super) fn first_non_finite(s: &RawState) -> Option<(&'static str, usize, f32)> {
    let groups: [(&str, &[f32]); 6] = [
        ("trunk position", &s.base_pos),
        ("trunk orientation", &s.base_quat),
        ("trunk linear velocity", &s.base_lin_vel),
        ("trunk angular velocity", &s.base_ang_vel),
        ("joint position", &s.q),
        ("joint velocity", &s.qd),
    ];
    groups
        .into_iter()
        .find_map(|(name, values)| values.iter().position(|v| !v.is_finite()).map(|i| (name, i, values[i])))
}
