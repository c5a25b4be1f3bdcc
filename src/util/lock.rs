//! One process at a time in a folder: an exclusive `flock` on a lock file, with
//! the holder (pid, host, command, start time) written into it so that a refusal
//! can say who holds it. A run folder (`run.lock`: `quadcl run`, `train`,
//! `finetune`, the workbench training into it) and a sweep folder's claim lock
//! (`state/claim.lock`) are both this lock.
//!
//! - The lock is held while the [`FolderLock`] lives and released when it is
//!   dropped or the process ends in any way (the kernel drops a dead process's
//!   `flock`, so a `kill -9` leaves no lock behind).
//! - A record left by a holder that is gone (killed, crashed) is taken over,
//!   and [`FolderLock::took_over`] names it so the caller can warn.
//! - The file is never removed (a removed lock file would let two processes
//!   lock two different files of one name); releasing empties it.
//! - On a file system without `flock` (some network mounts), the record alone
//!   decides: a live holder on this host, or any holder on another host, refuses.

use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Who holds (or held) a lock: what its file records.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Holder {
    pub pid: u32,
    pub host: String,
    /// The holder's command line (clipped).
    pub command: String,
    /// When it took the lock (seconds since the Unix epoch).
    pub since_unix_s: u64,
}

impl Holder {
    /// This process, now.
    fn this_process() -> Self {
        let command: Vec<String> = std::env::args().collect();
        Self {
            pid: std::process::id(),
            host: hostname(),
            command: super::text::clip(&command.join(" ")),
            since_unix_s: SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()),
        }
    }

    /// `pid 123 on host h (quadcl run ..., for 42 s)`.
    pub fn describe(&self) -> String {
        let now = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
        format!(
            "pid {} on host {} ({}, for {} s)",
            self.pid,
            super::text::one_line(&self.host),
            super::text::one_line(&self.command),
            now.saturating_sub(self.since_unix_s)
        )
    }

    /// Whether this holder is a process alive on this host (false for another host: unknown there).
    pub fn is_alive_here(&self) -> bool {
        self.host == hostname() && process_exists(self.pid)
    }
}

/// An exclusive lock on a folder, held until dropped (see the module doc).
#[derive(Debug)]
pub struct FolderLock {
    file: File,
    path: PathBuf,
    /// The record of a previous holder that had gone without releasing it.
    took_over: Option<Holder>,
}

/// How long a refused [`FolderLock::acquire`] retries while the holder's record is missing or
/// names a dead process (another process is between taking the lock and writing its record,
/// or only looked at it with [`FolderLock::holder`]).
const SETTLE: Duration = Duration::from_millis(1500);

impl FolderLock {
    /// Takes the lock file `path` (created with its folder if missing) or refuses at once:
    /// the error names `what` (the folder, as the user knows it) and the live holder.
    pub fn acquire(path: &Path, what: &str) -> anyhow::Result<Self> {
        let file = open(path)?;
        let started = std::time::Instant::now();
        loop {
            match try_flock(&file, libc::LOCK_EX | libc::LOCK_NB) {
                Ok(true) => return Self::record(file, path),
                Ok(false) => {
                    let holder = read_record(path);
                    let settling = holder.as_ref().is_none_or(|h| h.host == hostname() && !process_exists(h.pid));
                    if settling && started.elapsed() < SETTLE {
                        std::thread::sleep(Duration::from_millis(20));
                        continue;
                    }
                    let who = holder.map_or("another process (its record is not readable)".into(), |h| h.describe());
                    anyhow::bail!(
                        "{what} is in use by {who}: two processes writing one folder would corrupt it; wait for \
                         that one to end, or stop it"
                    );
                }
                Err(_) => return Self::record_only(file, path, what),
            }
        }
    }

    /// Waits for the lock file `path` (created with its folder if missing), however long
    /// another process holds it.
    pub fn wait(path: &Path) -> anyhow::Result<Self> {
        let file = open(path)?;
        loop {
            match try_flock(&file, libc::LOCK_EX) {
                Ok(true) => return Self::record(file, path),
                Ok(false) => continue,
                Err(e) => return Err(e).with_context(|| format!("locking {}", path.display())),
            }
        }
    }

    /// The live holder of the lock file `path`, if any, without taking it.
    pub fn holder(path: &Path) -> Option<Holder> {
        let file = File::open(path).ok()?;
        match try_flock(&file, libc::LOCK_SH | libc::LOCK_NB) {
            // Free: whatever the record says, its holder is gone. The shared lock ends with `file`.
            Ok(true) => None,
            Ok(false) => Some(read_record(path).unwrap_or(Holder {
                pid: 0,
                host: "unknown".into(),
                command: "its record is not readable".into(),
                since_unix_s: 0,
            })),
            Err(_) => read_record(path).filter(|h| h.host != hostname() || process_exists(h.pid)),
        }
    }

    /// The previous holder whose record this lock took over (it had gone without releasing it).
    pub fn took_over(&self) -> Option<&Holder> {
        self.took_over.as_ref()
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves the lock file into the folder `into` (same file system), still held: for a folder
    /// replaced as a whole ([`super::replace_dir`]), whose new content then carries the lock.
    pub fn move_into(&mut self, into: &Path) -> anyhow::Result<()> {
        let name = self.path.file_name().context("a lock file has a name")?;
        let to = into.join(name);
        std::fs::rename(&self.path, &to)
            .with_context(|| format!("moving {} to {}", self.path.display(), to.display()))?;
        self.path = to;
        Ok(())
    }

    /// Writes this process's record into the locked `file`.
    fn record(mut file: File, path: &Path) -> anyhow::Result<Self> {
        let previous = read_record(path);
        let ours = serde_json::to_string(&Holder::this_process())?;
        file.set_len(0)
            .and_then(|_| file.seek(SeekFrom::Start(0)))
            .and_then(|_| file.write_all(ours.as_bytes()))
            .and_then(|_| file.sync_data())
            .with_context(|| format!("writing {}", path.display()))?;
        let took_over = previous.filter(|h| h.pid != std::process::id() || h.host != hostname());
        if let Some(h) = &took_over {
            tracing::warn!(
                "{}: took over the lock of {}, which ended without releasing it",
                path.display(),
                h.describe()
            );
        }
        Ok(Self { file, path: path.to_path_buf(), took_over })
    }

    /// No `flock` on this file system: the record alone decides (see the module doc).
    fn record_only(file: File, path: &Path, what: &str) -> anyhow::Result<Self> {
        if let Some(h) = read_record(path) {
            let ours = h.pid == std::process::id() && h.host == hostname();
            anyhow::ensure!(
                ours || (h.host == hostname() && !process_exists(h.pid)),
                "{what} is in use by {} (this file system has no file locks, so its record decides: if that \
                 run has ended, remove {})",
                h.describe(),
                path.display()
            );
        }
        Self::record(file, path)
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Emptied, not removed (see the module doc); the kernel releases the flock with the file.
        let _ = self.file.set_len(0);
    }
}

/// Opens (creating it and its folder) the lock file `path` for reading and writing.
fn open(path: &Path) -> anyhow::Result<File> {
    if let Some(dir) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating folder {}", dir.display()))?;
    }
    std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .read(true)
        .write(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))
}

/// `flock(file, op)`: Ok(true) taken, Ok(false) held elsewhere (with LOCK_NB), Err when the
/// file system has no such locks (or another error).
fn try_flock(file: &File, op: libc::c_int) -> std::io::Result<bool> {
    loop {
        // SAFETY: flock on a descriptor `file` owns; released when the file closes.
        if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
            return Ok(true);
        }
        let err = std::io::Error::last_os_error();
        match err.raw_os_error() {
            Some(libc::EINTR) => continue,
            Some(libc::EWOULDBLOCK) => return Ok(false),
            _ => return Err(err),
        }
    }
}

/// The holder recorded in the lock file `path` (None: empty, missing or unreadable).
fn read_record(path: &Path) -> Option<Holder> {
    let mut text = String::new();
    File::open(path).ok()?.take(64 * 1024).read_to_string(&mut text).ok()?;
    serde_json::from_str(&text).ok()
}

/// This machine's host name ("unknown" if it cannot be read).
pub fn hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: gethostname writes at most buf.len() bytes into buf.
    let rc = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    if rc != 0 {
        return "unknown".into();
    }
    let end = buf.iter().position(|b| *b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..end]).into_owned()
}

/// Whether a process `pid` exists on this machine (and is not a zombie waiting to be reaped).
pub fn process_exists(pid: u32) -> bool {
    if pid == 0 {
        return false;
    }
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        // The state letter follows the command name in parentheses.
        Ok(stat) => stat.rsplit(')').next().and_then(|rest| rest.trim_start().chars().next()).is_some_and(|s| s != 'Z'),
        // SAFETY: signal 0 only checks that the process exists.
        Err(_) => !Path::new("/proc/self").exists() && unsafe { libc::kill(pid as libc::pid_t, 0) } == 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_a_held_folder_is_refused_naming_the_holder_and_released_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run").join("run.lock");
        let first = FolderLock::acquire(&path, "run folder run").unwrap();
        assert!(first.took_over().is_none());
        assert_eq!(FolderLock::holder(&path).map(|h| h.pid), Some(std::process::id()));
        // flock locks belong to the open file: a second open in this process is refused too.
        let err = format!("{:#}", FolderLock::acquire(&path, "run folder run").unwrap_err());
        assert!(err.contains("run folder run is in use by pid") && err.contains(&hostname()), "{err}");
        drop(first);
        assert_eq!(FolderLock::holder(&path), None);
        assert!(path.exists(), "the file stays, emptied");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "");
        FolderLock::acquire(&path, "run folder run").unwrap();
    }

    #[test]
    fn a_stale_record_of_a_dead_holder_is_taken_over_and_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.lock");
        let mut gone = std::process::Command::new("true").spawn().unwrap();
        let pid = gone.id();
        gone.wait().unwrap();
        let stale = Holder { pid, host: hostname(), command: "quadcl run".into(), since_unix_s: 1 };
        std::fs::write(&path, serde_json::to_string(&stale).unwrap()).unwrap();
        assert_eq!(FolderLock::holder(&path), None, "a record without a lock holds nothing");
        let lock = FolderLock::acquire(&path, "x").unwrap();
        assert_eq!(lock.took_over(), Some(&stale));
    }

    #[test]
    fn a_moved_lock_stays_held_under_its_new_name() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::create_dir_all(&b).unwrap();
        let mut lock = FolderLock::acquire(&a.join("run.lock"), "a").unwrap();
        lock.move_into(&b).unwrap();
        assert!(FolderLock::acquire(&b.join("run.lock"), "b").is_err());
        assert_eq!(lock.path(), b.join("run.lock"));
    }
}
