//! Build script: records which code a binary was built from, for the provenance
//! every result carries (`util::Provenance`): the git commit of the checkout and
//! whether its tree had uncommitted changes. Outside a git checkout (a tarball,
//! a vendored copy) or without `git` both are "unknown"; this never fails a build.

use std::path::Path;
use std::process::Command;

/// `git ARGS` in the crate's folder: its trimmed standard output, or None when git is
/// missing, this is not a checkout, or the command fails.
fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let commit = git(&["rev-parse", "HEAD"]).filter(|c| !c.is_empty());
    // Tracked files changed (untracked ones do not change what is built from the tree).
    let dirty = match (&commit, git(&["status", "--porcelain", "--untracked-files=no"])) {
        (Some(_), Some(status)) => if status.is_empty() { "false" } else { "true" }.to_string(),
        _ => "unknown".to_string(),
    };
    println!("cargo:rustc-env=QUADCL_GIT_COMMIT={}", commit.as_deref().unwrap_or("unknown"));
    println!("cargo:rustc-env=QUADCL_GIT_DIRTY={dirty}");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.toml");
    // A commit moves the branch's ref (or packed-refs), a checkout moves HEAD, staging changes the index.
    let mut watched = vec!["HEAD".to_string(), "index".to_string(), "packed-refs".to_string()];
    if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
        watched.push(branch);
    }
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--path-format=absolute", "--git-path", &name]) {
            if Path::new(&path).exists() {
                println!("cargo:rerun-if-changed={path}");
            }
        }
    }
}
