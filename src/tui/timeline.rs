//! The sequence timeline's rows: the tasks learned before the sequence (the
//! base policy's), then every step with its task, kind, status, budget and
//! final performance (from the evaluation matrix: right after the step).

use super::app::App;

/// What a row is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    /// Learned before the sequence (the base policy).
    Base,
    /// A task trained for the first time.
    New,
    /// A repeat of a learned task (METHOD.md 2.5: its private parameters and bias only).
    Repeat,
}

/// Where a row stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RowStatus {
    Learned,
    Training { iteration: usize, iterations: usize, paused: bool },
    Pending,
}

/// One timeline row.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The step (None for a base task).
    pub step: Option<usize>,
    pub task: String,
    pub kind: RowKind,
    pub status: RowStatus,
    pub budget: Option<usize>,
    /// Performance on the step's task right after the step (`R[step][task]`).
    pub performance: Option<f64>,
    /// The row's task is learned (here or at an earlier step): it can be recalled now.
    pub recallable: bool,
}

impl Row {
    /// Whether the row's task can be recalled now.
    pub fn learned(&self) -> bool {
        self.recallable
    }
}

/// Every row of the open run.
pub fn rows(app: &App) -> Vec<Row> {
    let Some(o) = &app.opened else { return Vec::new() };
    let mut rows: Vec<Row> = o
        .base_tasks
        .iter()
        .map(|t| Row {
            step: None,
            task: t.clone(),
            kind: RowKind::Base,
            status: RowStatus::Learned,
            budget: None,
            performance: None,
            recallable: true,
        })
        .collect();
    let done = o.results.steps.len();
    let learned = |name: &str| o.base_tasks.iter().any(|t| t == name) || o.results.steps.iter().any(|s| s.name == name);
    for (i, spec) in o.sequence.tasks.iter().enumerate() {
        let earlier = o.base_tasks.contains(&spec.name) || o.sequence.tasks[..i].iter().any(|t| t.name == spec.name);
        let status = match &app.live {
            _ if i < done => RowStatus::Learned,
            Some(l) if l.record.step == i => {
                RowStatus::Training { iteration: l.iteration, iterations: l.record.iterations, paused: app.paused }
            }
            _ => RowStatus::Pending,
        };
        let column = o.results.tasks.iter().position(|t| *t == spec.name);
        let performance =
            column.and_then(|j| o.results.eval_matrix.rows.get(i).and_then(|r| r.get(j).copied().flatten()));
        rows.push(Row {
            step: Some(i),
            task: spec.name.clone(),
            kind: if earlier { RowKind::Repeat } else { RowKind::New },
            status,
            // A finished step's budget is what it ran (a continued run's steps had their own run file).
            budget: Some(
                o.results.steps.get(i).map_or(spec.iterations.unwrap_or(o.sequence.iterations), |s| s.iterations),
            ),
            performance,
            recallable: learned(&spec.name),
        });
    }
    rows
}

/// The first row shown in a timeline panel of `height` (the cursor kept in view).
pub fn scroll(app: &App, height: u16) -> usize {
    let visible = (height as usize).saturating_sub(3).max(1);
    app.cursor.saturating_sub(visible - 1)
}
