//! What quadcl says about bad input quotes it, it does not echo it: a 5 MB task name or
//! string value in a run file gives an error of a few hundred characters that says how long
//! the value was, and a path is named once, not once per layer that passed the error on.

use std::process::Command;

fn quadcl_run(config: &std::path::Path, out: &std::path::Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["run", "--config"])
        .arg(config)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_huge_value_in_a_run_file_is_quoted_clipped_with_its_length() {
    let tmp = tempfile::tempdir().unwrap();
    let huge = "x".repeat(5 << 20);
    for (name, text) in [
        ("task.toml", format!("[[task]]\nname = \"{huge}\"\n")),
        ("value.toml", format!("[run]\nlearner = \"{huge}\"\n[[task]]\nname = \"crash:FL\"\n")),
    ] {
        let cfg = tmp.path().join(name);
        std::fs::write(&cfg, text).unwrap();
        let err = quadcl_run(&cfg, &tmp.path().join("out"));
        assert!(err.len() < 4000, "{name}: {} bytes of error", err.len());
        assert!(err.contains(name), "{name}: names the file: {err}");
        assert!(err.contains("characters)"), "{name}: says how long the cut text was: {err}");
    }
}

#[test]
fn an_error_names_a_path_once() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("no-such-run.toml");
    let err = quadcl_run(&missing, &tmp.path().join("out"));
    assert_eq!(err.matches("no-such-run.toml").count(), 1, "{err}");
}
