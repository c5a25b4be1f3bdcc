//! The robot description: a URDF read as tolerantly as the simulators
//! researchers use (`urdf_text`, `urdf_mesh`, `urdf_merge`), then validated
//! as a quadruped with its 12 leg joints found by structure (`legs`).
//!
//! A quadruped here is a tree whose root link (the trunk) has four leg
//! subtrees, each a chain of exactly three revolute joints (hip, thigh,
//! calf, in that order from the trunk). Links joined by fixed joints are
//! merged into one rigid body first. Legs are named from where their hip
//! sits in the trunk frame: x > 0 front, y > 0 left, so FL, FR, RL, RR
//! (`env.robot.legs` overrides this by hip joint name). The joint order used
//! everywhere (actions, observations) is FL hip/thigh/calf, FR ..., RL ..., RR ...
//! A revolute joint whose `<limit>` gives no position range (lower = upper = 0)
//! or a continuous joint is unlimited. Every tolerated problem is a warning,
//! kept in [`RobotModel::warnings`] and logged.

use super::legs::{find_legs, find_root, foot_of, link_index, Foot};
use super::urdf_merge::{merge_fixed_links, MergedLink};
use crate::config::RobotConfig;
use anyhow::{anyhow, bail, Context};
use std::path::{Path, PathBuf};
// rapier3d-urdf builds from its own urdf-rs version: use that one so the
// parsed description can be handed to it.
use rapier3d_urdf::urdf_rs::{self, JointType, Robot};

/// Number of legs.
pub const NUM_LEGS: usize = 4;
/// Revolute joints per leg.
pub const JOINTS_PER_LEG: usize = 3;

/// A leg, named from its hip position (x > 0 front, y > 0 left).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Leg {
    FL,
    FR,
    RL,
    RR,
}

impl Leg {
    /// All legs in the canonical order (also the action order).
    pub const ALL: [Leg; NUM_LEGS] = [Leg::FL, Leg::FR, Leg::RL, Leg::RR];

    /// Index in [`Leg::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// "FL", "FR", "RL", "RR".
    pub fn name(self) -> &'static str {
        match self {
            Leg::FL => "FL",
            Leg::FR => "FR",
            Leg::RL => "RL",
            Leg::RR => "RR",
        }
    }

    /// Whether the leg is on the left (y > 0).
    pub fn is_left(self) -> bool {
        matches!(self, Leg::FL | Leg::RL)
    }

    /// Whether the leg is at the front (x > 0).
    pub fn is_front(self) -> bool {
        matches!(self, Leg::FL | Leg::FR)
    }
}

/// One leg joint as described by the URDF.
#[derive(Debug, Clone)]
pub struct LegJoint {
    /// The URDF joint name (for messages only).
    pub name: String,
    /// Index in `Robot::joints`.
    pub urdf_joint: usize,
    /// Index in `Robot::links` of the link this joint moves.
    pub child_link: usize,
    /// Rotation axis in the joint frame (unit).
    pub axis: [f32; 3],
    /// Lower position limit, rad (`-inf` when unlimited).
    pub lower: f32,
    /// Upper position limit, rad (`inf` when unlimited).
    pub upper: f32,
    /// Effort limit, N m (the motor's torque clamp).
    pub effort: f32,
}

/// A parsed and validated quadruped description.
#[derive(Debug, Clone)]
pub struct RobotModel {
    /// Where it was read from (for messages).
    pub path: PathBuf,
    /// The urdf-rs description: meshes replaced by primitives, fixed links merged, no visuals.
    pub urdf: Robot,
    /// Index of the trunk (root link) in `urdf.links`.
    pub trunk_link: usize,
    /// The 12 leg joints, FL hip/thigh/calf, FR ..., RL ..., RR ...
    pub joints: Vec<LegJoint>,
    /// Foot point of each leg in its calf link's frame, metres.
    pub foot_offsets: [[f32; 3]; NUM_LEGS],
    /// Foot contact radius of each leg (0 when the foot has no sphere), metres.
    pub foot_radius: [f32; NUM_LEGS],
    /// Per leg, the indices in its calf link's collision list of the foot's shapes.
    pub foot_collisions: [Vec<usize>; NUM_LEGS],
    /// Per leg, where the foot was found (a link's name or "the sphere of link ...").
    pub foot_sources: [String; NUM_LEGS],
    /// Links folded into another by a fixed joint.
    pub merged: Vec<MergedLink>,
    /// The mass of the whole robot, kg (the file's total).
    pub total_mass: f64,
    /// Every tolerated problem of the file, one line each.
    pub warnings: Vec<String>,
    /// The description's text as it was read (what an exported contract embeds).
    pub text: String,
}

impl RobotModel {
    /// Loads the shipped A1 description, `scenes/a1.urdf`.
    pub fn a1() -> anyhow::Result<Self> {
        Self::load_shipped("scenes/a1.urdf", &RobotConfig::default())
    }

    /// Loads the description named by `cfg.urdf`: an absolute path, a path
    /// relative to the working directory, or else relative to the crate root
    /// (a shipped robot's description compiled in where the sources are absent,
    /// `sim::shipped`). The legs, feet and their names follow `cfg.robot`.
    pub fn for_config(cfg: &crate::config::EnvConfig) -> anyhow::Result<Self> {
        let path = Path::new(&cfg.urdf);
        if path.is_absolute() || path.exists() {
            return Self::load_with(path, &cfg.robot);
        }
        if super::shipped::is_shipped(path) {
            return Self::load_shipped(&cfg.urdf, &cfg.robot);
        }
        Self::load_with(&super::shipped::crate_path(&cfg.urdf), &cfg.robot)
    }

    /// A shipped description by its path from the crate's root (`scenes/a1.urdf`).
    fn load_shipped(relative: &str, robot: &RobotConfig) -> anyhow::Result<Self> {
        let path = super::shipped::crate_path(relative);
        let text = super::shipped::read_crate_file(relative)
            .with_context(|| format!("reading robot description {}", path.display()))?;
        Self::parse(&text, &path, robot).with_context(|| format!("in robot description {}", path.display()))
    }

    /// Reads and validates a URDF file. Errors name the file and the problem.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        Self::load_with(path, &RobotConfig::default())
    }

    /// [`RobotModel::load`] with leg and foot names from `robot` (`[env.robot]`).
    pub fn load_with(path: &Path, robot: &RobotConfig) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading robot description {}", path.display()))?;
        Self::parse(&text, path, robot).with_context(|| format!("in robot description {}", path.display()))
    }

    /// Parses and validates URDF text; `path` is used in messages and to find meshes.
    pub fn from_urdf_str(text: &str, path: &Path) -> anyhow::Result<Self> {
        Self::parse(text, path, &RobotConfig::default())
    }

    fn parse(text: &str, path: &Path, robot: &RobotConfig) -> anyhow::Result<Self> {
        let mut warnings = Vec::new();
        let clean = super::urdf_text::tolerant_urdf_text(text, &mut warnings)?;
        let mut urdf = urdf_rs::read_from_string(&clean).map_err(|e| anyhow!("malformed URDF: {e}"))?;
        check_numbers(&urdf)?;
        let total_mass = urdf.links.iter().map(|l| l.inertial.mass.value).sum();
        // The tree is checked before merging: a merge assumes one parent per link.
        find_root(&urdf)?;
        super::urdf_mesh::replace_meshes(&mut urdf.links, path, &mut warnings);
        let merged = merge_fixed_links(&mut urdf);
        let trunk_link = find_root(&urdf)?;
        let legs = find_legs(&urdf, trunk_link, &robot.legs)?;
        let mut joints = Vec::with_capacity(NUM_LEGS * JOINTS_PER_LEG);
        let mut feet: Vec<Foot> = Vec::with_capacity(NUM_LEGS);
        for (leg, chain) in Leg::ALL.iter().zip(&legs) {
            for &j in chain {
                joints.push(leg_joint(&urdf, j, &mut warnings)?);
            }
            let calf = joints.last().expect("three joints per leg").child_link;
            // A massless leaf makes the multibody's mass matrix singular (MuJoCo refuses it too).
            if urdf.links[calf].inertial.mass.value <= 0.0 {
                bail!(
                    "calf link '{}' (leg {}) has no mass, nor any link fixed to it: give it an <inertial>",
                    urdf.links[calf].name,
                    leg.name()
                );
            }
            feet.push(foot_of(&urdf, calf, &merged, &robot.foot_links).with_context(|| format!("leg {}", leg.name()))?);
        }
        // rapier3d-urdf limits a revolute joint to its <limit> range (here [0, 0]): make it continuous.
        for joint in joints.iter().filter(|j| !j.lower.is_finite()) {
            urdf.joints[joint.urdf_joint].joint_type = JointType::Continuous;
        }
        if urdf.links[trunk_link].inertial.mass.value <= 0.0 {
            bail!("trunk link '{}' has no mass (nor any link fixed to it)", urdf.links[trunk_link].name);
        }
        for w in &warnings {
            tracing::warn!("{}: {w}", path.display());
        }
        Ok(Self {
            path: path.to_path_buf(),
            urdf,
            trunk_link,
            joints,
            foot_offsets: std::array::from_fn(|l| feet[l].offset),
            foot_radius: std::array::from_fn(|l| feet[l].radius),
            foot_collisions: std::array::from_fn(|l| feet[l].collisions.clone()),
            foot_sources: std::array::from_fn(|l| feet[l].source.clone()),
            merged,
            total_mass,
            warnings,
            text: text.to_string(),
        })
    }

    /// Name of the trunk link.
    pub fn trunk_name(&self) -> &str {
        &self.urdf.links[self.trunk_link].name
    }
}

/// A leg joint from the URDF joint `j`: unlimited when it gives no position range.
fn leg_joint(urdf: &Robot, j: usize, warnings: &mut Vec<String>) -> anyhow::Result<LegJoint> {
    let joint = &urdf.joints[j];
    let (mut lower, mut upper, effort) =
        (joint.limit.lower as f32, joint.limit.upper as f32, joint.limit.effort as f32);
    let bad = |what: &str, v: f32| anyhow!("joint '{}' has a bad {what}: {v}", joint.name);
    if joint.joint_type == JointType::Continuous || (lower == 0.0 && upper == 0.0) {
        if joint.joint_type != JointType::Continuous {
            warnings.push(format!("joint '{}': its <limit> gives no position range; it is unlimited", joint.name));
        }
        (lower, upper) = (f32::NEG_INFINITY, f32::INFINITY);
    } else if !lower.is_finite() {
        return Err(bad("lower limit", lower));
    } else if !upper.is_finite() || upper <= lower {
        return Err(bad("upper limit (must be finite and above the lower limit)", upper));
    }
    if !effort.is_finite() || effort <= 0.0 {
        return Err(bad("effort limit (must be > 0; it is the motor's torque limit)", effort));
    }
    let a = joint.axis.xyz.0;
    let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        bail!("joint '{}' has a bad axis {a:?}", joint.name);
    }
    Ok(LegJoint {
        name: joint.name.clone(),
        urdf_joint: j,
        child_link: link_index(urdf, &joint.child.link)?,
        axis: a.map(|v| (v / norm) as f32),
        lower,
        upper,
        effort,
    })
}

/// Every mass, inertia and joint origin is finite (and masses and principal inertias >= 0).
fn check_numbers(urdf: &Robot) -> anyhow::Result<()> {
    for link in &urdf.links {
        let m = link.inertial.mass.value;
        if !m.is_finite() || m < 0.0 {
            bail!("bad number: link '{}' has mass {m} (must be finite and >= 0)", link.name);
        }
        let i = &link.inertial.inertia;
        if [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz].iter().any(|v| !v.is_finite())
            || i.ixx < 0.0
            || i.iyy < 0.0
            || i.izz < 0.0
        {
            bail!("bad number: link '{}' has inertia {:?}", link.name, [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz]);
        }
    }
    for joint in &urdf.joints {
        if joint.origin.xyz.0.iter().chain(joint.origin.rpy.0.iter()).any(|v| !v.is_finite()) {
            bail!(
                "bad number: joint '{}' has origin xyz {:?} rpy {:?}",
                joint.name,
                joint.origin.xyz.0,
                joint.origin.rpy.0
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a1_has_twelve_leg_joints_in_leg_order() {
        let robot = RobotModel::a1().unwrap();
        let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names[0], "FL_hip_joint");
        assert_eq!(names[4], "FR_thigh_joint");
        assert_eq!(names[8], "RL_calf_joint");
        assert_eq!(names[9], "RR_hip_joint");
        assert_eq!(robot.joints[1].effort, 55.0);
        assert_eq!(robot.joints[0].effort, 20.0);
        assert_eq!(robot.foot_offsets[0], [0.0, 0.0, -0.2]);
        assert_eq!(robot.trunk_name(), "trunk");
    }
}
