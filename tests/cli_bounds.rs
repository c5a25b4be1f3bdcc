//! Every numeric command-line option has a checked range (issue 16, items 1
//! and 2): out-of-range, non-finite and meaningless values are refused at
//! once, before any policy loads or anything runs, with an error naming the
//! option and the limit.

use std::process::{Command, Output};

fn quadcl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadcl")).current_dir(env!("CARGO_MANIFEST_DIR")).args(args).output().unwrap()
}

/// Runs `quadcl` with `args` and asserts it fails at once with an error containing every one of `expect`.
fn refused(args: &[&str], expect: &[&str]) {
    let start = std::time::Instant::now();
    let out = quadcl(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded: {err}");
    for e in expect {
        assert!(err.contains(e), "{args:?}: {e:?} not in {err}");
    }
    assert!(start.elapsed().as_secs() < 30, "{args:?} ran before refusing");
}

const POLICY: &str = "policies/base-a1-flat";

#[test]
fn gait_seconds_and_commands_out_of_range_are_refused_naming_the_option() {
    for seconds in ["1e9", "0", "nan", "inf"] {
        refused(&["gait", "--policy", POLICY, "--seconds", seconds], &["--seconds", "(0, 3600]"]);
    }
    for (option, v) in [("--vx", "100"), ("--vx", "nan"), ("--wz", "-11"), ("--wz", "inf")] {
        refused(&["gait", "--policy", POLICY, option, v], &[option, "[-10, 10]"]);
    }
}

#[test]
fn record_seconds_and_held_commands_out_of_range_are_refused_before_the_policy_loads() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.mcap");
    let out = out.to_str().unwrap();
    for seconds in ["1e12", "0", "nan"] {
        refused(&["record", "--policy", "no-such-policy", "--seconds", seconds, "--out", out], &["--seconds", "3600"]);
    }
    for (option, v) in [("--vx", "nan"), ("--vy", "50"), ("--wz", "-1e9")] {
        refused(&["record", "--policy", "no-such-policy", option, v, "--out", out], &[option, "[-10, 10]"]);
    }
    refused(&["record", "--policy", "no-such-policy", "--episodes", "0", "--out", out], &["--episodes"]);
    assert!(!dir.path().join("x.mcap").exists());
}

#[test]
fn bench_and_robot_seconds_out_of_range_are_refused() {
    for seconds in ["1e9", "0", "nan", "601"] {
        refused(&["bench", "--seconds", seconds], &["--seconds", "(0, 600]"]);
    }
    for seconds in ["61", "0", "nan"] {
        refused(&["robot", "--seconds", seconds], &["--seconds", "(0, 60]"]);
    }
}

#[test]
fn finetune_iterations_and_episodes_out_of_range_are_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let shift = dir.path().join("shift.toml");
    std::fs::write(&shift, "latency_s = 0.02\niterations = 2\n").unwrap();
    let (shift, out) = (shift.to_str().unwrap(), dir.path().join("tuned"));
    let base = ["finetune", "--policy", POLICY, "--task", "none", "--shift", shift, "--out", out.to_str().unwrap()];
    for (option, v, limit) in [
        ("--iterations", "0", "at least 1"),
        ("--iterations", "100000000", "at most 10000000"),
        ("--episodes", "0", "16384"),
        ("--episodes", "100000000", "16384"),
    ] {
        let args: Vec<&str> = base.iter().copied().chain([option, v]).collect();
        refused(&args, &[option, limit]);
    }
    assert!(!out.exists(), "nothing was written");
}

#[test]
fn run_stop_after_zero_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    refused(
        &["run", "--config", "scenes/smoke.toml", "--out", out.to_str().unwrap(), "--stop-after", "0"],
        &["--stop-after"],
    );
    assert!(!out.join("metrics.json").exists());
}
