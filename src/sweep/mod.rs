//! Sweeps (issue 32): methods x seeds x settings as a grid of runs, planned from
//! one sweep file, run here or as a Slurm array job, resumable cell by cell,
//! and collected into tables with 90 % bootstrap intervals over seeds.
//!
//! A sweep folder `DIR` holds:
//!
//! - `sweep.json`: the plan ([`Plan`]): axes, cells, names, groups, each cell's
//!   run file hash, the provenance of the planning build;
//! - `cells/I.toml`: cell I's run file (the base run file with its values);
//! - `runs/I/`: cell I's run folder (`quadcl run --out`);
//! - `logs/I.log`: the output of cell I's runs, local or on Slurm;
//! - `state/I.json`: `sweep local`'s marker of a cell it runs or that failed;
//! - `sweep.sbatch`, `slurm.json`: the array job script and the submitted jobs;
//! - `collected.json`, `collected.md`: the collected table;
//! - `collected-tasks.json`, `collected-tasks.md`: the same groups task by task (`--per-task`);
//! - `plasticity-trend.json`, `plasticity-trend.md`: each group's plasticity step by step, its
//!   first half against its second and its slope (`--plasticity-trend`);
//! - `contrast.json`, `contrast.md`: every group minus one, paired by seed (`--against GROUP`),
//!   and `contrast-vs-OTHER.*` against a group of another sweep folder (`--against-in OTHER`).
//!
//! One file per part: [`file`](mod@file) (the sweep file), [`plan`](mod@plan) (cells and
//! `sweep.json`), [`local`] (child processes here), [`slurm`] (array jobs), [`marker`] (what a
//! local runner says about a cell), [`status`](mod@status) (where every cell stands),
//! [`bootstrap`] (means and intervals), [`collect`](mod@collect) (the table), [`per_task`]
//! (its groups task by task), [`plasticity_trend`](mod@plasticity_trend) (plasticity over the
//! sequence) and [`contrast`](mod@contrast) (groups against one, paired by seed).
//!
//! Not a sweep but collected alike: [`finetunes`](mod@finetunes), the sim-to-real fine-tunings of
//! one task over seeds (a folder of `quadcl finetune --out` folders, one per seed; `quadcl
//! sweep finetunes DIR` writes `finetunes.md` and `.json` there).

pub mod bootstrap;
pub mod collect;
pub mod contrast;
pub mod file;
pub mod finetunes;
pub mod local;
pub mod marker;
pub mod per_task;
pub mod plan;
pub mod plasticity_trend;
pub mod slurm;
pub mod status;

pub use bootstrap::{estimate, Estimate};
pub use collect::{collect, collect_and_write, markdown, Collected, CollectedGroup, RunMeasures, MEASURES};
pub use contrast::{contrast, contrast_markdown, Contrast};
pub use file::{SweepFile, SEED_AXIS};
pub use finetunes::{finetunes, finetunes_and_write, finetunes_markdown, Finetunes};
pub use local::{run_local, LocalOptions, LocalReport};
pub use per_task::{collect_tasks, collect_tasks_and_write, tasks_markdown, CollectedTasks};
pub use plan::{check, plan, Cell, Plan};
pub use plasticity_trend::{plasticity_trend, plasticity_trend_and_write, trend_markdown, PlasticityTrend};
pub use slurm::{submit, write_sbatch, SlurmOptions};
pub use status::{status, status_lines, CellState, CellStatus};

/// The plan.
pub const PLAN_FILE: &str = "sweep.json";
/// The cells' run files.
pub const CELLS_DIR: &str = "cells";
/// The cells' run folders.
pub const RUNS_DIR: &str = "runs";
/// The cells' logs.
pub const LOGS_DIR: &str = "logs";
/// `sweep local`'s markers.
pub const STATE_DIR: &str = "state";
/// The array job script.
pub const SBATCH_FILE: &str = "sweep.sbatch";
/// The submitted array jobs.
pub const SLURM_FILE: &str = "slurm.json";
/// The collected table as JSON.
pub const COLLECTED_JSON: &str = "collected.json";
/// The collected table as Markdown.
pub const COLLECTED_MD: &str = "collected.md";
