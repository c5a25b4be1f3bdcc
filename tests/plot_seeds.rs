//! A sweep folder in `quadcl plot`: one run per group, the mean of its seeds with their range
//! as a band, on the committed sweep `policies/tuning/seeds-er` (2 groups x 3 seeds of real
//! runs): each group's curve is the mean of its three cells' curves, inside its band, and the
//! command's figures name every group with its number of seeds.

use quadcl::plot::{load_run, load_sweep, Measure};
use std::path::{Path, PathBuf};
use std::process::Command;

fn sweep() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/tuning/seeds-er")
}

#[test]
fn a_sweeps_group_is_drawn_as_the_mean_of_its_seeds_inside_their_range() {
    let groups = load_sweep(&sweep()).unwrap();
    let labels: Vec<&str> = groups.iter().map(|g| g.label.as_str()).collect();
    assert_eq!(
        labels,
        ["beta=0.01 name=er (mean of 3 seeds, range shaded)", "beta=1.0 name=er (mean of 3 seeds, range shaded)"]
    );
    // Cells 0-2 are the first group's seeds 1-3 (sweep.json).
    let cells: Vec<_> = (0..3).map(|i| load_run(&sweep().join(format!("runs/{i}")), None).unwrap()).collect();
    for (step, curves) in groups[0].steps.iter().enumerate() {
        let drawn = curves.curve(Measure::Performance);
        let band = drawn.band.as_ref().unwrap();
        assert!(drawn.points.len() > 100 && band.len() == drawn.points.len(), "step {step}");
        for (k, ((x, mean), (low, high))) in drawn.points.iter().zip(band).enumerate().step_by(37) {
            let seeds: Vec<f64> = cells.iter().map(|c| c.steps[step].performance.points[k].1).collect();
            assert!(cells.iter().all(|c| c.steps[step].performance.points[k].0 == *x), "step {step}, point {k}");
            assert!((mean - seeds.iter().sum::<f64>() / 3.0).abs() < 1e-12, "step {step} at {x}: {mean} vs {seeds:?}");
            assert!(low <= mean && mean <= high && seeds.iter().all(|s| low <= s && s <= high), "{low} {mean} {high}");
        }
    }
    let matrix = groups[0].eval_matrix.as_ref().unwrap();
    let last: f64 = cells.iter().map(|c| c.eval_matrix.as_ref().unwrap().rows[1][2].unwrap()).sum::<f64>() / 3.0;
    assert!((matrix.rows[1][2].unwrap() - last).abs() < 1e-12, "the matrix is the seeds' mean");
}

#[test]
fn the_plot_command_names_each_group_of_a_sweep_with_its_seeds() {
    let out = tempfile::tempdir().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["plot", sweep().to_str().unwrap(), "--out", out.path().to_str().unwrap(), "--label", "ER"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let svg = std::fs::read_to_string(out.path().join("task_curves.svg")).unwrap();
    for name in
        ["ER beta=0.01 name=er (mean of 3 seeds, range shaded)", "ER beta=1.0 name=er (mean of 3 seeds, range shaded)"]
    {
        assert!(svg.contains(name), "task_curves.svg does not name {name}");
    }
    // The summary: a row per group, the collected table's measures as panels.
    let summary = std::fs::read_to_string(out.path().join("summary.svg")).unwrap();
    for text in ["ER beta=0.01 name=er (3 seeds)", "ER beta=1.0 name=er (3 seeds)", "average performance", "forgetting"]
    {
        assert!(summary.contains(text), "summary.svg does not show {text}");
    }
    assert!(!summary.contains("forward transfer"), "no run of this sweep has a forward transfer");
}

#[test]
fn a_groups_summary_is_its_collected_rows_mean_interval_and_seeds() {
    let groups = load_sweep(&sweep()).unwrap();
    let table = quadcl::sweep::collect(&sweep()).unwrap();
    assert_eq!(groups.len(), table.groups.len());
    for (drawn, row) in groups.iter().zip(&table.groups) {
        let over = drawn.over_seeds.as_ref().unwrap();
        assert_eq!((over.group.as_str(), over.seeds), (row.name.as_str(), row.finished));
        for m in &over.measures {
            assert_eq!(m.estimate, row.measures[&m.key], "{} {}", row.name, m.key);
            let seeds: Vec<f64> = row.cells.iter().filter_map(|c| c.measures.get(&m.key).copied()).collect();
            assert_eq!(m.values, seeds, "{} {}", row.name, m.key);
        }
        let keys: Vec<&str> = over.measures.iter().map(|m| m.key.as_str()).collect();
        let table_keys: Vec<&str> = row.measures.keys().map(String::as_str).collect();
        assert_eq!(keys.len(), table_keys.len(), "{keys:?} {table_keys:?}");
    }
}
