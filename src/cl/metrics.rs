//! The continual-learning measures of METHOD.md section 4, on an evaluation
//! matrix `R[i][j]`: the performance on distinct task `j` after training step
//! `i` of the sequence (a task may be trained at several steps: repeats).
//!
//! Performance is normalised to [0, 1] by the caller (normalised episode
//! return, or a success rate); these functions only combine the numbers.

use serde::{Deserialize, Serialize};

/// `R[i][j]`: row `i` = after training step `i`, column `j` = distinct task `j`.
/// `None` where task `j` was not evaluated after step `i`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EvalMatrix {
    /// Distinct task names, one per column.
    pub tasks: Vec<String>,
    /// For each training step, the column of the task trained at that step.
    pub trained: Vec<usize>,
    /// One row per training step, one entry per distinct task.
    pub rows: Vec<Vec<Option<f64>>>,
}

impl EvalMatrix {
    /// An empty matrix over the distinct `tasks`.
    pub fn new(tasks: Vec<String>) -> Self {
        Self { tasks, trained: Vec::new(), rows: Vec::new() }
    }

    /// Records that training step `rows.len()` trained task column `task`
    /// and evaluated the tasks given in `results` (column, performance).
    pub fn push_step(&mut self, task: usize, results: &[(usize, f64)]) -> anyhow::Result<()> {
        anyhow::ensure!(task < self.tasks.len(), "task column {task} out of range ({} tasks)", self.tasks.len());
        let mut row = vec![None; self.tasks.len()];
        for &(j, value) in results {
            anyhow::ensure!(j < self.tasks.len(), "task column {j} out of range ({} tasks)", self.tasks.len());
            anyhow::ensure!(value.is_finite(), "performance of task {} is not finite: {value}", self.tasks[j]);
            row[j] = Some(value);
        }
        self.trained.push(task);
        self.rows.push(row);
        Ok(())
    }

    /// The last row: every task's performance at the end of the sequence.
    fn final_row(&self) -> Option<&[Option<f64>]> {
        self.rows.last().map(|r| r.as_slice())
    }

    /// The step at which task column `j` was last trained.
    fn last_trained_step(&self, j: usize) -> Option<usize> {
        self.trained.iter().rposition(|&t| t == j)
    }

    /// Mean over the trained tasks of their performance at the end.
    pub fn average_performance(&self) -> Option<f64> {
        let last = self.final_row()?;
        mean(self.trained_columns().filter_map(|j| last[j]))
    }

    /// Per task: performance right after it was last trained minus
    /// performance at the end. `None` for the task trained last (nothing came
    /// after it) and for tasks never evaluated.
    pub fn forgetting_per_task(&self) -> Vec<Option<f64>> {
        let n = self.rows.len();
        (0..self.tasks.len())
            .map(|j| {
                let step = self.last_trained_step(j)?;
                if step + 1 == n {
                    return None;
                }
                Some(self.rows[step][j]? - self.final_row()?[j]?)
            })
            .collect()
    }

    /// Mean forgetting over the tasks that have a value (METHOD.md 4).
    pub fn forgetting(&self) -> Option<f64> {
        mean(self.forgetting_per_task().into_iter().flatten())
    }

    /// Mean over training steps of the performance on the task just trained:
    /// how well new tasks are still learned (plasticity).
    pub fn plasticity(&self) -> Option<f64> {
        mean(self.trained.iter().enumerate().filter_map(|(i, &j)| self.rows[i][j]))
    }

    fn trained_columns(&self) -> impl Iterator<Item = usize> + '_ {
        let mut seen = vec![false; self.tasks.len()];
        self.trained.iter().copied().filter(move |&j| !std::mem::replace(&mut seen[j], true))
    }
}

/// Area under a normalised training curve (values in [0, 1], equally spaced
/// over the task's budget), by the trapezoid rule, scaled to [0, 1].
pub fn curve_auc(curve: &[f64]) -> Option<f64> {
    match curve.len() {
        0 => None,
        1 => Some(curve[0]),
        n => {
            let area: f64 = curve.windows(2).map(|w| 0.5 * (w[0] + w[1])).sum();
            Some(area / (n - 1) as f64)
        }
    }
}

/// Forward transfer (Continual World): `(AUC - AUC_ref) / (1 - AUC_ref)`,
/// where the reference is the same task trained alone from scratch.
/// `None` when the reference already reaches the top (nothing to gain).
pub fn forward_transfer(curve: &[f64], reference: &[f64]) -> Option<f64> {
    let auc = curve_auc(curve)?;
    let auc_ref = curve_auc(reference)?;
    let headroom = 1.0 - auc_ref;
    (headroom > 1e-12).then(|| (auc - auc_ref) / headroom)
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three tasks A, B, C trained in order; the hand-computed measures.
    fn three_task_matrix() -> EvalMatrix {
        let mut m = EvalMatrix::new(vec!["A".into(), "B".into(), "C".into()]);
        m.push_step(0, &[(0, 0.9)]).unwrap();
        m.push_step(1, &[(0, 0.7), (1, 0.8)]).unwrap();
        m.push_step(2, &[(0, 0.6), (1, 0.8), (2, 0.5)]).unwrap();
        m
    }

    #[test]
    fn average_performance_is_the_mean_of_the_final_row() {
        let m = three_task_matrix();
        assert!((m.average_performance().unwrap() - (0.6 + 0.8 + 0.5) / 3.0).abs() < 1e-12);
    }

    #[test]
    fn forgetting_compares_each_task_with_its_final_value() {
        let m = three_task_matrix();
        let per = m.forgetting_per_task();
        assert!((per[0].unwrap() - 0.3).abs() < 1e-12);
        assert_eq!(per[1], Some(0.0));
        assert_eq!(per[2], None, "the last task has nothing after it");
        assert!((m.forgetting().unwrap() - 0.15).abs() < 1e-12);
    }

    #[test]
    fn a_repeated_task_measures_forgetting_from_its_last_training() {
        let mut m = EvalMatrix::new(vec!["A".into(), "B".into()]);
        m.push_step(0, &[(0, 0.5)]).unwrap();
        m.push_step(1, &[(0, 0.2), (1, 0.9)]).unwrap();
        m.push_step(0, &[(0, 0.8), (1, 0.9)]).unwrap();
        m.push_step(1, &[(0, 0.7), (1, 0.9)]).unwrap();
        let per = m.forgetting_per_task();
        assert!((per[0].unwrap() - 0.1).abs() < 1e-12, "{per:?}");
        assert_eq!(per[1], None);
        assert!((m.average_performance().unwrap() - 0.8).abs() < 1e-12);
        assert!((m.plasticity().unwrap() - (0.5 + 0.9 + 0.8 + 0.9) / 4.0).abs() < 1e-12);
    }

    #[test]
    fn forward_transfer_matches_the_continual_world_formula() {
        let reference = [0.0, 0.5, 1.0]; // AUC 0.5
        let curve = [0.5, 1.0, 1.0]; // AUC 0.875
        let ft = forward_transfer(&curve, &reference).unwrap();
        assert!((ft - 0.75).abs() < 1e-12, "{ft}");
        assert_eq!(forward_transfer(&curve, &[1.0, 1.0]), None);
        assert!(forward_transfer(&reference, &curve).unwrap() < 0.0);
    }

    #[test]
    fn out_of_range_or_non_finite_results_are_errors() {
        let mut m = EvalMatrix::new(vec!["A".into()]);
        assert!(m.push_step(1, &[]).is_err());
        assert!(m.push_step(0, &[(3, 0.1)]).is_err());
        let err = m.push_step(0, &[(0, f64::NAN)]).unwrap_err().to_string();
        assert!(err.contains('A') && err.contains("not finite"), "{err}");
    }
}
