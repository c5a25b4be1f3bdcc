//! The URDF loader: legs found by structure, and malformed descriptions
//! give errors that name the file and the problem.

use quadcl::sim::RobotModel;
use std::path::{Path, PathBuf};

fn a1_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/a1.urdf")).unwrap()
}

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn load_err(name: &str, text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, name, text);
    format!("{:#}", RobotModel::load(&path).unwrap_err())
}

/// Removes the `<joint name="NAME" ...> ... </joint>` element.
fn without_joint(text: &str, name: &str) -> String {
    let start = text.find(&format!("<joint name=\"{name}\"")).unwrap();
    let end = start + text[start..].find("</joint>").unwrap() + "</joint>".len();
    format!("{}{}", &text[..start], &text[end..])
}

#[test]
fn legs_are_found_by_structure_not_by_joint_names() {
    // Rename every joint and link so no name says which leg it is.
    let mut text = a1_text();
    for (from, to) in [("FL_", "alpha_"), ("FR_", "beta_"), ("RL_", "gamma_"), ("RR_", "delta_")] {
        text = text.replace(from, to);
    }
    text = text.replace("_hip", "_a").replace("_thigh", "_b").replace("_calf", "_c");
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotModel::load(&write(&dir, "renamed.urdf", &text)).unwrap();
    let names: Vec<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names[..3], ["alpha_a_joint", "alpha_b_joint", "alpha_c_joint"]);
    assert_eq!(names[3], "beta_a_joint");
    assert_eq!(names[6], "gamma_a_joint");
    assert_eq!(names[9], "delta_a_joint");
}

#[test]
fn missing_joint_is_an_error_naming_the_file_and_the_leg() {
    // Dropping the calf joint leaves the calf link a second root.
    let text = without_joint(&a1_text(), "RL_calf_joint").replace(
        "<link name=\"RL_calf\">",
        "<joint name=\"RL_foot_fixed\" type=\"fixed\"><parent link=\"RL_thigh\"/><child link=\"RL_calf\"/></joint>\n  <link name=\"RL_calf\">",
    );
    let err = load_err("missing_calf.urdf", &text);
    assert!(err.contains("missing_calf.urdf"), "{err}");
    assert!(err.contains("missing joint") && err.contains("RL_hip_joint") && err.contains("expected 3"), "{err}");
}

#[test]
fn bad_number_is_an_error_naming_the_file_and_the_value() {
    let err =
        load_err("bad_number.urdf", &a1_text().replacen("<mass value=\"4.713\"/>", "<mass value=\"4.7x13\"/>", 1));
    assert!(err.contains("bad_number.urdf"), "{err}");
    assert!(err.contains("bad number") && err.contains("4.7x13") && err.contains("line 11"), "{err}");

    let err = load_err("nan_inertia.urdf", &a1_text().replacen("ixx=\"0.019886\"", "ixx=\"NaN\"", 1));
    assert!(err.contains("nan_inertia.urdf") && err.contains("bad number") && err.contains("trunk"), "{err}");

    let err = load_err("bad_effort.urdf", &a1_text().replacen("effort=\"55\"", "effort=\"-55\"", 1));
    assert!(err.contains("bad_effort.urdf") && err.contains("FL_thigh_joint") && err.contains("effort"), "{err}");
}

#[test]
fn a_tree_that_is_not_a_quadruped_is_an_error_naming_the_file() {
    let mut text = a1_text();
    for joint in ["RR_hip_joint", "RR_thigh_joint", "RR_calf_joint"] {
        text = without_joint(&text, joint);
    }
    for link in ["RR_hip", "RR_thigh", "RR_calf"] {
        let start = text.find(&format!("<link name=\"{link}\">")).unwrap();
        let end = start + text[start..].find("</link>").unwrap() + "</link>".len();
        text = format!("{}{}", &text[..start], &text[end..]);
    }
    let err = load_err("tripod.urdf", &text);
    assert!(
        err.contains("tripod.urdf") && err.contains("not a quadruped tree") && err.contains("3 leg chains"),
        "{err}"
    );
}

#[test]
fn a_mesh_it_cannot_load_is_skipped_not_fatal() {
    let text = a1_text().replacen(
        "<geometry><box size=\"0.267 0.194 0.114\"/></geometry>\n    </collision>",
        "<geometry><box size=\"0.267 0.194 0.114\"/></geometry>\n    </collision>\n    <collision><geometry><mesh filename=\"meshes/missing.dae\"/></geometry></collision>",
        1,
    );
    assert!(text.contains("missing.dae"));
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotModel::load(&write(&dir, "mesh.urdf", &text)).unwrap();
    assert_eq!(robot.urdf.links[robot.trunk_link].collision.len(), 1);
}

/// The A1 with each foot as its own link on a fixed joint (as Unitree's own URDF has it).
fn a1_with_foot_links() -> String {
    let mut text = a1_text();
    for leg in ["FL", "FR", "RL", "RR"] {
        let sphere = "    <collision>\n      <origin xyz=\"0 0 -0.2\" rpy=\"0 0 0\"/>\n      <geometry><sphere radius=\"0.02\"/></geometry>\n    </collision>\n";
        let calf_start = text.find(&format!("<link name=\"{leg}_calf\">")).unwrap();
        let at = calf_start + text[calf_start..].find(sphere).unwrap();
        text.replace_range(at..at + sphere.len(), "");
        let end = calf_start + text[calf_start..].find("</link>").unwrap() + "</link>".len();
        let foot = format!(
            "\n  <joint name=\"{leg}_foot_fixed\" type=\"fixed\">\n    <origin xyz=\"0 0 -0.2\" rpy=\"0 0 0\"/>\n    <parent link=\"{leg}_calf\"/>\n    <child link=\"{leg}_foot\"/>\n  </joint>\n  <link name=\"{leg}_foot\">\n    <inertial><mass value=\"0.06\"/><inertia ixx=\"1e-5\" ixy=\"0\" ixz=\"0\" iyy=\"1e-5\" iyz=\"0\" izz=\"1e-5\"/></inertial>\n    <collision><geometry><sphere radius=\"0.02\"/></geometry></collision>\n  </link>"
        );
        text.insert_str(end, &foot);
    }
    text
}

#[test]
fn feet_on_fixed_links_are_found_and_touch_the_ground() {
    use quadcl::config::EnvConfig;
    use quadcl::sim::{obs, LocomotionEnv, Perturbation, ACT_DIM};
    let dir = tempfile::tempdir().unwrap();
    let robot = RobotModel::load(&write(&dir, "feet.urdf", &a1_with_foot_links())).unwrap();
    assert_eq!(robot.foot_offsets, [[0.0, 0.0, -0.2]; 4]);
    assert_eq!(robot.foot_radius, [0.02; 4]);
    let cfg = EnvConfig { randomize: false, push_interval_s: 0.0, ..EnvConfig::default() };
    let mut env = LocomotionEnv::new(&cfg, &robot, &Perturbation::none()).unwrap();
    for _ in 0..100 {
        assert!(!env.step(&[0.0; ACT_DIM]).unwrap().terminated);
    }
    let contacts = &env.privileged_observation()[obs::PRIV_FOOT_CONTACTS..obs::PRIV_FOOT_CONTACTS + 4];
    assert_eq!(contacts, [1.0; 4]);
}

#[test]
fn a_link_with_two_parent_joints_is_an_error_not_an_endless_walk() {
    // A fixed joint from the calf back to the hip link closes a loop in the leg:
    // walking the leg would never end.
    let text = a1_text().replacen(
        "<link name=\"FL_calf\">",
        "<joint name=\"FL_loop\" type=\"fixed\"><parent link=\"FL_calf\"/><child link=\"FL_hip\"/></joint>\n  <link name=\"FL_calf\">",
        1,
    );
    let err = load_err("loop.urdf", &text);
    assert!(
        err.contains("loop.urdf") && err.contains("not a tree") && err.contains("FL_hip") && err.contains("FL_loop"),
        "{err}"
    );
}

#[test]
fn a_link_not_connected_to_the_trunk_is_an_error() {
    // Two links hanging from each other in a cycle, apart from the robot: no second root, but not a tree.
    let text = a1_text().replacen(
        "<link name=\"FL_calf\">",
        "<link name=\"ghost_a\"/><link name=\"ghost_b\"/>\n  <joint name=\"ghost_ab\" type=\"fixed\"><parent link=\"ghost_a\"/><child link=\"ghost_b\"/></joint>\n  <joint name=\"ghost_ba\" type=\"fixed\"><parent link=\"ghost_b\"/><child link=\"ghost_a\"/></joint>\n  <link name=\"FL_calf\">",
        1,
    );
    let err = load_err("ghost.urdf", &text);
    assert!(err.contains("ghost.urdf") && err.contains("not a tree") && err.contains("ghost_a"), "{err}");
}

#[test]
fn a_massless_calf_is_an_error_naming_the_link() {
    let text = a1_text().replacen("<mass value=\"0.166\"/>", "<mass value=\"0\"/>", 1);
    let err = load_err("massless_calf.urdf", &text);
    assert!(err.contains("massless_calf.urdf") && err.contains("FL_calf") && err.contains("no mass"), "{err}");
}
