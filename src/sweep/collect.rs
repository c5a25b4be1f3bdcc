//! Collecting a sweep (`quadcl sweep collect DIR`): per group of cells that
//! differ only in seed, the mean and the 90 % bootstrap interval over seeds
//! (see `bootstrap`) of each measure of the finished cells' `metrics.json`:
//! average performance, forgetting, plasticity, forward transfer, and at the
//! end of the sequence the fall rate and the tracking errors (means over the
//! tasks). Written as `DIR/collected.json` (per group its cells, their run
//! folders and values, for `quadcl plot`) and `DIR/collected.md`, and printed.
//! A cell that has not finished is listed but left out of the estimates; so is
//! one whose folder holds another run's results (its `metrics.json` records
//! another run file's sha256 than the plan's) or an unreadable `metrics.json`,
//! and the table says which and why under it.

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::plan::{Cell, Plan};
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

/// What a cell's run folder holds, checked against the plan.
#[derive(Debug, Clone, PartialEq)]
pub enum CellRun {
    /// No `metrics.json` yet.
    NotStarted,
    /// The cell's run: its `metrics.json` (path and text) records the run file the plan wrote
    /// (or no run file hash at all, as runs from before it was recorded).
    Planned { path: std::path::PathBuf, text: String },
    /// Another run's results: its `metrics.json` records another run file's sha256 (a folder
    /// copied from another sweep, or a cell re-planned since it ran).
    Foreign { recorded: String },
    /// A `metrics.json` that cannot be read or is not a run's.
    Unreadable { problem: String },
}

impl CellRun {
    /// The cell's own run as `T` (the fields `T` names): Ok(None) before it has a
    /// `metrics.json`; Err with why it is left out of every table when its folder holds another
    /// run's results, a `metrics.json` that cannot be read, or one that is not `T`.
    pub fn run<T: serde::de::DeserializeOwned>(&self, dir: &Path, cell: &Cell) -> Result<Option<T>, String> {
        let run = dir.join(&cell.run);
        let unreadable = |problem: &str| format!("cell {} ({}): {problem}; left out", cell.index, run.display());
        match self {
            CellRun::NotStarted => Ok(None),
            CellRun::Planned { path, text } => {
                parse_metrics(path, text).map(Some).map_err(|e| unreadable(&crate::util::text::error_text(&e)))
            }
            CellRun::Foreign { recorded } => Err(format!(
                "cell {} ({}): its {METRICS_FILE} records the run file sha256 {}…, not the {}… of {} that the \
                 plan holds: another run's results, left out",
                cell.index,
                run.display(),
                short_hash(recorded),
                short_hash(&cell.run_file_sha256),
                cell.config
            )),
            CellRun::Unreadable { problem } => Err(unreadable(problem)),
        }
    }
}

fn short_hash(hash: &str) -> String {
    crate::util::text::clip(&hash.chars().take(12).collect::<String>())
}

/// What the run folder of `cell` (of the sweep in `dir`) holds (see [`CellRun`]).
pub fn read_cell(dir: &Path, cell: &Cell) -> CellRun {
    #[derive(Deserialize)]
    struct Recorded {
        #[serde(default)]
        provenance: Option<RecordedProvenance>,
    }
    #[derive(Deserialize)]
    struct RecordedProvenance {
        #[serde(default)]
        run_file_sha256: Option<String>,
    }
    let (path, text) = match read_metrics(&dir.join(&cell.run)) {
        Ok(None) => return CellRun::NotStarted,
        Ok(Some(found)) => found,
        Err(e) => return CellRun::Unreadable { problem: crate::util::text::error_text(&e) },
    };
    match parse_metrics::<Recorded>(&path, &text) {
        Err(e) => CellRun::Unreadable { problem: crate::util::text::error_text(&e) },
        Ok(r) => match r.provenance.and_then(|p| p.run_file_sha256) {
            Some(recorded) if recorded != cell.run_file_sha256 => CellRun::Foreign { recorded },
            _ => CellRun::Planned { path, text },
        },
    }
}

/// The `metrics.json` of `cell`'s run as `T` (the fields `T` names) once the run has trained
/// its whole sequence; Ok(None) while it has steps left, and for a cell whose folder holds
/// another run's results or none that can be read (`sweep collect` names those). The file
/// (megabytes for a long sequence) is read once.
pub fn load_finished<T: serde::de::DeserializeOwned>(dir: &Path, cell: &Cell) -> anyhow::Result<Option<T>> {
    #[derive(Deserialize)]
    struct Progress {
        completed_steps: usize,
        total_steps: usize,
    }
    let CellRun::Planned { path, text } = read_cell(dir, cell) else { return Ok(None) };
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
    /// The cells left out of the estimates, each with why (another run's results in its
    /// folder, an unreadable `metrics.json`); empty when none is.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left_out: Vec<String>,
}

/// Collects the sweep in `dir` (see the module doc); nothing is written.
pub fn collect(dir: &Path) -> anyhow::Result<Collected> {
    let plan = Plan::load(dir)?;
    let mut groups = Vec::new();
    let mut left_out = Vec::new();
    for (name, indices) in plan.groups() {
        let mut cells = Vec::new();
        for &i in &indices {
            let cell = &plan.cells[i];
            let run = read_cell(dir, cell).run::<RunMeasures>(dir, cell).unwrap_or_else(|why| {
                left_out.push(why);
                None
            });
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
        left_out,
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
    if !table.left_out.is_empty() {
        out.push_str("\nLeft out of the estimates (the seeds column counts only the cells kept):\n");
        for why in &table.left_out {
            out.push_str(&format!("- {}\n", crate::util::text::one_line(why)));
        }
    }
    out
}

/// `text` as a Markdown table cell: on one line, its `|` escaped.
fn table_cell(text: &str) -> String {
    crate::util::text::one_line(text).replace('|', "\\|")
}

/// `header` and `rows` as a Markdown table padded to aligned columns.
pub fn aligned_table(header: &[String], rows: &[Vec<String>]) -> String {
    let escape = |cells: &[String]| cells.iter().map(|c| table_cell(c)).collect::<Vec<_>>();
    let (header, rows) = (escape(header), rows.iter().map(|r| escape(r)).collect::<Vec<_>>());
    let widths: Vec<usize> = (0..header.len())
        .map(|c| rows.iter().map(|r| r[c].chars().count()).chain([header[c].chars().count()]).max().unwrap_or(0))
        .collect();
    let line = |cells: &[String]| {
        let padded: Vec<String> = cells.iter().zip(&widths).map(|(c, w)| format!("{c:<w$}")).collect();
        format!("| {} |\n", padded.join(" | "))
    };
    let mut out = line(&header);
    out.push_str(&format!("|{}|\n", widths.iter().map(|w| "-".repeat(w + 2)).collect::<Vec<_>>().join("|")));
    for r in &rows {
        out.push_str(&line(r));
    }
    out
}
