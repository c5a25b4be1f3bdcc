//! Sim-to-real fine-tuning (METHOD.md 2.7) on the smoke run's policy: only
//! the fine-tuned task changes; every other task's evaluation is
//! bit-identical before and after; the new directory is a policy `quadcl
//! eval` reads; a bad shift file or an unknown task is a clear error.

use quadcl::engine::{sim2real, Shift};
use quadcl::headless::{run, RunOptions};
use std::path::Path;

#[test]
fn finetuning_one_task_leaves_every_other_task_bit_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let smoke = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml");
    let out = tmp.path().join("smoke");
    run(&smoke, &out, RunOptions::default()).unwrap();
    let policy = out.join("checkpoints/step-02-noise_FR");
    let shift = Shift {
        friction: Some([0.3, 0.5]),
        added_mass: Some([1.0, 2.0]),
        motor_strength: Some([0.8, 0.9]),
        latency_s: 0.04,
        iterations: 2,
    };
    let new = tmp.path().join("tuned");
    let r = sim2real(&policy, "invert:RR", &shift, &new, 5, 4, false).unwrap();
    assert_eq!(r.before.len(), 3);
    assert!(r.changed_other_tasks.is_empty(), "{:?}", r.changed_other_tasks);
    let tuned_before = r.before.iter().find(|e| e.report.task == "invert:RR").unwrap();
    let tuned_after = r.after.iter().find(|e| e.report.task == "invert:RR").unwrap();
    assert_ne!(tuned_before, tuned_after, "the fine-tuned task changed");
    let loaded = quadcl::rl::load_policy(&new, Some("crash:FL")).unwrap();
    assert_eq!(loaded.tasks.len(), 3);
    assert!(new.join("finetune.json").exists());

    let err = format!("{:#}", sim2real(&policy, "crash:RR", &shift, &tmp.path().join("x"), 5, 4, false).unwrap_err());
    assert!(err.contains("crash:RR") && err.contains("invert:RR"), "{err}");
    std::fs::write(tmp.path().join("bad.toml"), "fricton = [0.1, 0.2]\n").unwrap();
    let err = format!("{:#}", Shift::load(&tmp.path().join("bad.toml")).unwrap_err());
    assert!(err.contains("fricton") && err.contains("bad.toml"), "{err}");
}
