//! The deployment contract an exported policy carries as metadata (ONNX
//! `metadata_props`, safetensors `__metadata__`): what a robot-side program
//! must know to feed the model and use its output. Every value is JSON text
//! (`json.loads(meta["joint_names"])` in Python), keys in snake_case. Version 2 adds the physics
//! the policy was trained under (docs/export.md lists every key).

use super::dense_policy::DensePolicy;
use crate::config::EnvConfig;
use crate::sim::{self, RobotModel};
use crate::util::Provenance;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// Version of this contract's keys and graph layout; bumped when either changes meaning
/// (2: the physics a policy was trained under, its start, termination, commands, torque limits
/// and the URDF itself, so that another simulator can be set up from the contract alone).
pub const CONTRACT_VERSION: u32 = 2;

/// One named part of an observation frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObsField {
    pub name: &'static str,
    pub offset: usize,
    pub len: usize,
    /// Multiplied into the raw quantity before it enters the frame, one per element.
    pub scale: &'static [f32],
}

/// The policy observation frame (`sim/obs.rs`), in order: 45 floats.
pub const OBS_LAYOUT: [ObsField; 6] = [
    ObsField { name: "base_ang_vel_trunk_frame", offset: 0, len: 3, scale: &[sim::obs::ANG_VEL_SCALE; 3] },
    ObsField { name: "projected_gravity", offset: 3, len: 3, scale: &[1.0; 3] },
    ObsField { name: "command_vx_vy_wz", offset: 6, len: 3, scale: &sim::obs::COMMAND_SCALE },
    ObsField { name: "joint_pos_minus_default", offset: 9, len: 12, scale: &[1.0; 12] },
    ObsField { name: "joint_vel", offset: 21, len: 12, scale: &[sim::obs::JOINT_VEL_SCALE; 12] },
    ObsField { name: "previous_action_clipped", offset: 33, len: 12, scale: &[1.0; 12] },
];

/// Infinite limits become null (JSON has no infinity).
fn finite_or_null(values: &[f32]) -> Value {
    Value::Array(values.iter().map(|v| if v.is_finite() { json!(v) } else { Value::Null }).collect())
}

/// The robot facts the contract names: joint names in action order, standing pose,
/// PD gains and limits. Errors name the robot file.
pub struct RobotFacts {
    pub joint_names: Vec<String>,
    pub default_pose: Vec<f32>,
    pub kp: Vec<f32>,
    pub kd: Vec<f32>,
    pub limits: Vec<(f32, f32)>,
    /// Each joint's effort limit from the URDF, N m (the PD torque is clamped to it).
    pub effort: Vec<f32>,
    pub urdf: String,
    /// The robot description's text, as the simulator read it.
    pub urdf_text: String,
}

impl RobotFacts {
    pub fn of(env: &EnvConfig) -> anyhow::Result<Self> {
        let robot = RobotModel::for_config(env)?;
        let pose = sim::default_pose(env, &robot)?;
        let gains = sim::joint_gains(env, &robot)?;
        Ok(Self {
            joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
            default_pose: pose.to_vec(),
            kp: gains.kp.to_vec(),
            kd: gains.kd.to_vec(),
            limits: robot.joints.iter().map(|j| (j.lower, j.upper)).collect(),
            effort: robot.joints.iter().map(|j| j.effort).collect(),
            urdf: env.urdf.clone(),
            urdf_text: robot.text.clone(),
        })
    }
}

/// What another simulator needs to reproduce the world the policy was trained in (version 2).
fn physics_contract(robot: &RobotFacts, env: &EnvConfig) -> [(&'static str, Value); 9] {
    let effective_damping: Vec<f32> = robot.kp.iter().zip(&robot.kd).map(|(kp, kd)| kd + kp * env.physics_dt).collect();
    [
        ("robot_urdf_sha256", json!(crate::util::sha256_hex(robot.urdf_text.as_bytes()))),
        ("robot_urdf_text", json!(robot.urdf_text)),
        ("start_height", json!(env.start_height)),
        ("joint_effort_limits", json!(robot.effort)),
        (
            "pd_law",
            json!({
                "torque": "clamp(kp * s * (target - q) - kd * s * qd, -effort * s, effort * s), s = the episode's motor strength (1 when not randomised)",
                "integration": "each physics step as rapier's implicit joint spring (backward Euler): a stiffness kp pulls q towards the target, so besides kd the spring damps by about kp * physics_dt",
                "effective_damping": effective_damping,
                "torque_clamp": "where the PD torque at the step's start exceeds the effort limit, the spring's rest point moves so that it asks for exactly the limit",
                "joint_limits": "a joint that would cross a limit within a step meets a stiff spring resting on the limit (a mechanical stop)",
            }),
        ),
        (
            "frames",
            json!({
                "world": "right-handed, z up, gravity -9.81 m/s^2 along z",
                "base_ang_vel_trunk_frame": "the trunk's angular velocity in its own frame, rad/s, times its obs_layout scale",
                "projected_gravity": "the unit gravity vector in the trunk frame: (0, 0, -1) when upright",
                "command_vx_vy_wz": "forward and lateral velocity in the trunk's frame (m/s) and yaw rate (rad/s), times their scales",
                "joint_pos_minus_default": "joint angle minus default_joint_pos, rad, in joint_names order",
                "lin_vel_err": "the evaluation's velocity error is measured in the trunk frame, horizontal components",
            }),
        ),
        (
            "commands",
            json!({
                "vx": env.cmd_vx, "vy": env.cmd_vy, "wz": env.cmd_wz,
                "resample_s": env.command_resample_s,
                "history": "each history frame keeps the command it was observed with: a new command appears in the newest frame only (right after a reset every frame is a copy of the first observation, so all show it)",
            }),
        ),
        (
            "termination",
            json!({
                "fall": "the trunk touches the ground, or the tilt passes max_tilt_rad (projected_gravity z > -cos(max_tilt_rad))",
                "max_tilt_rad": env.max_tilt_rad,
                "time_out_s": env.episode_s,
            }),
        ),
        (
            "training_world",
            json!({
                "ground": "a flat plane at z = 0",
                "friction_nominal": 1.0,
                "randomize": env.randomize,
                "friction_range": env.friction_range,
                "added_mass_range_kg": env.added_mass_range,
                "motor_strength_range": env.motor_strength_range,
                "push_interval_s": env.push_interval_s,
                "push_max_vel": env.push_max_vel,
                "physics_dt_note": "physics_dt is rapier's step in training; another simulator should use its own stable step with the same control_dt",
            }),
        ),
    ]
}

/// The metadata of an exported task, each value JSON text.
pub fn contract(
    policy: &DensePolicy,
    robot: &RobotFacts,
    env: &EnvConfig,
    network_kind: &str,
    source: &str,
) -> BTreeMap<String, String> {
    let provenance = Provenance::of_this_build(None);
    let layout: Vec<Value> = OBS_LAYOUT
        .iter()
        .map(|f| json!({"name": f.name, "offset": f.offset, "len": f.len, "scale": f.scale}))
        .collect();
    let normalization = match &policy.normalizer {
        Some(n) => json!({"inside_model": true, "clip": n.clip, "formula": "clip((x - mean) * scale, -clip, clip)"}),
        None => json!({"inside_model": false}),
    };
    let values: [(&str, Value); 24] = [
        ("contract_version", json!(CONTRACT_VERSION)),
        ("task", json!(policy.task)),
        ("robot_urdf", json!(robot.urdf)),
        ("joint_names", json!(robot.joint_names)),
        ("default_joint_pos", json!(robot.default_pose)),
        ("joint_lower", finite_or_null(&robot.limits.iter().map(|l| l.0).collect::<Vec<_>>())),
        ("joint_upper", finite_or_null(&robot.limits.iter().map(|l| l.1).collect::<Vec<_>>())),
        ("kp", json!(robot.kp)),
        ("kd", json!(robot.kd)),
        ("action_scale", json!(policy.action_scale)),
        ("clip_actions", json!(policy.clip_actions)),
        ("control_dt", json!(env.policy_dt())),
        ("physics_dt", json!(env.physics_dt)),
        ("decimation", json!(env.decimation)),
        ("obs_dim", json!(policy.obs_dim)),
        ("history_len", json!(policy.history_len)),
        ("obs_layout", Value::Array(layout)),
        ("obs_normalization", normalization),
        (
            "inputs",
            json!({"obs_history": format!("(batch, {} * {}): the last {} observation frames, oldest first; the last is the current one; at an episode's start every frame is the first observation", policy.history_len, policy.obs_dim, policy.history_len)}),
        ),
        (
            "outputs",
            json!({"actions": "(batch, 12): clipped to [-clip_actions, clip_actions]; the next frame's previous_action", "joint_targets": "(batch, 12): default_joint_pos + action_scale * actions within the joint limits, rad, for PD control with kp and kd"}),
        ),
        ("network_kind", json!(network_kind)),
        ("source_policy", json!(source)),
        ("quadcl_version", json!(provenance.quadcl_version)),
        ("git_commit", json!(provenance.git_commit)),
    ];
    values.into_iter().chain(physics_contract(robot, env)).map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_observation_layout_tiles_the_frame_with_its_scales() {
        let mut next = 0;
        for f in OBS_LAYOUT {
            assert_eq!(f.offset, next, "{} starts where the previous field ends", f.name);
            assert_eq!(f.scale.len(), f.len, "{}: one scale per element", f.name);
            next += f.len;
        }
        assert_eq!(next, sim::OBS_DIM);
    }

    #[test]
    fn the_observation_layout_matches_what_the_simulator_writes() {
        // Every input quantity set to 1: each frame element is its scale.
        let input = sim::obs::ObsInput {
            base_ang_vel: [1.0; 3],
            projected_gravity: [1.0; 3],
            command: [1.0; 3],
            q_minus_default: [1.0; 12],
            qd: [1.0; 12],
            last_action: [1.0; 12],
            ..Default::default()
        };
        let mut frame = [0.0; sim::OBS_DIM];
        sim::obs::write_obs(&input, &mut frame);
        let scales: Vec<f32> = OBS_LAYOUT.iter().flat_map(|f| f.scale.iter().copied()).collect();
        assert_eq!(frame.to_vec(), scales);
    }
}
