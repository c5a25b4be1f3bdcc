//! The Sweep screen's state (`quadcl tui --sweep DIR`): every cell with its
//! status and progress and the collected table, both as the library reads them
//! from the sweep folder ([`SweepSnapshot`], taken on a thread of its own every
//! second while the screen is open: `sweep::status`, with `squeue` / `sacct`
//! when the sweep went to Slurm, and `sweep::collect`, which writes nothing).
//! The screen computes nothing itself. Enter on a cell that has a run asks for
//! that run to be opened in the workbench ([`SweepView::open`]); a cell being
//! trained right now is not opened (its `quadcl run` owns the folder), nor is one kept as
//! results only (a harvested sweep's: metrics.json and log.txt, nothing to continue from).

use crate::sweep::{CellState, CellStatus, Collected};
use std::path::{Path, PathBuf};

/// What the sweep folder says now.
#[derive(Debug, Clone)]
pub struct SweepSnapshot {
    pub cells: Result<Vec<CellStatus>, String>,
    pub table: Result<Collected, String>,
}

/// Reads the sweep folder `dir` (`scheduler`: ask Slurm too).
pub fn snapshot(dir: &Path, scheduler: bool) -> SweepSnapshot {
    SweepSnapshot {
        cells: crate::sweep::status(dir, scheduler).map_err(|e| crate::util::text::error_text(&e)),
        table: crate::sweep::collect(dir).map_err(|e| crate::util::text::error_text(&e)),
    }
}

/// Everything a key or the folder's reader can do on the Sweep screen.
#[derive(Debug, Clone)]
pub enum SweepAction {
    Up,
    Down,
    /// Open the selected cell's run in the workbench.
    Open,
    Quit,
    Resize(u16, u16),
    /// A fresh reading of the folder.
    Refresh(Box<SweepSnapshot>),
}

/// The Sweep screen.
#[derive(Debug, Clone)]
pub struct SweepView {
    /// The sweep folder as given.
    pub dir: PathBuf,
    pub cells: Vec<CellStatus>,
    pub table: Option<Collected>,
    /// Why the folder could not be read, if it could not.
    pub error: Option<String>,
    pub cursor: usize,
    /// The last thing the screen said.
    pub message: Option<String>,
    /// A run folder to open in the workbench (the event loop takes it).
    pub open: Option<PathBuf>,
    pub quit: bool,
    pub size: (u16, u16),
    /// Something changed since the last frame.
    pub dirty: bool,
}

impl SweepView {
    /// The screen of the sweep in `dir`, before its first reading.
    pub fn new(dir: PathBuf, size: (u16, u16)) -> Self {
        Self {
            dir,
            cells: Vec::new(),
            table: None,
            error: None,
            cursor: 0,
            message: None,
            open: None,
            quit: false,
            size,
            dirty: true,
        }
    }

    /// The selected cell.
    pub fn selected(&self) -> Option<&CellStatus> {
        self.cells.get(self.cursor)
    }

    /// Applies one action.
    pub fn update(&mut self, action: SweepAction) {
        self.dirty = true;
        match action {
            SweepAction::Up => self.cursor = self.cursor.saturating_sub(1),
            SweepAction::Down => self.cursor = (self.cursor + 1).min(self.cells.len().saturating_sub(1)),
            SweepAction::Open => self.open_selected(),
            SweepAction::Quit => self.quit = true,
            SweepAction::Resize(w, h) => self.size = (w, h),
            SweepAction::Refresh(s) => {
                let SweepSnapshot { cells, table } = *s;
                self.error = None;
                match cells {
                    Ok(cells) => self.cells = cells,
                    Err(e) => self.error = Some(e),
                }
                match table {
                    Ok(t) => self.table = Some(t),
                    Err(e) => self.error = self.error.take().or(Some(e)),
                }
                self.cursor = self.cursor.min(self.cells.len().saturating_sub(1));
            }
        }
    }

    fn open_selected(&mut self) {
        let Some(cell) = self.selected() else { return };
        let (index, state) = (cell.index, cell.state);
        let run = self.dir.join(crate::sweep::RUNS_DIR).join(index.to_string());
        self.message = Some(match state {
            CellState::Running => format!("cell {index} is training: open it when it has finished or stopped"),
            CellState::Pending | CellState::Queued => format!("cell {index} has not started: nothing to open yet"),
            CellState::Foreign => format!(
                "cell {index}'s folder holds another run's results, not the plan's (see `quadcl sweep status`): \
                 not opened"
            ),
            CellState::Failed if !crate::engine::RunDir::new(&run).has_run() => {
                format!("cell {index} failed before it recorded anything: see its log in logs/{index}.log")
            }
            _ if crate::engine::RunDir::new(&run).results_only() => format!(
                "cell {index} holds results only (no run file or checkpoint): see plots/ or retrain it from \
                 cells/{index}.toml"
            ),
            _ => {
                self.open = Some(run);
                format!("opening cell {index} ...")
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(index: usize, state: CellState) -> CellStatus {
        CellStatus {
            index,
            name: format!("seed={index}"),
            group: "all".into(),
            state,
            completed_steps: 0,
            total_steps: 3,
            done_iterations: 0,
            total_iterations: 9,
            note: String::new(),
        }
    }

    #[test]
    fn enter_opens_a_finished_cell_and_not_one_in_training() {
        let mut view = SweepView::new(PathBuf::from("sweep"), (120, 40));
        let cells = vec![cell(0, CellState::Finished), cell(1, CellState::Running), cell(2, CellState::Pending)];
        view.update(SweepAction::Refresh(Box::new(SweepSnapshot { cells: Ok(cells), table: Err("none".into()) })));
        assert_eq!(view.error.as_deref(), Some("none"));
        view.update(SweepAction::Open);
        assert_eq!(view.open.take(), Some(PathBuf::from("sweep/runs/0")));
        view.update(SweepAction::Down);
        view.update(SweepAction::Open);
        assert!(view.open.is_none() && view.message.as_deref().is_some_and(|m| m.contains("is training")));
        for _ in 0..5 {
            view.update(SweepAction::Down);
        }
        assert_eq!(view.cursor, 2, "the cursor stays on the last cell");
        view.update(SweepAction::Open);
        assert!(view.open.is_none() && view.message.as_deref().is_some_and(|m| m.contains("not started")));
    }
    #[test]
    fn a_cell_kept_as_results_only_is_not_opened_and_the_screen_says_where_its_figures_are() {
        let tmp = tempfile::tempdir().unwrap();
        let run = tmp.path().join("runs/0");
        std::fs::create_dir_all(&run).unwrap();
        std::fs::write(run.join("metrics.json"), "{}").unwrap();
        let mut view = SweepView::new(tmp.path().to_path_buf(), (120, 40));
        let cells = vec![cell(0, CellState::Finished)];
        view.update(SweepAction::Refresh(Box::new(SweepSnapshot { cells: Ok(cells), table: Err("none".into()) })));
        view.update(SweepAction::Open);
        assert!(view.open.is_none(), "a folder without its run file is not opened");
        let message = view.message.clone().unwrap_or_default();
        assert!(message.contains("results only") && message.contains("cells/0.toml"), "{message}");
        // With its run file the same cell opens.
        std::fs::write(run.join(crate::engine::RUN_FILE), "").unwrap();
        view.update(SweepAction::Open);
        assert_eq!(view.open.take(), Some(run));
    }
}
