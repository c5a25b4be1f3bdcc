//! The robot description: a URDF parsed with urdf-rs, validated as a
//! quadruped, with its 12 leg joints found by structure (not by name).
//!
//! A quadruped here is a tree whose root link (the trunk) has four leg
//! subtrees, each a chain of exactly three revolute joints (hip, thigh,
//! calf, in that order from the trunk; fixed joints may sit between them).
//! Legs are named from where their hip sits in the trunk frame: x > 0 front,
//! y > 0 left, so FL, FR, RL, RR. The joint order used everywhere (actions,
//! observations) is FL hip/thigh/calf, FR ..., RL ..., RR ...
//! The foot point is, in the calf frame, the origin of the calf's fixed child
//! link if it has one, else the centre of the calf's sphere collision shape.

use anyhow::{anyhow, bail, Context};
use std::path::{Path, PathBuf};
// rapier3d-urdf builds from its own urdf-rs version: use that one so the
// parsed description can be handed to it.
use rapier3d_urdf::urdf_rs::{self, Geometry, JointType, Robot};

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
    /// Lower position limit, rad.
    pub lower: f32,
    /// Upper position limit, rad.
    pub upper: f32,
    /// Effort limit, N m (the motor's torque clamp).
    pub effort: f32,
}

/// A parsed and validated quadruped description.
#[derive(Debug, Clone)]
pub struct RobotModel {
    /// Where it was read from (for messages).
    pub path: PathBuf,
    /// The urdf-rs description (meshes already removed).
    pub urdf: Robot,
    /// Index of the trunk (root link) in `urdf.links`.
    pub trunk_link: usize,
    /// The 12 leg joints, FL hip/thigh/calf, FR ..., RL ..., RR ...
    pub joints: Vec<LegJoint>,
    /// Foot point of each leg in its calf link's frame, metres.
    pub foot_offsets: [[f32; 3]; NUM_LEGS],
    /// Foot contact radius of each leg (0 when the foot has no sphere), metres.
    pub foot_radius: [f32; NUM_LEGS],
}

impl RobotModel {
    /// Loads the shipped A1 description, `scenes/a1.urdf`.
    pub fn a1() -> anyhow::Result<Self> {
        Self::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/a1.urdf"))
    }

    /// Loads the description named by `cfg.urdf`: an absolute path, a path
    /// relative to the working directory, or else relative to the crate root.
    pub fn for_config(cfg: &crate::config::EnvConfig) -> anyhow::Result<Self> {
        let path = Path::new(&cfg.urdf);
        if path.is_absolute() || path.exists() {
            Self::load(path)
        } else {
            Self::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
        }
    }

    /// Reads and validates a URDF file. Errors name the file and the problem.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading robot description {}", path.display()))?;
        Self::from_urdf_str(&text, path).with_context(|| format!("in robot description {}", path.display()))
    }

    /// Parses and validates URDF text; `path` is only used in messages.
    pub fn from_urdf_str(text: &str, path: &Path) -> anyhow::Result<Self> {
        let mut urdf = urdf_rs::read_from_string(text).map_err(|e| match find_bad_number(text) {
            Some(bad) => anyhow!("bad number: {bad} ({e})"),
            None => anyhow!("malformed URDF: {e}"),
        })?;
        strip_meshes(&mut urdf, path);
        let trunk_link = find_root(&urdf)?;
        let legs = find_legs(&urdf, trunk_link)?;
        let mut joints = Vec::with_capacity(NUM_LEGS * JOINTS_PER_LEG);
        let mut foot_offsets = [[0.0; 3]; NUM_LEGS];
        let mut foot_radius = [0.0; NUM_LEGS];
        for (leg, chain) in Leg::ALL.iter().zip(&legs) {
            for &j in chain {
                let joint = &urdf.joints[j];
                let (lower, upper, effort) =
                    (joint.limit.lower as f32, joint.limit.upper as f32, joint.limit.effort as f32);
                let bad = |what: &str, v: f32| anyhow!("joint '{}' has a bad {what}: {v}", joint.name);
                if !lower.is_finite() {
                    return Err(bad("lower limit", lower));
                }
                if !upper.is_finite() || upper <= lower {
                    return Err(bad("upper limit (must be finite and above the lower limit)", upper));
                }
                if !effort.is_finite() || effort <= 0.0 {
                    return Err(bad("effort limit (must be > 0)", effort));
                }
                joints.push(LegJoint {
                    name: joint.name.clone(),
                    urdf_joint: j,
                    child_link: link_index(&urdf, &joint.child.link)?,
                    lower,
                    upper,
                    effort,
                });
            }
            let calf = joints.last().expect("three joints per leg").child_link;
            let (offset, radius) = foot_of(&urdf, calf).with_context(|| format!("leg {}", leg.name()))?;
            foot_offsets[leg.index()] = offset;
            foot_radius[leg.index()] = radius;
        }
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
        if urdf.links[trunk_link].inertial.mass.value <= 0.0 {
            bail!("trunk link '{}' has no mass", urdf.links[trunk_link].name);
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
        Ok(Self { path: path.to_path_buf(), urdf, trunk_link, joints, foot_offsets, foot_radius })
    }

    /// Name of the trunk link.
    pub fn trunk_name(&self) -> &str {
        &self.urdf.links[self.trunk_link].name
    }
}

/// Attributes whose value is one or more numbers.
const NUMERIC_ATTRIBUTES: [&str; 17] = [
    "value", "xyz", "rpy", "ixx", "ixy", "ixz", "iyy", "iyz", "izz", "lower", "upper", "effort", "velocity", "radius",
    "length", "size", "scale",
];

/// The first numeric attribute that does not parse, as "line N: name=\"value\"".
fn find_bad_number(text: &str) -> Option<String> {
    for (line_no, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(eq) = rest.find("=\"") {
            let name = rest[..eq].rsplit(|c: char| c.is_whitespace() || c == '<').next().unwrap_or("");
            let after = &rest[eq + 2..];
            let Some(close) = after.find('"') else { break };
            let value = &after[..close];
            if NUMERIC_ATTRIBUTES.contains(&name) && value.split_whitespace().any(|t| t.parse::<f64>().is_err()) {
                return Some(format!("line {}: {name}=\"{value}\" is not a number", line_no + 1));
            }
            rest = &after[close + 1..];
        }
    }
    None
}

/// Removes mesh geometry (quadcl loads no meshes), warning once per mesh.
fn strip_meshes(urdf: &mut Robot, path: &Path) {
    for link in &mut urdf.links {
        let name = link.name.clone();
        link.collision.retain(|c| match &c.geometry {
            Geometry::Mesh { filename, .. } => {
                tracing::warn!(
                    "{}: link '{name}': collision mesh '{filename}' skipped (meshes are not loaded)",
                    path.display()
                );
                false
            }
            _ => true,
        });
        link.visual.clear();
    }
}

fn link_index(urdf: &Robot, name: &str) -> anyhow::Result<usize> {
    urdf.links
        .iter()
        .position(|l| l.name == name)
        .ok_or_else(|| anyhow!("joint refers to link '{name}', which does not exist"))
}

/// The unique link that is no joint's child; the joints must form a tree
/// (one parent joint per link, every link reachable from the root), else the
/// walks over the legs would never end.
fn find_root(urdf: &Robot) -> anyhow::Result<usize> {
    for joint in &urdf.joints {
        link_index(urdf, &joint.parent.link).with_context(|| format!("joint '{}'", joint.name))?;
        link_index(urdf, &joint.child.link).with_context(|| format!("joint '{}'", joint.name))?;
    }
    for link in &urdf.links {
        let parents: Vec<&str> =
            urdf.joints.iter().filter(|j| j.child.link == link.name).map(|j| j.name.as_str()).collect();
        if parents.len() > 1 {
            bail!("not a tree: link '{}' is the child of {} joints ({})", link.name, parents.len(), parents.join(", "));
        }
    }
    let roots: Vec<usize> =
        (0..urdf.links.len()).filter(|&i| !urdf.joints.iter().any(|j| j.child.link == urdf.links[i].name)).collect();
    match roots.as_slice() {
        [root] => {
            // One parent per link: a walk from the root visits each link at most once.
            let mut reached = vec![false; urdf.links.len()];
            let mut stack = vec![*root];
            while let Some(l) = stack.pop() {
                reached[l] = true;
                stack.extend(
                    children(urdf, &urdf.links[l].name)
                        .map(|j| link_index(urdf, &urdf.joints[j].child.link))
                        .collect::<anyhow::Result<Vec<_>>>()?,
                );
            }
            match reached.iter().position(|r| !r) {
                Some(l) => bail!(
                    "not a tree: link '{}' is not connected to the trunk '{}'",
                    urdf.links[l].name,
                    urdf.links[*root].name
                ),
                None => Ok(*root),
            }
        }
        [] => bail!("not a tree: every link is some joint's child (no trunk)"),
        many => bail!(
            "not a quadruped tree: {} root links ({}), expected one trunk",
            many.len(),
            many.iter().map(|&i| urdf.links[i].name.as_str()).collect::<Vec<_>>().join(", ")
        ),
    }
}

fn children<'a>(urdf: &'a Robot, link: &'a str) -> impl Iterator<Item = usize> + 'a {
    urdf.joints.iter().enumerate().filter(move |(_, j)| j.parent.link == link).map(|(i, _)| i)
}

/// The four leg chains (joint indices, hip first), ordered FL, FR, RL, RR.
fn find_legs(urdf: &Robot, trunk: usize) -> anyhow::Result<[Vec<usize>; NUM_LEGS]> {
    let revolute =
        urdf.joints.iter().filter(|j| matches!(j.joint_type, JointType::Revolute | JointType::Continuous)).count();
    let mut legs: Vec<(f64, f64, Vec<usize>, String)> = Vec::new();
    // Walk each subtree hanging from the trunk, composing fixed-joint offsets
    // (translations only: enough to tell front from rear and left from right).
    let mut stack: Vec<(usize, [f64; 3])> = children(urdf, &urdf.links[trunk].name).map(|j| (j, [0.0; 3])).collect();
    while let Some((j, offset)) = stack.pop() {
        let joint = &urdf.joints[j];
        let xyz = joint.origin.xyz.0;
        let pos = [offset[0] + xyz[0], offset[1] + xyz[1], offset[2] + xyz[2]];
        match &joint.joint_type {
            JointType::Fixed => stack.extend(children(urdf, &joint.child.link).map(|c| (c, pos))),
            JointType::Revolute | JointType::Continuous => {
                let chain = leg_chain(urdf, j)?;
                legs.push((pos[0], pos[1], chain, joint.name.clone()));
            }
            other => bail!(
                "not a quadruped tree: joint '{}' is {other:?}, only revolute and fixed joints are supported",
                joint.name
            ),
        }
    }
    if legs.len() != NUM_LEGS {
        bail!(
            "not a quadruped tree: {} leg chains hang from trunk '{}' ({} revolute joints in all), expected 4 legs of 3 revolute joints",
            legs.len(),
            urdf.links[trunk].name,
            revolute
        );
    }
    let mut out: [Vec<usize>; NUM_LEGS] = Default::default();
    for (x, y, chain, name) in legs {
        let leg = match (x > 0.0, y > 0.0) {
            (true, true) => Leg::FL,
            (true, false) => Leg::FR,
            (false, true) => Leg::RL,
            (false, false) => Leg::RR,
        };
        if !out[leg.index()].is_empty() {
            bail!(
                "not a quadruped tree: two legs in the {} quadrant (the second starts at joint '{name}', x={x}, y={y})",
                leg.name()
            );
        }
        out[leg.index()] = chain;
    }
    Ok(out)
}

/// The revolute joints of the leg starting at `hip`: must be a chain of three.
fn leg_chain(urdf: &Robot, hip: usize) -> anyhow::Result<Vec<usize>> {
    let mut chain = vec![hip];
    let mut frontier = vec![hip];
    while let Some(j) = frontier.pop() {
        let kids: Vec<usize> = children(urdf, &urdf.joints[j].child.link).collect();
        for k in kids {
            match &urdf.joints[k].joint_type {
                JointType::Fixed => frontier.push(k),
                JointType::Revolute | JointType::Continuous => {
                    chain.push(k);
                    frontier.push(k);
                }
                other => bail!("not a quadruped tree: joint '{}' is {other:?}", urdf.joints[k].name),
            }
        }
    }
    if chain.len() != JOINTS_PER_LEG {
        let names: Vec<&str> = chain.iter().map(|&j| urdf.joints[j].name.as_str()).collect();
        bail!(
            "missing joint: the leg starting at joint '{}' has {} revolute joints ({}), expected 3 (hip, thigh, calf) in one chain",
            urdf.joints[hip].name,
            chain.len(),
            names.join(", ")
        );
    }
    // A chain, not a fork: the calf must hang below the thigh (possibly via fixed joints).
    let thigh_child = &urdf.joints[chain[1]].child.link;
    let mut link = &urdf.joints[chain[2]].parent.link;
    while link != thigh_child {
        match urdf.joints.iter().find(|j| &j.child.link == link) {
            Some(j) if j.joint_type == JointType::Fixed => link = &j.parent.link,
            _ => bail!(
                "not a quadruped tree: the leg starting at joint '{}' forks (joint '{}' does not hang below joint '{}')",
                urdf.joints[hip].name,
                urdf.joints[chain[2]].name,
                urdf.joints[chain[1]].name
            ),
        }
    }
    Ok(chain)
}

/// Foot point and radius in the calf frame.
fn foot_of(urdf: &Robot, calf: usize) -> anyhow::Result<([f32; 3], f32)> {
    let calf_name = &urdf.links[calf].name;
    let sphere_on = |link: usize| {
        urdf.links[link].collision.iter().find_map(|c| match c.geometry {
            Geometry::Sphere { radius } => Some((c.origin.xyz.0, radius as f32)),
            _ => None,
        })
    };
    let fixed: Vec<usize> =
        children(urdf, calf_name).filter(|&j| urdf.joints[j].joint_type == JointType::Fixed).collect();
    if let Some(&j) = fixed.first() {
        let o = urdf.joints[j].origin.xyz.0;
        let child = link_index(urdf, &urdf.joints[j].child.link)?;
        let radius = sphere_on(child).map(|(_, r)| r).unwrap_or(0.0);
        return Ok(([o[0] as f32, o[1] as f32, o[2] as f32], radius));
    }
    match sphere_on(calf) {
        Some((o, r)) => Ok(([o[0] as f32, o[1] as f32, o[2] as f32], r)),
        None => {
            bail!("calf link '{calf_name}' has neither a fixed foot link nor a sphere collision shape for the foot")
        }
    }
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
