//! Reading a run for the figures: a `quadcl run` folder's `metrics.json` (the curves of every
//! step and the evaluation matrix) or a `quadcl train` folder's `metrics.jsonl` (one step, one
//! row per iteration). Only the fields the figures use are read, each optional where older
//! runs lack it, so a run from any version plots. Every error names the file.

use super::data::{Curve, Measure, RunData, StepCurves};
use crate::cl::EvalMatrix;
use anyhow::{bail, ensure, Context};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What `quadcl run` writes (`engine::run_dir`).
pub const RUN_METRICS: &str = "metrics.json";
/// What `quadcl train` writes (`rl::metrics_log`).
pub const TRAIN_METRICS: &str = "metrics.jsonl";

/// The most iterations a step may have (far beyond any run; it keeps positions exact in f64).
const MAX_ITERATIONS: usize = 1 << 40;

/// The part of `metrics.json` the figures read.
#[derive(Deserialize)]
struct RunFile {
    eval_matrix: EvalMatrix,
    #[serde(default)]
    steps: Vec<StepEntry>,
    curves: Vec<CurveEntry>,
}

#[derive(Deserialize)]
struct StepEntry {
    step: usize,
    iterations: usize,
}

/// A step's curves (`engine::TaskCurve`), with the plasticity measures when it has them.
#[derive(Deserialize)]
struct CurveEntry {
    step: usize,
    name: String,
    #[serde(default)]
    performance: Vec<f64>,
    #[serde(default)]
    lin_vel_err: Vec<f64>,
    #[serde(default)]
    ang_vel_err: Vec<f64>,
    #[serde(default)]
    fall_rate: Vec<f64>,
    #[serde(default)]
    plasticity: BTreeMap<String, Vec<f64>>,
}

/// Reads the run at `path`: a folder holding `metrics.json` or `metrics.jsonl`, or either file.
/// Its label is `label`, or else the folder's name.
pub fn load_run(path: &Path, label: Option<&str>) -> anyhow::Result<RunData> {
    let file = metrics_file(path)?;
    let mut run = if file.extension().is_some_and(|e| e == "jsonl") { read_train(&file)? } else { read_run(&file)? };
    ensure!(!run.steps.is_empty(), "{}: no training curves in it yet", file.display());
    run.label = match label {
        Some(l) => l.to_string(),
        None => default_label(&file),
    };
    Ok(run)
}

/// The metrics file of `path`: the file itself, or the one a run folder holds.
fn metrics_file(path: &Path) -> anyhow::Result<PathBuf> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    ensure!(path.is_dir(), "{}: no such file or folder", path.display());
    let found = [RUN_METRICS, TRAIN_METRICS].iter().map(|name| path.join(name)).find(|f| f.is_file());
    found.with_context(|| {
        format!(
            "{}: no {RUN_METRICS} (a `quadcl run` folder) or {TRAIN_METRICS} (a `quadcl train` folder) in it",
            path.display()
        )
    })
}

/// The name of the folder holding `file` (the file's own stem when it has no named folder).
fn default_label(file: &Path) -> String {
    let folder =
        std::path::absolute(file).ok().and_then(|f| Some(f.parent()?.file_name()?.to_string_lossy().into_owned()));
    folder.unwrap_or_else(|| file.file_stem().map_or("run".into(), |s| s.to_string_lossy().into_owned()))
}

fn read_run(file: &Path) -> anyhow::Result<RunData> {
    let text = std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let parsed: RunFile =
        serde_json::from_str(&text).with_context(|| format!("{}: not a quadcl run's {RUN_METRICS}", file.display()))?;
    check_matrix(&parsed.eval_matrix).with_context(|| format!("{}: eval_matrix", file.display()))?;
    let iterations_of: BTreeMap<usize, usize> = parsed.steps.iter().map(|s| (s.step, s.iterations)).collect();
    if let Some(s) = parsed.steps.iter().find(|s| s.iterations > MAX_ITERATIONS) {
        bail!("{}: step {} has {} iterations, more than {MAX_ITERATIONS}", file.display(), s.step, s.iterations);
    }
    let steps = parsed
        .curves
        .into_iter()
        .map(|c| {
            let longest = [&c.performance, &c.lin_vel_err, &c.ang_vel_err, &c.fall_rate]
                .into_iter()
                .chain(c.plasticity.values())
                .map(Vec::len)
                .max()
                .unwrap_or(0);
            let iterations = iterations_of.get(&c.step).copied().unwrap_or(longest).max(longest);
            // A measure with fewer values than the step's iterations lacks its first ones: the
            // iterations before any episode ended (a curve keeps only finite values).
            let curve = |values: &[f64]| Curve::from_values(values, iterations - values.len() + 1);
            StepCurves {
                task: c.name,
                iterations,
                performance: curve(&c.performance),
                lin_vel_err: curve(&c.lin_vel_err),
                ang_vel_err: curve(&c.ang_vel_err),
                fall_rate: curve(&c.fall_rate),
                plasticity: c.plasticity.iter().map(|(k, v)| (k.clone(), curve(v))).collect(),
            }
        })
        .collect();
    Ok(RunData {
        label: String::new(),
        source: file.to_path_buf(),
        steps,
        eval_matrix: Some(parsed.eval_matrix),
        over_seeds: None,
    })
}

/// A matrix the figures can index: a row per trained step, an entry per task in each row.
fn check_matrix(m: &EvalMatrix) -> anyhow::Result<()> {
    ensure!(
        m.trained.len() == m.rows.len(),
        "{} trained tasks for {} rows (one per step expected)",
        m.trained.len(),
        m.rows.len()
    );
    for (i, row) in m.rows.iter().enumerate() {
        ensure!(row.len() == m.tasks.len(), "row {i} has {} entries for {} tasks", row.len(), m.tasks.len());
    }
    if let Some(t) = m.trained.iter().find(|&&t| t >= m.tasks.len()) {
        bail!("trained task column {t} out of range ({} tasks)", m.tasks.len());
    }
    Ok(())
}

/// A `quadcl train` run: one step, named by the task in `summary.json` beside it when there is one.
fn read_train(file: &Path) -> anyhow::Result<RunData> {
    let text = std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let mut rows = Vec::with_capacity(lines.len());
    for (i, line) in lines.iter().enumerate() {
        match serde_json::from_str::<BTreeMap<String, serde_json::Value>>(line) {
            Ok(row) => rows.push(row),
            // A run still training may have its last row cut short.
            Err(_) if i + 1 == lines.len() && i > 0 => {}
            Err(e) => bail!("{}: line {}: not an iteration's metrics: {e}", file.display(), i + 1),
        }
    }
    let mut step = StepCurves { task: train_task(file), iterations: rows.len(), ..Default::default() };
    for (i, row) in rows.iter().enumerate() {
        let number = |key: &str| row.get(key).and_then(serde_json::Value::as_f64).filter(|v| v.is_finite());
        let iteration = number("charts/iteration").unwrap_or((i + 1) as f64);
        for measure in Measure::ALL {
            if let Some(v) = number(measure.metric_name()) {
                step.curve_mut(measure).points.push((iteration, v));
            }
        }
        for key in row.keys().filter(|k| k.starts_with("plasticity/")) {
            if let Some(v) = number(key) {
                step.plasticity.entry(key.clone()).or_default().points.push((iteration, v));
            }
        }
        ensure!(
            (0.0..=MAX_ITERATIONS as f64).contains(&iteration),
            "{}: line {}: charts/iteration = {iteration}, expected 0 to {MAX_ITERATIONS}",
            file.display(),
            i + 1
        );
        step.iterations = step.iterations.max(iteration as usize);
    }
    Ok(RunData {
        label: String::new(),
        source: file.to_path_buf(),
        steps: vec![step],
        eval_matrix: None,
        over_seeds: None,
    })
}

/// The task a `quadcl train` folder trained (its `summary.json`), or `train` when unknown.
fn train_task(file: &Path) -> String {
    let summary = file.with_file_name("summary.json");
    let task = std::fs::read_to_string(summary).ok().and_then(|text| {
        let value: serde_json::Value = serde_json::from_str(&text).ok()?;
        Some(value.get("task")?.as_str()?.to_string())
    });
    task.unwrap_or_else(|| "train".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    const TWO_STEPS: &str = r#"{
        "eval_matrix": {"tasks": ["none", "a", "b"], "trained": [1, 2],
                        "rows": [[0.9, 0.5, null], [0.9, 0.4, 0.6]]},
        "steps": [{"step": 0, "iterations": 4}, {"step": 1, "iterations": 3}],
        "curves": [
            {"step": 0, "name": "a", "performance": [0.1, 0.2, 0.3, 0.4], "lin_vel_err": [0.5, 0.4],
             "ang_vel_err": [], "episodic_return": []},
            {"step": 1, "name": "b", "performance": [0.3, 0.5, 0.6],
             "plasticity": {"plasticity/dormant/actor": [0.1, 0.05, 0.0]}}
        ]}"#;

    #[test]
    fn a_run_folder_reads_its_steps_aligning_short_curves_to_the_end() {
        let dir = tempfile::tempdir().unwrap();
        let run_dir = dir.path().join("my-run");
        std::fs::create_dir(&run_dir).unwrap();
        write(&run_dir, RUN_METRICS, TWO_STEPS);
        let run = load_run(&run_dir, None).unwrap();
        assert_eq!(run.label, "my-run");
        assert_eq!(run.steps.iter().map(|s| (s.task.as_str(), s.iterations)).collect::<Vec<_>>(), [("a", 4), ("b", 3)]);
        assert_eq!(run.steps[0].lin_vel_err.points, vec![(3.0, 0.5), (4.0, 0.4)]);
        assert_eq!(run.steps[1].plasticity["plasticity/dormant/actor"].points[2], (3.0, 0.0));
        let forgetting = run.eval_matrix.unwrap().forgetting_per_task();
        assert!(forgetting[0].is_none() && forgetting[2].is_none(), "{forgetting:?}");
        assert!((forgetting[1].unwrap() - 0.1).abs() < 1e-12, "{forgetting:?}");
        assert_eq!(load_run(&run_dir.join(RUN_METRICS), Some("named")).unwrap().label, "named");
    }

    #[test]
    fn a_train_folder_reads_one_step_named_by_its_summary() {
        let dir = tempfile::tempdir().unwrap();
        let rows = [
            r#"{"charts/iteration": 1, "charts/performance": 0.2}"#,
            r#"{"charts/iteration": 2, "charts/performance": 0.3, "charts/lin_vel_err": 0.4, "plasticity/effective_rank/actor": 12.5}"#,
            r#"{"charts/iteration": 3, "charts/perf"#,
        ];
        write(dir.path(), TRAIN_METRICS, &rows.join("\n"));
        write(dir.path(), "summary.json", r#"{"task": "crash:FL", "iterations": 2}"#);
        let run = load_run(dir.path(), None).unwrap();
        let step = &run.steps[0];
        assert_eq!((step.task.as_str(), step.iterations, run.eval_matrix.is_none()), ("crash:FL", 2, true));
        assert_eq!(step.performance.points, vec![(1.0, 0.2), (2.0, 0.3)]);
        assert_eq!(step.lin_vel_err.points, vec![(2.0, 0.4)]);
        assert_eq!(step.plasticity["plasticity/effective_rank/actor"].points, vec![(2.0, 12.5)]);
    }

    #[test]
    fn bad_input_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let err = |p: &Path| format!("{:#}", load_run(p, None).unwrap_err());
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        assert!(err(&empty).contains("empty: no metrics.json"), "{}", err(&empty));
        assert!(err(&dir.path().join("missing")).contains("missing: no such file or folder"));
        let broken = write(dir.path(), "broken.json", "{\"eval_matrix\": ");
        assert!(err(&broken).contains("broken.json: not a quadcl run's metrics.json"), "{}", err(&broken));
        let ragged = write(dir.path(), "ragged.json", &TWO_STEPS.replace("[0.9, 0.4, 0.6]", "[0.9]"));
        assert!(err(&ragged).contains("ragged.json: eval_matrix: row 1 has 1 entries for 3 tasks"), "{}", err(&ragged));
        let no_curves = write(
            dir.path(),
            "none.json",
            r#"{"eval_matrix": {"tasks": [], "trained": [], "rows": []}, "curves": []}"#,
        );
        assert!(err(&no_curves).contains("none.json: no training curves"), "{}", err(&no_curves));
        let bad_row = write(dir.path(), "bad.jsonl", "{\"charts/performance\": 0.1}\nnot json\n{}\n");
        assert!(err(&bad_row).contains("bad.jsonl: line 2"), "{}", err(&bad_row));
    }
}
