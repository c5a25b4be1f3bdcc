//! insta snapshot of `quadcl masks --json` for a fixed-seed task sequence
//! (three tasks, the third related to the first, then a fine-tuning of the
//! second), plus the readable table.

mod nn_common;
use nn_common::*;
use quadcl::nn::checkpoint::save_policy;
use quadcl::nn::{AdamConfig, MaskConfig, MaskReport, MaskedAdam};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

fn policy_dir() -> tempfile::TempDir {
    // The soft-score means at the optimiser's rate, as the snapshot was taken before issue 60.
    let cfg = MaskConfig {
        capacity: 0.25,
        vacant_share: 0.5,
        private_share: 0.05,
        score_learning_rate: 0.0,
        ..MaskConfig::default()
    };
    let mut net = quadcl::nn::MaskedMlp::new("actor", &[IN, 16, OUT], quadcl::nn::Activation::Elu, &cfg, 21).unwrap();
    let ts = tasks(3, 21);
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    train_task(&mut net, 0, &ts[0], 60, 1e-2, &mut rng);
    train_task(&mut net, 1, &ts[1], 60, 1e-2, &mut rng);
    // Task 2 names task 0 as related (forward-transfer bonus), trained by hand.
    net.begin_task(2, &[0]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig { learning_rate: 1e-2, ..AdamConfig::default() });
    for it in 0..60 {
        net.begin_iteration(it, &mut rng).unwrap();
        let x = inputs(64, &mut rng);
        let loss = net.forward(&x).unwrap().sub(&targets(&ts[2], &x)).unwrap().sqr().unwrap().mean_all().unwrap();
        let params = net.params();
        opt.step(&params, &loss.backward().unwrap()).unwrap();
    }
    net.end_task(&mut rng).unwrap();
    train_task(&mut net, 1, &ts[1], 20, 1e-2, &mut rng);
    let dir = tempfile::tempdir().unwrap();
    let names = ["none", "crash:FL", "invert:RR"].map(String::from);
    save_policy(dir.path(), &names, &[&net], &BTreeMap::new(), &serde_json::json!({})).unwrap();
    dir
}

#[test]
fn masks_json_of_a_fixed_seed_sequence() {
    let dir = policy_dir();
    let json = serde_json::to_string_pretty(&MaskReport::of_policy(dir.path()).unwrap()).unwrap();
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    // Structural facts that do not depend on the numbers.
    let layer = &value["networks"][0]["layers"][0];
    assert_eq!(layer["shape"], serde_json::json!([16, IN]));
    assert_eq!(layer["per_task"][0]["from_occupied"], 0);
    insta::with_settings!({snapshot_path => "../snapshots"}, {
        insta::assert_json_snapshot!("masks_json_fixed_seed_sequence", value);
    });
}

#[test]
fn masks_table_lists_every_layer_and_task() {
    let dir = policy_dir();
    let table = MaskReport::of_policy(dir.path()).unwrap().to_table();
    for needle in ["actor.l0 [16 x 8]", "actor.l1 [4 x 16]", "crash:FL", "invert:RR", "from_vacant"] {
        assert!(table.contains(needle), "missing {needle:?} in\n{table}");
    }
}
