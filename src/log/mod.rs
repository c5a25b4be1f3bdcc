//! Training curves for the tools researchers already use: TensorBoard event
//! files and a long-format CSV (`step,wall_time,tag,value`) side by side in one
//! folder per TensorBoard "run" ([`ScalarLog`]). `quadcl train` writes one into
//! `OUT/tb/`; `quadcl run` one per task (`tb/NN-TASK/`, the task's own iteration
//! axis) and one for the whole sequence (`tb/sequence/`, iterations counted over
//! the run, plus the evaluation measures after each task). Tags are the metric
//! names (`charts/*`, `losses/*`, `plasticity/*`, ...).
//!
//! A resumed run keeps what came before its resume point: the CSV is cut to
//! the rows before it, and a new event file starts with a `SessionLog` START
//! at that step, which makes TensorBoard drop the older files' events from
//! there on. Writing is buffered and flushed at checkpoints and task ends.

mod tfevents;

pub use tfevents::{crc32c, read_scalars, EventFile};

use crate::util::write_atomic;
use anyhow::Context;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};
use tfevents::{event, record, EventBody};

/// The CSV file of a [`ScalarLog`] folder.
pub const CSV_FILE: &str = "scalars.csv";

fn now() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

/// An event file name that sorts after every earlier one in `dir` (TensorBoard reads a run's
/// files in name order): `events.out.tfevents.SECONDS.quadcl.N`.
fn next_event_file(dir: &Path) -> anyhow::Result<PathBuf> {
    let secs = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let mut latest = String::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let name = entry?.file_name().to_string_lossy().into_owned();
        if name.starts_with("events.out.tfevents.") && name > latest {
            latest = name;
        }
    }
    let mut n = 0;
    loop {
        let name = format!("events.out.tfevents.{secs:010}.quadcl.{n:04}");
        if name > latest {
            return Ok(dir.join(name));
        }
        n += 1;
    }
}

/// One TensorBoard run folder: an event file and `scalars.csv`.
#[derive(Debug)]
pub struct ScalarLog {
    dir: PathBuf,
    events: BufWriter<File>,
    csv: BufWriter<File>,
}

impl ScalarLog {
    /// A new log in `dir`, replacing any event files and CSV there.
    pub fn create(dir: &Path) -> anyhow::Result<Self> {
        if dir.exists() {
            for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
                let path = entry?.path();
                let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                if name.starts_with("events.out.tfevents.") || name == CSV_FILE {
                    std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
                }
            }
        }
        Self::open(dir, None)
    }

    /// The log in `dir` of a run resumed at `step`: CSV rows at `step` and later are dropped,
    /// and a new event file starts with a session START at `step`.
    pub fn resume(dir: &Path, step: i64) -> anyhow::Result<Self> {
        let csv = dir.join(CSV_FILE);
        match std::fs::read_to_string(&csv) {
            Ok(text) => {
                let kept: String = text
                    .lines()
                    .enumerate()
                    .filter(|(i, line)| {
                        *i == 0 || line.split(',').next().and_then(|s| s.parse::<i64>().ok()).is_some_and(|s| s < step)
                    })
                    .flat_map(|(_, l)| [l, "\n"])
                    .collect();
                write_atomic(&csv, kept.as_bytes())?;
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("reading {}", csv.display())),
        }
        Self::open(dir, Some(step))
    }

    /// The log in `dir` of a run whose steps 1..=`done` are behind it: [`Self::create`] when
    /// none is, else [`Self::resume`] at step `done + 1`.
    pub fn after(dir: &Path, done: usize) -> anyhow::Result<Self> {
        match done {
            0 => Self::create(dir),
            _ => Self::resume(dir, done as i64 + 1),
        }
    }

    fn open(dir: &Path, restart: Option<i64>) -> anyhow::Result<Self> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = next_event_file(dir)?;
        let file = File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        let mut events = BufWriter::new(file);
        events.write_all(&record(&event(now(), 0, EventBody::FileVersion)))?;
        if let Some(step) = restart {
            events.write_all(&record(&event(now(), step, EventBody::SessionStart)))?;
        }
        let csv_path = dir.join(CSV_FILE);
        let fresh = !csv_path.exists();
        let csv = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&csv_path)
            .with_context(|| format!("opening {}", csv_path.display()))?;
        let mut csv = BufWriter::new(csv);
        if fresh {
            csv.write_all(b"step,wall_time,tag,value\n")?;
        }
        Ok(Self { dir: dir.to_path_buf(), events, csv })
    }

    /// Every finite value of `scalars` at `step`, tags as given (one event, one CSV row each).
    pub fn write<'a>(&mut self, step: i64, scalars: impl IntoIterator<Item = (&'a str, f64)>) -> anyhow::Result<()> {
        let wall = now();
        let values: Vec<(String, f32)> =
            scalars.into_iter().filter(|(_, v)| v.is_finite()).map(|(t, v)| (t.to_string(), v as f32)).collect();
        if values.is_empty() {
            return Ok(());
        }
        self.events.write_all(&record(&event(wall, step, EventBody::Scalars(&values))))?;
        for (tag, v) in &values {
            // Tags are metric names and task names: no commas or quotes, but quote defensively.
            if tag.contains([',', '"', '\n']) {
                writeln!(self.csv, "{step},{wall:.3},\"{}\",{v}", tag.replace('"', "\"\""))?;
            } else {
                writeln!(self.csv, "{step},{wall:.3},{tag},{v}")?;
            }
        }
        Ok(())
    }

    /// Writes everything buffered to the files.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.events.flush().with_context(|| format!("writing the event file in {}", self.dir.display()))?;
        self.csv.flush().with_context(|| format!("writing {}", self.dir.join(CSV_FILE).display()))
    }
}

impl Drop for ScalarLog {
    fn drop(&mut self) {
        let _ = self.flush();
    }
}

/// Every event file in `dir` read back in name order (TensorBoard's order).
pub fn read_dir_scalars(dir: &Path) -> anyhow::Result<Vec<EventFile>> {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("events.out.tfevents.")))
        .collect();
    names.sort();
    names.iter().map(|p| read_scalars(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(dir: &Path) -> Vec<String> {
        std::fs::read_to_string(dir.join(CSV_FILE)).unwrap().lines().skip(1).map(|l| l.to_string()).collect()
    }

    #[test]
    fn a_resumed_log_keeps_what_came_before_its_step_and_marks_the_restart() {
        let dir = tempfile::tempdir().unwrap();
        let mut log = ScalarLog::create(dir.path()).unwrap();
        for step in 0..5 {
            log.write(step, [("charts/performance", step as f64 / 10.0), ("losses/nan", f64::NAN)]).unwrap();
        }
        drop(log);
        assert_eq!(rows(dir.path()).len(), 5, "one row per finite value");
        let mut log = ScalarLog::resume(dir.path(), 3).unwrap();
        log.write(3, [("charts/performance", 0.9)]).unwrap();
        drop(log);
        let steps: Vec<i64> = rows(dir.path()).iter().map(|r| r.split(',').next().unwrap().parse().unwrap()).collect();
        assert_eq!(steps, vec![0, 1, 2, 3]);
        assert!(rows(dir.path())[3].ends_with(",charts/performance,0.9"));
        let files = read_dir_scalars(dir.path()).unwrap();
        assert_eq!(files.len(), 2, "a new event file after the resume");
        assert_eq!(files[0].scalars.len(), 5);
        assert_eq!(files[1].session_starts, vec![3]);
        assert_eq!(files[1].scalars, vec![(3, "charts/performance".to_string(), 0.9)]);
        // Creating anew replaces both.
        drop(ScalarLog::create(dir.path()).unwrap());
        assert_eq!(read_dir_scalars(dir.path()).unwrap().len(), 1);
        assert!(rows(dir.path()).is_empty());
    }
}
