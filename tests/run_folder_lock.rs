//! One process at a time in a run folder: while a run (or the workbench, or `train`,
//! `finetune`) holds a folder, a second `quadcl run` on it is refused with an error naming
//! the folder and the holder, and leaves the folder as the first one writes it; two runs
//! started at the same moment end with one refusal and one complete run; a lock left by a
//! killed run is taken over with a warning.

use quadcl::engine::{lock_folder, MetricsFile, Runner, LOCK_FILE};
use quadcl::headless::{run, RunOptions};
use std::path::Path;
use std::process::{Command, Stdio};

const RUN: &str = "seed = 3\niterations = 4\n[run]\nlearner = \"toy\"\n[[task]]\nname = \"crash:FL\"\n\
                   [[task]]\nname = \"invert:RR\"\n";

/// A toy run long enough (a few hundred ms) that a second process starts while it runs.
const LONG_RUN: &str = "seed = 3\niterations = 3000\n[run]\nlearner = \"toy\"\n[eval]\nepisodes = 1\n\
                        [[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n";

fn resume() -> RunOptions {
    RunOptions { resume: true, ..Default::default() }
}

#[test]
fn a_second_run_on_a_locked_folder_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, RUN).unwrap();
    let out = tmp.path().join("out");
    // The workbench holds a folder through its Runner for as long as it has it open.
    let held = Runner::open(&cfg, &out, quadcl::engine::OpenMode::New, false).unwrap();
    let before = std::fs::read(out.join("metrics.json")).unwrap();
    let err = format!("{:#}", run(&cfg, &out, resume()).unwrap_err());
    assert!(err.contains(&out.display().to_string()), "names the folder: {err}");
    assert!(err.contains(&format!("in use by pid {}", std::process::id())), "names the holder: {err}");
    assert_eq!(std::fs::read(out.join("metrics.json")).unwrap(), before, "the refused run wrote nothing");
    drop(held);
    let m = run(&cfg, &out, resume()).unwrap();
    assert_eq!(m.completed_steps, 2, "once released, the folder runs");
    // `train` and `finetune` take the same lock.
    let _lock = lock_folder(&out).unwrap();
    assert!(format!("{:#}", lock_folder(&out).unwrap_err()).contains("is in use by"));
}

/// Two `quadcl run --resume` on one folder: (exit codes, stderr of each).
fn two_runs(cfg: &Path, out: &Path, apart: std::time::Duration) -> Vec<(bool, String)> {
    let start = || {
        Command::new(env!("CARGO_BIN_EXE_quadcl"))
            .args(["run", "--resume", "--config"])
            .arg(cfg)
            .arg("--out")
            .arg(out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let first = start();
    std::thread::sleep(apart);
    let second = start();
    [first, second]
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
        })
        .collect()
}

#[test]
fn two_runs_started_together_on_one_folder_end_in_one_refusal_and_one_complete_run() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, LONG_RUN).unwrap();
    let reference = tmp.path().join("alone");
    let alone = run(&cfg, &reference, RunOptions { no_tensorboard: true, ..Default::default() }).unwrap();
    for (i, apart) in [0, 0, 300].into_iter().enumerate() {
        let out = tmp.path().join(format!("out{i}"));
        let ends = two_runs(&cfg, &out, std::time::Duration::from_millis(apart));
        let refused: Vec<&String> = ends.iter().filter(|(ok, _)| !ok).map(|(_, e)| e).collect();
        assert_eq!(refused.len(), 1, "try {i}: exactly one refusal: {ends:?}");
        assert!(refused[0].contains("is in use by pid"), "try {i}: {}", refused[0]);
        let m = MetricsFile::load(&out.join("metrics.json")).unwrap();
        assert_eq!(m.eval_matrix, alone.eval_matrix, "try {i}: the folder holds the run, uncorrupted");
        assert_eq!(std::fs::read_to_string(out.join(LOCK_FILE)).unwrap(), "", "released");
    }
}

#[test]
fn a_lock_left_by_a_killed_run_is_taken_over_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    std::fs::write(&cfg, RUN).unwrap();
    let out = tmp.path().join("out");
    // A run killed with SIGKILL leaves its record (the kernel drops only the flock).
    let mut gone = Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait().unwrap();
    std::fs::create_dir_all(&out).unwrap();
    let record = serde_json::json!({
        "pid": pid, "host": quadcl::util::hostname(), "command": "quadcl run", "since_unix_s": 1
    });
    std::fs::write(out.join(LOCK_FILE), record.to_string()).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["run", "--resume", "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("took over the lock of pid {pid}")), "{stderr}");
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert!(log.contains("took over the folder's lock"), "{log}");
}
