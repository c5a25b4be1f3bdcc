//! Planning a sweep (`quadcl sweep plan FILE --out DIR`): the axes crossed into
//! cells, one run file per cell (`DIR/cells/I.toml`: the base run file with the
//! cell's values set), and `DIR/sweep.json`, the plan every other sweep command
//! reads (cells, names, groups, each cell's run file hash, the provenance).
//!
//! Every value is checked against the run file before anything is written: each
//! axis value alone on the base (an error names the sweep file and the key), then
//! each cell as a whole (values that are fine alone may clash together). A folder
//! that already holds this plan is left as it is (planning is idempotent, so a
//! script may plan and run again); one that holds another sweep is refused.

use super::file::{apply_axis_value, value_label, SweepFile, SEED_AXIS};
use super::{CELLS_DIR, PLAN_FILE, RUNS_DIR};
use crate::engine::RunConfig;
use crate::util::text::{clip, one_line};
use crate::util::{sha256_hex, write_atomic, Provenance};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The version of `sweep.json`'s layout.
pub const PLAN_FORMAT_VERSION: u32 = 1;

/// One cell: one run file and its run folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// The cell's number: `cells/INDEX.toml`, `runs/INDEX`, Slurm array task INDEX.
    pub index: usize,
    /// The cell's values as a name (`capacity=0.2 seed=1`).
    pub name: String,
    /// The name of its group: the values other than the seed (`capacity=0.2`).
    pub group: String,
    /// Each axis key with this cell's value.
    pub values: BTreeMap<String, serde_json::Value>,
    /// Its run file, relative to the sweep folder.
    pub config: String,
    /// Its run folder, relative to the sweep folder.
    pub run: String,
    /// sha256 of its run file (what the run's `metrics.json` provenance records too).
    pub run_file_sha256: String,
    /// Training iterations of each step of its sequence (progress is measured in them).
    pub iterations: Vec<usize>,
}

/// An axis as the plan records it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisRecord {
    pub key: String,
    pub values: Vec<serde_json::Value>,
}

/// `sweep.json`: the planned sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub format_version: u32,
    /// The sweep file as it was given.
    pub sweep_file: String,
    /// sha256 of the sweep file's text.
    pub sweep_file_sha256: String,
    /// The base run file as resolved.
    pub base: String,
    /// sha256 of the base run file's text.
    pub base_sha256: String,
    /// The axes in the order they cross.
    pub axes: Vec<AxisRecord>,
    /// The cells, `cells[i].index == i`.
    pub cells: Vec<Cell>,
    /// The build and machine that planned it.
    pub provenance: Provenance,
}

impl Plan {
    /// Reads `DIR/sweep.json`; errors name the file.
    pub fn load(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(PLAN_FILE);
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!("reading {} (plan a sweep with `quadcl sweep plan FILE --out DIR`)", path.display())
        })?;
        let plan: Plan =
            serde_json::from_str(&text).with_context(|| format!("{}: not a quadcl sweep plan", path.display()))?;
        anyhow::ensure!(
            plan.format_version == PLAN_FORMAT_VERSION,
            "{}: format version {} is not supported (this build reads {PLAN_FORMAT_VERSION})",
            path.display(),
            plan.format_version
        );
        for (i, c) in plan.cells.iter().enumerate() {
            anyhow::ensure!(c.index == i, "{}: cell {i} has index {}", path.display(), c.index);
        }
        Ok(plan)
    }

    /// The groups (cells that differ only in seed) in order of their first cell: (name, cell indices).
    pub fn groups(&self) -> Vec<(String, Vec<usize>)> {
        let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
        for c in &self.cells {
            match groups.iter_mut().find(|(g, _)| *g == c.group) {
                Some((_, cells)) => cells.push(c.index),
                None => groups.push((c.group.clone(), vec![c.index])),
            }
        }
        groups
    }

    /// Checks every cell's run file in the sweep folder `dir` before anything runs: the one
    /// planned (the hash `sweep.json` records) and a valid run file; errors name the file.
    pub fn check_cells(&self, dir: &Path) -> anyhow::Result<()> {
        for cell in &self.cells {
            let path = dir.join(&cell.config);
            let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
            anyhow::ensure!(
                sha256_hex(text.as_bytes()) == cell.run_file_sha256,
                "{}: changed since the sweep was planned (its sha256 is not the one in sweep.json): plan again \
                 into another folder",
                path.display()
            );
            RunConfig::load_text(&path, &text)?;
        }
        Ok(())
    }

    /// The seed of cell `index` (its `seed` axis value), if the sweep has a seed axis.
    pub fn seed_of(&self, index: usize) -> Option<&serde_json::Value> {
        self.cells.get(index)?.values.get(SEED_AXIS)
    }
}

/// A cell's run file text and what the plan records of it.
struct PlannedCell {
    cell: Cell,
    text: String,
}

/// Plans the sweep file `file` into the folder `out` (see the module doc); returns the plan.
pub fn plan(file: &Path, out: &Path) -> anyhow::Result<Plan> {
    let (plan, planned) = prepare(file)?;
    write_plan(out, &plan, &planned)
}

/// Plans the sweep file `file` and checks every cell without writing anything.
pub fn check(file: &Path) -> anyhow::Result<Plan> {
    Ok(prepare(file)?.0)
}

/// The plan of `file` and its cells' run files, every value checked.
fn prepare(file: &Path) -> anyhow::Result<(Plan, Vec<PlannedCell>)> {
    let sweep = SweepFile::load(file)?;
    let shown = file.display();
    let base_text = std::fs::read_to_string(&sweep.base)
        .with_context(|| format!("sweep file {shown}: base = {}: cannot read it", sweep.base.display()))?;
    RunConfig::load_text(&sweep.base, &base_text)
        .with_context(|| format!("sweep file {shown}: the base run file {} is not valid", sweep.base.display()))?;
    let base: toml::Value = toml::from_str(&base_text)
        .map_err(|e| anyhow::anyhow!("sweep file {shown}: base {}: {e}", sweep.base.display()))?;
    let base = with_absolute_run_paths(base, &sweep.base)
        .with_context(|| format!("sweep file {shown}: base {}", sweep.base.display()))?;
    // Each value alone first: the error then names the one key that is wrong.
    for axis in &sweep.axes {
        for value in &axis.values {
            let mut one = base.clone();
            apply_axis_value(&mut one, &axis.key, value)
                .and_then(|_| with_absolute_run_paths(one, &sweep.path))
                .and_then(|one| RunConfig::from_toml_str(&toml::to_string(&one)?))
                .with_context(|| {
                    format!("sweep file {shown}: [axes] \"{}\" = {}", axis.key, clip(&value.to_string()))
                })?;
        }
    }
    let names = short_names(&sweep);
    let mut planned = Vec::new();
    for (index, choice) in cross(&sweep).into_iter().enumerate() {
        planned.push(plan_cell(&sweep, &base, &names, index, &choice)?);
    }
    let plan = Plan {
        format_version: PLAN_FORMAT_VERSION,
        sweep_file: file.display().to_string(),
        sweep_file_sha256: sha256_hex(sweep.text.as_bytes()),
        base: sweep.base.display().to_string(),
        base_sha256: sha256_hex(base_text.as_bytes()),
        axes: sweep
            .axes
            .iter()
            .map(|a| AxisRecord { key: a.key.clone(), values: a.values.iter().map(json_of).collect() })
            .collect(),
        cells: planned.iter().map(|p| p.cell.clone()).collect(),
        provenance: Provenance::of_this_build(None),
    };
    Ok((plan, planned))
}

/// Writes the cells' run files and `sweep.json` into `out`, unless it already holds this plan.
fn write_plan(out: &Path, plan: &Plan, planned: &[PlannedCell]) -> anyhow::Result<Plan> {
    // Two plans into one folder at once would mix their cells: the check and the writes happen
    // under the folder's claim lock.
    let _claim = super::marker::claim_lock(out)?;
    if out.join(PLAN_FILE).exists() {
        let existing = Plan::load(out)?;
        let hashes = |p: &Plan| p.cells.iter().map(|c| c.run_file_sha256.clone()).collect::<Vec<_>>();
        anyhow::ensure!(
            hashes(&existing) == hashes(plan),
            "{} already holds another sweep (planned from {}): plan into another --out",
            out.display(),
            existing.sweep_file
        );
        return Ok(existing);
    }
    for p in planned {
        write_atomic(&out.join(&p.cell.config), p.text.as_bytes())?;
    }
    std::fs::create_dir_all(out.join(RUNS_DIR))
        .with_context(|| format!("creating {}", out.join(RUNS_DIR).display()))?;
    // The plan goes last: a folder with sweep.json has every cell's run file.
    write_atomic(&out.join(PLAN_FILE), serde_json::to_string_pretty(plan)?.as_bytes())?;
    Ok(plan.clone())
}

/// Cell `index` with the value `choice[a]` of each axis `a`: its run file, checked.
fn plan_cell(
    sweep: &SweepFile,
    base: &toml::Value,
    names: &[String],
    index: usize,
    choice: &[usize],
) -> anyhow::Result<PlannedCell> {
    let mut run = base.clone();
    let mut values = BTreeMap::new();
    let (mut name, mut group) = (Vec::new(), Vec::new());
    for ((axis, short), &c) in sweep.axes.iter().zip(names).zip(choice) {
        let value = &axis.values[c];
        apply_axis_value(&mut run, &axis.key, value)?;
        values.insert(axis.key.clone(), json_of(value));
        let part = format!("{short}={}", value_label(value));
        if axis.key != SEED_AXIS {
            group.push(part.clone());
        }
        name.push(part);
    }
    // A path an axis gives is found as the base's are (from here, else beside the sweep file).
    let run = with_absolute_run_paths(run, &sweep.path)?;
    let name = name.join(" ");
    let group = if group.is_empty() { "all".to_string() } else { group.join(" ") };
    let body = toml::to_string(&run)?;
    // The comment quotes user-given text (the sweep file's path, the values): on one line, so
    // that no line break in them can add a key to the run file.
    let text = format!(
        "# Cell {index} of the sweep {}: {}\n{body}",
        one_line(&sweep.path.display().to_string()),
        one_line(&name)
    );
    let config = format!("{CELLS_DIR}/{index}.toml");
    let cfg = RunConfig::from_toml_str(&text)
        .with_context(|| format!("sweep file {}: cell {index} ({name})", sweep.path.display()))?;
    let iterations = (0..cfg.sequence.tasks.len()).map(|i| cfg.sequence.iterations_of(i)).collect();
    let cell = Cell {
        index,
        name,
        group,
        values,
        config,
        run: format!("{RUNS_DIR}/{index}"),
        run_file_sha256: sha256_hex(text.as_bytes()),
        iterations,
    };
    Ok(PlannedCell { cell, text })
}

/// Every choice of one value per axis, the last axis varying fastest.
fn cross(sweep: &SweepFile) -> Vec<Vec<usize>> {
    let mut all = vec![Vec::new()];
    for axis in &sweep.axes {
        all = all
            .into_iter()
            .flat_map(|prefix: Vec<usize>| {
                (0..axis.values.len()).map(move |v| {
                    let mut c = prefix.clone();
                    c.push(v);
                    c
                })
            })
            .collect();
    }
    all
}

/// Each axis's name in cell names: its last key segment (`capacity`), or the whole key
/// when two axes share that segment.
fn short_names(sweep: &SweepFile) -> Vec<String> {
    let last = |k: &str| k.rsplit('.').next().unwrap_or(k).to_string();
    sweep
        .axes
        .iter()
        .map(|a| {
            let shared = sweep.axes.iter().filter(|b| last(&b.key) == last(&a.key)).count() > 1;
            if shared {
                a.key.clone()
            } else {
                last(&a.key)
            }
        })
        .collect()
}

fn json_of(value: &toml::Value) -> serde_json::Value {
    serde_json::to_value(value).unwrap_or_else(|_| serde_json::Value::String(value.to_string()))
}

/// The paths of a run file as absolute paths, found the way a run finds them (as given, else
/// beside the file `beside`): `[run] reference` and `base_policy`, and `[env] urdf` (a shipped
/// robot's description, `scenes/a1.urdf`, is left as it is: every build has it). A cell's run
/// file lives elsewhere, and runs from the sweep folder. A path found neither way is an error
/// here, not a cell that fails later.
fn with_absolute_run_paths(mut run: toml::Value, beside: &Path) -> anyhow::Result<toml::Value> {
    let folder = beside.parent().unwrap_or(Path::new("."));
    for (table, key) in [("run", "reference"), ("run", "base_policy"), ("env", "urdf")] {
        let Some(toml::Value::String(p)) = run.get_mut(table).and_then(|t| t.get_mut(key)) else { continue };
        let given = PathBuf::from(&*p);
        if table == "env" && given.is_relative() && crate::engine::is_shipped_description(&given) {
            continue;
        }
        let found = if given.is_relative() && !given.exists() { folder.join(&given) } else { given };
        if !found.exists() {
            let here = std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default();
            anyhow::bail!(
                "[{table}] {key} = \"{}\" exists neither from the current folder ({here}) nor beside {} \
                 ({}): plan from the folder its paths are relative to (the repository root for the shipped files)",
                clip(p),
                beside.display(),
                folder.display()
            );
        }
        if let Ok(absolute) = std::path::absolute(&found) {
            *p = absolute.display().to_string();
        }
    }
    Ok(run)
}
