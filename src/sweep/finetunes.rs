//! Sim-to-real fine-tunings over seeds (`quadcl sweep finetunes DIR`): DIR holds
//! one folder per seed, each with the `finetune.json` that `quadcl finetune --out
//! DIR/NAME` wrote (every learned task evaluated on the shifted robot before and
//! after fine-tuning one of them, with the same evaluation seeds). Per task, its
//! performance before and after as a mean over the seeds with its 90 % bootstrap
//! interval (`bootstrap`), the change paired within each seed, and the seeds at
//! which its evaluation changed at all (for every task but the fine-tuned one:
//! none, when fine-tuning forgets nothing); for the fine-tuned task also its fall
//! rate and tracking errors, seed by seed. Written as `DIR/finetunes.md` and
//! `.json`. Every report must fine-tune the same task on the same shift of the
//! same task list; the folders are read in natural order (`seed2` before
//! `seed10`).

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::collect::{aligned_table, estimate_text};
use crate::engine::{Evaluation, Shift, Sim2RealReport};
use crate::util::write_atomic;
use anyhow::{ensure, Context};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The report `quadcl finetune --out` writes beside its policy.
pub const FINETUNE_FILE: &str = "finetune.json";
/// `finetunes.md`, in the folder of the seeds' folders.
pub const FINETUNES_MD: &str = "finetunes.md";
/// `finetunes.json`, beside it.
pub const FINETUNES_JSON: &str = "finetunes.json";

/// A measure before and after fine-tuning, over the seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Change {
    pub before: Estimate,
    pub after: Estimate,
    /// After minus before, paired within each seed.
    pub after_minus_before: Estimate,
    /// Each seed's (before, after), in the order of `seeds`.
    pub per_seed: Vec<(f64, f64)>,
}

/// One task's performance on the shifted robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskChange {
    pub task: String,
    /// Whether it is the task that was fine-tuned.
    pub fine_tuned: bool,
    pub performance: Change,
    /// The seeds at which any part of its evaluation differs before and after.
    pub changed_at: Vec<String>,
}

/// The fine-tunings of one folder over its seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Finetunes {
    /// The task fine-tuned.
    pub task: String,
    pub shift: Shift,
    /// The seeds' folder names, in natural order.
    pub seeds: Vec<String>,
    pub confidence: f64,
    pub resamples: usize,
    /// Every learned task, in the policy's order.
    pub tasks: Vec<TaskChange>,
    /// The fine-tuned task's measures: (name as printed, change), performance first.
    pub fine_tuned_measures: Vec<(String, Change)>,
}

/// A folder name's natural sort key: its text before trailing digits, then their number.
fn natural_key(name: &str) -> (String, u64, String) {
    let digits = name.len() - name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    let (stem, number) = name.split_at(name.len() - digits);
    (stem.to_string(), number.parse().unwrap_or(0), name.to_string())
}

/// The fine-tuning reports under `dir`: (folder name, report), in natural order.
fn load_reports(dir: &Path) -> anyhow::Result<Vec<(String, PathBuf, Sim2RealReport)>> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("{}: cannot read the folder", dir.display()))?;
    let mut found = Vec::new();
    for entry in entries {
        let path = entry?.path().join(FINETUNE_FILE);
        if path.is_file() {
            let name = path.parent().and_then(|p| p.file_name()).unwrap_or_default().to_string_lossy().into_owned();
            found.push((name, path));
        }
    }
    ensure!(
        !found.is_empty(),
        "{}: no fine-tuning report (NAME/{FINETUNE_FILE}, as `quadcl finetune --out {}/NAME` writes)",
        dir.display(),
        dir.display()
    );
    found.sort_by_key(|(name, _)| natural_key(name));
    found
        .into_iter()
        .map(|(name, path)| {
            let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
            let report: Sim2RealReport = serde_json::from_str(&text)
                .with_context(|| format!("{}: not a report of `quadcl finetune`", path.display()))?;
            Ok((name, path, report))
        })
        .collect()
}

fn change(per_seed: Vec<(f64, f64)>) -> Change {
    let column = |f: fn(&(f64, f64)) -> f64| per_seed.iter().map(f).collect::<Vec<_>>();
    let some = |v: Vec<f64>| estimate(&v).expect("at least one seed");
    Change {
        before: some(column(|p| p.0)),
        after: some(column(|p| p.1)),
        after_minus_before: some(column(|p| p.1 - p.0)),
        per_seed,
    }
}

/// The fine-tunings under `dir` over their seeds.
pub fn finetunes(dir: &Path) -> anyhow::Result<Finetunes> {
    let reports = load_reports(dir)?;
    let (_, first_path, first) = &reports[0];
    let names = |evals: &[Evaluation]| evals.iter().map(|e| e.report.task.clone()).collect::<Vec<_>>();
    let tasks = names(&first.before);
    for (_, path, r) in &reports {
        ensure!(
            names(&r.after) == names(&r.before),
            "{}: the tasks evaluated after fine-tuning ({:?}) are not those before ({:?})",
            path.display(),
            names(&r.after),
            names(&r.before)
        );
        let same = r.task == first.task && r.shift == first.shift && names(&r.before) == tasks;
        ensure!(
            same,
            "{} and {}: not the same fine-tuning (task {} and {}, their shifts or learned tasks differ); \
             a folder holds the seeds of one",
            first_path.display(),
            path.display(),
            first.task,
            r.task
        );
        ensure!(tasks.contains(&r.task), "{}: the fine-tuned task {} is not evaluated", path.display(), r.task);
    }
    let seeds: Vec<String> = reports.iter().map(|(name, _, _)| name.clone()).collect();
    let rows = tasks
        .iter()
        .enumerate()
        .map(|(t, task)| {
            let pairs = reports.iter().map(|(_, _, r)| (r.before[t].performance, r.after[t].performance)).collect();
            let changed_at =
                reports.iter().filter(|(_, _, r)| r.before[t] != r.after[t]).map(|(name, _, _)| name.clone()).collect();
            TaskChange { task: task.clone(), fine_tuned: *task == first.task, performance: change(pairs), changed_at }
        })
        .collect();
    let t = tasks.iter().position(|x| *x == first.task).expect("checked above");
    let measure =
        |f: fn(&Evaluation) -> f64| change(reports.iter().map(|(_, _, r)| (f(&r.before[t]), f(&r.after[t]))).collect());
    let fine_tuned_measures = vec![
        ("performance".to_string(), measure(|e| e.performance)),
        ("fall rate".to_string(), measure(|e| e.report.fall_rate)),
        ("lin vel err (m/s)".to_string(), measure(|e| e.report.lin_vel_err)),
        ("ang vel err (rad/s)".to_string(), measure(|e| e.report.ang_vel_err)),
    ];
    Ok(Finetunes {
        task: first.task.clone(),
        shift: first.shift.clone(),
        seeds,
        confidence: CONFIDENCE,
        resamples: RESAMPLES,
        tasks: rows,
        fine_tuned_measures,
    })
}

/// [`finetunes`], written as `DIR/finetunes.md` and `.json`.
pub fn finetunes_and_write(dir: &Path) -> anyhow::Result<Finetunes> {
    let table = finetunes(dir)?;
    write_atomic(&dir.join(FINETUNES_MD), finetunes_markdown(&table).as_bytes())?;
    write_atomic(&dir.join(FINETUNES_JSON), serde_json::to_string_pretty(&table)?.as_bytes())?;
    Ok(table)
}

/// The shift in words: `friction 0.3-0.5, added mass 1-3 kg, ...`.
fn shift_text(s: &Shift) -> String {
    let range = |r: &Option<[f32; 2]>, name: &str, unit: &str| r.map(|[a, b]| format!("{name} {a}-{b}{unit}"));
    let mut parts: Vec<String> = [
        range(&s.friction, "friction", ""),
        range(&s.added_mass, "added mass", " kg"),
        range(&s.motor_strength, "motor strength", ""),
    ]
    .into_iter()
    .flatten()
    .collect();
    parts.push(format!("latency {} s", s.latency_s));
    parts.join(", ")
}

/// The fine-tunings as Markdown: every task before and after, then the fine-tuned task seed by seed.
pub fn finetunes_markdown(table: &Finetunes) -> String {
    let n = table.seeds.len();
    let mut out = format!(
        "Fine-tuning {} on the shifted robot ({}; {} iterations), {} seeds ({}): mean over seeds \
         [{:.0} % bootstrap interval, {} resamples of the seeds]\n\n",
        table.task,
        shift_text(&table.shift),
        table.shift.iterations,
        n,
        table.seeds.join(", "),
        table.confidence * 100.0,
        table.resamples
    );
    let header: Vec<String> = ["task", "performance before", "after", "after minus before", "evaluation unchanged at"]
        .map(String::from)
        .into();
    let rows: Vec<Vec<String>> = table
        .tasks
        .iter()
        .map(|t| {
            let name = if t.fine_tuned { format!("{} (fine-tuned)", t.task) } else { t.task.clone() };
            let unchanged = n - t.changed_at.len();
            let seeds = if t.changed_at.is_empty() {
                format!("{unchanged}/{n} seeds")
            } else {
                format!("{unchanged}/{n} seeds (changed: {})", t.changed_at.join(", "))
            };
            vec![
                name,
                estimate_text(&t.performance.before),
                estimate_text(&t.performance.after),
                estimate_text(&t.performance.after_minus_before),
                seeds,
            ]
        })
        .collect();
    out.push_str(&aligned_table(&header, &rows));
    let changed: Vec<&TaskChange> = table.tasks.iter().filter(|t| !t.fine_tuned && !t.changed_at.is_empty()).collect();
    if changed.is_empty() {
        out.push_str("\nEvery other task's evaluation is the same before and after, at every seed.\n");
    } else {
        let names: Vec<&str> = changed.iter().map(|t| t.task.as_str()).collect();
        out.push_str(&format!(
            "\nOther tasks whose evaluation changed: {} (fine-tuning must not touch them).\n",
            names.join(", ")
        ));
    }
    out.push_str(&format!("\n{}, seed by seed (before -> after):\n\n", table.task));
    let mut header = vec!["measure".to_string(), "before".into(), "after".into(), "after minus before".into()];
    header.extend(table.seeds.iter().cloned());
    let rows: Vec<Vec<String>> = table
        .fine_tuned_measures
        .iter()
        .map(|(name, c)| {
            let mut row = vec![
                name.clone(),
                estimate_text(&c.before),
                estimate_text(&c.after),
                estimate_text(&c.after_minus_before),
            ];
            row.extend(c.per_seed.iter().map(|(b, a)| format!("{b:.3} -> {a:.3}")));
            row
        })
        .collect();
    out.push_str(&aligned_table(&header, &rows));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_folders_sort_by_their_number_not_their_text() {
        let mut names = vec!["seed10", "seed2", "seed1", "other"];
        names.sort_by_key(|n| natural_key(n));
        assert_eq!(names, ["other", "seed1", "seed2", "seed10"]);
    }

    #[test]
    fn a_shift_names_only_the_ranges_it_sets() {
        let s = Shift { friction: Some([0.3, 0.5]), latency_s: 0.02, iterations: 200, ..Shift::default() };
        assert_eq!(shift_text(&s), "friction 0.3-0.5, latency 0.02 s");
    }
}
