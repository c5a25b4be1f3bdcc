//! Plasticity over a sweep's sequence (`quadcl sweep collect DIR
//! --plasticity-trend`): whether later tasks are learned as well as earlier ones.
//! A task's plasticity is its performance right after its own training step
//! (the evaluation matrix's diagonal, `rows[i][trained[i]]`; the run's
//! `plasticity` is their mean). Per group of cells that differ only in seed,
//! and per finished seed:
//!
//! - the mean plasticity of the first half of the steps and of the second half
//!   (with an odd number of steps the middle one is in neither),
//! - the second half minus the first, paired within the seed,
//! - the least-squares slope of plasticity against the step (per task),
//!
//! each as a mean over seeds with its 90 % bootstrap interval (`bootstrap`),
//! with every seed's own value beside it; and step by step, the plasticity over
//! seeds. Written as `DIR/plasticity-trend.md` and `.json`. A falling trend can
//! be a loss of plasticity or later tasks that are harder: the sequence's order
//! decides which tasks fall in which half.

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::collect::{aligned_table, estimate_text, load_finished};
use super::plan::Plan;
use crate::util::write_atomic;
use anyhow::ensure;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `plasticity-trend.md`, beside `collected.md`.
pub const PLASTICITY_TREND_MD: &str = "plasticity-trend.md";
/// `plasticity-trend.json`, beside `collected.json`.
pub const PLASTICITY_TREND_JSON: &str = "plasticity-trend.json";

/// What the trend reads of a run's `metrics.json`.
#[derive(Debug, Deserialize)]
struct RunMatrix {
    eval_matrix: Matrix,
}

#[derive(Debug, Deserialize)]
struct Matrix {
    tasks: Vec<String>,
    trained: Vec<usize>,
    rows: Vec<Vec<Option<f64>>>,
}

impl RunMatrix {
    /// The tasks trained, step by step.
    fn trained_tasks(&self) -> Vec<String> {
        self.eval_matrix.trained.iter().map(|&j| self.eval_matrix.tasks.get(j).cloned().unwrap_or_default()).collect()
    }

    /// Each step's plasticity (None where that evaluation is missing or not finite).
    fn plasticity(&self) -> Vec<Option<f64>> {
        let m = &self.eval_matrix;
        m.trained
            .iter()
            .enumerate()
            .map(|(i, &j)| m.rows.get(i).and_then(|row| row.get(j)).copied().flatten().filter(|v| v.is_finite()))
            .collect()
    }
}

/// One seed's trend: the halves, their difference and the slope.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Trend {
    pub first_half: f64,
    pub second_half: f64,
    pub second_minus_first: f64,
    /// Least-squares slope of plasticity against the step, per step.
    pub slope: f64,
}

/// The trend of one run's step-by-step plasticity; None with fewer than two steps or a
/// step without a value.
pub fn trend(plasticity: &[Option<f64>]) -> Option<Trend> {
    let p: Vec<f64> = plasticity.iter().copied().collect::<Option<_>>()?;
    let n = p.len();
    if n < 2 {
        return None;
    }
    let half = n / 2;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (first_half, second_half) = (mean(&p[..half]), mean(&p[n - half..]));
    let x_mean = (n as f64 + 1.0) / 2.0;
    let p_mean = mean(&p);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in p.iter().enumerate() {
        let dx = (i + 1) as f64 - x_mean;
        sxy += dx * (v - p_mean);
        sxx += dx * dx;
    }
    Some(Trend { first_half, second_half, second_minus_first: second_half - first_half, slope: sxy / sxx })
}

/// One finished seed of a group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedTrend {
    /// Its seed (the `seed` axis value), when the sweep has a seed axis.
    pub seed: Option<serde_json::Value>,
    /// Its run folder, relative to the sweep folder.
    pub run: String,
    /// Each step's plasticity.
    pub plasticity: Vec<Option<f64>>,
    /// None where a step has no value.
    pub trend: Option<Trend>,
}

/// One step of a group: its task and plasticity over the seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepPlasticity {
    /// 1 for the first task trained.
    pub step: usize,
    pub task: String,
    pub plasticity: Option<Estimate>,
}

/// One group: its seeds, the trend's measures over them, and step by step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupTrend {
    pub name: String,
    pub planned: usize,
    pub finished: usize,
    pub seeds: Vec<SeedTrend>,
    pub first_half: Option<Estimate>,
    pub second_half: Option<Estimate>,
    pub second_minus_first: Option<Estimate>,
    pub slope: Option<Estimate>,
    pub steps: Vec<StepPlasticity>,
}

/// `plasticity-trend.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlasticityTrend {
    pub sweep_file: String,
    pub confidence: f64,
    pub resamples: usize,
    pub groups: Vec<GroupTrend>,
}

/// The trend of every group of the sweep in `dir`; nothing is written. Errors name the run
/// whose sequence differs from its group's first finished seed.
pub fn plasticity_trend(dir: &Path) -> anyhow::Result<PlasticityTrend> {
    let plan = Plan::load(dir)?;
    let mut groups = Vec::new();
    for (name, indices) in plan.groups() {
        let mut seeds: Vec<SeedTrend> = Vec::new();
        let mut sequence: Option<(String, Vec<String>)> = None;
        for &i in &indices {
            let folder = &plan.cells[i].run;
            let Some(r) = load_finished::<RunMatrix>(dir, &plan.cells[i])? else { continue };
            let tasks = r.trained_tasks();
            match &sequence {
                Some((first, expected)) => ensure!(
                    tasks == *expected,
                    "{}: trained {:?}, but {} of the same group trained {:?}",
                    dir.join(folder).display(),
                    tasks,
                    dir.join(first).display(),
                    expected
                ),
                None => sequence = Some((folder.clone(), tasks)),
            }
            let plasticity = r.plasticity();
            seeds.push(SeedTrend {
                seed: plan.seed_of(i).cloned(),
                run: folder.clone(),
                trend: trend(&plasticity),
                plasticity,
            });
        }
        let over = |f: fn(&Trend) -> f64| {
            let values: Vec<f64> = seeds.iter().filter_map(|s| s.trend.as_ref().map(f)).collect();
            estimate(&values)
        };
        let steps = sequence
            .map(|(_, tasks)| tasks)
            .unwrap_or_default()
            .into_iter()
            .enumerate()
            .map(|(i, task)| {
                let values: Vec<f64> = seeds.iter().filter_map(|s| s.plasticity[i]).collect();
                StepPlasticity { step: i + 1, task, plasticity: estimate(&values) }
            })
            .collect();
        groups.push(GroupTrend {
            name,
            planned: indices.len(),
            finished: seeds.len(),
            first_half: over(|t| t.first_half),
            second_half: over(|t| t.second_half),
            second_minus_first: over(|t| t.second_minus_first),
            slope: over(|t| t.slope),
            seeds,
            steps,
        });
    }
    Ok(PlasticityTrend { sweep_file: plan.sweep_file, confidence: CONFIDENCE, resamples: RESAMPLES, groups })
}

/// Computes the trend of `dir` and writes `plasticity-trend.json` and `.md` into it.
pub fn plasticity_trend_and_write(dir: &Path) -> anyhow::Result<PlasticityTrend> {
    let table = plasticity_trend(dir)?;
    write_atomic(&dir.join(PLASTICITY_TREND_JSON), serde_json::to_string_pretty(&table)?.as_bytes())?;
    write_atomic(&dir.join(PLASTICITY_TREND_MD), trend_markdown(&table).as_bytes())?;
    Ok(table)
}

/// A row of a group's trend table: its label, the estimate over seeds, a seed's value and
/// whether that value is a change (printed with its sign).
type TrendRow = (String, Option<Estimate>, fn(&Trend) -> f64, bool);

/// The tables as aligned Markdown: per group, the trend's measures with each seed's value,
/// then step by step.
pub fn trend_markdown(table: &PlasticityTrend) -> String {
    let mut out = format!(
        "Sweep {}, plasticity over the sequence (each task's performance right after its own training): \
         mean over finished seeds [{:.0} % bootstrap interval, {} resamples of the seeds]\n",
        table.sweep_file,
        table.confidence * 100.0,
        table.resamples
    );
    for g in &table.groups {
        out.push_str(&format!("\n{} ({}/{} seeds)\n\n", g.name, g.finished, g.planned));
        if g.steps.is_empty() {
            out.push_str("no finished cell yet\n");
            continue;
        }
        let n = g.steps.len();
        let half = n / 2;
        let seed_name = |s: &SeedTrend| s.seed.as_ref().map_or_else(|| s.run.clone(), |v| format!("seed {v}"));
        let mut header = vec!["measure".to_string(), "over seeds".to_string()];
        header.extend(g.seeds.iter().map(seed_name));
        // Levels plain, changes signed.
        let measures: [TrendRow; 4] = [
            (format!("first half (steps 1-{half})"), g.first_half, |t| t.first_half, false),
            (format!("second half (steps {}-{n})", n - half + 1), g.second_half, |t| t.second_half, false),
            ("second minus first".into(), g.second_minus_first, |t| t.second_minus_first, true),
            ("slope per step".into(), g.slope, |t| t.slope, true),
        ];
        let rows: Vec<Vec<String>> = measures
            .iter()
            .map(|(label, e, f, signed)| {
                let mut row = vec![label.clone(), e.as_ref().map_or("-".into(), estimate_text)];
                let value = |v: f64| if *signed { format!("{v:+.3}") } else { format!("{v:.3}") };
                row.extend(g.seeds.iter().map(|s| s.trend.as_ref().map_or("-".into(), |t| value(f(t)))));
                row
            })
            .collect();
        out.push_str(&aligned_table(&header, &rows));
        out.push('\n');
        let header = ["step".to_string(), "task".to_string(), "plasticity".to_string()];
        let rows: Vec<Vec<String>> = g
            .steps
            .iter()
            .map(|s| vec![s.step.to_string(), s.task.clone(), s.plasticity.as_ref().map_or("-".into(), estimate_text)])
            .collect();
        out.push_str(&aligned_table(&header, &rows));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_sequence_has_no_trend_and_a_falling_one_a_negative_slope() {
        let flat = trend(&[Some(0.5); 4]).unwrap();
        assert_eq!((flat.second_minus_first, flat.slope), (0.0, 0.0));
        // 0.8, 0.6, 0.4, 0.2: halves 0.7 and 0.3, slope -0.2 a step.
        let falling = trend(&[Some(0.8), Some(0.6), Some(0.4), Some(0.2)]).unwrap();
        assert!((falling.second_minus_first + 0.4).abs() < 1e-12, "{falling:?}");
        assert!((falling.slope + 0.2).abs() < 1e-12, "{falling:?}");
    }

    #[test]
    fn an_odd_sequence_leaves_its_middle_step_out_of_both_halves() {
        let t = trend(&[Some(0.2), Some(9.0), Some(0.6)]).unwrap();
        assert_eq!((t.first_half, t.second_half), (0.2, 0.6));
    }

    #[test]
    fn a_step_without_a_value_or_a_single_step_gives_no_trend() {
        assert!(trend(&[Some(0.5), None, Some(0.4)]).is_none());
        assert!(trend(&[Some(0.5)]).is_none());
    }
}
