//! `metrics.jsonl` of a training run: one JSON row per iteration, appended as
//! the run goes, so memory and the write per iteration stay the same over a
//! run of any length (the whole file used to be kept in memory and rewritten
//! every 10 iterations). Rows are made durable before each checkpoint names
//! them; a resume first cuts the file, atomically, to the rows up to its
//! checkpoint and then appends. A reader during training may see a last row
//! cut short.

use super::metrics::Metrics;
use crate::util::write_atomic;
use anyhow::Context;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// An open `metrics.jsonl`.
#[derive(Debug)]
pub struct MetricsLog {
    path: PathBuf,
    file: File,
}

impl MetricsLog {
    /// A new, empty log at `path` (a file already there is replaced).
    pub fn create(path: &Path) -> anyhow::Result<Self> {
        write_atomic(path, b"")?;
        Self::open(path)
    }

    /// The log of a run resumed after `rows` iterations: its first `rows` rows are kept (all of
    /// them when it has fewer), later ones dropped. Returns the log and the kept rows that parse.
    pub fn resume(path: &Path, rows: usize) -> anyhow::Result<(Self, Vec<Metrics>)> {
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        };
        let kept: String = text.lines().take(rows).flat_map(|l| [l, "\n"]).collect();
        write_atomic(path, kept.as_bytes())?;
        let parsed = kept.lines().filter_map(|l| serde_json::from_str::<Metrics>(l).ok()).collect();
        Ok((Self::open(path)?, parsed))
    }

    fn open(path: &Path) -> anyhow::Result<Self> {
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .with_context(|| format!("opening {} to append to it", path.display()))?;
        Ok(Self { path: path.to_path_buf(), file })
    }

    /// Appends one iteration's row (one write).
    pub fn append(&mut self, m: &Metrics) -> anyhow::Result<()> {
        let mut row = serde_json::to_string(m)?;
        row.push('\n');
        self.file.write_all(row.as_bytes()).with_context(|| format!("writing {}", self.path.display()))
    }

    /// Makes every row appended so far durable (before a checkpoint that counts them).
    pub fn sync(&self) -> anyhow::Result<()> {
        self.file.sync_data().with_context(|| format!("syncing {}", self.path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(i: f64) -> Metrics {
        Metrics::from([("charts/iteration".to_string(), i)])
    }

    #[test]
    fn a_resumed_log_keeps_the_rows_up_to_its_checkpoint_and_appends_after_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("metrics.jsonl");
        let mut log = MetricsLog::create(&path).unwrap();
        for i in 1..=5 {
            log.append(&row(f64::from(i))).unwrap();
        }
        log.sync().unwrap();
        drop(log);
        // A row cut short by a kill, past the checkpoint at 3.
        std::fs::OpenOptions::new().append(true).open(&path).unwrap().write_all(b"{\"charts/itera").unwrap();
        let (mut log, kept) = MetricsLog::resume(&path, 3).unwrap();
        assert_eq!(kept, vec![row(1.0), row(2.0), row(3.0)]);
        log.append(&row(4.5)).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let rows: Vec<Metrics> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        assert_eq!(rows, vec![row(1.0), row(2.0), row(3.0), row(4.5)]);
        // A new log replaces the file.
        MetricsLog::create(&path).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "");
    }
}
