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
