//! The deployment contract an exported policy carries as metadata (ONNX
//! `metadata_props`, safetensors `__metadata__`): what a robot-side program
//! must know to feed the model and use its output. Every value is JSON text
//! (`json.loads(meta["joint_names"])` in Python), keys in snake_case.

use super::dense_policy::DensePolicy;
use crate::config::EnvConfig;
use crate::sim::{self, RobotModel};
use crate::util::Provenance;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// Version of this contract's keys and graph layout; bumped when either changes meaning.
pub const CONTRACT_VERSION: u32 = 1;

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
    pub urdf: String,
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
            urdf: env.urdf.clone(),
        })
    }
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
    values.into_iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
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
