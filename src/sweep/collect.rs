//! Collecting a sweep (`quadcl sweep collect DIR`): per group of cells that
//! differ only in seed, the mean and the 90 % bootstrap interval over seeds
//! (see `bootstrap`) of each measure of the finished cells' `metrics.json`:
//! average performance, forgetting, plasticity, forward transfer, and at the
//! end of the sequence the fall rate and the tracking errors (means over the
//! tasks). Written as `DIR/collected.json` (per group its cells, their run
//! folders and values, for `quadcl plot`) and `DIR/collected.md`, and printed.
//! A cell that has not finished is listed but left out of the estimates.

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::plan::Plan;
use super::{COLLECTED_JSON, COLLECTED_MD, SEED_AXIS};
use crate::engine::{Summary, METRICS_FILE};
use crate::util::write_atomic;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The measures of a collected table: (key, heading).
pub const MEASURES: [(&str, &str); 7] = [
    ("average_performance", "average performance"),
    ("forgetting", "forgetting"),
    ("plasticity", "plasticity"),
    ("forward_transfer", "forward transfer"),
    ("fall_rate", "fall rate"),
    ("lin_vel_err", "lin vel err (m/s)"),
    ("ang_vel_err", "ang vel err (rad/s)"),
];

/// What a collected table reads of a run's `metrics.json`.
#[derive(Debug, Clone, Deserialize)]
pub struct RunMeasures {
    pub completed_steps: usize,
    pub total_steps: usize,
    #[serde(flatten)]
    pub summary: Summary,
}

/// The `metrics.json` of the run folder `run` (its path and text); Ok(None) when there is none yet.
fn read_metrics(run: &Path) -> anyhow::Result<Option<(std::path::PathBuf, String)>> {
    let path = run.join(METRICS_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Some((path, text)))
}

/// `text`, the `metrics.json` at `path`, as `T` (the fields `T` names).
fn parse_metrics<T: serde::de::DeserializeOwned>(path: &Path, text: &str) -> anyhow::Result<T> {
    serde_json::from_str(text).with_context(|| format!("{}: not a quadcl run's metrics.json", path.display()))
}

/// Reads the `metrics.json` of the run folder `run` as `T` (the fields `T` names); Ok(None)
/// when there is none yet.
pub fn load_metrics<T: serde::de::DeserializeOwned>(run: &Path) -> anyhow::Result<Option<T>> {
    read_metrics(run)?.map(|(path, text)| parse_metrics(&path, &text)).transpose()
}

/// [`load_metrics`] of a run that trained its whole sequence; Ok(None) also while it has steps
/// left. The file (megabytes for a long sequence) is read once.
pub fn load_finished<T: serde::de::DeserializeOwned>(run: &Path) -> anyhow::Result<Option<T>> {
    #[derive(Deserialize)]
    struct Progress {
        completed_steps: usize,
        total_steps: usize,
    }
    let Some((path, text)) = read_metrics(run)? else { return Ok(None) };
    let p: Progress = parse_metrics(&path, &text)?;
    if p.total_steps > 0 && p.completed_steps == p.total_steps {
        parse_metrics(&path, &text).map(Some)
    } else {
        Ok(None)
    }
}

impl RunMeasures {
    /// Reads the `metrics.json` of the run folder `run`; Ok(None) when there is none yet.
    pub fn load(run: &Path) -> anyhow::Result<Option<Self>> {
        load_metrics(run)
    }

    /// Whether the run trained its whole sequence.
    pub fn finished(&self) -> bool {
        self.total_steps > 0 && self.completed_steps == self.total_steps
    }

    /// The value of measure `key` (one of [`MEASURES`]); None when the run has none.
    pub fn measure(&self, key: &str) -> Option<f64> {
        let s = &self.summary;
        let over_tasks = |v: &[Option<f64>]| {
            let known: Vec<f64> = v.iter().flatten().copied().collect();
            (!known.is_empty()).then(|| known.iter().sum::<f64>() / known.len() as f64)
        };
        match key {
            "average_performance" => s.average_performance,
            "forgetting" => s.forgetting,
            "plasticity" => s.plasticity,
            "forward_transfer" => s.forward_transfer_mean,
            "fall_rate" => over_tasks(&s.command_tracking.fall_rate),
            "lin_vel_err" => over_tasks(&s.command_tracking.lin_vel_err),
            "ang_vel_err" => over_tasks(&s.command_tracking.ang_vel_err),
            _ => None,
        }
        .filter(|v| v.is_finite())
    }
}

/// One cell in a collected table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollectedCell {
    pub index: usize,
    /// Its seed (the `seed` axis value), when the sweep has a seed axis.
    pub seed: Option<serde_json::Value>,
    /// Its run folder, relative to the sweep folder.
    pub run: String,
    pub finished: bool,
    /// Its measures (only of a finished run).
    pub measures: BTreeMap<String, f64>,
}

/// One group of a collected table: the cells that differ only in seed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollectedGroup {
    /// The values other than the seed (`capacity=0.2`; `all` when only seeds vary).
    pub name: String,
    /// Those values by key.
    pub values: BTreeMap<String, serde_json::Value>,
    pub planned: usize,
    pub finished: usize,
    pub cells: Vec<CollectedCell>,
    /// Per measure, over the finished cells (absent: no finished cell has it).
    pub measures: BTreeMap<String, Estimate>,
}

/// `collected.json`: the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Collected {
    /// The sweep file the plan came from.
    pub sweep_file: String,
    pub confidence: f64,
    pub resamples: usize,
    /// (key, heading) of each measure, in the table's order.
    pub measures: Vec<(String, String)>,
    pub groups: Vec<CollectedGroup>,
}

/// Collects the sweep in `dir` (see the module doc); nothing is written.
pub fn collect(dir: &Path) -> anyhow::Result<Collected> {
    let plan = Plan::load(dir)?;
    let mut groups = Vec::new();
    for (name, indices) in plan.groups() {
        let mut cells = Vec::new();
        for &i in &indices {
            let cell = &plan.cells[i];
            let run = RunMeasures::load(&dir.join(&cell.run))?;
            let finished = run.as_ref().is_some_and(|r| r.finished());
            let measures = match &run {
                Some(r) if finished => {
                    MEASURES.iter().filter_map(|(k, _)| Some((k.to_string(), r.measure(k)?))).collect()
                }
                _ => BTreeMap::new(),
            };
            cells.push(CollectedCell {
                index: i,
                seed: plan.seed_of(i).cloned(),
                run: cell.run.clone(),
                finished,
                measures,
            });
        }
        let measures = MEASURES
            .iter()
            .filter_map(|(k, _)| {
                let values: Vec<f64> = cells.iter().filter_map(|c| c.measures.get(*k).copied()).collect();
                Some((k.to_string(), estimate(&values)?))
            })
            .collect();
        let first = &plan.cells[indices[0]];
        groups.push(CollectedGroup {
            values: first.values.iter().filter(|(k, _)| *k != SEED_AXIS).map(|(k, v)| (k.clone(), v.clone())).collect(),
            name,
            planned: indices.len(),
            finished: cells.iter().filter(|c| c.finished).count(),
            cells,
            measures,
        });
    }
    Ok(Collected {
        sweep_file: plan.sweep_file,
        confidence: CONFIDENCE,
        resamples: RESAMPLES,
        measures: MEASURES.iter().map(|(k, h)| (k.to_string(), h.to_string())).collect(),
        groups,
    })
}

/// Collects `dir` and writes `collected.json` and `collected.md` into it.
pub fn collect_and_write(dir: &Path) -> anyhow::Result<Collected> {
    let table = collect(dir)?;
    write_collected(dir, &table)?;
    Ok(table)
}

/// Writes `table` as `collected.json` and `collected.md` into `dir`.
pub fn write_collected(dir: &Path, table: &Collected) -> anyhow::Result<()> {
    write_atomic(&dir.join(COLLECTED_JSON), serde_json::to_string_pretty(table)?.as_bytes())?;
    write_atomic(&dir.join(COLLECTED_MD), markdown(table).as_bytes())
}

/// `mean [low, high]` to three decimals (one seed: the value alone).
pub fn estimate_text(e: &Estimate) -> String {
    if e.n < 2 {
        format!("{:.3}", e.mean)
    } else {
        format!("{:.3} [{:.3}, {:.3}]", e.mean, e.low, e.high)
    }
}

/// The table's rows as text cells: group, seeds finished of planned, then each measure.
pub fn rows(table: &Collected) -> (Vec<String>, Vec<Vec<String>>) {
    let mut header = vec!["group".to_string(), "seeds".to_string()];
    header.extend(table.measures.iter().map(|(_, h)| h.clone()));
    let rows = table
        .groups
        .iter()
        .map(|g| {
            let mut row = vec![g.name.clone(), format!("{}/{}", g.finished, g.planned)];
            row.extend(table.measures.iter().map(|(k, _)| g.measures.get(k).map_or("-".into(), estimate_text)));
            row
        })
        .collect();
    (header, rows)
}

/// The table as aligned Markdown (readable as it is in a terminal), with a line saying what it shows.
pub fn markdown(table: &Collected) -> String {
    let (header, rows) = rows(table);
    let mut out = format!(
        "Sweep {}: mean over finished seeds [{:.0} % bootstrap interval, {} resamples of the seeds]\n\n",
        table.sweep_file,
        table.confidence * 100.0,
        table.resamples
    );
    out.push_str(&aligned_table(&header, &rows));
    out
}

/// `header` and `rows` as a Markdown table padded to aligned columns.
pub fn aligned_table(header: &[String], rows: &[Vec<String>]) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|c| rows.iter().map(|r| r[c].chars().count()).chain([header[c].chars().count()]).max().unwrap_or(0))
        .collect();
    let line = |cells: &[String]| {
        let padded: Vec<String> = cells.iter().zip(&widths).map(|(c, w)| format!("{c:<w$}")).collect();
        format!("| {} |\n", padded.join(" | "))
    };
    let mut out = line(header);
    out.push_str(&format!("|{}|\n", widths.iter().map(|w| "-".repeat(w + 2)).collect::<Vec<_>>().join("|")));
    for r in rows {
        out.push_str(&line(r));
    }
    out
}
