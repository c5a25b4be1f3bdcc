//! What the engine needs from a learner: the [`Learner`] trait. The PPO
//! agent implements it (`engine::ppo_learner`); a tiny masked regression
//! learner (`engine::toy_learner`) implements it too, so the session's
//! step-by-step behaviour, resume and recall are tested in milliseconds.
//!
//! Life cycle per training step of a sequence: `begin_task` ->
//! `train_iteration` x budget -> `end_task`; then `evaluate` on any finished
//! task; `save`/`load` capture everything needed to go on identically.

use crate::config::net::MaskConfig;
use crate::nn::{LayerLift, LayerView, MaskReport, TaskId};
use crate::rl::{EvalReport, Metrics};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Everything a learner needs to start one training step of a sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskStart {
    /// The training step (0-based position in the sequence).
    pub step: usize,
    /// The task's id (its column in the evaluation matrix); a repeat reuses it.
    pub task: TaskId,
    /// The task's canonical name (`crash:FL`, ...).
    pub name: String,
    /// Finished tasks whose masks seed the soft scores (METHOD.md 2.6); empty for scratch.
    pub related: Vec<TaskId>,
    /// Mask settings for this task (the method's switches applied).
    pub mask: MaskConfig,
    /// Training iterations of this step.
    pub iterations: usize,
    /// Seed of every random stream of this step, derived from (master seed, step).
    pub seed: u64,
}

/// One evaluation of one task (deterministic for a given seed): the
/// `quadcl eval` figures plus the normalised performance the continual
/// measures are computed from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// Return, tracking errors, falls, survival, the task's name and the seed.
    #[serde(flatten)]
    pub report: EvalReport,
    /// Normalised performance R (METHOD.md 4): mean return over the best return a task allows.
    pub performance: f64,
}

/// A learner the engine drives task by task.
pub trait Learner: Send {
    /// Starts a training step: a new task, or a repeat of a finished one (METHOD.md 2.5).
    fn begin_task(&mut self, start: &TaskStart) -> anyhow::Result<()>;
    /// One training iteration of the task in progress; returns its metrics. The
    /// metric `charts/performance` (normalised, as [`Evaluation::performance`]) feeds
    /// the training curve, `charts/lin_vel_err` / `charts/ang_vel_err` the tracking curves.
    fn train_iteration(&mut self) -> anyhow::Result<Metrics>;
    /// Ends the task in progress (final masks, frozen per-task state).
    fn end_task(&mut self) -> anyhow::Result<()>;
    /// Evaluates finished task `task` (named `name`) with its recalled parameters.
    fn evaluate(&mut self, task: TaskId, name: &str, seed: u64) -> anyhow::Result<Evaluation>;
    /// Per network, layer and task: the mask statistics (`tasks[t]` names task t).
    fn mask_report(&self, tasks: &[String]) -> MaskReport;
    /// Every element of every layer as task `task` sees it (its live selection while it trains).
    fn mask_views(&self, task: TaskId) -> Vec<LayerView>;
    /// Per layer, the elements the transfer bonus would lift for a new task naming `related`.
    fn transfer_lift(&self, related: &[TaskId]) -> Vec<LayerLift>;
    /// Writes everything needed to recall every finished task and to go on
    /// training identically (between tasks only) into the directory `dir`.
    fn save(&self, dir: &Path, tasks: &[String]) -> anyhow::Result<()>;
    /// Restores the state [`Learner::save`] wrote; returns its task names.
    fn load(&mut self, dir: &Path) -> anyhow::Result<Vec<String>>;
}
