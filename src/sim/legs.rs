//! The kinematic tree of a quadruped, found by structure rather than by name:
//! the trunk (the one root link), its four leg chains of three revolute
//! joints, and each leg's foot.
//!
//! Runs on the description after fixed links are merged (`urdf_merge`), so
//! a leg is a plain chain hip -> thigh -> calf, and a foot link joined to
//! the calf by a fixed joint is now part of the calf, remembered as a
//! [`MergedLink`]. The foot is, in the calf frame: the frame of a merged
//! link named by `env.robot.foot_links`; else the farthest from the knee of
//! the calf's sphere collision shapes and of its merged links carrying
//! one; else the farthest merged link; a calf with none of these is an error.

use super::robot::{Leg, JOINTS_PER_LEG, NUM_LEGS};
use super::urdf_merge::MergedLink;
use crate::config::robot::glob_match;
use anyhow::{anyhow, bail, Context};
use rapier3d_urdf::urdf_rs::{Geometry, JointType, Robot};
use std::collections::BTreeMap;

pub(super) fn link_index(urdf: &Robot, name: &str) -> anyhow::Result<usize> {
    urdf.links
        .iter()
        .position(|l| l.name == name)
        .ok_or_else(|| anyhow!("joint refers to link '{name}', which does not exist"))
}

/// The unique link that is no joint's child; the joints must form a tree
/// (one parent joint per link, every link reachable from the root), else the
/// walks over the legs would never end.
pub(super) fn find_root(urdf: &Robot) -> anyhow::Result<usize> {
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

pub(super) fn children<'a>(urdf: &'a Robot, link: &'a str) -> impl Iterator<Item = usize> + 'a {
    urdf.joints.iter().enumerate().filter(move |(_, j)| j.parent.link == link).map(|(i, _)| i)
}

/// The four leg chains (joint indices, hip first), ordered FL, FR, RL, RR.
/// With `overrides` (leg name -> pattern of its hip joint's name), the chain
/// whose hip matches a leg's pattern is that leg, wherever it sits.
pub(super) fn find_legs(
    urdf: &Robot,
    trunk: usize,
    overrides: &BTreeMap<String, String>,
) -> anyhow::Result<[Vec<usize>; NUM_LEGS]> {
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
    if !overrides.is_empty() {
        for leg in Leg::ALL {
            let pattern = &overrides[leg.name()];
            let hits: Vec<&(f64, f64, Vec<usize>, String)> =
                legs.iter().filter(|(_, _, _, hip)| glob_match(pattern, hip)).collect();
            match hits.as_slice() {
                [(_, _, chain, _)] => out[leg.index()] = chain.clone(),
                _ => bail!(
                    "env.robot.legs.{} = \"{pattern}\" matches {} of the hip joints ({}); it must match one",
                    leg.name(),
                    hits.len(),
                    legs.iter().map(|l| l.3.as_str()).collect::<Vec<_>>().join(", ")
                ),
            }
        }
        let mut starts: Vec<usize> = out.iter().map(|c| c[0]).collect();
        starts.sort_unstable();
        starts.dedup();
        anyhow::ensure!(starts.len() == NUM_LEGS, "env.robot.legs: two legs name the same hip joint");
        return Ok(out);
    }
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

/// A leg's foot, in its calf's frame.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Foot {
    /// The foot point, metres.
    pub offset: [f32; 3],
    /// The radius of its sphere (0 when the foot is not a sphere), metres.
    pub radius: f32,
    /// Indices in the calf's collision list of the shapes that are the foot.
    pub collisions: Vec<usize>,
    /// Where it was found, for `quadcl robot`.
    pub source: String,
}

/// The foot of the calf link `calf` (see the module header).
pub(super) fn foot_of(urdf: &Robot, calf: usize, merged: &[MergedLink], foot_links: &[String]) -> anyhow::Result<Foot> {
    let link = &urdf.links[calf];
    let into_calf: Vec<&MergedLink> = merged.iter().filter(|m| m.into == link.name).collect();
    let sphere_in = |range: std::ops::Range<usize>| {
        range.filter_map(|k| match link.collision[k].geometry {
            Geometry::Sphere { radius } => Some((k, link.collision[k].origin.xyz.0, radius as f32)),
            _ => None,
        })
    };
    let f32s = |v: [f64; 3]| v.map(|x| x as f32);
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let from_link = |m: &MergedLink| {
        let sphere = sphere_in(m.collisions.clone()).next();
        Foot {
            offset: f32s(m.origin.xyz.0),
            radius: sphere.map_or(0.0, |s| s.2),
            collisions: m.collisions.clone().collect(),
            source: format!("link '{}' (merged into '{}')", m.name, link.name),
        }
    };
    if !foot_links.is_empty() {
        let hits: Vec<&&MergedLink> =
            into_calf.iter().filter(|m| foot_links.iter().any(|p| glob_match(p, &m.name))).collect();
        return match hits.as_slice() {
            [m] => Ok(from_link(m)),
            _ => bail!(
                "env.robot.foot_links matches {} of the links fixed to calf '{}' ({}); it must match one",
                hits.len(),
                link.name,
                into_calf.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join(", ")
            ),
        };
    }
    let spheres = sphere_in(0..link.collision.len());
    if let Some((k, centre, radius)) = spheres.max_by(|a, b| norm(a.1).total_cmp(&norm(b.1))) {
        let owner = into_calf.iter().find(|m| m.collisions.contains(&k));
        return Ok(match owner {
            Some(m) => from_link(m),
            None => Foot {
                offset: f32s(centre),
                radius,
                collisions: vec![k],
                source: format!("the sphere of link '{}'", link.name),
            },
        });
    }
    match into_calf.iter().max_by(|a, b| norm(a.origin.xyz.0).total_cmp(&norm(b.origin.xyz.0))) {
        Some(m) => Ok(from_link(m)),
        None => Err(anyhow!(
            "calf link '{}' has neither a fixed foot link nor a sphere collision shape for the foot \
             (name the foot's link in env.robot.foot_links)",
            link.name
        )),
    }
}
