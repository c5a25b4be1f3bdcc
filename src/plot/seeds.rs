//! Runs that differ only in seed drawn as one: each curve the mean over the seeds at every
//! iteration all of them have, with a band from the lowest to the highest seed there (with
//! three seeds, the whole spread rather than an interval that would claim more); the
//! evaluation matrix the mean of theirs entry by entry. `quadcl plot` makes one of these per
//! group of a sweep folder (`sweep::collect`'s groups, finished cells only).

use super::data::{Curve, Measure, OverSeeds, RunData, SeedMeasure, StepCurves};
use super::load::load_run;
use crate::cl::EvalMatrix;
use crate::sweep::{estimate, Plan, RunMeasures, MEASURES};
use anyhow::{ensure, Context};
use std::path::Path;

/// The mean and range of `curves` at each iteration that all of them have.
pub fn curve_across_seeds(curves: &[&Curve]) -> Curve {
    let (mut points, mut band) = (Vec::new(), Vec::new());
    for (x, ys) in Curve::aligned(curves) {
        let low = ys.iter().copied().fold(f64::INFINITY, f64::min);
        let high = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        points.push((x, ys.iter().sum::<f64>() / ys.len() as f64));
        band.push((low, high));
    }
    Curve { points, band: Some(band) }
}

/// One run standing for `runs` (the same tasks in the same order, e.g. one setting's
/// seeds), labelled `label`. Errors name the runs that do not match.
pub fn runs_across_seeds(label: &str, runs: &[RunData]) -> anyhow::Result<RunData> {
    let first = runs.first().context("no runs to draw across seeds")?;
    let tasks = |r: &RunData| r.steps.iter().map(|s| s.task.clone()).collect::<Vec<_>>();
    for run in &runs[1..] {
        ensure!(
            tasks(run) == tasks(first),
            "{} trained {:?}, {} trained {:?}: only runs of the same tasks are drawn as one",
            first.source.display(),
            tasks(first),
            run.source.display(),
            tasks(run)
        );
    }
    let steps = (0..first.steps.len())
        .map(|i| {
            let seeds: Vec<&StepCurves> = runs.iter().map(|r| &r.steps[i]).collect();
            let mut step = StepCurves {
                task: seeds[0].task.clone(),
                iterations: seeds.iter().map(|s| s.iterations).max().unwrap_or(0),
                ..Default::default()
            };
            for m in Measure::ALL {
                *step.curve_mut(m) = curve_across_seeds(&seeds.iter().map(|s| s.curve(m)).collect::<Vec<_>>());
            }
            for name in seeds[0].plasticity.keys() {
                let curves: Vec<&Curve> = seeds.iter().filter_map(|s| s.plasticity.get(name)).collect();
                if curves.len() == runs.len() {
                    step.plasticity.insert(name.clone(), curve_across_seeds(&curves));
                }
            }
            step
        })
        .collect();
    let matrices: Option<Vec<&EvalMatrix>> = runs.iter().map(|r| r.eval_matrix.as_ref()).collect();
    Ok(RunData {
        label: label.to_string(),
        source: first.source.clone(),
        steps,
        eval_matrix: matrices.and_then(|m| mean_matrix(&m)),
        over_seeds: None,
    })
}

/// The entry-by-entry mean of matrices over the same tasks and steps (an entry some lack: none).
fn mean_matrix(matrices: &[&EvalMatrix]) -> Option<EvalMatrix> {
    let first = *matrices.first()?;
    let same =
        |m: &&EvalMatrix| m.tasks == first.tasks && m.trained == first.trained && m.rows.len() == first.rows.len();
    if !matrices.iter().all(same) {
        return None;
    }
    let rows = (0..first.rows.len())
        .map(|i| {
            (0..first.tasks.len())
                .map(|j| {
                    let values: Option<Vec<f64>> =
                        matrices.iter().map(|m| m.rows[i].get(j).copied().flatten()).collect();
                    values.map(|v| v.iter().sum::<f64>() / v.len() as f64)
                })
                .collect()
        })
        .collect();
    Some(EvalMatrix { tasks: first.tasks.clone(), trained: first.trained.clone(), rows })
}

/// Whether `path` is a sweep folder (it holds the plan, `sweep.json`).
pub fn is_sweep(path: &Path) -> bool {
    path.join(crate::sweep::PLAN_FILE).is_file()
}

/// One run per group of the sweep in `dir` with a finished cell: its finished cells drawn
/// across seeds, labelled with the group's name and its number of seeds (`capacity=0.2 (mean
/// of 3 seeds, range shaded)`).
pub fn load_sweep(dir: &Path) -> anyhow::Result<Vec<RunData>> {
    // The plan's groups and finished cells, as `sweep collect` has them, without its intervals.
    let plan = Plan::load(dir)?;
    let mut out = Vec::new();
    for (name, indices) in plan.groups() {
        let (mut runs, mut measures) = (Vec::new(), Vec::new());
        for i in indices {
            let run = dir.join(&plan.cells[i].run);
            if let Some(m) = RunMeasures::load(&run)?.filter(|m| m.finished()) {
                runs.push(load_run(&run, None)?);
                measures.push(m);
            }
        }
        if runs.is_empty() {
            continue;
        }
        let seeds =
            if runs.len() == 1 { "1 seed".to_string() } else { format!("mean of {} seeds, range shaded", runs.len()) };
        let mut group = runs_across_seeds(&format!("{name} ({seeds})"), &runs)?;
        group.over_seeds = Some(over_seeds(&name, &measures));
        out.push(group);
    }
    ensure!(
        !out.is_empty(),
        "{}: no finished cell to draw yet (`quadcl sweep status` shows where they stand)",
        dir.display()
    );
    Ok(out)
}

/// The collected table's measures of one group's finished runs (those all of them lack left out).
fn over_seeds(group: &str, runs: &[RunMeasures]) -> OverSeeds {
    let measures = MEASURES
        .iter()
        .filter_map(|(key, heading)| {
            let values: Vec<f64> = runs.iter().filter_map(|r| r.measure(key)).collect();
            Some(SeedMeasure {
                key: key.to_string(),
                heading: heading.to_string(),
                estimate: estimate(&values)?,
                values,
            })
        })
        .collect();
    OverSeeds { group: group.to_string(), seeds: runs.len(), measures }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn across_seeds_a_curve_is_their_mean_with_their_range_where_all_have_a_value() {
        let a = Curve::from_values(&[0.2, 0.4, 0.6], 1);
        let b = Curve::from_values(&[0.6, 0.0], 2);
        let c = curve_across_seeds(&[&a, &b]);
        assert_eq!(c.points, vec![(2.0, 0.5), (3.0, 0.3)]);
        assert_eq!(c.band, Some(vec![(0.4, 0.6), (0.0, 0.6)]));
    }

    #[test]
    fn the_mean_matrix_leaves_an_entry_empty_where_a_seed_has_none() {
        let m =
            |rows: Vec<Vec<Option<f64>>>| EvalMatrix { tasks: vec!["a".into(), "b".into()], trained: vec![0, 1], rows };
        let (x, y) = (
            m(vec![vec![Some(0.2), None], vec![Some(0.4), Some(1.0)]]),
            m(vec![vec![Some(0.6), Some(0.5)], vec![Some(0.2), Some(0.0)]]),
        );
        let mean = mean_matrix(&[&x, &y]).unwrap();
        assert_eq!(mean.rows[0][1], None);
        assert!((mean.rows[0][0].unwrap() - 0.4).abs() < 1e-12 && (mean.rows[1][1].unwrap() - 0.5).abs() < 1e-12);
        let other = EvalMatrix { tasks: vec!["a".into(), "c".into()], ..x.clone() };
        assert!(mean_matrix(&[&x, &other]).is_none(), "matrices of other tasks are not averaged");
    }

    #[test]
    fn runs_of_other_tasks_are_refused_by_name() {
        let run = |task: &str, source: &str| RunData {
            label: source.into(),
            source: source.into(),
            steps: vec![StepCurves { task: task.into(), iterations: 1, ..Default::default() }],
            eval_matrix: None,
            over_seeds: None,
        };
        let err = runs_across_seeds("g", &[run("crash:FL", "r1"), run("noise:FR", "r2")]).unwrap_err().to_string();
        assert!(err.contains("r1") && err.contains("r2") && err.contains("noise:FR"), "{err}");
    }
}
