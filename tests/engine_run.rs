//! Headless runs (`quadcl run`) on the toy masked learner: the metrics.json
//! fields, resume after an interruption gives the same metrics as an
//! uninterrupted run, and a corrupt checkpoint or config is a clear error
//! that leaves the existing results intact.

mod engine_common;
use engine_common::assert_metrics_json_complete;
use quadcl::engine::MetricsFile;
use quadcl::headless::{run, RunOptions};
use std::path::{Path, PathBuf};

const RUN: &str = "seed = 11\niterations = 5\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 2\n\
[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\niterations = 7\n[[task]]\nname = \"noise:FR\"\n[task.switches]\nreinit = false\n";

fn write_run(dir: &Path, text: &str) -> PathBuf {
    write_named(dir, "run.toml", text)
}

fn write_named(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn opts(resume: bool, stop_after: Option<usize>) -> RunOptions {
    RunOptions { resume, progress: false, stop_after, ..Default::default() }
}

#[test]
fn a_run_writes_every_metrics_field_checkpoints_and_a_log() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write_run(tmp.path(), RUN);
    let out = tmp.path().join("out");
    let m = run(&cfg, &out, opts(false, None)).unwrap();
    assert_eq!((m.completed_steps, m.total_steps), (3, 3));
    let json = assert_metrics_json_complete(&out);
    assert_eq!(json["method"], "ours");
    assert_eq!(json["forgetting"], 0.0);
    assert_eq!(json["eval_matrix"]["rows"].as_array().unwrap().len(), 3);
    assert_eq!(json["curves"][1]["performance"].as_array().unwrap().len(), 7);
    assert!(json["command_tracking"]["lin_vel_err"][0].is_f64());
    assert_eq!(json["steps"][2]["switches"]["reinit_weights"], false);
    for (step, task) in [(0, "crash_FL"), (1, "invert_RR"), (2, "noise_FR")] {
        assert!(out.join(format!("checkpoints/step-{step:02}-{task}/manifest.json")).exists());
    }
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert!(log.contains("task_started") && log.contains("after step 2: crash:FL"), "{log}");
}

#[test]
fn resume_after_an_interruption_gives_the_same_metrics_as_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write_run(tmp.path(), RUN);
    let whole = run(&cfg, &tmp.path().join("whole"), opts(false, None)).unwrap();
    let out = tmp.path().join("parts");
    let first = run(&cfg, &out, opts(false, Some(1))).unwrap();
    assert_eq!(first.completed_steps, 1);
    assert_eq!(MetricsFile::load(&out.join("metrics.json")).unwrap().completed_steps, 1);
    run(&cfg, &out, opts(true, Some(1))).unwrap();
    let resumed = run(&cfg, &out, opts(true, None)).unwrap();
    assert_eq!(resumed, whole, "every number, curve and evaluation is identical");
    // Resuming a finished run does nothing and changes nothing.
    assert_eq!(run(&cfg, &out, opts(true, None)).unwrap(), whole);
}

#[test]
fn a_corrupt_checkpoint_is_an_error_and_leaves_the_results_intact() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write_run(tmp.path(), RUN);
    let out = tmp.path().join("out");
    run(&cfg, &out, opts(false, Some(2))).unwrap();
    let before = std::fs::read(out.join("metrics.json")).unwrap();
    let model = out.join("checkpoints/step-01-invert_RR/model.safetensors");
    let mut bytes = std::fs::read(&model).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&model, bytes).unwrap();
    let err = format!("{:#}", run(&cfg, &out, opts(true, None)).unwrap_err());
    assert!(err.contains("model.safetensors") || err.contains("step-01"), "{err}");
    assert_eq!(std::fs::read(out.join("metrics.json")).unwrap(), before);
    assert!(!out.join("checkpoints/step-02-noise_FR").exists(), "nothing trained");
}

#[test]
fn a_corrupt_or_changed_config_is_an_error_and_leaves_the_results_intact() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write_run(tmp.path(), RUN);
    let out = tmp.path().join("out");
    run(&cfg, &out, opts(false, Some(1))).unwrap();
    let before = std::fs::read(out.join("metrics.json")).unwrap();

    let typo = write_named(tmp.path(), "typo.toml", &RUN.replace("iterations = 5", "iteratons = 5"));
    let err = format!("{:#}", run(&typo, &out, opts(true, None)).unwrap_err());
    assert!(err.contains("iteratons") && err.contains("typo.toml"), "{err}");

    let changed = write_named(tmp.path(), "changed.toml", &RUN.replace("seed = 11", "seed = 12"));
    let err = format!("{:#}", run(&changed, &out, opts(true, None)).unwrap_err());
    assert!(err.contains("differs"), "{err}");

    let err = format!("{:#}", run(&cfg, &out, opts(false, None)).unwrap_err());
    assert!(err.contains("already holds a run"), "{err}");

    std::fs::write(out.join("metrics.json"), b"{ not json").unwrap();
    let err = format!("{:#}", run(&cfg, &out, opts(true, None)).unwrap_err());
    assert!(err.contains("metrics.json"), "{err}");
    std::fs::write(out.join("metrics.json"), &before).unwrap();

    let resumed = run(&cfg, &out, opts(true, None)).unwrap();
    assert_eq!(resumed.completed_steps, 3, "the intact run still resumes");
}

#[test]
fn a_bad_run_file_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write_run(tmp.path(), "[run]\nlearner = \"toy\"\n[[task]]\nname = \"wobble:FL\"\n");
    let out = tmp.path().join("out");
    let err = format!("{:#}", run(&cfg, &out, opts(false, None)).unwrap_err());
    assert!(err.contains("wobble"), "{err}");
    assert!(!out.exists());
}

#[test]
fn keeping_only_the_last_checkpoint_still_resumes_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = run(&write_run(tmp.path(), RUN), &tmp.path().join("whole"), opts(false, None)).unwrap();
    let cfg = write_named(
        tmp.path(),
        "last.toml",
        &RUN.replace("learner = \"toy\"", "learner = \"toy\"\nkeep_last_checkpoint_only = true"),
    );
    let out = tmp.path().join("out");
    run(&cfg, &out, opts(false, Some(2))).unwrap();
    let kept: Vec<_> = std::fs::read_dir(out.join("checkpoints")).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(kept, vec![std::ffi::OsString::from("step-01-invert_RR")]);
    // The same results; the provenance differs only in the run file's hash (one more key).
    let (mut resumed, mut whole) = (run(&cfg, &out, opts(true, None)).unwrap(), whole);
    let hash = |m: &quadcl::engine::MetricsFile| m.provenance.as_ref().and_then(|p| p.run_file_sha256.clone());
    assert_ne!(hash(&resumed), hash(&whole));
    (resumed.provenance, whole.provenance) = (None, None);
    assert_eq!(resumed, whole);
}

#[test]
fn the_shipped_metrics_json_written_before_the_renames_still_reads_and_round_trips() {
    // policies/sequence-a1-adapter was written with `fine_tune` step flags and evaluations without return_std.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/sequence-a1-adapter/metrics.json");
    let m = MetricsFile::load(&path).unwrap();
    assert_eq!((m.completed_steps, m.tasks.len()), (4, 5));
    assert!(m.steps.iter().all(|s| !s.repeat), "no step of that run repeats a task");
    assert!(m.evaluations.iter().flatten().all(|e| e.report.return_std.is_none()));
    assert_eq!(m.summary.forgetting, Some(0.0));
    let raw: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(m.summary.average_performance, raw["average_performance"].as_f64());
    assert_eq!(m.summary.command_tracking.fall_rate[1], raw["command_tracking"]["fall_rate"][1].as_f64());
    let again: MetricsFile = serde_json::from_str(&serde_json::to_string_pretty(&m).unwrap()).unwrap();
    assert_eq!(again, m, "what it reads it writes back unchanged");
}

#[test]
fn a_run_folder_from_before_issue_60_resumes_with_the_readings_it_ran() {
    let tmp = tempfile::tempdir().unwrap();
    // Budgets of 10: the paper's share would give E = 2 where the run had 100, and the means a
    // fixed 1e-3 where they had the optimiser's rate.
    let unpinned = "seed = 5\niterations = 10\n[run]\nlearner = \"toy\"\n[[task]]\nname = \"crash:FL\"\n\
                    [[task]]\nname = \"invert:RR\"\n";
    let pinned =
        unpinned.replacen("[[task]]", "[net.mask]\nentropy_iterations = 100\nscore_learning_rate = 0.0\n[[task]]", 1);
    let (unpinned_file, pinned_file) =
        (write_named(tmp.path(), "new.toml", unpinned), write_named(tmp.path(), "old.toml", &pinned));
    let reference = run(&pinned_file, &tmp.path().join("reference"), opts(false, None)).unwrap();
    // A folder as a run before issue 60 left it: its run.toml names neither reading, and its
    // steps record no soft-score schedule.
    let old = tmp.path().join("old");
    run(&pinned_file, &old, opts(false, Some(1))).unwrap();
    std::fs::write(old.join("run.toml"), unpinned).unwrap();
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(old.join("metrics.json")).unwrap()).unwrap();
    for step in m["steps"].as_array_mut().unwrap() {
        assert!(step.as_object_mut().unwrap().remove("soft_scores").is_some(), "a step records its schedule");
    }
    std::fs::write(old.join("metrics.json"), serde_json::to_string(&m).unwrap()).unwrap();
    let resumed = run(&unpinned_file, &old, opts(true, None)).unwrap();
    assert_eq!(resumed.eval_matrix, reference.eval_matrix, "the old run goes on as it ran");
    assert_eq!(resumed.curves, reference.curves);
    let last = resumed.steps[1].soft_scores.unwrap();
    assert_eq!((last.entropy_iterations, last.score_learning_rate), (100, 0.0));
    // A run begun now takes the paper's readings: the same file trains otherwise.
    let new = run(&unpinned_file, &tmp.path().join("new"), opts(false, None)).unwrap();
    assert_eq!(new.steps[0].soft_scores.unwrap().entropy_iterations, 2);
    assert_ne!(new.curves, reference.curves);
}
