//! `quadcl sweep collect DIR --plasticity-trend` on a sweep built here from the committed
//! fixture's plan (`tests/sweep_fixture/sweep.json`: capacity x seed, 2 x 3) with run folders
//! whose evaluation matrices have a known diagonal: each seed's halves, their difference and
//! slope, the intervals over seeds in closed form (values {x, x, y}: [x, x + 2 (y - x) / 3]),
//! an unfinished seed left out, and a seed that trained another sequence named as an error.

use quadcl::sweep::plasticity_trend::{PLASTICITY_TREND_JSON, PLASTICITY_TREND_MD};
use quadcl::sweep::{plasticity_trend, trend_markdown, PlasticityTrend};
use std::path::Path;
use std::process::Command;

const TASKS: [&str; 5] = ["none", "crash:FL", "invert:RR", "noise:FR", "crash:FR"];

/// A run's metrics.json whose step i trained task `order[i]` (an index into TASKS) and reached
/// `diagonal[i]` on it; every other entry of the matrix is 0.1. `completed` of the 4 steps.
fn metrics(order: [usize; 4], diagonal: [f64; 4], completed: usize) -> String {
    let rows: Vec<Vec<Option<f64>>> = (0..completed)
        .map(|i| (0..TASKS.len()).map(|j| Some(if j == order[i] { diagonal[i] } else { 0.1 })).collect())
        .collect();
    serde_json::json!({
        "completed_steps": completed,
        "total_steps": 4,
        "eval_matrix": { "tasks": TASKS, "trained": &order[..completed], "rows": rows },
        // What the collected table reads (left empty: not what this test is about).
        "average_performance": null, "forgetting": null, "forgetting_per_task": [], "plasticity": null,
        "forward_transfer": [], "forward_transfer_mean": null,
        "command_tracking": { "lin_vel_err": [], "ang_vel_err": [], "fall_rate": [] },
    })
    .to_string()
}

/// The fixture's plan in a new folder, cell i's run folder holding `runs[i]` (None: not started).
fn sweep(runs: [Option<String>; 6]) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep_fixture/sweep.json");
    std::fs::copy(fixture, tmp.path().join("sweep.json")).unwrap();
    for (i, run) in runs.into_iter().enumerate() {
        if let Some(text) = run {
            let dir = tmp.path().join(format!("runs/{i}"));
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join("metrics.json"), text).unwrap();
        }
    }
    tmp
}

const ORDER: [usize; 4] = [1, 2, 3, 4];
const FALLING: [f64; 4] = [0.8, 0.6, 0.4, 0.2];
const STEADY: [f64; 4] = [0.5; 4];

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn each_groups_trend_is_paired_within_seeds_with_its_interval_over_them() {
    let tmp = sweep([
        Some(metrics(ORDER, FALLING, 4)),
        Some(metrics(ORDER, STEADY, 4)),
        Some(metrics(ORDER, FALLING, 4)),
        Some(metrics(ORDER, STEADY, 4)),
        Some(metrics(ORDER, [0.2, 0.4, 0.6, 0.8], 4)),
        Some(metrics(ORDER, FALLING, 1)),
    ]);
    let table = plasticity_trend(tmp.path()).unwrap();
    let (a, b) = (&table.groups[0], &table.groups[1]);
    assert_eq!((a.name.as_str(), a.planned, a.finished), ("capacity=0.2", 3, 3));
    // Seeds 1 and 3 fall by 0.4 from the first half to the second (0.2 a step), seed 2 not.
    let d = a.second_minus_first.unwrap();
    assert!(close(d.mean, -0.8 / 3.0) && close(d.low, -0.4) && close(d.high, -0.4 + 0.8 / 3.0), "{d:?}");
    let s = a.slope.unwrap();
    assert!(close(s.mean, -0.4 / 3.0) && close(s.low, -0.2) && close(s.high, -0.2 + 0.4 / 3.0), "{s:?}");
    assert!(close(a.first_half.unwrap().mean, (0.7 + 0.5 + 0.7) / 3.0));
    // Step by step: the task trained at the step and its plasticity over the seeds.
    assert_eq!(a.steps.iter().map(|s| s.task.as_str()).collect::<Vec<_>>(), &TASKS[1..]);
    assert!(close(a.steps[3].plasticity.unwrap().mean, 0.3));
    // capacity=0.3: seed 3 stopped after its first task and is left out; seeds 1 and 2 cancel.
    assert_eq!((b.finished, b.seeds.len()), (2, 2));
    let d = b.second_minus_first.unwrap();
    assert!(close(d.mean, 0.2) && close(d.low, 0.0) && close(d.high, 0.4), "{d:?}");

    let md = trend_markdown(&table);
    let row = md.lines().find(|l| l.starts_with("| second minus first")).unwrap();
    assert!(row.contains("-0.267 [-0.400, -0.133]") && row.contains("| -0.400 | +0.000 | -0.400 |"), "{row}");
    let first = md.lines().find(|l| l.starts_with("| first half (steps 1-2)")).unwrap();
    assert!(first.contains("| 0.700  | 0.500  | 0.700  |"), "{first}");
    assert!(md.contains("| seed 1 ") && md.contains("| 4    | crash:FR  |"), "{md}");
}

#[test]
fn a_seed_that_trained_another_sequence_is_an_error_naming_its_run() {
    let tmp = sweep([Some(metrics(ORDER, STEADY, 4)), Some(metrics([1, 3, 2, 4], STEADY, 4)), None, None, None, None]);
    let err = format!("{:#}", plasticity_trend(tmp.path()).unwrap_err());
    assert!(err.contains("runs/1") && err.contains("runs/0") && err.contains("noise:FR"), "{err}");
}

#[test]
fn collect_writes_the_trend_it_prints_when_asked() {
    let tmp = sweep([
        Some(metrics(ORDER, FALLING, 4)),
        Some(metrics(ORDER, STEADY, 4)),
        Some(metrics(ORDER, FALLING, 4)),
        None,
        None,
        None,
    ]);
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["sweep", "collect", "--plasticity-trend"])
        .arg(tmp.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let md = std::fs::read_to_string(tmp.path().join(PLASTICITY_TREND_MD)).unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains(&md));
    let json: PlasticityTrend =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join(PLASTICITY_TREND_JSON)).unwrap()).unwrap();
    assert_eq!(json, plasticity_trend(tmp.path()).unwrap());
    assert_eq!(trend_markdown(&json), md);
}
