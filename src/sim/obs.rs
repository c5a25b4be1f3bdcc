//! Observation vectors (DESIGN.md, "Observation").
//!
//! Policy observation, `OBS_DIM` = 45 floats:
//!
//! | offset | len | what | scale |
//! | --- | --- | --- | --- |
//! | 0 | 3 | base angular velocity, trunk frame | x0.25 |
//! | 3 | 3 | projected gravity (unit gravity direction in the trunk frame) | x1 |
//! | 6 | 3 | command (vx, vy, wz) | x(2, 2, 0.25) |
//! | 9 | 12 | joint positions minus default, leg order FL/FR/RL/RR x hip/thigh/calf | x1 |
//! | 21 | 12 | joint velocities | x0.05 |
//! | 33 | 12 | previous action (the policy's, clipped, before the task perturbation) | x1 |
//!
//! Privileged observation (critic only), `PRIV_OBS_DIM` = 57 floats: the 45
//! above, then
//!
//! | offset | len | what | scale |
//! | --- | --- | --- | --- |
//! | 45 (`PRIV_BASE_LIN_VEL`) | 3 | base linear velocity, trunk frame | x2 |
//! | 48 | 4 | foot contacts FL, FR, RL, RR | 0 / 1 |
//! | 52 | 1 | friction coefficient | x1 |
//! | 53 | 1 | added trunk mass, kg | x1 |
//! | 54 | 1 | motor strength factor | x1 |
//! | 55 | 2 | push state: the (x, y) velocity change of a push in the last second, world frame | x1 |
//!
//! The observation history for the CENet is the last `HISTORY_LEN`
//! observations, oldest first: (HISTORY_LEN * OBS_DIM,). At reset it holds
//! HISTORY_LEN copies of the first observation.

/// Policy observation length.
pub const OBS_DIM: usize = 45;
/// Action length (12 joint target offsets).
pub const ACT_DIM: usize = 12;
/// Observations kept for the CENet.
pub const HISTORY_LEN: usize = 5;
/// Offset of the scaled (x2) base linear velocity in the privileged observation.
pub const PRIV_BASE_LIN_VEL: usize = OBS_DIM;
/// Offset of the foot contacts in the privileged observation.
pub const PRIV_FOOT_CONTACTS: usize = PRIV_BASE_LIN_VEL + 3;
/// Offset of friction, added mass, motor strength (one each).
pub const PRIV_PHYSICS: usize = PRIV_FOOT_CONTACTS + 4;
/// Offset of the push state (2).
pub const PRIV_PUSH: usize = PRIV_PHYSICS + 3;
/// Privileged observation length.
pub const PRIV_OBS_DIM: usize = PRIV_PUSH + 2;

/// Scale of the base angular velocity.
pub const ANG_VEL_SCALE: f32 = 0.25;
/// Scale of the base linear velocity (privileged).
pub const LIN_VEL_SCALE: f32 = 2.0;
/// Scale of the joint velocities.
pub const JOINT_VEL_SCALE: f32 = 0.05;
/// Scales of the command (vx, vy, wz).
pub const COMMAND_SCALE: [f32; 3] = [2.0, 2.0, 0.25];

/// The quantities the observations are made of.
#[derive(Debug, Clone, Default)]
pub struct ObsInput {
    pub base_ang_vel: [f32; 3],
    pub projected_gravity: [f32; 3],
    pub command: [f32; 3],
    pub q_minus_default: [f32; 12],
    pub qd: [f32; 12],
    pub last_action: [f32; 12],
    pub base_lin_vel: [f32; 3],
    pub foot_contacts: [bool; 4],
    pub friction: f32,
    pub added_mass: f32,
    pub motor_strength: f32,
    pub push: [f32; 2],
}

/// Writes the policy observation.
pub fn write_obs(i: &ObsInput, out: &mut [f32; OBS_DIM]) {
    for k in 0..3 {
        out[k] = i.base_ang_vel[k] * ANG_VEL_SCALE;
        out[3 + k] = i.projected_gravity[k];
        out[6 + k] = i.command[k] * COMMAND_SCALE[k];
    }
    for j in 0..12 {
        out[9 + j] = i.q_minus_default[j];
        out[21 + j] = i.qd[j] * JOINT_VEL_SCALE;
        out[33 + j] = i.last_action[j];
    }
}

/// Writes the privileged observation (its first OBS_DIM entries are `obs`).
pub fn write_priv_obs(i: &ObsInput, obs: &[f32; OBS_DIM], out: &mut [f32; PRIV_OBS_DIM]) {
    out[..OBS_DIM].copy_from_slice(obs);
    for k in 0..3 {
        out[PRIV_BASE_LIN_VEL + k] = i.base_lin_vel[k] * LIN_VEL_SCALE;
    }
    for f in 0..4 {
        out[PRIV_FOOT_CONTACTS + f] = if i.foot_contacts[f] { 1.0 } else { 0.0 };
    }
    out[PRIV_PHYSICS] = i.friction;
    out[PRIV_PHYSICS + 1] = i.added_mass;
    out[PRIV_PHYSICS + 2] = i.motor_strength;
    out[PRIV_PUSH] = i.push[0];
    out[PRIV_PUSH + 1] = i.push[1];
}

/// Rotates a world-frame vector into the frame of the unit quaternion (x, y, z, w).
pub fn rotate_into_frame(quat: [f32; 4], v: [f32; 3]) -> [f32; 3] {
    let [x, y, z, w] = quat;
    // conj(q) * v * q, written out: v - 2w (u x v) + 2 u x (u x v), u = (x, y, z).
    let u = [x, y, z];
    let c1 = cross(u, v);
    let c2 = cross(u, c1);
    [v[0] - 2.0 * w * c1[0] + 2.0 * c2[0], v[1] - 2.0 * w * c1[1] + 2.0 * c2[1], v[2] - 2.0 * w * c1[2] + 2.0 * c2[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn privileged_layout_is_as_documented() {
        assert_eq!(PRIV_BASE_LIN_VEL, 45);
        assert_eq!(PRIV_OBS_DIM, 57);
    }

    #[test]
    fn gravity_in_a_trunk_pitched_nose_down_points_forward() {
        // Rotation of +90 degrees about y: the trunk's x axis points to world -z.
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let g = rotate_into_frame([0.0, h, 0.0, h], [0.0, 0.0, -1.0]);
        assert!((g[0] - 1.0).abs() < 1e-6 && g[1].abs() < 1e-6 && g[2].abs() < 1e-6, "{g:?}");
    }
}
