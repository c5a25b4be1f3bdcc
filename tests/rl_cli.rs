//! `quadcl train` and `quadcl eval` through the binary: a one-iteration
//! training run on the simulated robot, then the eval JSON schema.

use std::process::Command;

fn quadcl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_quadcl"))
}

const TINY: &str = r#"
seed = 3
[ppo]
num_envs = 4
steps_per_env = 4
iterations = 1
minibatches = 2
epochs = 1
cenet_decoder_hidden = [16]
[net.actor]
hidden = [16]
[net.critic]
hidden = [16]
[net.cenet]
hidden = [16]
"#;

/// One iteration of `quadcl train` on TINY in a fresh folder; returns it and the run's output folder.
fn train_tiny() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("tiny.toml");
    std::fs::write(&config, TINY).unwrap();
    let out = dir.path().join("run");
    let status = quadcl().args(["train", "--config"]).arg(&config).arg("--out").arg(&out).status().unwrap();
    assert!(status.success());
    (dir, out)
}

#[test]
fn one_iteration_of_train_then_eval_prints_the_documented_json() {
    let (_dir, out) = train_tiny();
    for file in ["config.toml", "metrics.jsonl", "summary.json", "policy/manifest.json", "policy/model.safetensors"] {
        assert!(out.join(file).exists(), "missing {file}");
    }

    let output = quadcl()
        .args(["eval", "--policy"])
        .arg(out.join("policy"))
        .args(["--task", "none", "--episodes", "2", "--seed", "1", "--json"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let keys: Vec<&str> = report.as_object().unwrap().keys().map(String::as_str).collect();
    for key in ["task", "episodes", "mean_return", "lin_vel_err", "ang_vel_err", "fall_rate", "survival_s"] {
        assert!(keys.contains(&key), "missing {key} in {report}");
    }
    assert_eq!(report["task"], "none");
    assert_eq!(report["episodes"], 2);
    let fall_rate = report["fall_rate"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&fall_rate));
}

#[test]
fn eval_of_a_missing_policy_names_the_directory() {
    let output = quadcl().args(["eval", "--policy", "/nonexistent/policy", "--json"]).output().unwrap();
    assert!(!output.status.success());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(err.contains("/nonexistent/policy"), "{err}");
}

#[test]
fn eval_of_a_training_checkpoint_equals_the_policy_its_task_ends_with() {
    // The last checkpoint is written before the task ends; evaluated, it ends the
    // task in memory (masks = top-k of the score means) and must score exactly as
    // the policy that training wrote after ending the task.
    let (_dir, out) = train_tiny();
    let eval = |policy: std::path::PathBuf| {
        let output = quadcl()
            .args(["eval", "--policy"])
            .arg(policy)
            .args(["--episodes", "3", "--seed", "2", "--json"])
            .output()
            .unwrap();
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        serde_json::from_slice::<serde_json::Value>(&output.stdout).unwrap()
    };
    let (from_checkpoint, from_policy) = (eval(out.join("checkpoint")), eval(out.join("policy")));
    assert_eq!(from_checkpoint, from_policy);
    assert!(from_policy["mean_return"].as_f64().unwrap().is_finite());
}

#[test]
fn eval_push_flags_replace_the_training_pushes() {
    // The same policy scored without pushes, with the interval set to 0, and under
    // pushes far past what any robot recovers from (8 m/s every 0.5 s).
    let (_dir, out) = train_tiny();
    let eval = |extra: &[&str]| {
        let output = quadcl()
            .args(["eval", "--policy"])
            .arg(out.join("policy"))
            .args(["--episodes", "2", "--seed", "4", "--json"])
            .args(extra)
            .output()
            .unwrap();
        assert!(output.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&output.stderr));
        serde_json::from_slice::<serde_json::Value>(&output.stdout).unwrap()
    };
    let calm = eval(&["--no-pushes"]);
    assert_eq!(eval(&["--push-interval-s", "0"]), calm);
    let shoved = eval(&["--push-interval-s", "0.5", "--push-max-vel", "8"]);
    assert_eq!(shoved["fall_rate"], 1.0, "{shoved}");
    let (calm_s, shoved_s) = (calm["survival_s"].as_f64().unwrap(), shoved["survival_s"].as_f64().unwrap());
    assert!(shoved_s < calm_s, "survival {shoved_s} s under pushes against {calm_s} s without");

    for (flag, value) in [("--push-interval-s", "-1"), ("--push-max-vel", "NaN")] {
        let output = quadcl()
            .args(["eval", "--policy"])
            .arg(out.join("policy"))
            .arg(format!("{flag}={value}"))
            .output()
            .unwrap();
        assert!(!output.status.success());
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(err.contains(flag) && err.contains(value), "{err}");
    }
}

#[test]
fn gait_reports_the_contact_pattern_of_a_held_command() {
    let (_dir, out) = train_tiny();
    let output = quadcl()
        .args(["gait", "--policy"])
        .arg(out.join("policy"))
        .args(["--vx", "-0.3", "--wz", "0.5", "--seconds", "3", "--json"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["command"], serde_json::json!([-0.3, 0.0, 0.5]));
    let fell = report["fell"].as_bool().unwrap();
    let seconds = report["seconds"].as_f64().unwrap();
    // An untrained policy may fall; a recording stops there.
    assert!(if fell { seconds < 3.0 } else { (seconds - 3.0).abs() < 1e-4 }, "{report}");
    let duty: Vec<f64> = report["duty_factor"].as_array().unwrap().iter().map(|d| d.as_f64().unwrap()).collect();
    assert_eq!(duty.len(), 4);
    assert!(duty.iter().all(|d| (0.0..=1.0).contains(d)), "{report}");
    assert!(["trot", "pace", "bound", "stand", "irregular"].contains(&report["gait"].as_str().unwrap()));
    let strip = report["contact_strip"].as_array().unwrap();
    assert_eq!(strip.len(), 4);
    for (line, foot) in strip.iter().zip(["FL", "FR", "RL", "RR"]) {
        assert!(line.as_str().unwrap().starts_with(foot), "{line}");
    }
}

#[test]
fn train_refuses_an_out_that_holds_a_run_unless_resume_or_force() {
    let (dir, out) = train_tiny();
    let config = dir.path().join("tiny.toml");
    let before = std::fs::read(out.join("metrics.jsonl")).unwrap();
    let again = quadcl().args(["train", "--config"]).arg(&config).arg("--out").arg(&out).output().unwrap();
    assert!(!again.status.success());
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(
        err.contains("already holds a training run") && err.contains("--force") && err.contains("--resume"),
        "{err}"
    );
    assert_eq!(std::fs::read(out.join("metrics.jsonl")).unwrap(), before, "nothing was touched");
    let forced = quadcl()
        .args(["train", "--force", "--seed", "9", "--config"])
        .arg(&config)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(forced.success());
    assert_ne!(std::fs::read(out.join("metrics.jsonl")).unwrap(), before, "--force trained anew (another seed)");
}

/// Ends a copy of the shipped base run (`policies/base-a1-flat-run`) with `scene` (train --resume
/// at its last iteration) and returns the folder the ended policy is in.
fn end_base_run_with(scene: &str, dir: &std::path::Path) -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = dir.join("base");
    std::fs::create_dir_all(out.join("checkpoint")).unwrap();
    let run = root.join("policies/base-a1-flat-run");
    for f in ["config.toml", "summary.json", "metrics.jsonl"] {
        std::fs::copy(run.join(f), out.join(f)).unwrap();
    }
    for entry in std::fs::read_dir(run.join("checkpoint")).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), out.join("checkpoint").join(entry.file_name())).unwrap();
    }
    let output = quadcl()
        .current_dir(root)
        .args(["train", "--config", scene, "--resume", "--iterations", "3175", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    out.join("policy")
}

/// The shipped base run (`policies/base-a1-flat-run`) was saved before issue 13 changed the
/// soft-score defaults (its manifest names no `sigma_scale`) and before issue 31 split the
/// re-initialisation (no `reinit_scores`). It must still be read as it ran, so the recipe of
/// policies/base-a1-flat-shared/README.md that ends it with p = 0 resumes and makes the shipped `base-a1-flat-shared` again, byte
/// for byte.
#[test]
fn a_base_run_saved_before_the_score_gap_unit_resumes_and_ends_as_it_did() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let policy = end_base_run_with("scenes/train-base-shared.toml", dir.path());
    let made = std::fs::read(policy.join("masks.safetensors")).unwrap();
    let shipped = std::fs::read(root.join("policies/base-a1-flat-shared/masks.safetensors")).unwrap();
    assert!(made == shipped, "the ended masks differ from the shipped base-a1-flat-shared");
}

/// The paper regime's base (issue 31): the same run ended keeping the base's ranking makes the
/// shipped `base-a1-flat-ranked`: its masks file byte for byte and every tensor of its model (the
/// kept means, the redrawn vacant weights and means) bit for bit.
#[test]
fn the_base_run_ended_with_the_ranking_kept_is_the_shipped_ranked_base() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let policy = end_base_run_with("scenes/train-base-ranked.toml", dir.path());
    let read = |dir: &std::path::Path, file: &str| std::fs::read(dir.join(file)).unwrap();
    let shipped = root.join("policies/base-a1-flat-ranked");
    assert!(
        read(&policy, "masks.safetensors") == read(&shipped, "masks.safetensors"),
        "masks.safetensors differs from the shipped base-a1-flat-ranked"
    );
    // model.safetensors carries the manifest's hash, which changes whenever a setting is added
    // to the config (issue 39's piggyback_learning_rate): its tensors must be the same bytes.
    let (made, kept) = (read(&policy, "model.safetensors"), read(&shipped, "model.safetensors"));
    let (made, kept) =
        (safetensors::SafeTensors::deserialize(&made).unwrap(), safetensors::SafeTensors::deserialize(&kept).unwrap());
    let mut names = made.names();
    names.sort();
    let mut kept_names = kept.names();
    kept_names.sort();
    assert_eq!(names, kept_names);
    for name in names {
        assert!(made.tensor(name).unwrap().data() == kept.tensor(name).unwrap().data(), "{name} differs");
    }
}
