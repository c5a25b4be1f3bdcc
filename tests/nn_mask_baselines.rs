//! The mask baselines' rules on real masked layers: PackNet prunes a task's
//! fresh weights by magnitude, retrains and freezes the kept ones, and its
//! recall ignores later tasks' weights; Piggyback never moves a weight, masks
//! only the base's, and recalls exactly.

mod nn_common;
use candle_core::Tensor;
use nn_common::{input, train_steps};
use quadcl::nn::{Activation, ElementState, MaskConfig, MaskedMlp, ScoreReinit, SelectionRule};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn values(t: &Tensor) -> Vec<f32> {
    t.flatten_all().unwrap().to_vec1().unwrap()
}

/// Trains `task` for `iterations` steps of a squared-output loss under `cfg`.
fn train(net: &mut MaskedMlp, task: usize, cfg: &MaskConfig, iterations: usize) {
    net.set_mask_config(cfg).unwrap();
    net.begin_task(task, &[]).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(task as u64);
    train_steps(net, task, iterations, &mut rng);
    net.end_task(&mut rng).unwrap();
}

fn count(net: &MaskedMlp, state: ElementState) -> usize {
    net.layers().iter().map(|l| l.states().iter().filter(|s| **s == state).count()).sum()
}

#[test]
fn packnet_keeps_the_largest_fresh_weights_freezes_them_and_recalls_without_later_weights() {
    let cfg = MaskConfig {
        rule: SelectionRule::PackNet,
        capacity: 1.0,
        private_share: 0.0,
        reinit_weights: false,
        reinit_scores: ScoreReinit::None,
        entropy: false,
        entropy_iterations: Some(0),
        packnet_keep: 0.5,
        packnet_prune_at: Some(8),
        ..MaskConfig::default()
    };
    let mut net = MaskedMlp::new("actor", &[6, 10, 3], Activation::Elu, &cfg, 3).unwrap();
    let total: usize = net.layers().iter().map(|l| l.states().len()).sum();
    train(&mut net, 0, &cfg, 10);
    let occupied = count(&net, ElementState::Occupied);
    assert_eq!(occupied, net.layers().iter().map(|l| (l.states().len() as f64 * 0.5).round() as usize).sum::<usize>());
    for l in net.layers() {
        let w = l.weight_values().unwrap();
        let (kept, pruned): (Vec<usize>, Vec<usize>) =
            (0..w.len()).partition(|&i| l.states()[i] == ElementState::Occupied);
        assert!(pruned.iter().all(|&i| w[i] == 0.0), "{}: a pruned weight is not zero", l.name());
        let smallest_kept = kept.iter().map(|&i| w[i].abs()).fold(f32::INFINITY, f32::min);
        assert!(smallest_kept > 0.0, "{}: kept weights are the non-zero ones", l.name());
        assert_eq!(l.task_mask(0).unwrap().count_ones(), kept.len(), "task 0's mask is its kept weights");
    }
    let x = input(99);
    let recall = values(&net.forward_task(0, &x).unwrap());
    let frozen: Vec<Vec<f32>> = net.layers().iter().map(|l| l.weight_values().unwrap()).collect();
    let vacant_per_layer: Vec<usize> =
        net.layers().iter().map(|l| l.states().iter().filter(|s| **s == ElementState::Vacant).count()).collect();
    train(&mut net, 1, &cfg, 10);
    assert_eq!(values(&net.forward_task(0, &x).unwrap()), recall, "task 0's recall after task 1");
    for (l, before) in net.layers().iter().zip(&frozen) {
        let w = l.weight_values().unwrap();
        let mask = l.task_mask(0).unwrap();
        assert!((0..w.len()).filter(|&i| mask.get(i)).all(|i| w[i] == before[i]), "a frozen weight moved");
        let task1 = l.task_mask(1).unwrap();
        assert!((0..w.len()).all(|i| !mask.get(i) || task1.get(i)), "task 1 uses every weight of task 0");
    }
    let kept_by_task1: usize = vacant_per_layer.iter().map(|&v| (v as f64 * 0.5).round() as usize).sum();
    assert_eq!(count(&net, ElementState::Occupied), occupied + kept_by_task1);
    assert_eq!(count(&net, ElementState::Vacant), total - occupied - kept_by_task1, "the pruned stay free");
}

/// Piggyback's mask configuration as the method sets it, at the default score rate.
fn piggyback() -> MaskConfig {
    MaskConfig {
        rule: SelectionRule::Piggyback,
        private_share: 0.0,
        reinit_weights: false,
        reinit_scores: ScoreReinit::None,
        entropy: false,
        entropy_iterations: Some(0),
        ..MaskConfig::default()
    }
}

#[test]
fn piggyback_scores_step_at_their_own_rate_so_a_task_starts_from_the_base() {
    let ours = MaskConfig { private_share: 0.0, ..MaskConfig::default() };
    let base_on =
        |net: &MaskedMlp, task| -> usize { net.layers().iter().map(|l| l.task_mask(task).unwrap().count_ones()).sum() };
    let run = |rate: f64| {
        let mut net = MaskedMlp::new("actor", &[6, 10, 3], Activation::Elu, &ours, 4).unwrap();
        train(&mut net, 0, &ours, 5);
        let cfg = MaskConfig { piggyback_learning_rate: rate, ..piggyback() };
        net.set_mask_config(&cfg).unwrap();
        net.begin_task(1, &[]).unwrap();
        let rates: Vec<Option<f64>> =
            net.params().into_iter().filter(|p| p.name.ends_with(".score")).map(|p| p.fixed_learning_rate).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        train_steps(&mut net, 1, 20, &mut rng);
        net.end_task(&mut rng).unwrap();
        (rates, base_on(&net, 0), base_on(&net, 1))
    };
    // Adam moves a score by about its rate a step: 20 steps of 1e-4 stay inside the 5e-3
    // margin between init and threshold, so the task still uses every base weight.
    let (rates, base, kept) = run(1e-4);
    assert!(rates.iter().all(|r| *r == Some(1e-4)), "{rates:?}");
    assert_eq!(kept, base, "at 1e-4 a score crossed the threshold within 20 steps");
    // At the optimiser's rate the same 20 steps switch base weights off.
    let (rates, base, kept) = run(0.0);
    assert!(rates.iter().all(Option::is_none), "{rates:?}");
    assert!(kept < base, "at the optimiser's rate no score crossed the threshold");
}

#[test]
fn piggyback_moves_no_weight_masks_only_the_base_and_recalls_exactly() {
    // The base: task 0 of the method, all of its elements left occupied (private share 0).
    let ours = MaskConfig { private_share: 0.0, ..MaskConfig::default() };
    let mut net = MaskedMlp::new("actor", &[6, 10, 3], Activation::Elu, &ours, 4).unwrap();
    train(&mut net, 0, &ours, 5);
    let base: Vec<Vec<f32>> = net.layers().iter().map(|l| l.weight_values().unwrap()).collect();
    let x = input(7);
    let recall = values(&net.forward_task(0, &x).unwrap());
    // At the optimiser's rate (piggyback_learning_rate 0), so that 20 steps move scores
    // across the threshold.
    let cfg = MaskConfig { piggyback_learning_rate: 0.0, ..piggyback() };
    for task in 1..3 {
        train(&mut net, task, &cfg, 20);
        for (l, before) in net.layers().iter().zip(&base) {
            assert_eq!(&l.weight_values().unwrap(), before, "{}: piggyback moved a weight", l.name());
            let (mask, base_mask) = (l.task_mask(task).unwrap(), l.task_mask(0).unwrap());
            assert!((0..mask.len()).all(|i| !mask.get(i) || base_mask.get(i)), "a mask outside the base");
        }
        assert_eq!(values(&net.forward_task(0, &x).unwrap()), recall);
    }
    // The scores learned something: some base weight was switched off for a task.
    let on: usize = net.layers().iter().map(|l| l.task_mask(1).unwrap().count_ones()).sum();
    let base_on: usize = net.layers().iter().map(|l| l.task_mask(0).unwrap().count_ones()).sum();
    assert!(on < base_on, "task 1 kept all {base_on} base weights");
    assert_eq!(
        count(&net, ElementState::Vacant) + base_on,
        net.layers().iter().map(|l| l.states().len()).sum::<usize>()
    );
}
