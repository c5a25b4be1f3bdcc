//! Where a result came from (issue 32): the quadcl version, the git commit the
//! binary was built from and whether that tree had uncommitted changes (both
//! recorded by `build.rs`; "unknown" outside a git checkout), the sha256 of the
//! exact run file, and the machine's cores and the worker threads the run used.
//! `metrics.json`, a policy's `manifest.json` and a sweep's `sweep.json` carry
//! one, so every number in a table can be traced to the code that made it.
//! Provenance is never part of what a result is compared by (a resumed run on
//! another machine gives the same numbers with another provenance).

use serde::{Deserialize, Serialize};

/// The build and machine behind a result.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// `CARGO_PKG_VERSION` of the binary.
    pub quadcl_version: String,
    /// The commit the binary was built from, or "unknown" (not built from a git checkout).
    pub git_commit: String,
    /// Whether tracked files differed from that commit when it was built; None when unknown.
    pub git_dirty: Option<bool>,
    /// sha256 of the run file as the run used it (the run folder's `run.toml`); None for a
    /// result that has no run file (a sweep's plan records each cell's instead).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run_file_sha256: Option<String>,
    /// Cores available to the process (`std::thread::available_parallelism`: the machine's,
    /// or fewer under an affinity mask or a Slurm allocation).
    pub cores: usize,
    /// Worker threads of the parallel work (rayon's pool: `RAYON_NUM_THREADS` when set).
    pub threads: usize,
}

impl Provenance {
    /// This build on this machine; `run_file` is the exact run file's text, when there is one.
    pub fn of_this_build(run_file: Option<&[u8]>) -> Self {
        Self {
            quadcl_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: env!("QUADCL_GIT_COMMIT").to_string(),
            git_dirty: match env!("QUADCL_GIT_DIRTY") {
                "true" => Some(true),
                "false" => Some(false),
                _ => None,
            },
            run_file_sha256: run_file.map(super::sha256_hex),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            threads: rayon::current_num_threads(),
        }
    }

    /// One line for a table's footer: `quadcl 0.1.0 (commit 1234567, dirty), 16 cores`.
    pub fn line(&self) -> String {
        let commit: String = self.git_commit.chars().take(12).collect();
        let dirty = match self.git_dirty {
            Some(true) => ", dirty",
            Some(false) => "",
            None => ", tree state unknown",
        };
        format!("quadcl {} (commit {commit}{dirty}), {} cores", self.quadcl_version, self.cores)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn provenance_hashes_the_run_file_and_names_this_build() {
        let p = Provenance::of_this_build(Some(b"abc"));
        assert_eq!(
            p.run_file_sha256.as_deref(),
            Some("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad")
        );
        assert_eq!(p.quadcl_version, env!("CARGO_PKG_VERSION"));
        assert!(p.cores >= 1 && p.threads >= 1);
        assert!(p.git_commit == "unknown" || p.git_commit.len() == 40, "{}", p.git_commit);
        let back: Provenance = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
        assert!(Provenance::of_this_build(None).run_file_sha256.is_none());
    }
}
