//! Where every cell of a sweep stands (`quadcl sweep status DIR`, the
//! workbench's Sweep screen), read from the folder alone: the cell's run
//! folder (steps completed of its sequence), its log (the iteration the step
//! in progress has reached: `quadcl run` without a terminal writes a line every
//! 25 iterations and at each task's last), the marker `sweep local` keeps, and,
//! when the sweep was submitted to Slurm and `squeue` / `sacct` answer, the
//! scheduler's word (queued, running, failed).

use super::collect::{read_cell, RunMeasures};
use super::marker::{read_marker, running_elsewhere, Marker};
use super::plan::{Cell, Plan};
use super::slurm::task_states;
use super::LOGS_DIR;
use crate::util::text::one_line;
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// A cell's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellState {
    /// Nothing has run yet.
    Pending,
    /// Waiting in the Slurm queue.
    Queued,
    /// A `quadcl run` of it is alive (here, or on Slurm).
    Running,
    /// Started, not running now, not finished: the next `sweep local` or array task resumes it.
    Stopped,
    /// Its last run failed (its log says why).
    Failed,
    /// Its whole sequence is trained.
    Finished,
    /// Its folder holds another run's results (its `metrics.json` records another run file
    /// than the plan's) or an unreadable `metrics.json`: it counts in no table.
    Foreign,
}

impl CellState {
    /// The word shown for it.
    pub fn label(self) -> &'static str {
        match self {
            CellState::Pending => "pending",
            CellState::Queued => "queued",
            CellState::Running => "running",
            CellState::Stopped => "stopped",
            CellState::Failed => "failed",
            CellState::Finished => "finished",
            CellState::Foreign => "foreign",
        }
    }
}

/// One cell's status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellStatus {
    pub index: usize,
    pub name: String,
    pub group: String,
    pub state: CellState,
    pub completed_steps: usize,
    pub total_steps: usize,
    /// Training iterations done (completed steps, and the step in progress as far as its log says).
    pub done_iterations: usize,
    pub total_iterations: usize,
    /// What the scheduler or the runner said, when it says more than the state (`TIMEOUT`, `exit status 1`).
    pub note: String,
}

impl CellStatus {
    /// Iterations done over all, 0 to 1.
    pub fn progress(&self) -> f64 {
        self.done_iterations as f64 / self.total_iterations.max(1) as f64
    }
}

/// Whether cell `cell` of the sweep in `dir` has trained its whole sequence (its own run: a
/// folder holding another run's results has not).
pub fn cell_finished(dir: &Path, cell: &Cell) -> bool {
    read_cell(dir, cell).run::<RunMeasures>(dir, cell).ok().flatten().is_some_and(|m| m.finished())
}

/// The status of every cell of the sweep in `dir`; `scheduler`: ask `squeue` and `sacct`
/// when the sweep was submitted to Slurm.
pub fn status(dir: &Path, scheduler: bool) -> anyhow::Result<Vec<CellStatus>> {
    let plan = Plan::load(dir)?;
    let queue = if scheduler { task_states(dir, "squeue") } else { None };
    let accounting = if scheduler { task_states(dir, "sacct") } else { None };
    let mut out = Vec::new();
    for cell in &plan.cells {
        let (run, foreign) = match read_cell(dir, cell).run::<RunMeasures>(dir, cell) {
            Ok(run) => (run, None),
            Err(why) => (None, Some(why)),
        };
        let completed = run.as_ref().map_or(0, |r| r.completed_steps);
        let total_steps = run.as_ref().map_or(cell.iterations.len(), |r| r.total_steps);
        // Saturating: the counts come from a file (sweep.json) that may have been edited.
        let sum = |n: usize| cell.iterations.iter().take(n).fold(0usize, |a, b| a.saturating_add(*b));
        let mut done = sum(completed);
        let total = sum(usize::MAX);
        let queued = queue.as_ref().and_then(|q| q.get(&cell.index)).map(String::as_str);
        let accounted = accounting.as_ref().and_then(|a| a.get(&cell.index)).map(String::as_str);
        let marker = read_marker(dir, cell.index);
        let mut note = String::new();
        let state = if let Some(why) = foreign {
            note = why;
            CellState::Foreign
        } else if run.as_ref().is_some_and(|r| r.finished()) {
            CellState::Finished
        } else if let Some(q) = queued.filter(|q| ["PENDING", "CONFIGURING", "REQUEUED", "REQUEUE_HOLD"].contains(q)) {
            note = q.to_string();
            CellState::Queued
        } else if queued.is_some_and(|q| ["RUNNING", "COMPLETING"].contains(&q)) || running_elsewhere(dir, cell) {
            CellState::Running
        } else if let Some(Marker::Failed { exit_code, .. }) = &marker {
            note = exit_code.map_or("killed by a signal".into(), |c| format!("exit status {c}"));
            CellState::Failed
        } else if let Some(a) = accounted.filter(|a| !["COMPLETED", "PENDING", "RUNNING", "REQUEUED"].contains(a)) {
            note = a.to_string();
            CellState::Failed
        } else if run.is_some() {
            CellState::Stopped
        } else {
            CellState::Pending
        };
        if state == CellState::Running {
            if let Some((step, iteration)) = last_iteration(&dir.join(LOGS_DIR).join(format!("{}.log", cell.index))) {
                if step == completed {
                    done = done.saturating_add(iteration.min(cell.iterations.get(step).copied().unwrap_or(0)));
                }
            }
        }
        out.push(CellStatus {
            index: cell.index,
            name: cell.name.clone(),
            group: cell.group.clone(),
            state,
            completed_steps: completed,
            total_steps,
            done_iterations: done,
            total_iterations: total,
            note,
        });
    }
    Ok(out)
}

/// The last `step S iteration I/N:` line in the end of the log `path`: (S, I).
fn last_iteration(path: &Path) -> Option<(usize, usize)> {
    const TAIL: u64 = 64 * 1024;
    let mut file = std::fs::File::open(path).ok()?;
    let len = file.metadata().ok()?.len();
    file.seek(SeekFrom::Start(len.saturating_sub(TAIL))).ok()?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes).ok()?;
    String::from_utf8_lossy(&bytes).lines().rev().find_map(parse_iteration_line)
}

/// `step 1 iteration 25/300: return ...` -> (1, 25).
fn parse_iteration_line(line: &str) -> Option<(usize, usize)> {
    let rest = line.strip_prefix("step ")?;
    let (step, rest) = rest.split_once(" iteration ")?;
    let (iteration, _) = rest.split_once('/')?;
    Some((step.parse().ok()?, iteration.parse().ok()?))
}

/// One line per cell, for `quadcl sweep status`: index, state, progress, steps, name.
pub fn status_lines(cells: &[CellStatus]) -> String {
    let mut out = String::new();
    for c in cells {
        let note = if c.note.is_empty() { String::new() } else { format!(" ({})", one_line(&c.note)) };
        out.push_str(&format!(
            "{:>4}  {:<9} {:>5.1} %  step {}/{}  {}{note}\n",
            c.index,
            c.state.label(),
            100.0 * c.progress(),
            c.completed_steps,
            c.total_steps,
            one_line(&c.name)
        ));
    }
    let count = |s: CellState| cells.iter().filter(|c| c.state == s).count();
    out.push_str(&format!(
        "{} cells: {} finished, {} running, {} queued, {} stopped, {} failed, {} pending{}\n",
        cells.len(),
        count(CellState::Finished),
        count(CellState::Running),
        count(CellState::Queued),
        count(CellState::Stopped),
        count(CellState::Failed),
        count(CellState::Pending),
        match count(CellState::Foreign) {
            0 => String::new(),
            n => format!(", {n} foreign (another run's results: in no table)"),
        }
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_progress_of_a_step_is_read_from_the_runs_iteration_lines() {
        assert_eq!(parse_iteration_line("step 2 iteration 25/300: return 1.2 fall_rate 0.1"), Some((2, 25)));
        assert_eq!(parse_iteration_line("{\"event\":\"task_started\"}"), None);
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("0.log");
        std::fs::write(&log, "step 0 iteration 3/3: x\n{\"event\":\"task_finished\"}\nstep 1 iteration 2/3: y\n")
            .unwrap();
        assert_eq!(last_iteration(&log), Some((1, 2)));
        assert_eq!(last_iteration(&dir.path().join("none.log")), None);
    }
}
