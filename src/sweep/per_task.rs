//! A sweep's groups task by task (`quadcl sweep collect DIR --per-task`): per
//! group of cells that differ only in seed, and per distinct task of their
//! sequence (the base's own task first, as `none`), the mean and 90 % bootstrap
//! interval over the finished seeds of what the run's `metrics.json` says of that
//! task after the last step: its performance (the evaluation matrix's last row),
//! its forgetting, fall rate and tracking errors. Written as
//! `DIR/collected-tasks.md` and `.json`. Where `collected.md` averages over the
//! tasks, this shows which task a mean hides (a twelve-task sequence's one task
//! that falls).

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::collect::{estimate_text, load_finished};
use super::plan::Plan;
use crate::util::write_atomic;
use anyhow::ensure;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// `collected-tasks.md`, beside `collected.md`.
pub const COLLECTED_TASKS_MD: &str = "collected-tasks.md";
/// `collected-tasks.json`, beside `collected.json`.
pub const COLLECTED_TASKS_JSON: &str = "collected-tasks.json";

/// The measures per task: (key, heading).
pub const TASK_MEASURES: [(&str, &str); 5] = [
    ("performance", "performance at the end"),
    ("forgetting", "forgetting"),
    ("fall_rate", "fall rate"),
    ("lin_vel_err", "lin vel err (m/s)"),
    ("ang_vel_err", "ang vel err (rad/s)"),
];

/// What the per-task table reads of a run's `metrics.json`.
#[derive(Debug, Deserialize)]
struct RunTasks {
    eval_matrix: Matrix,
    forgetting_per_task: Vec<Option<f64>>,
    command_tracking: Tracking,
}

#[derive(Debug, Deserialize)]
struct Matrix {
    tasks: Vec<String>,
    rows: Vec<Vec<Option<f64>>>,
}

#[derive(Debug, Deserialize)]
struct Tracking {
    lin_vel_err: Vec<Option<f64>>,
    ang_vel_err: Vec<Option<f64>>,
    fall_rate: Vec<Option<f64>>,
}

impl RunTasks {
    /// The value of `key` (one of [`TASK_MEASURES`]) for distinct task `j`.
    fn value(&self, key: &str, j: usize) -> Option<f64> {
        let at = |v: &[Option<f64>]| v.get(j).copied().flatten();
        match key {
            "performance" => self.eval_matrix.rows.last().and_then(|row| at(row)),
            "forgetting" => at(&self.forgetting_per_task),
            "fall_rate" => at(&self.command_tracking.fall_rate),
            "lin_vel_err" => at(&self.command_tracking.lin_vel_err),
            "ang_vel_err" => at(&self.command_tracking.ang_vel_err),
            _ => None,
        }
        .filter(|v| v.is_finite())
    }
}

/// One task of one group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskRow {
    pub task: String,
    /// Per measure, over the group's finished seeds (absent where none has a value).
    pub measures: BTreeMap<String, Estimate>,
}

/// One group (cells that differ only in seed), task by task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupTasks {
    pub name: String,
    pub planned: usize,
    pub finished: usize,
    pub tasks: Vec<TaskRow>,
}

/// `collected-tasks.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollectedTasks {
    pub sweep_file: String,
    pub confidence: f64,
    pub resamples: usize,
    pub measures: Vec<(String, String)>,
    pub groups: Vec<GroupTasks>,
}

/// The per-task tables of the sweep in `dir`; nothing is written. Errors name the
/// run whose tasks differ from its group's first finished seed.
pub fn collect_tasks(dir: &Path) -> anyhow::Result<CollectedTasks> {
    let plan = Plan::load(dir)?;
    let mut groups = Vec::new();
    for (name, indices) in plan.groups() {
        let mut runs: Vec<(String, RunTasks)> = Vec::new();
        for &i in &indices {
            let folder = &plan.cells[i].run;
            if let Some(r) = load_finished::<RunTasks>(dir, &plan.cells[i])? {
                if let Some((first, f)) = runs.first() {
                    ensure!(
                        r.eval_matrix.tasks == f.eval_matrix.tasks,
                        "{}: tasks {:?}, but {} of the same group has {:?}",
                        dir.join(folder).display(),
                        r.eval_matrix.tasks,
                        dir.join(first).display(),
                        f.eval_matrix.tasks
                    );
                }
                runs.push((folder.clone(), r));
            }
        }
        let task_names = runs.first().map(|(_, r)| r.eval_matrix.tasks.clone()).unwrap_or_default();
        let tasks = task_names
            .iter()
            .enumerate()
            .map(|(j, task)| TaskRow {
                task: task.clone(),
                measures: TASK_MEASURES
                    .iter()
                    .filter_map(|(k, _)| {
                        let values: Vec<f64> = runs.iter().filter_map(|(_, r)| r.value(k, j)).collect();
                        Some((k.to_string(), estimate(&values)?))
                    })
                    .collect(),
            })
            .collect();
        groups.push(GroupTasks { name, planned: indices.len(), finished: runs.len(), tasks });
    }
    Ok(CollectedTasks {
        sweep_file: plan.sweep_file,
        confidence: CONFIDENCE,
        resamples: RESAMPLES,
        measures: TASK_MEASURES.iter().map(|(k, h)| (k.to_string(), h.to_string())).collect(),
        groups,
    })
}

/// Collects `dir` task by task and writes `collected-tasks.json` and `.md` into it.
pub fn collect_tasks_and_write(dir: &Path) -> anyhow::Result<CollectedTasks> {
    let table = collect_tasks(dir)?;
    write_atomic(&dir.join(COLLECTED_TASKS_JSON), serde_json::to_string_pretty(&table)?.as_bytes())?;
    write_atomic(&dir.join(COLLECTED_TASKS_MD), tasks_markdown(&table).as_bytes())?;
    Ok(table)
}

/// The tables as aligned Markdown: one per group, a row per task.
pub fn tasks_markdown(table: &CollectedTasks) -> String {
    let mut out = format!(
        "Sweep {}, task by task after the last step: mean over finished seeds [{:.0} % bootstrap interval, {} resamples of the seeds]\n",
        table.sweep_file,
        table.confidence * 100.0,
        table.resamples
    );
    let mut header = vec!["task".to_string()];
    header.extend(table.measures.iter().map(|(_, h)| h.clone()));
    for g in &table.groups {
        out.push_str(&format!("\n{} ({}/{} seeds)\n\n", g.name, g.finished, g.planned));
        if g.tasks.is_empty() {
            out.push_str("no finished cell yet\n");
            continue;
        }
        let rows: Vec<Vec<String>> = g
            .tasks
            .iter()
            .map(|t| {
                let mut row = vec![t.task.clone()];
                row.extend(table.measures.iter().map(|(k, _)| t.measures.get(k).map_or("-".into(), estimate_text)));
                row
            })
            .collect();
        out.push_str(&super::collect::aligned_table(&header, &rows));
    }
    out
}
