//! `sweep plan`: a sweep file's axes crossed into cells with names derived from their
//! values, one checked run file per cell, and every bad key or value refused, naming the
//! sweep file and the key, before anything is written.

use quadcl::engine::RunConfig;
use quadcl::sweep::{plan, Plan};
use std::path::{Path, PathBuf};

fn smoke() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")
}

/// A sweep file beside a copy of smoke.toml (the base named relative to it).
fn sweep_file(dir: &Path, axes: &str) -> PathBuf {
    std::fs::copy(smoke(), dir.join("smoke.toml")).unwrap();
    let path = dir.join("sweep.toml");
    std::fs::write(&path, format!("base = \"smoke.toml\"\n[axes]\n{axes}")).unwrap();
    path
}

#[test]
fn a_two_by_two_sweep_plans_four_named_cells_each_a_valid_run_file() {
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path(), "seed = [1, 2]\n\"net.mask.capacity\" = [0.2, 0.3]\n");
    let out = tmp.path().join("out");
    let p = plan(&file, &out).unwrap();
    let names: Vec<&str> = p.cells.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["capacity=0.2 seed=1", "capacity=0.2 seed=2", "capacity=0.3 seed=1", "capacity=0.3 seed=2"]);
    let groups = p.groups();
    assert_eq!(groups, vec![("capacity=0.2".to_string(), vec![0, 1]), ("capacity=0.3".to_string(), vec![2, 3])]);
    for (cell, (capacity, seed)) in p.cells.iter().zip([(0.2, 1), (0.2, 2), (0.3, 1), (0.3, 2)]) {
        let path = out.join(&cell.config);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(quadcl::util::sha256_hex(text.as_bytes()), cell.run_file_sha256);
        let run = RunConfig::load(&path).unwrap();
        assert_eq!((run.config.net.mask.capacity, run.config.seed), (capacity, seed));
        // Everything else is the base run file's.
        let base = RunConfig::load(&smoke()).unwrap();
        assert_eq!((run.sequence, run.config.ppo), (base.sequence, base.config.ppo));
        assert_eq!(cell.iterations, vec![3, 3, 3]);
    }
    assert_eq!(Plan::load(&out).unwrap(), p);
    // A cell's run file edited after planning is refused before anything runs (local or Slurm).
    p.check_cells(&out).unwrap();
    let cell0 = out.join(&p.cells[0].config);
    let edited = std::fs::read_to_string(&cell0).unwrap().replace("seed = 1", "seed = 9");
    std::fs::write(&cell0, &edited).unwrap();
    let err = format!("{:#}", p.check_cells(&out).unwrap_err());
    assert!(err.contains("cells/0.toml") && err.contains("changed since the sweep was planned"), "{err}");
    let err = format!("{:#}", quadcl::sweep::write_sbatch(&out, &Default::default()).unwrap_err());
    assert!(err.contains("changed since the sweep was planned"), "{err}");
    std::fs::write(&cell0, std::fs::read_to_string(&cell0).unwrap().replace("seed = 9", "seed = 1")).unwrap();
    // Planning the same sweep again keeps the folder; another sweep is refused.
    assert_eq!(plan(&file, &out).unwrap(), p);
    let other = sweep_file(tmp.path(), "seed = [1, 2, 3]\n");
    let err = format!("{:#}", plan(&other, &out).unwrap_err());
    assert!(err.contains("already holds another sweep"), "{err}");
}

#[test]
fn a_method_axis_and_a_list_index_reach_their_keys() {
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path(), "\"method.name\" = [\"ours\", \"finetune\"]\n\"task.1.iterations\" = [2]\n");
    let p = plan(&file, &tmp.path().join("out")).unwrap();
    assert_eq!(p.cells[1].name, "name=finetune iterations=2");
    let run = RunConfig::load(&tmp.path().join("out").join(&p.cells[1].config)).unwrap();
    assert_eq!(run.method, "finetune");
    assert_eq!(p.cells[1].iterations, vec![3, 2, 3]);
}

#[test]
fn a_bad_key_or_a_refused_value_names_the_sweep_file_and_the_key_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    for (axes, needles) in [
        ("\"net.mask.capacty\" = [0.2]\nseed = [1]\n", vec!["net.mask.capacty", "capacty"]),
        ("\"net.mask.capacity\" = [0.2, 1.5]\n", vec!["\"net.mask.capacity\" = 1.5", "capacity"]),
        ("seed = [1, \"two\"]\n", vec!["\"seed\" = \"two\""]),
        ("\"ppo.num_envs\" = [0]\n", vec!["\"ppo.num_envs\" = 0", "num_envs"]),
        ("\"method.name\" = [\"ourz\"]\n", vec!["\"method.name\" = \"ourz\"", "ourz"]),
        ("seed = []\n", vec!["\"seed\"", "empty"]),
    ] {
        let file = sweep_file(tmp.path(), axes);
        let out = tmp.path().join("never");
        let err = format!("{:#}", plan(&file, &out).unwrap_err());
        assert!(err.contains(&file.display().to_string()), "{axes}: {err}");
        for n in needles {
            assert!(err.contains(n), "{axes}: expected {n:?} in {err}");
        }
        assert!(!out.exists(), "{axes}: nothing is written before every cell is checked");
    }
}

#[test]
fn a_base_policy_found_neither_from_here_nor_beside_the_base_is_refused_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path(), "seed = [1]\n");
    let base = tmp.path().join("smoke.toml");
    let text = std::fs::read_to_string(&base).unwrap();
    std::fs::write(&base, format!("{text}\n[run]\nbase_policy = \"policies/no-such-base\"\n")).unwrap();
    let out = tmp.path().join("never");
    let err = format!("{:#}", plan(&file, &out).unwrap_err());
    for needle in [file.display().to_string(), "base_policy".into(), "policies/no-such-base".into()] {
        assert!(err.contains(&needle), "expected {needle:?} in {err}");
    }
    assert!(!out.exists(), "nothing is written");

    // Beside the base it is found, and the cell names it by its absolute path.
    std::fs::create_dir_all(tmp.path().join("policies/no-such-base")).unwrap();
    let p = plan(&file, &out).unwrap();
    let cell = std::fs::read_to_string(out.join("cells").join("0.toml")).unwrap();
    assert!(cell.contains(&tmp.path().join("policies/no-such-base").display().to_string()), "{cell}");
    assert_eq!(p.cells.len(), 1);
}

#[test]
fn a_newline_in_a_sweep_value_cannot_add_a_key() {
    let tmp = tempfile::tempdir().unwrap();
    // A robot description whose file name holds a line break and a run file key after it.
    let odd = tmp.path().join("a1.urdf\nrun = { keep_last_checkpoint_only = true }");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/a1.urdf"), &odd).unwrap();
    let axis = toml::Value::String(odd.display().to_string());
    let file = sweep_file(tmp.path(), &format!("\"env.urdf\" = [{axis}]\n"));
    // The sweep file's own path holds one too.
    let odd_file = tmp.path().join("sweep\n[run]\nkeep_last_checkpoint_only = true\n#.toml");
    std::fs::rename(&file, &odd_file).unwrap();
    let out = tmp.path().join("out");
    let p = plan(&odd_file, &out).unwrap();
    let path = out.join(&p.cells[0].config);
    let text = std::fs::read_to_string(&path).unwrap();
    let run = RunConfig::load(&path).unwrap();
    assert!(!run.run.keep_last_checkpoint_only, "a key came from a value:\n{text}");
    assert_eq!(run.config.env.urdf, odd.display().to_string(), "the value itself is kept whole");
    let comment = text.lines().next().unwrap();
    assert!(comment.starts_with("# Cell 0") && comment.contains("\\n"), "{comment}");
    let toml: toml::Table = toml::from_str(&text).unwrap();
    assert_eq!(toml.get("run").and_then(|r| r.get("keep_last_checkpoint_only")), None, "{text}");
}

#[test]
fn a_path_value_that_does_not_exist_is_refused_when_planning() {
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path(), "\"env.urdf\" = [\"scenes/a1.urdf\", \"robots/no-such.urdf\"]\n");
    let out = tmp.path().join("never");
    let err = format!("{:#}", plan(&file, &out).unwrap_err());
    for needle in ["env.urdf", "robots/no-such.urdf", "exists neither"] {
        assert!(err.contains(needle), "expected {needle:?} in {err}");
    }
    assert!(!out.exists(), "nothing is written");
    // A shipped description stays as the run file names it (every build has it).
    let file = sweep_file(tmp.path(), "\"env.urdf\" = [\"scenes/a1.urdf\"]\n");
    let p = plan(&file, &out).unwrap();
    assert_eq!(RunConfig::load(&out.join(&p.cells[0].config)).unwrap().config.env.urdf, "scenes/a1.urdf");
}

#[test]
fn two_sweeps_planned_into_one_folder_at_once_never_mix_their_cells() {
    for _ in 0..5 {
        let tmp = tempfile::tempdir().unwrap();
        let a = sweep_file(tmp.path(), "seed = [1, 2]\n");
        let b = tmp.path().join("b.toml");
        std::fs::write(&b, "base = \"smoke.toml\"\n[axes]\nseed = [3, 4, 5]\n").unwrap();
        let out = tmp.path().join("out");
        let (oa, ob) = (out.clone(), out.clone());
        let ta = std::thread::spawn(move || plan(&a, &oa));
        let tb = std::thread::spawn(move || plan(&b, &ob));
        let results = [ta.join().unwrap(), tb.join().unwrap()];
        assert_eq!(results.iter().filter(|r| r.is_ok()).count(), 1, "one plan wins, the other is refused");
        let kept = Plan::load(&out).unwrap();
        for cell in &kept.cells {
            let text = std::fs::read_to_string(out.join(&cell.config)).unwrap();
            assert_eq!(quadcl::util::sha256_hex(text.as_bytes()), cell.run_file_sha256, "cell {}", cell.index);
        }
        let files = std::fs::read_dir(out.join("cells")).unwrap().count();
        assert_eq!(files, kept.cells.len(), "no cell file of the refused sweep");
    }
}
