//! Setting a session up from what came before it: the tasks a base policy
//! already knows, and the results and checkpoint of a run that stopped (or of
//! a shorter run whose steps are the first steps of this sequence).

use super::Session;
use crate::cl::{EvalMatrix, KnownBefore};
use crate::engine::results::SessionResults;
use std::path::Path;

impl Session {
    /// Declares tasks the learner already knows before the sequence starts
    /// (a base policy's): they come first among the task ids and columns, count
    /// as finished (a sequence entry naming one repeats it, METHOD.md 2.5)
    /// and are evaluated after every step. Only before any training.
    pub fn with_learned_tasks(mut self, learned: &[String]) -> anyhow::Result<Self> {
        anyhow::ensure!(
            self.results.steps.is_empty() && self.in_progress.is_none(),
            "learned tasks are declared before training"
        );
        self.sequence.validate_with(KnownBefore::Tasks(learned.to_vec()))?;
        let mut tasks = learned.to_vec();
        for t in self.sequence.distinct_tasks() {
            if !tasks.contains(&t) {
                tasks.push(t);
            }
        }
        self.finished = (0..tasks.len()).map(|i| i < learned.len()).collect();
        self.results.eval_matrix = EvalMatrix::new(tasks.clone());
        self.results.tasks = tasks;
        Ok(self)
    }

    /// Continues from `results` (the steps completed so far) and the learner
    /// state saved after the last of them in `checkpoint`. The results may come
    /// from a shorter sequence whose steps begin this one (its tasks the first of
    /// this sequence's tasks): the workbench continues a finished 4-task run with
    /// the rest of the 12-task sequence so. Errors (a corrupt checkpoint, results
    /// from another sequence) leave the session untouched.
    pub fn restore(&mut self, mut results: SessionResults, checkpoint: &Path) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.in_progress.is_none() && self.results.steps.is_empty(),
            "restore: the session has already trained"
        );
        anyhow::ensure!(
            self.results.tasks.starts_with(&results.tasks),
            "the saved results are for tasks {:?}, the sequence has {:?}",
            results.tasks,
            self.results.tasks
        );
        let done = results.steps.len();
        anyhow::ensure!(
            done <= self.sequence.tasks.len(),
            "the saved results have {done} steps, the sequence only {}",
            self.sequence.tasks.len()
        );
        for (i, s) in results.steps.iter().enumerate() {
            anyhow::ensure!(
                s.step == i && s.name == self.sequence.tasks[i].name,
                "saved step {i} ({}) does not match the sequence ({})",
                s.name,
                self.sequence.tasks[i].name
            );
        }
        anyhow::ensure!(
            results.eval_matrix.rows.len() == done && results.curves.len() == done && results.evaluations.len() == done,
            "the saved results are inconsistent: {done} steps, {} matrix rows, {} curves, {} evaluation rows",
            results.eval_matrix.rows.len(),
            results.curves.len(),
            results.evaluations.len()
        );
        if done > 0 {
            let names = self.learner.load(checkpoint)?;
            // Tasks added after the checkpoint was written (in the workbench) follow its own.
            anyhow::ensure!(
                !names.is_empty() && results.tasks.starts_with(&names),
                "{}: checkpoint tasks {names:?} differ from the saved results' {:?}",
                checkpoint.display(),
                results.tasks
            );
        }
        let tasks = self.results.tasks.clone();
        let mut matrix = EvalMatrix::new(tasks.clone());
        matrix.trained = results.eval_matrix.trained.clone();
        matrix.rows = results
            .eval_matrix
            .rows
            .iter()
            .map(|r| (0..tasks.len()).map(|j| r.get(j).copied().flatten()).collect())
            .collect();
        results.eval_matrix = matrix;
        results.tasks = tasks;
        results.steps.iter().for_each(|s| self.finished[s.task] = true);
        self.results = results;
        Ok(())
    }
}
