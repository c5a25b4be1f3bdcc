//! Real robots' URDFs: the loader is as tolerant as MuJoCo's and Isaac Gym's
//! import (massless roots, fixed links, unlimited joints, repeated elements,
//! missing meshes, other joint names, knees bending the other way), merged
//! masses add up to the file's, and every such robot stands at its pose.

use quadcl::config::EnvConfig;
use quadcl::sim::{stand_test, RobotModel};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// What a generated quadruped has.
#[derive(Clone, Default)]
struct Features {
    /// A massless root link `base` with the trunk on a fixed joint.
    massless_root: bool,
    /// The thigh and calf joints' `<limit>` has only effort and velocity.
    unlimited: bool,
    /// Each visual repeats its `<material>` (with a different colour).
    repeated_material: bool,
    /// The feet are their own links on fixed joints (else a sphere on the calf).
    foot_links: bool,
    /// Each calf's collision is a mesh file that does not exist (the thigh's too, with nothing else).
    missing_meshes: bool,
    /// ANYmal names (LF_HAA, ...) and knees bending towards the body.
    anymal_style: bool,
}

const LEGS: [(&str, &str, f64, f64); 4] =
    [("FL", "LF", 1.0, 1.0), ("FR", "RF", 1.0, -1.0), ("RL", "LH", -1.0, 1.0), ("RR", "RH", -1.0, -1.0)];

fn inertial(m: f64, i: f64, z: f64) -> String {
    format!("<inertial><origin xyz=\"0 0 {z}\"/><mass value=\"{m}\"/><inertia ixx=\"{i}\" ixy=\"0\" ixz=\"0\" iyy=\"{i}\" iyz=\"0\" izz=\"{}\"/></inertial>", i / 10.0)
}

fn visual(f: &Features) -> String {
    let extra = if f.repeated_material { "<material name=\"b\"><color rgba=\"0 0 1 1\"/></material>" } else { "" };
    format!("<visual><geometry><mesh filename=\"package://robot/meshes/x.dae\"/></geometry><material name=\"a\"><color rgba=\"1 0 0 1\"/></material>{extra}</visual>")
}

/// An A1-sized quadruped with the given features; the total mass is 12.4 kg.
fn quadruped(f: &Features) -> String {
    let mut s = String::from("<robot name=\"gen\">\n");
    let trunk = if f.massless_root { "body" } else { "base" };
    if f.massless_root {
        s += "<link name=\"base\"/>\n<joint name=\"root_fixed\" type=\"fixed\"><parent link=\"base\"/><child link=\"body\"/></joint>\n";
    }
    let _ = writeln!(
        s,
        "<link name=\"{trunk}\">{}{}<collision><geometry><box size=\"0.27 0.19 0.11\"/></geometry></collision></link>",
        visual(f),
        inertial(4.8, 0.03, 0.0)
    );
    let limit = |lo: f64, hi: f64, effort: f64| {
        if f.unlimited {
            format!("<limit effort=\"{effort}\" velocity=\"20\"/>")
        } else {
            format!("<limit lower=\"{lo}\" upper=\"{hi}\" effort=\"{effort}\" velocity=\"20\"/>")
        }
    };
    for (quadcl, anymal, sx, sy) in LEGS {
        let name = |part: &str, anymal_part: &str| {
            if f.anymal_style {
                format!("{anymal}_{anymal_part}")
            } else {
                format!("{quadcl}_{part}")
            }
        };
        let (hip_j, thigh_j, calf_j) =
            (name("hip_joint", "HAA"), name("thigh_joint", "HFE"), name("calf_joint", "KFE"));
        let (hip, thigh, calf) = (name("hip", "HIP"), name("thigh", "THIGH"), name("calf", "SHANK"));
        // Knees towards the body: the hind calves' range is mirrored.
        let (calf_lo, calf_hi) = if f.anymal_style && sx < 0.0 { (0.9, 2.7) } else { (-2.7, -0.9) };
        let _ = writeln!(s, "<joint name=\"{hip_j}\" type=\"revolute\"><origin xyz=\"{} {} 0\"/><parent link=\"{trunk}\"/><child link=\"{hip}\"/><axis xyz=\"1 0 0\"/><limit lower=\"-0.8\" upper=\"0.8\" effort=\"20\" velocity=\"50\"/></joint>", 0.18 * sx, 0.05 * sy);
        let _ = writeln!(s, "<link name=\"{hip}\">{}</link>", inertial(0.7, 5e-4, 0.0));
        let _ = writeln!(s, "<joint name=\"{thigh_j}\" type=\"revolute\"><origin xyz=\"0 {} 0\"/><parent link=\"{hip}\"/><child link=\"{thigh}\"/><axis xyz=\"0 1 0\"/>{}</joint>", 0.085 * sy, limit(-1.0, 4.0, 55.0));
        let thigh_collision = if f.missing_meshes {
            "<collision><geometry><mesh filename=\"package://robot/meshes/thigh.stl\"/></geometry></collision>"
                .to_string()
        } else {
            "<collision><origin xyz=\"0 0 -0.1\"/><geometry><capsule radius=\"0.017\" length=\"0.15\"/></geometry></collision>".to_string()
        };
        let _ =
            writeln!(s, "<link name=\"{thigh}\">{}{}{thigh_collision}</link>", visual(f), inertial(1.0, 3e-3, -0.1));
        let _ = writeln!(s, "<joint name=\"{calf_j}\" type=\"revolute\"><origin xyz=\"0 0 -0.2\"/><parent link=\"{thigh}\"/><child link=\"{calf}\"/><axis xyz=\"0 1 0\"/>{}</joint>", limit(calf_lo, calf_hi, 55.0));
        let calf_mesh = if f.missing_meshes {
            "<collision><geometry><mesh filename=\"../meshes/calf.obj\"/></geometry></collision>"
        } else {
            ""
        };
        let foot_sphere =
            "<collision><origin xyz=\"0 0 -0.2\"/><geometry><sphere radius=\"0.02\"/></geometry></collision>";
        if f.foot_links {
            let _ = writeln!(s, "<link name=\"{calf}\">{}{calf_mesh}</link>", inertial(0.14, 5e-4, -0.1));
            let foot = name("foot", "FOOT");
            let _ = writeln!(s, "<joint name=\"{foot}_fixed\" type=\"fixed\"><origin xyz=\"0 0 -0.2\"/><parent link=\"{calf}\"/><child link=\"{foot}\"/></joint>");
            let _ = writeln!(
                s,
                "<link name=\"{foot}\">{}<collision><geometry><sphere radius=\"0.02\"/></geometry></collision></link>",
                inertial(0.06, 1e-5, 0.0)
            );
        } else {
            let _ = writeln!(s, "<link name=\"{calf}\">{}{calf_mesh}{foot_sphere}</link>", inertial(0.2, 5e-4, -0.1));
        }
    }
    s + "</robot>\n"
}

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn cfg_for(path: &Path) -> EnvConfig {
    EnvConfig { urdf: path.display().to_string(), ..EnvConfig::default() }
}

/// The ANYmal-style standing pose: front knees back, hind knees forward.
fn anymal_pose() -> BTreeMap<String, f32> {
    [("*_HAA", 0.0), ("?F_HFE", 0.8), ("?H_HFE", -0.8), ("?F_KFE", -1.5), ("?H_KFE", 1.5)]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

fn merged_mass(robot: &RobotModel) -> f64 {
    robot.urdf.links.iter().map(|l| l.inertial.mass.value).sum()
}

fn assert_stands(cfg: &EnvConfig, robot: &RobotModel) {
    let report = stand_test(cfg, robot, 2.0).unwrap();
    assert!(report.stood, "{}: {report:?}", robot.path.display());
    assert!(report.trunk_height > 0.2, "{report:?}");
}

#[test]
fn a_massless_root_with_the_trunk_on_a_fixed_joint_is_merged_and_stands() {
    let dir = tempfile::tempdir().unwrap();
    let f = Features { massless_root: true, foot_links: true, ..Features::default() };
    let path = write(&dir, "massless.urdf", &quadruped(&f));
    let robot = RobotModel::load(&path).unwrap();
    assert_eq!(robot.trunk_name(), "base");
    assert!((robot.total_mass - 12.4).abs() < 1e-9, "{}", robot.total_mass);
    assert!((merged_mass(&robot) - robot.total_mass).abs() < 1e-9);
    assert_eq!(robot.urdf.links.len(), 13, "trunk + 12 leg links: the feet and the body are merged");
    let merged: Vec<(&str, &str)> = robot.merged.iter().map(|m| (m.name.as_str(), m.into.as_str())).collect();
    assert!(merged.contains(&("body", "base")) && merged.contains(&("RR_foot", "RR_calf")), "{merged:?}");
    assert_eq!(robot.foot_offsets, [[0.0, 0.0, -0.2]; 4]);
    assert_eq!(robot.foot_radius, [0.02; 4]);
    assert!(robot.foot_sources[0].contains("FL_foot"), "{:?}", robot.foot_sources);
    assert_stands(&cfg_for(&path), &robot);
}

#[test]
fn revolute_joints_without_a_position_range_are_unlimited_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "unlimited.urdf", &quadruped(&Features { unlimited: true, ..Features::default() }));
    let robot = RobotModel::load(&path).unwrap();
    for j in &robot.joints {
        let hip = j.name.contains("hip");
        assert_eq!(j.lower.is_finite(), hip, "{j:?}");
        assert_eq!(j.upper.is_finite(), hip, "{j:?}");
    }
    assert_eq!(robot.warnings.iter().filter(|w| w.contains("unlimited")).count(), 8, "{:?}", robot.warnings);
    assert_stands(&cfg_for(&path), &robot);
}

#[test]
fn repeated_visual_elements_are_tolerated_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let text = quadruped(&Features { repeated_material: true, ..Features::default() });
    // urdf-rs alone refuses it, as the issue found.
    assert!(format!("{:?}", rapier3d_urdf::urdf_rs::read_from_string(&text).unwrap_err()).contains("material"));
    let path = write(&dir, "materials.urdf", &text);
    let robot = RobotModel::load(&path).unwrap();
    let repeats = robot.warnings.iter().filter(|w| w.contains("repeated <material>")).count();
    assert_eq!(repeats, 5, "the trunk's and four thighs' visuals: {:?}", robot.warnings);
    assert_stands(&cfg_for(&path), &robot);
}

#[test]
fn missing_meshes_fall_back_to_other_geometry_or_the_inertia_box() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "meshes.urdf", &quadruped(&Features { missing_meshes: true, ..Features::default() }));
    let robot = RobotModel::load(&path).unwrap();
    let fl_thigh = &robot.urdf.links[robot.joints[1].child_link];
    // The thigh had only the mesh: the box of its inertia replaces it, at its centre of mass.
    assert_eq!(fl_thigh.collision.len(), 1);
    assert!(matches!(fl_thigh.collision[0].geometry, rapier3d_urdf::urdf_rs::Geometry::Box { .. }));
    assert_eq!(fl_thigh.collision[0].origin.xyz.0, [0.0, 0.0, -0.1]);
    // The calf keeps its sphere, the foot.
    let fl_calf = &robot.urdf.links[robot.joints[2].child_link];
    assert_eq!(fl_calf.collision.len(), 1);
    let w = &robot.warnings;
    assert_eq!(w.iter().filter(|w| w.contains("thigh.stl") && w.contains("box of the link's inertia")).count(), 4);
    assert_eq!(w.iter().filter(|w| w.contains("calf.obj") && w.contains("other collision shapes")).count(), 4);
    assert_stands(&cfg_for(&path), &robot);
}

#[test]
fn a_mesh_that_is_there_becomes_the_box_or_sphere_of_its_bounds() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("robot/urdf")).unwrap();
    std::fs::create_dir_all(dir.path().join("robot/meshes")).unwrap();
    // A thigh mesh 4 x 4 x 20 cm around its centre, a calf "foot" mesh: a 4 cm cube at the calf's end.
    std::fs::write(dir.path().join("robot/meshes/thigh.stl"), "solid t\nfacet normal 0 0 1\nouter loop\nvertex -0.02 -0.02 -0.2\nvertex 0.02 0.02 0\nvertex 0 0 0\nendloop\nendfacet\nendsolid\n").unwrap();
    std::fs::write(dir.path().join("robot/meshes/calf.obj"), "v -0.02 -0.02 -0.22\nv 0.02 0.02 -0.18\n").unwrap();
    let text = quadruped(&Features { missing_meshes: true, ..Features::default() })
        .replace("<collision><origin xyz=\"0 0 -0.2\"/><geometry><sphere radius=\"0.02\"/></geometry></collision>", "");
    let path = dir.path().join("robot/urdf/robot.urdf");
    std::fs::write(&path, text).unwrap();
    let robot = RobotModel::load(&path).unwrap();
    let thigh = &robot.urdf.links[robot.joints[1].child_link].collision[0];
    match thigh.geometry {
        rapier3d_urdf::urdf_rs::Geometry::Box { ref size } => {
            assert!((size.0[0] - 0.04).abs() < 1e-6 && (size.0[2] - 0.2).abs() < 1e-6, "{size:?}")
        }
        ref other => panic!("{other:?}"),
    }
    assert!((thigh.origin.xyz.0[2] + 0.1).abs() < 1e-9);
    // The cube-like calf mesh is a sphere, and so it is the foot.
    assert!((robot.foot_offsets[0][2] + 0.2).abs() < 1e-6 && (robot.foot_radius[0] - 0.02).abs() < 1e-6);
    assert_stands(&cfg_for(&path), &robot);
}

#[test]
fn other_joint_names_and_knees_bending_towards_the_body_stand_at_a_pose_given_by_pattern() {
    let dir = tempfile::tempdir().unwrap();
    let f = Features { anymal_style: true, foot_links: true, massless_root: true, ..Features::default() };
    let path = write(&dir, "anymal_style.urdf", &quadruped(&f));
    let robot = RobotModel::load(&path).unwrap();
    let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names[..3], ["LF_HAA", "LF_HFE", "LF_KFE"]);
    assert_eq!(names[9..], ["RH_HAA", "RH_HFE", "RH_KFE"]);
    let mut cfg = cfg_for(&path);
    // The A1's conventions put the hind calves outside their mirrored range: a clear error.
    let err = format!("{:#}", stand_test(&cfg, &robot, 0.1).unwrap_err());
    assert!(err.contains("LH_KFE") && err.contains("outside its limits"), "{err}");
    cfg.robot.default_pose = anymal_pose();
    let pose = quadcl::sim::default_pose(&cfg, &robot).unwrap();
    assert_eq!(pose[..3], [0.0, 0.8, -1.5]);
    assert_eq!(pose[6..9], [0.0, -0.8, 1.5]);
    let report = stand_test(&cfg, &robot, 2.0).unwrap();
    assert!(report.stood, "{report:?}");
    // Knees towards the body: the front knees sit behind their feet, the hind knees ahead of theirs.
    let mut env = quadcl::sim::LocomotionEnv::new(&cfg, &robot, &quadcl::sim::Perturbation::none()).unwrap();
    env.step(&[0.0; 12]).unwrap();
    let legs = env.pose().legs;
    assert!(legs[0].knee[0] < legs[0].foot[0] && legs[2].knee[0] > legs[2].foot[0], "{legs:?}");
}

#[test]
fn gains_per_joint_and_the_leg_and_foot_overrides_follow_their_patterns() {
    let dir = tempfile::tempdir().unwrap();
    let f = Features { anymal_style: true, foot_links: true, ..Features::default() };
    let path = write(&dir, "anymal_style.urdf", &quadruped(&f));
    let mut cfg = cfg_for(&path);
    cfg.robot.default_pose = anymal_pose();
    cfg.robot.kp = [("*_KFE".to_string(), 30.0), ("LF_KFE".to_string(), 35.0)].into_iter().collect();
    cfg.robot.kd = [("*".to_string(), 0.7)].into_iter().collect();
    let robot = RobotModel::for_config(&cfg).unwrap();
    let gains = quadcl::sim::joint_gains(&cfg, &robot).unwrap();
    assert_eq!(gains.kp[..6], [20.0, 20.0, 35.0, 20.0, 20.0, 30.0]);
    assert_eq!(gains.kd, [0.7; 12]);
    // Swap which chain is FL and FR by naming their hips.
    cfg.robot.legs = [("FL", "RF_*"), ("FR", "LF_*"), ("RL", "LH_*"), ("RR", "RH_*")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    cfg.robot.foot_links = vec!["*_FOOT".into()];
    let swapped = RobotModel::for_config(&cfg).unwrap();
    assert_eq!(swapped.joints[0].name, "RF_HAA");
    assert_eq!(swapped.joints[3].name, "LF_HAA");
    assert!(swapped.foot_sources[0].contains("RF_FOOT"), "{:?}", swapped.foot_sources);
    // Patterns that match nothing, or match twice, are errors naming the table.
    cfg.robot.legs.insert("RR".into(), "*_HAA".into());
    let err = format!("{:#}", RobotModel::for_config(&cfg).unwrap_err());
    assert!(err.contains("env.robot.legs.RR") && err.contains("matches 4"), "{err}");
    cfg.robot.legs.clear();
    cfg.robot.foot_links = vec!["*_TOE".into()];
    let err = format!("{:#}", RobotModel::for_config(&cfg).unwrap_err());
    assert!(err.contains("env.robot.foot_links") && err.contains("LF_FOOT"), "{err}");
    cfg.robot.foot_links.clear();
    cfg.robot.kp.insert("*_KEF".into(), 10.0);
    let err = format!("{:#}", quadcl::sim::joint_gains(&cfg, &robot).unwrap_err());
    assert!(err.contains("env.robot.kp") && err.contains("\"*_KEF\" matches none"), "{err}");
    // A pose table that misses a joint names it.
    cfg.robot.default_pose.remove("?H_KFE");
    let err = format!("{:#}", quadcl::sim::default_pose(&cfg, &robot).unwrap_err());
    assert!(err.contains("LH_KFE") && err.contains("no angle"), "{err}");
}

#[test]
fn a_standing_pose_set_both_ways_is_an_error() {
    let mut cfg = EnvConfig::default();
    cfg.robot.default_pose = anymal_pose();
    cfg.default_calf = -1.4;
    let err = format!("{:#}", cfg.validate().unwrap_err());
    assert!(err.contains("env.default_calf") && err.contains("env.robot.default_pose"), "{err}");
}

/// The shipped scenes: each robot stands under its run file's settings, and the A1's figures are its own.
#[test]
fn the_shipped_robots_stand_with_their_run_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (scene, mass, trunk) in [("anymal_c", 49.6, "base"), ("aliengo", 20.636, "base"), ("a1", 12.213, "trunk")] {
        let cfg = if scene == "a1" {
            EnvConfig::default()
        } else {
            quadcl::engine::RunConfig::load(&root.join(format!("scenes/{scene}.toml"))).unwrap().config.env
        };
        let robot = RobotModel::for_config(&cfg).unwrap();
        assert!((robot.total_mass - mass).abs() < 1e-6 && (merged_mass(&robot) - mass).abs() < 1e-6, "{scene}");
        assert_eq!(robot.trunk_name(), trunk);
        assert!(robot.warnings.is_empty(), "{scene}: {:?}", robot.warnings);
        let report = stand_test(&cfg, &robot, 2.0).unwrap();
        assert!(report.stood, "{scene}: {report:?}");
        let sag = report.trunk_height / cfg.height_target;
        assert!(
            sag > 0.8 && sag < 1.1,
            "{scene}: trunk {} m against the target {}",
            report.trunk_height,
            cfg.height_target
        );
    }
}

/// A file as xacro leaves it (issue 36): a byte-order mark, an XML declaration, xacro
/// expressions inside a comment and a processing instruction. It loads as the same robot
/// as the file without them, and stands.
#[test]
fn xacro_leftovers_in_comments_and_a_byte_order_mark_load_and_stand() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = quadcl::engine::RunConfig::load(&root.join("scenes/aliengo.toml")).unwrap().config.env;
    let plain = RobotModel::for_config(&cfg).unwrap();
    cfg.urdf = root.join("tests/fuzz_corpus/xacro-leftovers.urdf").display().to_string();
    let robot = RobotModel::for_config(&cfg).unwrap();
    assert!((robot.total_mass - plain.total_mass).abs() < 1e-9, "{} against {}", robot.total_mass, plain.total_mass);
    assert_stands(&cfg, &robot);
}

/// Issue 36: `package://` and `file://` mesh paths that resolve nowhere (a file copied out of
/// its ROS package). The file loads as the aliengo it was made from (same joints and mass), the
/// thighs with only a mesh get their inertia box, the others keep their primitives, one warning
/// per mesh, and it stands.
#[test]
fn unresolved_package_and_file_mesh_paths_fall_back_and_the_robot_stands() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = quadcl::engine::RunConfig::load(&root.join("scenes/aliengo.toml")).unwrap().config.env;
    let plain = RobotModel::for_config(&cfg).unwrap();
    cfg.urdf = root.join("tests/fuzz_corpus/unresolved-meshes.urdf").display().to_string();
    let robot = RobotModel::for_config(&cfg).unwrap();
    assert!((robot.total_mass - plain.total_mass).abs() < 1e-9);
    let names = |r: &RobotModel| r.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&robot), names(&plain));
    let link = |name: &str| robot.urdf.links.iter().find(|l| l.name == name).unwrap();
    use rapier3d_urdf::urdf_rs::Geometry;
    for thigh in ["FR_thigh", "RL_thigh"] {
        let c = &link(thigh).collision;
        assert!(c.len() == 1 && matches!(c[0].geometry, Geometry::Box { .. }), "{thigh}: {c:?}");
    }
    // (The calf also holds its foot's sphere, merged from the foot link.)
    for (name, kept, n) in [("FL_thigh", "box", 1), ("RR_thigh", "box", 1), ("FL_calf", "cylinder", 2)] {
        let c = &link(name).collision;
        assert_eq!(c.len(), n, "{name}: {c:?}");
        let ok = match kept {
            "box" => matches!(c[0].geometry, Geometry::Box { .. }),
            _ => matches!(c[0].geometry, Geometry::Cylinder { .. }),
        };
        assert!(ok, "{name} keeps its {kept}: {c:?}");
    }
    let w = &robot.warnings;
    let inertia = w.iter().filter(|w| w.contains("package://") && w.contains("box of the link's inertia")).count();
    let dropped = w.iter().filter(|w| w.contains("file://") && w.contains("other collision shapes are used")).count();
    assert_eq!((inertia, dropped, w.len()), (2, 3, 5), "{w:#?}");
    assert_stands(&cfg, &robot);
}

/// Issue 36: the ROS extensions (`<transmission>` naming every joint, `<ros2_control>`,
/// `<gazebo>` blocks, one with a `<link>` and a `<joint>` inside a plugin, xacro leftovers in
/// them) are skipped unread, silently: the robot is the aliengo it was made from, and stands.
#[test]
fn transmission_gazebo_and_ros2_control_blocks_are_skipped_and_the_robot_stands() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = quadcl::engine::RunConfig::load(&root.join("scenes/aliengo.toml")).unwrap().config.env;
    let plain = RobotModel::for_config(&cfg).unwrap();
    cfg.urdf = root.join("tests/fuzz_corpus/ros-extensions.urdf").display().to_string();
    let robot = RobotModel::for_config(&cfg).unwrap();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    assert!((robot.total_mass - plain.total_mass).abs() < 1e-9, "the plugin's 100 kg link is not a link");
    let links = |r: &RobotModel| r.urdf.links.iter().map(|l| l.name.clone()).collect::<Vec<_>>();
    let joints = |r: &RobotModel| r.urdf.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>();
    assert_eq!(links(&robot), links(&plain));
    assert_eq!(joints(&robot), joints(&plain));
    assert_stands(&cfg, &robot);
}
