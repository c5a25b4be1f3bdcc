//! What `quadcl sweep local` says about a cell it runs: `DIR/state/I.json`
//! holds `running` (with the child's pid and the host) while the cell's
//! `quadcl run` is alive, `failed` (with its exit status) after it failed,
//! and nothing once it finished. A `running` marker whose process is gone
//! (the sweep was killed) reads as not running: the run folder says how far
//! the cell got, and the next `sweep local` resumes it. `DIR/state/claim.lock`
//! is the lock under which a `sweep local` checks a cell and starts it; the cell's run
//! folder's own lock (`runs/I/run.lock`) says that a run is training it, whoever started it.

use super::plan::Cell;
use super::STATE_DIR;
use crate::util::{hostname, process_exists, write_atomic, FolderLock};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A cell's marker.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum Marker {
    /// A `quadcl run` of the cell is (or was, if `pid` is gone) running on `host`.
    Running { pid: u32, host: String },
    /// The cell's last `quadcl run` failed; its log says why.
    Failed { exit_code: Option<i32>, host: String },
}

impl Marker {
    /// Whether this marker's run is alive: `running` on this host with its process still there
    /// (and, where `/proc` tells, still a `quadcl run ... --resume`: a reused pid is not the cell's).
    pub fn is_alive(&self) -> bool {
        match self {
            Marker::Running { pid, host } => *host == hostname() && process_exists(*pid) && runs_resume(*pid),
            Marker::Failed { .. } => false,
        }
    }
}

/// Whether a live run is training `cell` of the sweep in `dir`: this host's by its marker (a
/// run just started, before it locked its folder), or any process holding the cell's run
/// folder's lock.
pub fn running_elsewhere(dir: &Path, cell: &Cell) -> bool {
    read_marker(dir, cell.index).is_some_and(|m| m.is_alive())
        || FolderLock::holder(&dir.join(&cell.run).join(crate::engine::LOCK_FILE)).is_some()
}

/// The marker file of cell `index` in the sweep folder `dir`.
pub fn marker_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(STATE_DIR).join(format!("{index}.json"))
}

/// The marker of cell `index`, if any (an unreadable one counts as none).
pub fn read_marker(dir: &Path, index: usize) -> Option<Marker> {
    let text = std::fs::read_to_string(marker_path(dir, index)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Writes (atomically) or, with None, removes the marker of cell `index`.
pub fn write_marker(dir: &Path, index: usize, marker: Option<&Marker>) -> anyhow::Result<()> {
    let path = marker_path(dir, index);
    match marker {
        Some(m) => write_atomic(&path, serde_json::to_string(m)?.as_bytes()),
        None if path.exists() => std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display())),
        None => Ok(()),
    }
}

/// The folder's claim lock (`DIR/state/claim.lock`, the [`FolderLock`] every run folder has
/// too), waited for and held while a `sweep local` checks that a cell is still free and starts
/// it (or changes its marker), so that several `sweep local` on one folder never start the same
/// cell twice. Released when dropped.
pub fn claim_lock(dir: &Path) -> anyhow::Result<FolderLock> {
    FolderLock::wait(&dir.join(STATE_DIR).join("claim.lock"))
}

/// Whether process `pid`'s arguments include `--resume` (true where `/proc` cannot say).
fn runs_resume(pid: u32) -> bool {
    match std::fs::read(format!("/proc/{pid}/cmdline")) {
        Ok(cmdline) => cmdline.split(|b| *b == 0).any(|arg| arg == b"--resume"),
        Err(_) => !Path::new("/proc/self").exists(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_marker_is_alive_only_while_its_process_runs_on_this_host() {
        let dir = tempfile::tempdir().unwrap();
        // A stand-in for a cell's `quadcl run ... --resume`.
        let mut cell = std::process::Command::new("sh").args(["-c", "sleep 5", "run", "--resume"]).spawn().unwrap();
        let running = Marker::Running { pid: cell.id(), host: hostname() };
        write_marker(dir.path(), 3, Some(&running)).unwrap();
        assert_eq!(read_marker(dir.path(), 3), Some(running.clone()));
        assert!(running.is_alive());
        assert!(!Marker::Running { pid: cell.id(), host: "elsewhere".into() }.is_alive());
        // A live process that is not a cell's run (a reused pid): not alive.
        assert!(!Marker::Running { pid: std::process::id(), host: hostname() }.is_alive());
        cell.kill().unwrap();
        cell.wait().unwrap();
        assert!(!running.is_alive(), "its process is gone");
        write_marker(dir.path(), 3, None).unwrap();
        assert_eq!(read_marker(dir.path(), 3), None);
    }
}
