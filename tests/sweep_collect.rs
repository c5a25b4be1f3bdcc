//! `sweep collect` on a committed fixture (`tests/sweep_fixture`: a planned 2 x 3 sweep,
//! capacity x seed, whose run folders hold small metrics.json files, one of them stopped
//! after its first task): per group the mean and the 90 % bootstrap interval over the
//! finished seeds, known in closed form (with two seeds the interval is their range; with
//! values {x, x, y} it is [x, x + 2 (y - x) / 3]), and the stopped cell left out.

use quadcl::sweep::{collect, markdown};
use std::path::Path;

fn fixture() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/sweep_fixture"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn the_fixture_collects_into_the_known_means_and_intervals() {
    let table = collect(fixture()).unwrap();
    assert_eq!(table.groups.len(), 2);
    let (a, b) = (&table.groups[0], &table.groups[1]);
    assert_eq!((a.name.as_str(), a.planned, a.finished), ("capacity=0.2", 3, 3));
    assert_eq!((b.name.as_str(), b.planned, b.finished), ("capacity=0.3", 3, 2));
    let expect = |g: &quadcl::sweep::CollectedGroup, key: &str, mean: f64, low: f64, high: f64, n: usize| {
        let e = g.measures[key];
        assert!(
            close(e.mean, mean) && close(e.low, low) && close(e.high, high) && e.n == n,
            "{}: {key}: {e:?}",
            g.name
        );
    };
    // capacity=0.2: average performance {0.4, 0.7, 0.4}.
    expect(a, "average_performance", 0.5, 0.4, 0.6, 3);
    expect(a, "plasticity", 0.6, 0.5, 0.7, 3);
    // Fall rates averaged over each run's tasks: {0.375, 0.25, 0.25}.
    expect(a, "fall_rate", 0.875 / 3.0, 0.25, 0.25 + 2.0 * 0.125 / 3.0, 3);
    expect(a, "forgetting", 0.0, 0.0, 0.0, 3);
    expect(a, "lin_vel_err", 0.5, 0.5, 0.5, 3);
    // capacity=0.3: seeds 1 and 2 ({0.5, 0.3}); seed 3 stopped after one task is left out.
    expect(b, "average_performance", 0.4, 0.3, 0.5, 2);
    expect(b, "fall_rate", 0.25, 0.0, 0.5, 2);
    assert!(!b.cells[2].finished && b.cells[2].measures.is_empty());
    assert_eq!(b.cells[2].run, "runs/5", "each group lists its cells' run folders");
    assert_eq!(b.cells[0].seed, Some(serde_json::json!(1)));
    // No run has a forward-transfer reference: the measure is absent, a dash in the table.
    assert!(!a.measures.contains_key("forward_transfer"));
    let md = markdown(&table);
    let row = md.lines().find(|l| l.starts_with("| capacity=0.3")).unwrap();
    assert!(row.contains("| 2/3 ") && row.contains("0.400 [0.300, 0.500]") && row.contains("| -"), "{row}");
    // The same table every time.
    assert_eq!(collect(fixture()).unwrap(), table);
}

/// A copy of the fixture to change.
fn fixture_copy() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let copy = |from: &Path, to: &Path| {
        for entry in walk(from) {
            let target = to.join(entry.strip_prefix(from).unwrap());
            std::fs::create_dir_all(target.parent().unwrap()).unwrap();
            std::fs::copy(&entry, &target).unwrap();
        }
    };
    copy(fixture(), tmp.path());
    tmp
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// Cell `cell`'s metrics.json with its provenance recording `run_file_sha256`.
fn record_run_file(dir: &Path, cell: usize, run_file_sha256: &str) {
    let path = dir.join(format!("runs/{cell}/metrics.json"));
    let mut m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    m["provenance"] = serde_json::json!({
        "quadcl_version": "0.1.0", "git_commit": "unknown", "git_dirty": null,
        "run_file_sha256": run_file_sha256, "cores": 2, "threads": 2
    });
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
}

#[test]
fn a_foreign_cell_is_left_out_by_collect_and_named_by_status() {
    let tmp = fixture_copy();
    let dir = tmp.path();
    let planned = quadcl::sweep::Plan::load(dir).unwrap().cells[0].run_file_sha256.clone();
    // Cell 0 records the run file the plan wrote: kept. Cell 1 holds another sweep's run
    // (another run file): left out, as is cell 2, whose metrics.json is torn.
    record_run_file(dir, 0, &planned);
    record_run_file(dir, 1, &"f".repeat(64));
    std::fs::write(dir.join("runs/2/metrics.json"), "{\"completed_steps\": 3, \"tot").unwrap();
    let table = collect(dir).unwrap();
    let a = &table.groups[0];
    assert_eq!((a.planned, a.finished), (3, 1), "only cell 0 of capacity=0.2 counts");
    assert_eq!(a.measures["average_performance"].n, 1);
    assert_eq!(table.left_out.len(), 2, "{:?}", table.left_out);
    assert!(
        table.left_out[0].starts_with("cell 1 (") && table.left_out[0].contains("ffffffffffff"),
        "{:?}",
        table.left_out
    );
    assert!(
        table.left_out[1].starts_with("cell 2 (") && table.left_out[1].contains("metrics.json"),
        "{:?}",
        table.left_out
    );
    let md = markdown(&table);
    let row = md.lines().find(|l| l.starts_with("| capacity=0.2")).unwrap();
    assert!(row.contains("| 1/3 "), "{row}");
    assert!(md.contains("Left out of the estimates") && md.contains("- cell 1 ("), "{md}");
    // The other group is untouched.
    assert_eq!(table.groups[1], collect(fixture()).unwrap().groups[1]);

    let cells = quadcl::sweep::status(dir, false).unwrap();
    let state = |i: usize| cells[i].state;
    use quadcl::sweep::CellState;
    assert_eq!((state(0), state(1), state(2)), (CellState::Finished, CellState::Foreign, CellState::Foreign));
    let lines = quadcl::sweep::status_lines(&cells);
    assert!(lines.contains("foreign") && lines.contains("2 foreign"), "{lines}");
}
