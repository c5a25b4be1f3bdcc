//! `quadcl robot` and `quadcl run` through the binary for the robots shipped
//! besides the A1: what the loader understood, that each stands, and that the
//! smoke sequence runs on each (`scenes/smoke-<robot>.toml`).

use std::path::Path;
use std::process::Command;

fn quadcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_quadcl")).current_dir(env!("CARGO_MANIFEST_DIR")).args(args).output().unwrap()
}

#[test]
fn quadcl_robot_reports_legs_masses_feet_and_that_each_shipped_robot_stands() {
    for (scene, first_joint, merged) in
        [("anymal_c", "LF_HAA", 5), ("aliengo", "FL_hip_joint", 5), ("a1", "FL_hip_joint", 0)]
    {
        let config = format!("scenes/{scene}.toml");
        let mut args = vec!["robot", "--json"];
        if scene != "a1" {
            args.extend(["--config", &config]);
        }
        let out = quadcl(&args);
        assert!(out.status.success(), "{scene}: {}", String::from_utf8_lossy(&out.stderr));
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(r["joints"].as_array().unwrap().len(), 12, "{scene}");
        assert_eq!(r["joints"][0]["name"], first_joint, "{scene}");
        assert_eq!(r["merged"].as_array().unwrap().len(), merged, "{scene}");
        let links: f64 = r["links"].as_array().unwrap().iter().map(|l| l[1].as_f64().unwrap()).sum();
        assert!((links - r["total_mass"].as_f64().unwrap()).abs() < 1e-9, "{scene}: {r}");
        assert_eq!(r["stand"]["stood"], true, "{scene}: {}", r["stand"]);
        assert_eq!(r["feet"].as_array().unwrap().len(), 4);
    }
    // The text form says it too, and the ANYmal without its run file's pose does not stand.
    let out = quadcl(&["robot", "scenes/anymal_c.urdf"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("LF_KFE") && text.contains("did NOT stand"), "{text}");
}

#[test]
fn quadcl_robot_errors_name_the_file_and_the_problem() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = tmp.path().join("bad.urdf");
    std::fs::write(
        &bad,
        "<robot name=\"r\"><link name=\"a\"><inertial><mass value=\"1\"/><mass value=\"2\"/></inertial></link></robot>",
    )
    .unwrap();
    let out = quadcl(&["robot", bad.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("bad.urdf") && err.contains("two different <mass>"), "{err}");
    let cfg = tmp.path().join("pose.toml");
    std::fs::write(&cfg, "[env]\nurdf = \"scenes/anymal_c.urdf\"\n[env.robot.default_pose]\n\"*_HFE\" = 0.4\n")
        .unwrap();
    let out = quadcl(&["robot", "--config", cfg.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("LF_HAA") && err.contains("no angle"), "{err}");
}

#[test]
fn the_smoke_sequence_runs_on_each_new_robot() {
    for scene in ["anymal_c", "aliengo"] {
        let tmp = tempfile::tempdir().unwrap();
        let out_dir = tmp.path().join("run");
        let config = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/smoke-{scene}.toml"));
        let out = quadcl(&["run", "--config", config.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
        assert!(out.status.success(), "{scene}: {}", String::from_utf8_lossy(&out.stderr));
        let metrics: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out_dir.join("metrics.json")).unwrap()).unwrap();
        assert_eq!(metrics["completed_steps"], 3, "{scene}");
        let run_toml = std::fs::read_to_string(out_dir.join("run.toml")).unwrap();
        assert!(run_toml.contains(&format!("scenes/{scene}.urdf")), "{run_toml}");
    }
}
