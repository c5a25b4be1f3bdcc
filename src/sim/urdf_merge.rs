//! Links joined by fixed joints become one rigid body, as MuJoCo's URDF
//! import and Isaac Gym's `collapse_fixed_joints` do.
//!
//! A fixed joint from parent P to child C with origin T (C's frame in P's)
//! folds C into P: C's collision shapes move to P with origin T * o, C's
//! child joints hang from P with origin T * o, and the inertias combine
//! about the joint centre of mass (the parallel-axis theorem):
//!   m = m_P + m_C,  c = (m_P c_P + m_C c_C) / m,
//!   I = sum_k R_k I_k R_k^T + m_k (|d_k|^2 E - d_k d_k^T),  d_k = c_k - c,
//! with R_k the rotation of link k's inertial frame in P's frame. The merged
//! link keeps P's name; every merged link is remembered with its frame in
//! P's frame, so a foot link folded into a calf still names the foot point.
//! A massless root is fine once a fixed child has brought its mass.

use rapier3d_urdf::urdf_rs::{Inertia, Inertial, JointType, Pose, Robot, Vec3};

/// A link folded into another by a fixed joint.
#[derive(Debug, Clone)]
pub struct MergedLink {
    /// The link's name in the URDF.
    pub name: String,
    /// The name of the link it is now part of.
    pub into: String,
    /// Its frame in that link's frame.
    pub origin: Pose,
    /// Its own mass, kg.
    pub mass: f64,
    /// Where its collision shapes are in that link's collision list.
    pub collisions: std::ops::Range<usize>,
}

/// Folds every fixed joint's child into its parent; returns the folded links in the order folded.
pub(super) fn merge_fixed_links(urdf: &mut Robot) -> Vec<MergedLink> {
    let mut merged = Vec::new();
    while let Some(j) = urdf.joints.iter().position(|j| j.joint_type == JointType::Fixed) {
        let joint = urdf.joints.remove(j);
        let (parent, child) = (joint.parent.link.clone(), joint.child.link.clone());
        let Some(c) = urdf.links.iter().position(|l| l.name == child) else { continue };
        let child_link = urdf.links.remove(c);
        let Some(p) = urdf.links.iter().position(|l| l.name == parent) else { continue };
        let t = &joint.origin;
        let shift = urdf.links[p].collision.len();
        // Links merged earlier into the child now live in the parent.
        for m in merged.iter_mut().filter(|m: &&mut MergedLink| m.into == child) {
            m.into = parent.clone();
            m.origin = compose(t, &m.origin);
            m.collisions = m.collisions.start + shift..m.collisions.end + shift;
        }
        merged.push(MergedLink {
            name: child.clone(),
            into: parent.clone(),
            origin: t.clone(),
            mass: child_link.inertial.mass.value,
            collisions: shift..shift + child_link.collision.len(),
        });
        let link = &mut urdf.links[p];
        link.inertial = combine(&link.inertial, &child_link.inertial, t);
        link.collision.extend(child_link.collision.into_iter().map(|mut c| {
            c.origin = compose(t, &c.origin);
            c
        }));
        link.visual.extend(child_link.visual.into_iter().map(|mut v| {
            v.origin = compose(t, &v.origin);
            v
        }));
        for k in urdf.joints.iter_mut().filter(|k| k.parent.link == child) {
            k.parent.link = parent.clone();
            k.origin = compose(t, &k.origin);
        }
    }
    merged
}

type Mat = [[f64; 3]; 3];

/// The pose `b` (given in frame A, which sits at `a` in frame P) in frame P.
pub(super) fn compose(a: &Pose, b: &Pose) -> Pose {
    let ra = rotation(a.rpy.0);
    let xyz = add(a.xyz.0, mul_vec(&ra, b.xyz.0));
    Pose { xyz: Vec3(xyz), rpy: Vec3(rpy_of(&mul(&ra, &rotation(b.rpy.0)))) }
}

/// Link P's inertial combined with link C's, C at `t` in P; the result's frame is unrotated.
fn combine(p: &Inertial, c: &Inertial, t: &Pose) -> Inertial {
    let c_in_p = compose(t, &c.origin);
    let parts = [
        (p.mass.value, p.origin.xyz.0, rotation(p.origin.rpy.0), &p.inertia),
        (c.mass.value, c_in_p.xyz.0, rotation(c_in_p.rpy.0), &c.inertia),
    ];
    let mass: f64 = parts.iter().map(|k| k.0).sum();
    let com: [f64; 3] = if mass > 0.0 {
        std::array::from_fn(|i| parts.iter().map(|k| k.0 * k.1[i]).sum::<f64>() / mass)
    } else {
        p.origin.xyz.0
    };
    let mut total = [[0.0; 3]; 3];
    for (m, pos, r, inertia) in parts {
        let local = tensor(inertia);
        let rotated = mul(&mul(&r, &local), &transpose(&r));
        let d = sub(pos, com);
        let dd = dot(d, d);
        for i in 0..3 {
            for j in 0..3 {
                let eye = if i == j { 1.0 } else { 0.0 };
                total[i][j] += rotated[i][j] + m * (dd * eye - d[i] * d[j]);
            }
        }
    }
    let mut out = p.clone();
    out.mass.value = mass;
    out.origin = Pose { xyz: Vec3(com), rpy: Vec3([0.0; 3]) };
    out.inertia = Inertia {
        ixx: total[0][0],
        ixy: total[0][1],
        ixz: total[0][2],
        iyy: total[1][1],
        iyz: total[1][2],
        izz: total[2][2],
    };
    out
}

fn tensor(i: &Inertia) -> Mat {
    [[i.ixx, i.ixy, i.ixz], [i.ixy, i.iyy, i.iyz], [i.ixz, i.iyz, i.izz]]
}

/// URDF's fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
fn rotation([r, p, y]: [f64; 3]) -> Mat {
    let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), y.sin(), y.cos());
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// Roll, pitch, yaw of a rotation matrix (the inverse of [`rotation`]).
fn rpy_of(m: &Mat) -> [f64; 3] {
    let pitch = (-m[2][0]).clamp(-1.0, 1.0).asin();
    if m[2][0].abs() < 1.0 - 1e-12 {
        [m[2][1].atan2(m[2][2]), pitch, m[1][0].atan2(m[0][0])]
    } else {
        // Gimbal lock: put the whole turn about z into yaw.
        [0.0, pitch, (-m[0][1]).atan2(m[1][1])]
    }
}

fn mul(a: &Mat, b: &Mat) -> Mat {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn mul_vec(a: &Mat, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn transpose(a: &Mat) -> Mat {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] - b[i])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d_urdf::urdf_rs;

    fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
        Pose { xyz: Vec3(xyz), rpy: Vec3(rpy) }
    }

    #[test]
    fn rpy_round_trips_through_the_rotation_matrix() {
        for rpy in [[0.3, -0.7, 2.0], [0.0, 0.0, 0.0], [-1.2, 0.4, -3.0], [3.0, 1.5, 0.1]] {
            let back = rpy_of(&rotation(rpy));
            let (a, b) = (rotation(rpy), rotation(back));
            for i in 0..3 {
                for j in 0..3 {
                    assert!((a[i][j] - b[i][j]).abs() < 1e-9, "{rpy:?} -> {back:?}");
                }
            }
        }
    }

    #[test]
    fn composing_poses_moves_a_point_as_two_frames_do() {
        let a = pose([1.0, 0.0, 0.0], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let b = pose([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
        let ab = compose(&a, &b);
        assert!((ab.xyz.0[0] - 1.0).abs() < 1e-12 && (ab.xyz.0[1] - 1.0).abs() < 1e-12, "{ab:?}");
        assert!((ab.rpy.0[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    /// Two point-like masses 1 kg at x = 0 and 3 kg at x = 2 (via the fixed joint): the merged
    /// centre of mass is at 1.5, and the inertia about y is 1 * 1.5^2 + 3 * 0.5^2 = 3.
    #[test]
    fn merging_two_masses_puts_the_centre_of_mass_between_them_and_adds_the_parallel_axis_terms() {
        let text = r#"<robot name="r">
          <link name="a"><inertial><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
          <link name="b"><inertial><mass value="3"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial>
            <collision><origin xyz="0 0 1"/><geometry><sphere radius="0.1"/></geometry></collision></link>
          <link name="c"/>
          <joint name="ab" type="fixed"><origin xyz="2 0 0" rpy="0 0 1.5707963267948966"/><parent link="a"/><child link="b"/></joint>
          <joint name="bc" type="revolute"><origin xyz="0 1 0"/><parent link="b"/><child link="c"/><axis xyz="1 0 0"/>
            <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        </robot>"#;
        let mut urdf = urdf_rs::read_from_string(text).unwrap();
        let merged = merge_fixed_links(&mut urdf);
        assert_eq!(urdf.links.len(), 2);
        assert_eq!(merged.len(), 1);
        let m = &merged[0];
        assert_eq!((m.name.as_str(), m.into.as_str(), m.mass, m.collisions.clone()), ("b", "a", 3.0, 0..1));
        assert_eq!(m.origin.xyz.0, [2.0, 0.0, 0.0]);
        let a = &urdf.links[0].inertial;
        assert_eq!(a.mass.value, 4.0);
        assert!((a.origin.xyz.0[0] - 1.5).abs() < 1e-12);
        // b's own inertia turns by 90 degrees about z: its ixx 0.1 / iyy 0.2 swap.
        assert!((a.inertia.iyy - (3.0 + 0.1)).abs() < 1e-9, "{:?}", a.inertia);
        assert!((a.inertia.ixx - 0.2).abs() < 1e-9, "{:?}", a.inertia);
        assert!((a.inertia.izz - (3.0 + 0.3)).abs() < 1e-9, "{:?}", a.inertia);
        // The collision shape and the revolute joint now hang from a, moved through the fixed joint.
        let c = &urdf.links[0].collision[0].origin.xyz.0;
        assert!((c[0] - 2.0).abs() < 1e-12 && (c[2] - 1.0).abs() < 1e-12, "{c:?}");
        let j = &urdf.joints[0];
        assert_eq!(j.parent.link, "a");
        assert!((j.origin.xyz.0[0] - 1.0).abs() < 1e-12 && (j.origin.xyz.0[1]).abs() < 1e-12, "{:?}", j.origin);
    }
}
