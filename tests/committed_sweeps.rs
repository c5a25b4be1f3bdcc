//! Every sweep committed under `policies/` (a folder with `sweep.json`: the
//! baselines' tuning, the findings) carries the tables `quadcl sweep collect`
//! prints from its own run files, so no number in a committed table can drift
//! from the `metrics.json` it came from. Collecting writes nothing here: the
//! tables are computed and compared with the committed bytes.

use quadcl::sweep::{collect, markdown};
use std::path::{Path, PathBuf};

fn sweep_folders(dir: &Path, found: &mut Vec<PathBuf>) {
    if dir.join("sweep.json").exists() {
        found.push(dir.to_path_buf());
        return;
    }
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    entries.sort();
    for e in entries {
        sweep_folders(&e, found);
    }
}

#[test]
fn every_committed_sweeps_tables_are_what_collect_prints_from_its_run_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("policies");
    let mut folders = Vec::new();
    sweep_folders(&root, &mut folders);
    assert!(folders.len() >= 10, "only {} committed sweeps found under {}", folders.len(), root.display());
    for dir in folders {
        let table = collect(&dir).unwrap_or_else(|e| panic!("{}: {e:#}", dir.display()));
        let finished: usize = table.groups.iter().map(|g| g.finished).sum();
        assert!(finished > 0, "{}: a committed sweep with no finished cell", dir.display());
        let md = std::fs::read_to_string(dir.join("collected.md"))
            .unwrap_or_else(|e| panic!("{}: collected.md: {e}", dir.display()));
        assert_eq!(md, markdown(&table), "{}: collected.md differs from `quadcl sweep collect`", dir.display());
        let json = std::fs::read_to_string(dir.join("collected.json"))
            .unwrap_or_else(|e| panic!("{}: collected.json: {e}", dir.display()));
        assert_eq!(
            json,
            serde_json::to_string_pretty(&table).unwrap(),
            "{}: collected.json differs from `quadcl sweep collect`",
            dir.display()
        );
    }
}

#[test]
fn a_committed_table_edited_by_hand_is_caught() {
    // The comparison above must be able to fail: one digit changed in one cell's
    // metrics.json changes the collected table.
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/tuning/seeds-er");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seeds-er");
    copy_dir(&src, &dir);
    let before = markdown(&collect(&dir).unwrap());
    let metrics = dir.join("runs/0/metrics.json");
    let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
    let old = json["average_performance"].as_f64().unwrap();
    json["average_performance"] = serde_json::json!(old - 0.1);
    std::fs::write(&metrics, serde_json::to_string(&json).unwrap()).unwrap();
    let after = markdown(&collect(&dir).unwrap());
    assert_ne!(before, after, "a changed run file left the collected table as it was");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let target = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &target);
        } else {
            std::fs::copy(&p, &target).unwrap();
        }
    }
}
