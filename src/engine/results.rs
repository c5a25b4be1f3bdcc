//! What a session has produced so far: one record per training step, the
//! evaluation matrix, every evaluation, and the training curves. This is the
//! body of `metrics.json`, and what `--resume` reads back.

use super::learner::Evaluation;
use crate::cl::{forward_transfer, EvalMatrix, Switches};
use crate::nn::TaskId;
use crate::rl::{metric_names, Metrics};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One training step as it ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    pub step: usize,
    pub task: TaskId,
    pub name: String,
    pub iterations: usize,
    /// The switches in force for this step; none for a method whose networks they do not act
    /// on (the dense baselines).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub switches: Option<Switches>,
    /// The entropy phase and the soft-score means' rate the step trained with (for a method
    /// with switches); none in runs written before issue 60, which ran E = their
    /// `entropy_iterations` (100 unless set) and the means at the optimiser's rate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub soft_scores: Option<SoftScoreSettings>,
    /// The related tasks whose masks seeded the soft scores (after `random` drawing).
    pub related: Vec<TaskId>,
    /// A repeat of a finished task (METHOD.md 2.5): only its private parameters and biases trained.
    /// (`fine_tune` in runs written before the rename.)
    #[serde(alias = "fine_tune")]
    pub repeat: bool,
    /// How the task's selection used the masked networks (none for a dense method, and in runs
    /// written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity: Option<StepCapacity>,
}

/// The soft networks' schedule a step trained with (docs/method.md, "The entropy phase").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SoftScoreSettings {
    /// E: the iterations of the task the entropy phase lasted (its share of the budget resolved).
    pub entropy_iterations: usize,
    /// The soft-score means' fixed Adam rate; 0: the optimiser's (KL-adapted) rate.
    pub score_learning_rate: f64,
}

impl SoftScoreSettings {
    /// What a task's resolved settings `mask` train with.
    pub fn of(mask: &crate::config::net::MaskConfig) -> Self {
        Self {
            entropy_iterations: mask.resolved_entropy_iterations(),
            score_learning_rate: mask.score_rate().unwrap_or(0.0),
        }
    }
}

/// How a masked task's selection used the networks, from the mask statistics right after
/// it ended (METHOD.md 2.1): what a sequence has left for the tasks after it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepCapacity {
    /// Vacant elements over all elements of every masked layer, after the step.
    pub vacant_share_after: f64,
    /// The share of the task's selected elements that earlier tasks had occupied (reuse).
    pub from_occupied_share: f64,
    /// Layers with no vacant element left after the step: later tasks can only reuse there.
    pub exhausted_layers: Vec<String>,
}

impl StepCapacity {
    /// The figures of task `task` in `report`; None when the report has no mask of it.
    pub fn from_report(report: &crate::nn::MaskReport, task: &str) -> Option<Self> {
        let layers: Vec<&crate::nn::LayerMasks> = report.networks.iter().flat_map(|n| &n.layers).collect();
        let (mut vacant, mut total, mut selected, mut reused) = (0usize, 0usize, 0usize, 0usize);
        for l in &layers {
            vacant += l.vacant;
            total += l.shape[0] * l.shape[1];
            let m = l.per_task.iter().find(|m| m.task == task)?;
            selected += m.selected;
            reused += m.from_occupied;
        }
        let round = |v: f64| (v * 1e6).round() / 1e6;
        Some(Self {
            vacant_share_after: round(vacant as f64 / total.max(1) as f64),
            from_occupied_share: round(reused as f64 / selected.max(1) as f64),
            exhausted_layers: layers.iter().filter(|l| l.vacant == 0).map(|l| l.name.clone()).collect(),
        })
    }
}

/// A training step's curves, one value per iteration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TaskCurve {
    pub step: usize,
    pub task: TaskId,
    pub name: String,
    /// Normalised performance (`charts/performance`).
    pub performance: Vec<f64>,
    /// `charts/episodic_return`.
    pub episodic_return: Vec<f64>,
    /// `charts/lin_vel_err`, m/s.
    pub lin_vel_err: Vec<f64>,
    /// `charts/ang_vel_err`, rad/s.
    pub ang_vel_err: Vec<f64>,
    /// `charts/fall_rate`: the share of the iteration's finished episodes that ended in a fall
    /// (absent from runs written before it was recorded).
    #[serde(default)]
    pub fall_rate: Vec<f64>,
    /// Per masked layer, its soft-score sigma each iteration (`charts/sigma/LAYER`, in the
    /// run's `sigma_scale` units): the entropy phase's first E iterations widen it.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub sigma: BTreeMap<String, Vec<f64>>,
    /// Per masked layer, its mask churn from the second iteration on (`charts/mask_churn/LAYER`):
    /// how much of the hard mask each iteration redrew.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub mask_churn: BTreeMap<String, Vec<f64>>,
    /// The plasticity diagnostics each iteration, by full metric name (`plasticity/dormant/NET`,
    /// `plasticity/effective_rank/NET`, `plasticity/selected_abs_w/LAYER`,
    /// `plasticity/trainable_share/LAYER`: `rl/plasticity.rs`); absent from runs written before.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub plasticity: BTreeMap<String, Vec<f64>>,
}

impl TaskCurve {
    /// Appends one iteration's metrics; a metric that is missing or not finite is skipped.
    pub fn push(&mut self, m: &Metrics) {
        let put = |v: &mut Vec<f64>, key: &str| {
            if let Some(x) = m.get(key).filter(|x| x.is_finite()) {
                v.push(*x);
            }
        };
        put(&mut self.performance, metric_names::PERFORMANCE);
        put(&mut self.episodic_return, metric_names::EPISODIC_RETURN);
        put(&mut self.lin_vel_err, metric_names::LIN_VEL_ERR);
        put(&mut self.ang_vel_err, metric_names::ANG_VEL_ERR);
        put(&mut self.fall_rate, metric_names::FALL_RATE);
        for (key, value) in m.iter().filter(|(_, v)| v.is_finite()) {
            let per_layer = |prefix: &str| key.strip_prefix(prefix).and_then(|k| k.strip_prefix('/'));
            if let Some(layer) = per_layer(metric_names::SIGMA) {
                self.sigma.entry(layer.to_string()).or_default().push(*value);
            } else if let Some(layer) = per_layer(metric_names::MASK_CHURN) {
                self.mask_churn.entry(layer.to_string()).or_default().push(*value);
            } else if per_layer(metric_names::PLASTICITY).is_some() {
                self.plasticity.entry(key.clone()).or_default().push(*value);
            }
        }
    }
}

/// Everything a session has produced.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SessionResults {
    /// The method's name.
    pub method: String,
    /// The method's settings (`[method.NAME]`), null for a method without any.
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub method_settings: serde_json::Value,
    /// Distinct task names (the learner's task ids, the matrix's columns).
    pub tasks: Vec<String>,
    /// The completed training steps.
    pub steps: Vec<StepRecord>,
    /// `R[i][j]`: performance on task j after step i.
    pub eval_matrix: EvalMatrix,
    /// Every evaluation after each step (the tracking errors, fall rates, ...).
    pub evaluations: Vec<Vec<Evaluation>>,
    /// Per step, the training curves.
    pub curves: Vec<TaskCurve>,
}

/// The summary figures of `metrics.json` (METHOD.md 4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Mean over the trained tasks of their performance at the end.
    pub average_performance: Option<f64>,
    /// Mean of [`Summary::forgetting_per_task`] over the tasks that have one.
    pub forgetting: Option<f64>,
    /// Per distinct task: performance right after it was last trained minus at the end.
    pub forgetting_per_task: Vec<Option<f64>>,
    /// Mean over training steps of the performance on the task just trained.
    pub plasticity: Option<f64>,
    /// Per distinct task: forward transfer against the reference curve of the
    /// same task trained alone from scratch (null without a reference).
    pub forward_transfer: Vec<Option<f64>>,
    /// Mean forward transfer over the tasks that have one.
    pub forward_transfer_mean: Option<f64>,
    /// Command tracking and falls per distinct task at the end of the sequence.
    pub command_tracking: CommandTracking,
}

/// Command tracking at the end of the run, per distinct task (METHOD.md 4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CommandTracking {
    /// Mean |v_xy - v_cmd| (m/s) per task, after the last completed step.
    pub lin_vel_err: Vec<Option<f64>>,
    /// Mean |w_z - w_cmd| (rad/s) per task.
    pub ang_vel_err: Vec<Option<f64>>,
    /// Fall rate per task.
    pub fall_rate: Vec<Option<f64>>,
}

impl SessionResults {
    /// The summary measures; `reference` gives per task name a from-scratch curve.
    pub fn summary(&self, reference: &dyn Fn(&str) -> Option<Vec<f64>>) -> Summary {
        let m = &self.eval_matrix;
        let forward: Vec<Option<f64>> = self
            .tasks
            .iter()
            .map(|name| {
                let curve = self.curves.iter().find(|c| &c.name == name)?;
                forward_transfer(&curve.performance, &reference(name)?)
            })
            .collect();
        let known: Vec<f64> = forward.iter().flatten().copied().collect();
        let last = self.evaluations.last();
        let final_of = |f: &dyn Fn(&Evaluation) -> f64| -> Vec<Option<f64>> {
            self.tasks.iter().map(|name| last.and_then(|l| l.iter().find(|e| &e.report.task == name)).map(f)).collect()
        };
        Summary {
            average_performance: m.average_performance(),
            forgetting: m.forgetting(),
            forgetting_per_task: m.forgetting_per_task(),
            plasticity: m.plasticity(),
            forward_transfer_mean: (!known.is_empty()).then(|| known.iter().sum::<f64>() / known.len() as f64),
            forward_transfer: forward,
            command_tracking: CommandTracking {
                lin_vel_err: final_of(&|e| e.report.lin_vel_err),
                ang_vel_err: final_of(&|e| e.report.ang_vel_err),
                fall_rate: final_of(&|e| e.report.fall_rate),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_curve_keeps_each_finite_metric_and_skips_the_rest() {
        let mut curve = TaskCurve::default();
        let it = |fall: f64, lin: f64| -> Metrics {
            [("charts/fall_rate".to_string(), fall), ("charts/lin_vel_err".to_string(), lin)].into_iter().collect()
        };
        curve.push(&it(0.25, 0.3));
        curve.push(&it(f64::NAN, 0.2));
        assert_eq!((curve.fall_rate, curve.lin_vel_err, curve.performance), (vec![0.25], vec![0.3, 0.2], vec![]));
        let old: TaskCurve = serde_json::from_str(
            r#"{"step":0,"task":1,"name":"x","performance":[],"episodic_return":[],"lin_vel_err":[],"ang_vel_err":[]}"#,
        )
        .unwrap();
        assert!(old.fall_rate.is_empty(), "a run written before fall_rate was recorded still reads");
        assert!(old.plasticity.is_empty(), "and one written before the plasticity diagnostics");
    }

    #[test]
    fn a_curve_keeps_the_plasticity_diagnostics_by_full_name() {
        let mut curve = TaskCurve::default();
        let it = |dormant: f64| -> Metrics {
            [
                ("plasticity/dormant/actor".to_string(), dormant),
                ("plasticity/trainable_share/actor.l0".to_string(), 0.25),
                ("charts/performance".to_string(), 0.5),
            ]
            .into_iter()
            .collect()
        };
        curve.push(&it(0.1));
        curve.push(&it(0.2));
        assert_eq!(curve.plasticity["plasticity/dormant/actor"], vec![0.1, 0.2]);
        assert_eq!(curve.plasticity["plasticity/trainable_share/actor.l0"], vec![0.25, 0.25]);
        assert_eq!(curve.plasticity.len(), 2, "only the plasticity/ metrics");
        let text = serde_json::to_string(&curve).unwrap();
        assert!(text.contains(r#""plasticity":{"plasticity/dormant/actor":[0.1,0.2]"#), "{text}");
        assert!(!serde_json::to_string(&TaskCurve::default()).unwrap().contains("plasticity"), "left out when empty");
    }
}
