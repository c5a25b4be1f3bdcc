//! Exact recall (METHOD.md 2.4, 2.5, 2.7): after every task of a ten-task
//! sequence, every earlier task's outputs are bit-identical to what they were
//! when that task ended; with re-initialisation on (the soft scores of vacant
//! elements or all of them redrawn) and off, and with a private fine-tuning of
//! one finished task in between.

mod nn_common;
use nn_common::*;
use quadcl::nn::{MaskConfig, ScoreReinit};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

fn check_recall(reinit: bool, scores: ScoreReinit, fine_tune_after: Option<(usize, usize)>) {
    let cfg = MaskConfig { reinit_weights: reinit, reinit_scores: scores, ..MaskConfig::default() };
    let ts = tasks(10, 7);
    let mut net = small_mlp(&cfg, 7);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let x = probe();
    let mut reference: BTreeMap<usize, Vec<u32>> = BTreeMap::new();
    for (id, task) in ts.iter().enumerate() {
        train_task(&mut net, id, task, 150, 1e-2, &mut rng);
        reference.insert(id, bits(&net.forward_task(id, &x).unwrap()));
        if let Some((after, tuned)) = fine_tune_after {
            if id == after {
                // Fine-tune the finished task `tuned` on shifted targets: only its private elements and bias move.
                let shifted = LinearTask { a: (&ts[tuned].a * 1.1).unwrap() };
                let before = bits(&net.forward_task(tuned, &x).unwrap());
                train_task(&mut net, tuned, &shifted, 100, 1e-2, &mut rng);
                let after_tuning = bits(&net.forward_task(tuned, &x).unwrap());
                assert_ne!(before, after_tuning, "fine-tuning task {tuned} changed nothing");
                reference.insert(tuned, after_tuning);
            }
        }
        for (&old, want) in &reference {
            let got = bits(&net.forward_task(old, &x).unwrap());
            assert!(got == *want, "task {old} drifted after training task {id} (reinit {reinit})");
        }
    }
}

#[test]
fn recall_is_bit_identical_after_ten_tasks_with_reinit() {
    check_recall(true, ScoreReinit::Vacant, None);
}

#[test]
fn recall_is_bit_identical_after_ten_tasks_with_every_score_redrawn() {
    check_recall(true, ScoreReinit::All, None);
}

#[test]
fn recall_is_bit_identical_after_ten_tasks_without_reinit() {
    check_recall(false, ScoreReinit::None, None);
}

#[test]
fn private_fine_tuning_changes_only_its_own_task() {
    check_recall(true, ScoreReinit::Vacant, Some((5, 2)));
}

#[test]
fn same_seed_gives_bit_identical_training() {
    let run = || {
        let cfg = MaskConfig::default();
        let ts = tasks(2, 3);
        let mut net = small_mlp(&cfg, 3);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for (id, t) in ts.iter().enumerate() {
            train_task(&mut net, id, t, 40, 1e-2, &mut rng);
        }
        (bits(&net.forward_task(0, &probe()).unwrap()), bits(&net.forward_task(1, &probe()).unwrap()))
    };
    assert_eq!(run(), run());
}
