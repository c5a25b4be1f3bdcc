//! The sequence files under `scenes/` parse, and say what they claim: the
//! default sequence is the twelve single-leg tasks, once each; the Figure 11
//! runs differ only in the mixed task's initialisation.

use quadcl::cl::TransferInit;
use quadcl::engine::RunConfig;
use std::path::Path;

fn scene(name: &str) -> RunConfig {
    RunConfig::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).unwrap()
}

#[test]
fn the_default_sequence_has_every_single_leg_task_once() {
    let cfg = scene("sequence-a1.toml");
    let mut names = cfg.sequence.distinct_tasks();
    assert_eq!(names.len(), 12);
    assert_eq!(cfg.sequence.tasks.len(), 12);
    names.sort();
    let mut expected: Vec<String> = ["crash", "invert", "noise"]
        .iter()
        .flat_map(|k| ["FL", "FR", "RL", "RR"].map(|l| format!("{k}:{l}")))
        .collect();
    expected.sort();
    assert_eq!(names, expected);
    let four = scene("sequence-a1-4-adapter.toml");
    assert_eq!(four.sequence.distinct_tasks(), cfg.sequence.distinct_tasks()[..4].to_vec(), "its first four tasks");
    assert_eq!(four.config, cfg.config, "the same experiment settings");
    assert_eq!((four.switches, four.run.base_policy), (cfg.switches, cfg.run.base_policy), "the same method and base");
}

#[test]
fn the_figure_11_runs_differ_only_in_the_mixed_tasks_initialisation() {
    let related = scene("fig11-related.toml");
    for (file, init) in [
        ("fig11-related.toml", TransferInit::Related),
        ("fig11-random.toml", TransferInit::Random),
        ("fig11-scratch.toml", TransferInit::Scratch),
    ] {
        let cfg = scene(file);
        let last = cfg.sequence.tasks.last().unwrap();
        assert_eq!(last.name, "invert:RR+noise:FR");
        assert_eq!(last.related, vec!["invert:RR", "noise:FR"]);
        assert_eq!(last.init, init, "{file}");
        let mut same = cfg.clone();
        same.sequence.tasks.last_mut().unwrap().init = TransferInit::Related;
        assert_eq!(same, related, "{file} differs elsewhere");
    }
    let reference = scene("fig11-reference.toml");
    assert_eq!(reference.sequence.distinct_tasks(), vec!["invert:RR+noise:FR"]);
}
