//! `quadcl run` through the binary, as under nohup (stderr not a terminal):
//! no progress bar, so the task events and a line every 25 iterations (and
//! at each task's last) go to stderr for `tail -f`.

use std::path::Path;
use std::process::Command;

#[test]
fn a_run_without_a_terminal_reports_iterations_and_tasks_on_stderr() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("smoke");
    let output = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["run", "--config"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stderr = String::from_utf8_lossy(&output.stderr);
    // smoke.toml: three tasks of 3 iterations, so only each task's last iteration is echoed.
    let lines: Vec<&str> = stderr.lines().filter(|l| l.contains(" iteration ")).collect();
    assert_eq!(lines.len(), 3, "{stderr}");
    for (step, line) in lines.iter().enumerate() {
        assert!(line.starts_with(&format!("step {step} iteration 3/3: return ")), "{line}");
        assert!(line.contains(" fall_rate ") && line.contains(" SPS "), "{line}");
    }
    assert_eq!(stderr.matches("\"event\":\"task_started\"").count(), 3, "{stderr}");
    assert!(out.join("metrics.json").is_file());
    // The run's figures are drawn when it ends.
    for file in ["task_curves.png", "task_curves.svg", "sequence.png", "eval_matrix.svg"] {
        assert!(out.join("plots").join(file).is_file(), "no plots/{file}");
    }
}

#[test]
fn figures_that_cannot_be_written_are_a_warning_and_leave_the_run_as_it_was() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("smoke");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_quadcl"))
            .args(["run", "--config"])
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml"))
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    std::fs::create_dir_all(&out).unwrap();
    // A file where the figures' folder goes: they cannot be written.
    std::fs::write(out.join("plots"), "not a folder").unwrap();
    let output = run(&[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("warning: ") && stderr.contains("the figures were not drawn"), "{stderr}");
    let metrics = std::fs::read(out.join("metrics.json")).unwrap();
    assert!(String::from_utf8_lossy(&output.stdout).contains("3 steps of 3"));
    // The folder is still a run that resumes, to the same results.
    let resumed = run(&["--resume"]);
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    assert_eq!(std::fs::read(out.join("metrics.json")).unwrap(), metrics, "metrics.json changed");
}
