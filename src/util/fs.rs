//! Writes that a crash cannot tear: a file, or a whole folder, replaced at once.

use anyhow::Context;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically: a temporary file in the same folder,
/// flushed and synced, then renamed over the target. A crash leaves either
/// the old file or the new one, never a torn one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).with_context(|| format!("creating folder {}", dir.display()))?;
    let file_name = path.file_name().with_context(|| format!("{} has no file name", path.display()))?.to_string_lossy();
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("writing {}", path.display()))
}

/// `DIR.new` and `DIR.old`, the two names [`replace_dir`] works with.
fn aside_names(dir: &Path) -> anyhow::Result<(std::path::PathBuf, std::path::PathBuf)> {
    let name = dir.file_name().with_context(|| format!("{} has no folder name", dir.display()))?.to_string_lossy();
    Ok((dir.with_file_name(format!("{name}.new")), dir.with_file_name(format!("{name}.old"))))
}

/// Finishes a [`replace_dir`] that was interrupted between its two renames:
/// `dir` missing, the old content moved aside to `DIR.old` and the complete new
/// one in `DIR.new` (fill always ends before the old one moves). Then `DIR.new`
/// becomes `dir`. Anything else is left as it is. Readers call it before
/// looking for `dir`, and [`replace_dir`] before it clears stale folders.
pub fn recover_replaced_dir(dir: &Path) -> anyhow::Result<()> {
    let (fresh, old) = aside_names(dir)?;
    if !dir.exists() && old.is_dir() && fresh.is_dir() {
        std::fs::rename(&fresh, dir).with_context(|| format!("renaming {} to {}", fresh.display(), dir.display()))?;
        tracing::warn!("{}: completed a replacement that was interrupted", dir.display());
    }
    Ok(())
}

/// Replaces the folder `dir` as a whole: `fill` writes the new content into
/// `DIR.new/`, which is then renamed to `dir` (the old one moved aside to
/// `DIR.old/` first and removed last). An interruption at any moment leaves
/// `dir` as it was or complete, or (between the two renames) both aside,
/// which [`recover_replaced_dir`] completes.
pub fn replace_dir(dir: &Path, fill: impl FnOnce(&Path) -> anyhow::Result<()>) -> anyhow::Result<()> {
    recover_replaced_dir(dir)?;
    let (fresh, old) = aside_names(dir)?;
    for stale in [&fresh, &old] {
        if stale.exists() {
            std::fs::remove_dir_all(stale).with_context(|| format!("removing {}", stale.display()))?;
        }
    }
    if let Err(e) = fill(&fresh) {
        let _ = std::fs::remove_dir_all(&fresh);
        return Err(e);
    }
    if dir.exists() {
        std::fs::rename(dir, &old).with_context(|| format!("moving {} aside", dir.display()))?;
    }
    std::fs::rename(&fresh, dir).with_context(|| format!("renaming {} to {}", fresh.display(), dir.display()))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).with_context(|| format!("removing {}", old.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_atomic_replaces_content_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_atomic(&path, b"old").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1, "left behind: {names:?}");
    }

    #[test]
    fn an_interruption_between_the_two_renames_is_completed_not_lost() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("checkpoint");
        replace_dir(&dir, |d| write_atomic(&d.join("a"), b"1").map(|_| ())).unwrap();
        // As a kill leaves it after `dir` moved aside and before `DIR.new` took its place.
        std::fs::rename(&dir, tmp.path().join("checkpoint.old")).unwrap();
        std::fs::create_dir(tmp.path().join("checkpoint.new")).unwrap();
        std::fs::write(tmp.path().join("checkpoint.new").join("a"), b"2").unwrap();
        recover_replaced_dir(&dir).unwrap();
        assert_eq!(std::fs::read(dir.join("a")).unwrap(), b"2");
        // The next replacement clears what is left aside and keeps the newest content until it is done.
        replace_dir(&dir, |d| write_atomic(&d.join("a"), b"3").map(|_| ())).unwrap();
        assert_eq!(std::fs::read(dir.join("a")).unwrap(), b"3");
        assert!(!tmp.path().join("checkpoint.old").exists() && !tmp.path().join("checkpoint.new").exists());
        // A fill cut short (only `DIR.new`, nothing aside) is not taken for a checkpoint.
        std::fs::remove_dir_all(&dir).unwrap();
        std::fs::create_dir(tmp.path().join("checkpoint.new")).unwrap();
        recover_replaced_dir(&dir).unwrap();
        assert!(!dir.exists());
    }

    #[test]
    fn replace_dir_swaps_the_whole_folder_and_a_failed_fill_keeps_the_old_one() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("checkpoint");
        replace_dir(&dir, |d| write_atomic(&d.join("a"), b"1")).unwrap();
        replace_dir(&dir, |d| write_atomic(&d.join("b"), b"2")).unwrap();
        assert!(!dir.join("a").exists() && dir.join("b").exists(), "the new folder replaced the old one whole");
        let err = replace_dir(&dir, |_| anyhow::bail!("disk full")).unwrap_err();
        assert!(err.to_string().contains("disk full"));
        assert_eq!(std::fs::read(dir.join("b")).unwrap(), b"2", "a failed write keeps the previous folder");
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1, "left behind: {names:?}");
    }
}
