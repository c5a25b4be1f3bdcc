//! Where the robot is, in world coordinates, for drawing it as a stick
//! figure: the trunk as an oriented box, and per leg the hip, thigh and calf
//! joints, the foot point and whether the foot touches the ground.
//!
//! Everything is read from the rapier multibody: the trunk pose and the
//! leg links' world transforms (`RobotSim::joint_positions`,
//! `RobotSim::state`), with the foot offsets and the trunk's collision box
//! from the [`RobotModel`]. Built by [`LocomotionEnv::pose`](super::LocomotionEnv::pose).

use super::physics::RawState;
use super::robot::{RobotModel, NUM_LEGS};
use rapier3d_urdf::urdf_rs::Geometry;

/// One leg, world frame, metres (z up, the ground at z = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPose {
    /// The hip (abduction) joint, where the leg hangs from the trunk.
    pub hip: [f32; 3],
    /// The thigh joint, the top of the thigh (the hip link's outer end).
    pub thigh: [f32; 3],
    /// The calf (knee) joint: the thigh's lower end.
    pub knee: [f32; 3],
    /// The foot point: the calf's lower end (the centre of the foot sphere).
    pub foot: [f32; 3],
    /// Whether the foot touched the ground in the last step (false right after a reset).
    pub contact: bool,
}

/// The robot, world frame, metres. Draw the trunk box from [`RobotPose::trunk_corners`],
/// then per leg hip - thigh - knee - foot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotPose {
    /// Centre of the trunk box.
    pub trunk_center: [f32; 3],
    /// Trunk orientation as a rotation matrix, row-major: `world = R * body`, so
    /// column j (`trunk_rotation[i][j]` over i) is the trunk's body axis j (x forward, y left, z up).
    pub trunk_rotation: [[f32; 3]; 3],
    /// Half the trunk box's size along the body axes: the URDF trunk's box collision shape, or,
    /// for a trunk without one, the box spanned by the four hip joints (no height).
    pub trunk_half_extents: [f32; 3],
    /// FL, FR, RL, RR.
    pub legs: [LegPose; NUM_LEGS],
}

impl RobotPose {
    /// The trunk box's 8 corners: index bit 0 set is +x (front), bit 1 +y (left), bit 2 +z (top).
    pub fn trunk_corners(&self) -> [[f32; 3]; 8] {
        std::array::from_fn(|k| {
            let h = self.trunk_half_extents;
            let sign = |bit: usize| if k & (1 << bit) != 0 { 1.0 } else { -1.0 };
            let local = [sign(0) * h[0], sign(1) * h[1], sign(2) * h[2]];
            add(self.trunk_center, mat_vec(&self.trunk_rotation, local))
        })
    }
}

/// The pose from the state after a step, the 12 leg joints' world positions (leg-joint order:
/// hip, thigh, calf of FL, FR, RL, RR) and the foot contacts.
pub(super) fn robot_pose(
    robot: &RobotModel,
    state: &RawState,
    joints: &[[f32; 3]; 12],
    contacts: [bool; NUM_LEGS],
) -> RobotPose {
    let rotation = rotation_matrix(state.base_quat);
    let legs: [LegPose; NUM_LEGS] = std::array::from_fn(|l| LegPose {
        hip: joints[3 * l],
        thigh: joints[3 * l + 1],
        knee: joints[3 * l + 2],
        foot: state.foot_pos[l],
        contact: contacts[l],
    });
    let (offset, half_extents) = trunk_box(robot).unwrap_or_else(|| {
        // The hips in the trunk frame: R^T (hip - base).
        let local = legs.map(|leg| mat_t_vec(&rotation, sub(leg.hip, state.base_pos)));
        let max = |i: usize| local.iter().map(|p| p[i].abs()).fold(0.0f32, f32::max);
        ([0.0; 3], [max(0), max(1), 0.0])
    });
    RobotPose {
        trunk_center: add(state.base_pos, mat_vec(&rotation, offset)),
        trunk_rotation: rotation,
        trunk_half_extents: half_extents,
        legs,
    }
}

/// The first box collision shape of the trunk: (its centre in the trunk frame, its half extents).
fn trunk_box(robot: &RobotModel) -> Option<([f32; 3], [f32; 3])> {
    robot.urdf.links[robot.trunk_link].collision.iter().find_map(|c| match c.geometry {
        Geometry::Box { size } => {
            let (o, s) = (c.origin.xyz.0, size.0);
            Some(([o[0] as f32, o[1] as f32, o[2] as f32], [0.5 * s[0] as f32, 0.5 * s[1] as f32, 0.5 * s[2] as f32]))
        }
        _ => None,
    })
}

/// Rotation matrix (row-major) of a unit quaternion (x, y, z, w).
fn rotation_matrix([x, y, z, w]: [f32; 4]) -> [[f32; 3]; 3] {
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

fn mat_vec(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

fn mat_t_vec(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|i| m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2])
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|i| a[i] - b[i])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::EnvConfig;
    use crate::sim::{LocomotionEnv, Perturbation};

    fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
        let d = sub(a, b);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    fn a1_env() -> (EnvConfig, RobotModel, LocomotionEnv) {
        let cfg = EnvConfig { randomize: false, push_interval_s: 0.0, ..EnvConfig::default() };
        let robot = RobotModel::a1().unwrap();
        let env = LocomotionEnv::new(&cfg, &robot, &Perturbation::none()).unwrap();
        (cfg, robot, env)
    }

    /// The A1's links: thigh and calf 0.2 m, hips at (+-0.183, +-0.047) in the trunk, thigh
    /// joints 0.085 m further out; the pose shows them at those distances.
    #[test]
    fn the_reset_pose_is_the_upright_standing_pose_at_the_start_height() {
        let (cfg, _, env) = a1_env();
        let pose = env.pose();
        let [cx, cy, cz] = pose.trunk_center;
        assert!(cx.abs() < 1e-4 && cy.abs() < 1e-4 && (cz - cfg.start_height).abs() < 1e-4, "{pose:?}");
        for (i, row) in pose.trunk_rotation.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert!((v - f32::from(u8::from(i == j))).abs() < 1e-5, "not upright: {pose:?}");
            }
        }
        assert_eq!(pose.trunk_half_extents, [0.1335, 0.097, 0.057]);
        for (l, leg) in pose.legs.iter().enumerate() {
            let (front, left) = (l < 2, l % 2 == 0);
            assert_eq!(leg.hip[0] > 0.0, front, "leg {l}: {leg:?}");
            assert_eq!(leg.hip[1] > 0.0, left, "leg {l}: {leg:?}");
            assert!((leg.hip[0].abs() - 0.183).abs() < 1e-4 && (leg.hip[2] - cz).abs() < 1e-4, "leg {l}: {leg:?}");
            assert!((dist(leg.hip, leg.thigh) - 0.08505).abs() < 1e-4, "leg {l}: {leg:?}");
            assert!((dist(leg.thigh, leg.knee) - 0.2).abs() < 1e-4, "leg {l}: {leg:?}");
            assert!((dist(leg.knee, leg.foot) - 0.2).abs() < 1e-4, "leg {l}: {leg:?}");
            // Knee below the hip, foot below the knee, and near the thigh joint's vertical (calf
            // -1.5 rad against thigh 0.8 / 1.0 rad: within 8 cm).
            assert!(leg.knee[2] < leg.thigh[2] - 0.1 && leg.foot[2] < leg.knee[2] - 0.1, "leg {l}: {leg:?}");
            assert!(dist([leg.foot[0], leg.foot[1], 0.0], [leg.thigh[0], leg.thigh[1], 0.0]) < 0.08, "{leg:?}");
            assert_eq!(leg.foot, env.raw_state().foot_pos[l]);
            // The robot starts in the air: no step has touched the ground yet.
            assert!(!leg.contact && leg.foot[2] > 0.05, "leg {l}: {leg:?}");
        }
        let corners = pose.trunk_corners();
        assert!((corners[7][0] - 0.1335).abs() < 1e-4 && (corners[7][2] - (cz + 0.057)).abs() < 1e-4);
        assert!((corners[0][1] + 0.097).abs() < 1e-4 && (corners[0][2] - (cz - 0.057)).abs() < 1e-4);
    }

    #[test]
    fn standing_after_the_drop_the_feet_rest_on_the_ground_in_contact() {
        let (cfg, robot, mut env) = a1_env();
        let steps = (1.5 / cfg.policy_dt()).round() as usize;
        for _ in 0..steps {
            assert!(!env.step(&[0.0; 12]).unwrap().terminated);
        }
        let pose = env.pose();
        let height = pose.trunk_center[2];
        assert!(height > 0.22 && height < 0.34, "standing height {height}: {pose:?}");
        assert!(pose.trunk_rotation[2][2] > 0.99, "tilted: {pose:?}");
        for (l, leg) in pose.legs.iter().enumerate() {
            assert!(leg.contact, "leg {l} not in contact: {leg:?}");
            let ground_gap = leg.foot[2] - robot.foot_radius[l];
            assert!(ground_gap.abs() < 0.02, "leg {l}: foot sphere {ground_gap} m from the ground: {leg:?}");
            assert!(leg.foot[2] < leg.knee[2] && leg.knee[2] < leg.thigh[2] && leg.foot[2] < leg.hip[2], "{leg:?}");
        }
        // The box turns with the trunk: its corners stay at the half extents' distance from the centre.
        let h = pose.trunk_half_extents;
        let diagonal = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        for c in pose.trunk_corners() {
            assert!((dist(c, pose.trunk_center) - diagonal).abs() < 1e-4);
        }
    }
}
