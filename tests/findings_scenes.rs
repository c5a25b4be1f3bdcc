//! The findings' sweep files (issues 34 and 60, `scenes/findings/`) plan as their headers say: every
//! cell's run file is checked (`sweep::check`, nothing written), and each sweep has its cells
//! and at least three seeds per variant (the budget is the base file's, or an axis of one
//! value, the same for all).
//! fig11-transfer measures forward transfer against fig11-reference's seed-1 run, so until
//! that has run its planning is refused naming the missing file.

use quadcl::sweep::check;
use std::path::{Path, PathBuf};

fn findings(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/findings").join(format!("{name}.toml"))
}

#[test]
fn each_findings_sweep_plans_its_cells_with_three_seeds_per_variant() {
    for (name, cells, variants) in [
        ("sequence-12", 3, 1),
        ("fig4-methods", 30, 10),
        ("fig4-budget", 6, 2),
        ("fig5-selection", 9, 3),
        ("fig8-plasticity", 12, 4),
        ("fig11-reference", 3, 1),
        ("ladder", 18, 6),
        ("ladder-candidates", 18, 6),
        ("paper-shape", 12, 4),
    ] {
        let plan = check(&findings(name)).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_eq!(plan.cells.len(), cells, "{name}");
        let groups = plan.groups();
        assert_eq!(groups.len(), variants, "{name}");
        for (group, indices) in &groups {
            assert!(indices.len() >= 3, "{name}: {group} has {} seeds", indices.len());
        }
    }
}

#[test]
fn fig11_transfer_waits_for_its_reference_run_and_says_which() {
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("runs/findings/fig11-reference/runs/0/metrics.json");
    if reference.exists() {
        let plan = check(&findings("fig11-transfer")).unwrap();
        assert_eq!((plan.cells.len(), plan.groups().len()), (9, 3));
    } else {
        let err = format!("{:#}", check(&findings("fig11-transfer")).unwrap_err());
        assert!(err.contains("fig11-reference/runs/0/metrics.json"), "{err}");
    }
}

#[test]
fn the_ladders_fresh_weight_arms_redraw_the_bases_vacant_weights_and_refuse_a_dense_method() {
    use quadcl::engine::{make_learner, RunConfig};
    let path = findings("ladder-task");
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |extra: &str| text.replace("[run]\n", &format!("[run]\n{extra}"));
    let learned = |t: &str| make_learner(&RunConfig::load_text(&path, t).unwrap()).map(|(_, tasks)| tasks);
    let redrawn = with("base_vacant = \"redrawn\"\n");
    assert_eq!(learned(&redrawn).unwrap(), learned(&text).unwrap(), "the base's tasks are kept");
    let dense = redrawn.replace("name = \"ours\"", "name = \"finetune\"");
    let err = format!("{:#}", learned(&dense).expect_err("a dense method has no vacant weights"));
    assert!(err.contains("base_vacant") && err.contains("finetune"), "{err}");
}
