//! Sim-to-real fine-tuning, `sim2real` in code (METHOD.md 2.7; the command is
//! `quadcl finetune`, distinct from the `finetune` baseline that trains on
//! with nothing protecting old tasks): one learned
//! task of a policy directory trains again on a shifted environment; only
//! its PRIVATE elements, its biases, its action std and its observation
//! statistics move (the masked networks' repeat mode, METHOD.md 2.5). Every other task's
//! outputs are bit-identical before and after: the report shows their
//! evaluations side by side.

use super::learner::{Evaluation, Learner, TaskStart};
use super::ppo_learner::PpoTaskLearner;
use super::shift::Shift;
use crate::rl::{iteration_summary, metric_names, progress_bar};
use crate::util::{derive_seed, replace_dir, write_atomic, Stream};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What `finetune.json` (beside the new policy) holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sim2RealReport {
    pub task: String,
    pub shift: Shift,
    pub iterations: usize,
    /// Every task evaluated in the shifted environment before fine-tuning.
    pub before: Vec<Evaluation>,
    /// The same evaluations (same seeds) after.
    pub after: Vec<Evaluation>,
    /// Tasks other than `task` whose evaluation changed (must be empty).
    pub changed_other_tasks: Vec<String>,
    /// Per iteration, `charts/performance`.
    pub curve: Vec<f64>,
}

/// Fine-tunes task `task` of the policy in `policy` on `shift` and writes the
/// new policy directory `out` (with `finetune.json`). `iterations` overrides the shift file's.
pub fn sim2real(
    policy: &Path,
    task: &str,
    shift: &Shift,
    out: &Path,
    seed: u64,
    episodes: usize,
    progress: bool,
) -> anyhow::Result<Sim2RealReport> {
    shift.validate()?;
    anyhow::ensure!(out != policy, "--out must be a new directory, not the policy itself");
    anyhow::ensure!(
        !out.join(crate::nn::checkpoint::MANIFEST_FILE).exists(),
        "{} already holds a policy",
        out.display()
    );
    let (mut learner, tasks) = PpoTaskLearner::from_policy(policy, episodes)?;
    let id = tasks.iter().position(|t| t == task).ok_or_else(|| {
        anyhow::anyhow!("{}: no task {task:?} to fine-tune; it has {tasks:?} (fine-tuning trains a learned task's private parameters)", policy.display())
    })?;
    // One fine-tuning at a time into `out` (its lock file is the one thing it may hold).
    let mut lock = super::run_dir::lock_folder(out)?;
    // The new policy replaces `out` as a whole: anything else in it would be lost.
    let holds_files = out
        .read_dir()
        .map(|mut entries| entries.any(|e| e.is_ok_and(|e| e.file_name() != super::run_dir::LOCK_FILE)))
        .unwrap_or(false);
    anyhow::ensure!(
        !holds_files,
        "--out {} is not empty: name a new directory for the fine-tuned policy",
        out.display()
    );
    learner.set_shift(shift);
    let evaluate_all = |learner: &mut PpoTaskLearner| -> anyhow::Result<Vec<Evaluation>> {
        let learned: Vec<usize> = (0..tasks.len()).filter(|&t| learner.has_task(t)).collect();
        learned
            .into_iter()
            .map(|t| learner.evaluate(t, &tasks[t], derive_seed(seed, Stream::Sim2RealEval(t))))
            .collect()
    };
    let before = evaluate_all(&mut learner)?;
    let start = TaskStart {
        step: 0,
        task: id,
        name: task.to_string(),
        related: Vec::new(),
        mask: learner.mask_config(),
        iterations: shift.iterations,
        seed: derive_seed(seed, Stream::Sim2RealTrain),
    };
    learner.begin_task(&start)?;
    let bar = progress_bar(shift.iterations, progress);
    bar.set_prefix(format!("sim2real {task}"));
    let mut curve = Vec::new();
    for _ in 0..shift.iterations {
        let m = learner.train_iteration()?;
        if let Some(p) = m.get(metric_names::PERFORMANCE) {
            curve.push(*p);
        }
        bar.set_message(iteration_summary(&m));
        bar.inc(1);
    }
    bar.finish();
    learner.end_task()?;
    let after = evaluate_all(&mut learner)?;
    let changed_other_tasks = before
        .iter()
        .zip(&after)
        .filter(|(b, a)| b.report.task != task && b != a)
        .map(|(b, _)| b.report.task.clone())
        .collect();
    let report = Sim2RealReport {
        task: task.to_string(),
        shift: shift.clone(),
        iterations: shift.iterations,
        before,
        after,
        changed_other_tasks,
        curve,
    };
    // The new policy and its report appear together, or not at all.
    replace_dir(out, |dir| {
        learner.save(dir, &tasks)?;
        write_atomic(&dir.join("finetune.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
        // The new folder carries the lock.
        lock.move_into(dir)
    })?;
    Ok(report)
}
