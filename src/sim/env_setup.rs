//! The pieces of a `LocomotionEnv` that are plain functions of its config and
//! robot: the standing pose, the soft joint limits, a uniform draw, the world,
//! and the check that the physics gave a finite state.

use super::physics::{PdGains, PhysicsParams, RawState, RobotSim};
use super::robot::RobotModel;
use crate::config::robot::{check_patterns_match, pattern_value};
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

/// The standing pose, in leg-joint order: from `env.robot.default_pose` by
/// joint name when it is set (every leg joint must match a pattern), else
/// from `env.default_hip_left` and the rest (the A1's conventions). Errors
/// name the joint that no pattern matches or whose angle is outside its limits.
pub fn default_pose(cfg: &EnvConfig, robot: &RobotModel) -> anyhow::Result<[f32; 12]> {
    let mut q = [0.0; 12];
    let table = &cfg.robot.default_pose;
    if table.is_empty() {
        for leg in super::robot::Leg::ALL {
            let l = leg.index();
            q[3 * l] = if leg.is_left() { cfg.default_hip_left } else { cfg.default_hip_right };
            q[3 * l + 1] = if leg.is_front() { cfg.default_thigh_front } else { cfg.default_thigh_rear };
            q[3 * l + 2] = cfg.default_calf;
        }
    } else {
        let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
        check_patterns_match("default_pose", table.keys(), &names)?;
        for (i, joint) in robot.joints.iter().enumerate() {
            q[i] = pattern_value("default_pose", table, &joint.name)?.ok_or_else(|| {
                anyhow::anyhow!(
                    "env.robot.default_pose gives no angle for joint '{}' (no pattern matches it)",
                    joint.name
                )
            })?;
        }
    }
    for (i, joint) in robot.joints.iter().enumerate() {
        anyhow::ensure!(
            q[i] >= joint.lower && q[i] <= joint.upper,
            "the standing angle {} rad of joint '{}' is outside its limits [{}, {}]",
            q[i],
            joint.name,
            joint.lower,
            joint.upper
        );
    }
    Ok(q)
}

/// PD stiffness and damping per leg joint: `env.robot.kp` / `kd` by joint
/// name, else `env.kp` / `env.kd`.
pub fn joint_gains(cfg: &EnvConfig, robot: &RobotModel) -> anyhow::Result<PdGains> {
    let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
    check_patterns_match("kp", cfg.robot.kp.keys(), &names)?;
    check_patterns_match("kd", cfg.robot.kd.keys(), &names)?;
    let mut kp = [cfg.kp; 12];
    let mut kd = [cfg.kd; 12];
    for (i, name) in names.iter().enumerate() {
        kp[i] = pattern_value("kp", &cfg.robot.kp, name)?.unwrap_or(cfg.kp);
        kd[i] = pattern_value("kd", &cfg.robot.kd, name)?.unwrap_or(cfg.kd);
    }
    Ok(PdGains { kp, kd })
}

/// The soft limits (a fraction of the range, centred); unlimited joints have none.
pub(super) fn soft_limit(robot: &RobotModel, cfg: &EnvConfig, i: usize) -> (f32, f32) {
    let j = &robot.joints[i];
    if !(j.lower.is_finite() && j.upper.is_finite()) {
        return (j.lower, j.upper);
    }
    let mid = 0.5 * (j.lower + j.upper);
    let half = 0.5 * (j.upper - j.lower) * cfg.soft_limit_fraction;
    (mid - half, mid + half)
}

pub(super) fn build_sim(
    cfg: &EnvConfig,
    robot: &RobotModel,
    params: PhysicsParams,
    q0: &[f32; 12],
    gains: &PdGains,
) -> anyhow::Result<RobotSim> {
    RobotSim::new(robot, cfg, params, q0, gains)
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
