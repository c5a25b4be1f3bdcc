//! A run's output folder (`quadcl run --out DIR`):
//!
//! - `run.toml`: a copy of the run file (a resumed run must match it);
//! - `metrics.json`: the measures and everything needed to resume (see [`MetricsFile`]), and
//!   the provenance (build, run file hash, cores);
//! - `checkpoints/step-NN-TASK/`: the learner after each completed step (a policy directory);
//! - `log.txt`: one line per task start/end and evaluation;
//! - `episodes/step-NN-TASK/T.mcap`: with `--record mcap`, an evaluation episode of every
//!   learned task T after the step;
//! - `next-step.json`: switches and related tasks chosen in the workbench for the step to
//!   train next (only while there are any);
//! - `run.lock`: the folder's lock ([`RunDir::lock`]), held by the one process that may write
//!   it (`quadcl run`, `train`, `finetune`, the workbench training into it), with its pid and
//!   host; empty once released.
//!
//! After each step the checkpoint is written first, then `metrics.json`;
//! both atomically, so an interruption at any moment leaves a folder that
//! `--resume` continues from the last step `metrics.json` records.

use super::learner::{Evaluation, Learner};
use super::results::{SessionResults, StepRecord, Summary, TaskCurve};
use crate::cl::EvalMatrix;
use crate::util::{replace_dir, write_atomic, FolderLock, Provenance};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub const METRICS_FILE: &str = "metrics.json";
pub const RUN_FILE: &str = "run.toml";
pub const LOG_FILE: &str = "log.txt";
pub const CHECKPOINTS: &str = "checkpoints";
/// One recorded evaluation episode per learned task after each step (`quadcl run --record mcap`).
pub const EPISODES: &str = "episodes";
/// The settings chosen in the workbench for the next step (see `engine::ChosenSettings`).
pub const CHOSEN_FILE: &str = "next-step.json";
/// The folder's lock file (see [`RunDir::lock`]).
pub const LOCK_FILE: &str = "run.lock";

/// The content of `metrics.json`: the session's results and their [`Summary`]
/// (its fields stand at the top level of the file, after `eval_matrix`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MetricsFile {
    pub method: String,
    /// The method's settings (`[method.NAME]`); absent for a method without any (`ours`'
    /// switches are recorded per step).
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub method_settings: serde_json::Value,
    /// Distinct task names (columns of `eval_matrix.rows`).
    pub tasks: Vec<String>,
    pub completed_steps: usize,
    pub total_steps: usize,
    /// `R[i][j]` (`rows`), with the task trained at each step (`trained`).
    pub eval_matrix: EvalMatrix,
    /// Average performance, forgetting, plasticity, forward transfer (against
    /// the `[run] reference` curves; null without one), command tracking.
    #[serde(flatten)]
    pub summary: Summary,
    /// The steps as they ran (switches, related tasks, repeats).
    pub steps: Vec<StepRecord>,
    /// Every evaluation after every step.
    pub evaluations: Vec<Vec<Evaluation>>,
    /// Per step, the training curves.
    pub curves: Vec<TaskCurve>,
    /// The build, run file and machine that wrote the file (absent from runs written before
    /// it was recorded). Not a result: a run resumed elsewhere has the same numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

impl MetricsFile {
    /// The file for `results` of a sequence of `total_steps`; `reference` gives from-scratch curves by task name.
    pub fn new(results: &SessionResults, total_steps: usize, reference: &dyn Fn(&str) -> Option<Vec<f64>>) -> Self {
        Self {
            method: results.method.clone(),
            method_settings: results.method_settings.clone(),
            tasks: results.tasks.clone(),
            completed_steps: results.steps.len(),
            total_steps,
            eval_matrix: results.eval_matrix.clone(),
            summary: results.summary(reference),
            steps: results.steps.clone(),
            evaluations: results.evaluations.clone(),
            curves: results.curves.clone(),
            provenance: None,
        }
    }

    /// The session results this file records.
    pub fn results(&self) -> SessionResults {
        SessionResults {
            method: self.method.clone(),
            method_settings: self.method_settings.clone(),
            tasks: self.tasks.clone(),
            steps: self.steps.clone(),
            eval_matrix: self.eval_matrix.clone(),
            evaluations: self.evaluations.clone(),
            curves: self.curves.clone(),
        }
    }

    /// Reads a `metrics.json`; errors name the file. A step's switches recorded before issue 31
    /// are read as they ran ([`crate::config::net::MaskConfig::fill_in_pre_issue_31`]: `reinit`
    /// redrew every score, over the effective fan-in, with the related tasks' bias).
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let not_metrics = || format!("{}: not a quadcl run's metrics.json", path.display());
        let mut value: serde_json::Value = serde_json::from_str(&text).with_context(not_metrics)?;
        if let Some(steps) = value.get_mut("steps").and_then(|s| s.as_array_mut()) {
            for switches in steps.iter_mut().filter_map(|s| s.get_mut("switches")) {
                crate::config::net::MaskConfig::fill_in_pre_issue_31(switches);
            }
        }
        serde_json::from_value(value).with_context(not_metrics)
    }

    /// Whether the run began before issue 60: a step with switches but no record of its soft
    /// networks' schedule ([`super::results::StepRecord::soft_scores`]). Such a run is resumed
    /// or continued with its run file read as it then was (`RunConfig::load_text_as_ran_before_issue_60`).
    pub fn ran_before_issue_60(&self) -> bool {
        self.steps.iter().any(|s| s.switches.is_some() && s.soft_scores.is_none())
    }

    /// The per-step curves of normalised performance, by task name (first training of each).
    pub fn reference_curve(&self, task: &str) -> Option<Vec<f64>> {
        self.curves.iter().find(|c| c.name == task).map(|c| c.performance.clone())
    }
}

/// `task` as a file-name part: `crash:FL` -> `crash_FL`, `invert:RR+noise:FR` -> `invert_RR_noise_FR`.
pub fn task_file_name(task: &str) -> String {
    task.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

/// Takes the lock of the output folder `root` (a run's, a training's, a fine-tuning's), or
/// refuses naming the folder and its holder (see [`FolderLock`]).
pub fn lock_folder(root: &Path) -> anyhow::Result<FolderLock> {
    FolderLock::acquire(
        &root.join(LOCK_FILE),
        &format!("the folder {}", crate::util::text::one_line(&root.display().to_string())),
    )
}

/// The output folder of a run.
#[derive(Debug, Clone)]
pub struct RunDir {
    pub root: PathBuf,
}

impl RunDir {
    pub fn new(root: &Path) -> Self {
        Self { root: root.to_path_buf() }
    }

    /// Takes the folder's lock (creating the folder), or refuses with an error naming the
    /// folder and the process that holds it: no second process may write a run folder.
    pub fn lock(&self) -> anyhow::Result<FolderLock> {
        lock_folder(&self.root)
    }

    pub fn metrics_path(&self) -> PathBuf {
        self.root.join(METRICS_FILE)
    }

    /// The checkpoint folder of step `step` (0-based) training `task`.
    pub fn checkpoint(&self, step: usize, task: &str) -> PathBuf {
        self.root.join(CHECKPOINTS).join(format!("step-{step:02}-{}", task_file_name(task)))
    }

    /// Whether the folder already holds a run: a `metrics.json` (written right after
    /// `run.toml` when a run starts) or a checkpoint. A `run.toml` alone is a start that
    /// was interrupted before anything was recorded: nothing is lost by starting again.
    pub fn has_run(&self) -> bool {
        let checkpoints = std::fs::read_dir(self.root.join(CHECKPOINTS)).is_ok_and(|mut d| d.next().is_some());
        self.metrics_path().exists() || checkpoints
    }

    /// Whether the folder holds a run's results but not the run: a `metrics.json` without
    /// its `run.toml` (a harvested sweep keeps each cell so, with no checkpoints), which can
    /// be read (`quadcl plot`, `sweep collect`) but not reopened or continued.
    pub fn results_only(&self) -> bool {
        self.metrics_path().exists() && !self.root.join(RUN_FILE).exists()
    }

    /// Writes the checkpoint of step `step` (training `task`) as a whole
    /// (see [`replace_dir`]): the learner's state with the sequence's task names, its
    /// manifest stamped with `provenance`.
    pub fn write_checkpoint(
        &self,
        step: usize,
        task: &str,
        learner: &dyn Learner,
        tasks: &[String],
        provenance: &Provenance,
    ) -> anyhow::Result<()> {
        replace_dir(&self.checkpoint(step, task), |dir| {
            learner.save(dir, tasks)?;
            crate::nn::checkpoint::write_provenance(dir, provenance)
        })
    }

    /// Writes `metrics.json` atomically.
    pub fn write_metrics(&self, metrics: &MetricsFile) -> anyhow::Result<()> {
        write_atomic(&self.metrics_path(), serde_json::to_string_pretty(metrics)?.as_bytes())
    }

    /// Writes the log atomically.
    pub fn write_log(&self, log: &str) -> anyhow::Result<()> {
        write_atomic(&self.root.join(LOG_FILE), log.as_bytes())
    }

    /// The existing log (empty when there is none).
    pub fn read_log(&self) -> String {
        std::fs::read_to_string(self.root.join(LOG_FILE)).unwrap_or_default()
    }
}
