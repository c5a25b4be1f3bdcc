//! Every sweep committed under `policies/` (a folder with `sweep.json`: the
//! baselines' tuning, the findings) carries the tables `quadcl sweep collect`
//! prints from its own run files, so no number in a committed table can drift
//! from the `metrics.json` it came from. Collecting writes nothing here: the
//! tables are computed and compared with the committed bytes.

use quadcl::sweep::contrast::contrast_across;
use quadcl::sweep::{
    collect, collect_tasks, contrast, contrast_markdown, markdown, plasticity_trend, tasks_markdown, trend_markdown,
    Contrast,
};
use quadcl::sweep::{finetunes, finetunes_markdown};
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
        check_folder(&dir);
    }
}

/// Folders under `dir` that hold fine-tuning reports (`NAME/finetune.json`, one per seed).
fn finetune_folders(dir: &Path, found: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    entries.sort();
    if entries.iter().any(|e| e.join("finetune.json").is_file()) {
        found.push(dir.to_path_buf());
        return;
    }
    for e in entries {
        finetune_folders(&e, found);
    }
}

#[test]
fn every_committed_fine_tuning_table_is_what_the_command_prints_from_its_reports() {
    let mut folders = Vec::new();
    finetune_folders(&Path::new(env!("CARGO_MANIFEST_DIR")).join("policies"), &mut folders);
    for dir in folders {
        let md = std::fs::read_to_string(dir.join("finetunes.md")).unwrap_or_else(|_| {
            panic!("{}: fine-tuning reports without finetunes.md (quadcl sweep finetunes)", dir.display())
        });
        let table = finetunes(&dir).unwrap_or_else(|e| panic!("{}: {e:#}", dir.display()));
        assert_eq!(md, finetunes_markdown(&table), "{}: finetunes.md differs", dir.display());
        let json = std::fs::read_to_string(dir.join("finetunes.json")).unwrap();
        assert_eq!(json, serde_json::to_string_pretty(&table).unwrap(), "{}", dir.display());
    }
}

/// The tables in `dir` are what `quadcl sweep collect` computes from its run files; the number
/// of contrast files checked.
fn check_folder(dir: &Path) -> usize {
    let dir = dir.to_path_buf();
    {
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
        // The per-task tables, where the folder ships them (`sweep collect --per-task`).
        if let Ok(md) = std::fs::read_to_string(dir.join("collected-tasks.md")) {
            let tasks = collect_tasks(&dir).unwrap_or_else(|e| panic!("{}: {e:#}", dir.display()));
            assert_eq!(md, tasks_markdown(&tasks), "{}: collected-tasks.md differs", dir.display());
            let json = std::fs::read_to_string(dir.join("collected-tasks.json")).unwrap();
            assert_eq!(json, serde_json::to_string_pretty(&tasks).unwrap(), "{}", dir.display());
        }
        // Plasticity over the sequence, where the folder ships it (`--plasticity-trend`).
        if let Ok(md) = std::fs::read_to_string(dir.join("plasticity-trend.md")) {
            let trend = plasticity_trend(&dir).unwrap_or_else(|e| panic!("{}: {e:#}", dir.display()));
            assert_eq!(md, trend_markdown(&trend), "{}: plasticity-trend.md differs", dir.display());
            let json = std::fs::read_to_string(dir.join("plasticity-trend.json")).unwrap();
            assert_eq!(json, serde_json::to_string_pretty(&trend).unwrap(), "{}", dir.display());
        }
        // The paired differences, against the baseline each shipped file names (`--against`,
        // in this folder or another: `contrast-vs-OTHER.json`).
        let mut contrasts: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                let name = p.file_name().unwrap().to_string_lossy();
                name.starts_with("contrast") && name.ends_with(".json")
            })
            .collect();
        contrasts.sort();
        let checked = contrasts.len();
        for file in contrasts {
            let json = std::fs::read_to_string(&file).unwrap();
            let shipped: Contrast = serde_json::from_str(&json).unwrap();
            let now = match &shipped.baseline_sweep {
                None => contrast(&table, &shipped.baseline).unwrap(),
                Some(other) => {
                    let other_table = collect(&dir.join(other)).unwrap();
                    contrast_across(&table, &other_table, other, &shipped.baseline).unwrap()
                }
            };
            assert_eq!(json, serde_json::to_string_pretty(&now).unwrap(), "{} differs", file.display());
            let md = std::fs::read_to_string(file.with_extension("md")).unwrap();
            assert_eq!(md, contrast_markdown(&now), "{} differs", file.with_extension("md").display());
        }
        checked
    }
}

#[test]
fn a_contrast_against_another_sweeps_group_is_checked_from_both_folders() {
    let policies = Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/tuning");
    let tmp = tempfile::tempdir().unwrap();
    for name in ["seeds-er", "seeds-rwalk"] {
        copy_dir(&policies.join(name), &tmp.path().join(name));
    }
    let er = tmp.path().join("seeds-er");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["sweep", "collect", er.to_str().unwrap(), "--against", "lambda=1.0", "--against-in"])
        .arg(tmp.path().join("seeds-rwalk"))
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(er.join("contrast-vs-seeds-rwalk.json")).unwrap()).unwrap();
    assert_eq!(written["baseline_sweep"], "../seeds-rwalk");
    assert_eq!(check_folder(&er), 2, "contrast.json and contrast-vs-seeds-rwalk.json");
    // The other folder's run files changed: the shipped table no longer matches.
    let metrics = tmp.path().join("seeds-rwalk/runs/3/metrics.json");
    let text = std::fs::read_to_string(&metrics).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["average_performance"] = serde_json::json!(json["average_performance"].as_f64().unwrap() + 0.2);
    std::fs::write(&metrics, serde_json::to_string(&json).unwrap()).unwrap();
    let changed = std::panic::catch_unwind(|| check_folder(&er));
    assert!(changed.is_err(), "a changed baseline run left the cross-sweep contrast as shipped");
}

#[test]
fn per_task_rows_are_each_tasks_values_after_the_last_step_over_the_seeds() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/tuning/seeds-er");
    let table = collect_tasks(&dir).unwrap();
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(table.groups.len(), 2);
    for group in &table.groups {
        assert_eq!((group.finished, group.planned), (3, 3), "{}", group.name);
        let names: Vec<&str> = group.tasks.iter().map(|t| t.task.as_str()).collect();
        assert_eq!(names, ["none", "crash:FL", "invert:RL"]);
        // The group's runs, read directly: the last row of each evaluation matrix and the fall rates.
        let runs: Vec<serde_json::Value> = plan["cells"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["group"] == group.name.as_str())
            .map(|c| {
                let path = dir.join(c["run"].as_str().unwrap()).join("metrics.json");
                serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
            })
            .collect();
        assert_eq!(runs.len(), 3, "{}", group.name);
        for (j, row) in group.tasks.iter().enumerate() {
            let mean = |f: &dyn Fn(&serde_json::Value) -> f64| runs.iter().map(f).sum::<f64>() / 3.0;
            let last = |m: &serde_json::Value| {
                m["eval_matrix"]["rows"].as_array().unwrap().last().unwrap()[j].as_f64().unwrap()
            };
            let fall = |m: &serde_json::Value| m["command_tracking"]["fall_rate"][j].as_f64().unwrap();
            assert!((row.measures["performance"].mean - mean(&last)).abs() < 1e-12, "{} {}", group.name, row.task);
            assert!((row.measures["fall_rate"].mean - mean(&fall)).abs() < 1e-12, "{} {}", group.name, row.task);
            assert_eq!(row.measures.contains_key("forgetting"), row.task == "crash:FL", "{}", row.task);
        }
    }
    let md = tasks_markdown(&table);
    assert!(md.contains("| invert:RL |") && md.contains("(3/3 seeds)"), "{md}");
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
