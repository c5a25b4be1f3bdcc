//! Nothing a user can type allocates without bound, and values that make a
//! run meaningless are refused: each error names the file or option, the key
//! and the limit (issue 16, items 1 and 2).

use std::path::Path;
use std::process::Command;

fn quadcl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_quadcl")).current_dir(env!("CARGO_MANIFEST_DIR")).args(args).output().unwrap()
}

#[test]
fn a_huge_episode_count_is_refused_at_once_with_the_limit() {
    for episodes in ["100000000", "16385", "0"] {
        let out = quadcl(&["eval", "--policy", "policies/base-a1-flat", "--task", "none", "--episodes", episodes]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("--episodes") && err.contains("16384"), "{episodes}: {err}");
    }
}

#[test]
fn run_files_with_sizes_that_cannot_fit_or_ranges_that_cannot_work_name_the_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let smoke = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")).unwrap();
    for (from, to, key) in [
        ("episodes = 4", "episodes = 100000000", "[eval] episodes"),
        ("num_envs = 8", "num_envs = 0", "ppo.num_envs"),
        ("num_envs = 8", "num_envs = 1000000", "at most 16384"),
        ("hidden = [64, 32]", "hidden = [0, 32]", "net.actor.hidden"),
        ("episode_s = 2.0", "episode_s = 2.0\nmotor_strength_range = [-5.0, -5.0]", "env.motor_strength_range"),
        ("episode_s = 2.0", "episode_s = 2.0\nfriction_range = [-1.0, 1.0]", "env.friction_range"),
    ] {
        assert!(smoke.contains(from), "{from}");
        let path = dir.path().join("bad-run.toml");
        std::fs::write(&path, smoke.replacen(from, to, 1)).unwrap();
        let out =
            quadcl(&["run", "--config", path.to_str().unwrap(), "--out", dir.path().join("out").to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("bad-run.toml") && err.contains(key), "{to}: {err}");
        assert!(!dir.path().join("out").join("metrics.json").exists(), "{to}: nothing ran");
    }
}

#[test]
fn a_shift_file_latency_beyond_the_limit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shift.toml");
    for latency in ["1e12", "11.0", "-1.0", "nan"] {
        std::fs::write(&path, format!("latency_s = {latency}\n")).unwrap();
        let err = format!("{:#}", quadcl::engine::Shift::load(&path).unwrap_err());
        assert!(err.contains("shift.toml") && err.contains("latency_s") && err.contains("[0, 10]"), "{latency}: {err}");
    }
}
