//! The switches for the method's unlabelled interpretations (issue 13 item 1),
//! on real masked layers: with `score_grad_occupied` off only vacant elements'
//! scores train; with `bias_start = "zero"` a task with related tasks starts
//! from a zero bias, as a task without any does; with `entropy_target =
//! "action"` the entropy phase leaves the soft scores alone and hands beta_H to
//! the learner's action-entropy bonus for the first E iterations of a new task.

mod nn_common;
use nn_common::train_steps;
use quadcl::nn::{Activation, BiasStart, ElementState, EntropyTarget, MaskConfig, MaskedMlp, ScoreReinit};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Starts `task` (related to `related`) under `cfg`.
fn start(net: &mut MaskedMlp, task: usize, related: &[usize], cfg: &MaskConfig) {
    net.set_mask_config(cfg).unwrap();
    net.begin_task(task, related).unwrap();
}

/// `iterations` steps of the task in progress, the masks drawn from a stream seeded by `task`.
fn steps(net: &mut MaskedMlp, task: usize, iterations: usize) {
    train_steps(net, task, iterations, &mut ChaCha8Rng::seed_from_u64(task as u64));
}

fn first_task(cfg: &MaskConfig) -> MaskedMlp {
    let mut net = MaskedMlp::new("actor", &[6, 16, 3], Activation::Elu, cfg, 2).unwrap();
    start(&mut net, 0, &[], cfg);
    steps(&mut net, 0, 5);
    net.end_task(&mut ChaCha8Rng::seed_from_u64(0)).unwrap();
    net
}

#[test]
fn without_the_occupied_score_gradient_only_vacant_scores_train() {
    for occupied_too in [true, false] {
        let cfg = MaskConfig {
            score_grad_occupied: occupied_too,
            reinit_weights: false,
            reinit_scores: ScoreReinit::None,
            ..MaskConfig::default()
        };
        let mut net = first_task(&cfg);
        start(&mut net, 1, &[], &cfg);
        let before: Vec<Vec<f32>> = net.layers().iter().map(|l| l.score_values().unwrap()).collect();
        steps(&mut net, 1, 5);
        let (mut occupied_moved, mut vacant_moved) = (0, 0);
        for (l, start) in net.layers().iter().zip(&before) {
            let now = l.score_values().unwrap();
            for i in (0..now.len()).filter(|&i| now[i] != start[i]) {
                match l.states()[i] {
                    ElementState::Occupied => occupied_moved += 1,
                    ElementState::Vacant => vacant_moved += 1,
                    ElementState::Private(_) => {}
                }
            }
        }
        assert!(vacant_moved > 0, "vacant scores train either way");
        assert_eq!(occupied_moved > 0, occupied_too, "occupied scores moved {occupied_moved} (switch {occupied_too})");
    }
}

#[test]
fn a_zero_bias_start_ignores_the_related_tasks_biases() {
    for (bias_start, zero) in [(BiasStart::Related, false), (BiasStart::Zero, true)] {
        let cfg = MaskConfig { bias_start, ..MaskConfig::default() };
        let mut net = first_task(&cfg);
        start(&mut net, 1, &[0], &cfg);
        for l in net.layers() {
            let bias = l.training_bias().unwrap().unwrap();
            let related = l.task_bias(0).unwrap();
            assert!(related.iter().any(|b| *b != 0.0), "task 0 learned a bias");
            if zero {
                assert!(bias.iter().all(|b| *b == 0.0), "{}: {bias:?}", l.name());
            } else {
                assert_eq!(bias, related, "{}: the related task's bias", l.name());
            }
        }
    }
}

#[test]
fn an_entropy_term_on_the_action_leaves_the_soft_scores_and_acts_for_e_iterations() {
    for target in [EntropyTarget::SoftScores, EntropyTarget::Action] {
        let cfg = MaskConfig {
            entropy_target: target,
            entropy_iterations: Some(3),
            entropy_weight: 0.02,
            ..MaskConfig::default()
        };
        let mut net = first_task(&cfg);
        start(&mut net, 1, &[], &cfg);
        let on_action = target == EntropyTarget::Action;
        for it in 0..5 {
            net.begin_iteration(it, &mut ChaCha8Rng::seed_from_u64(it as u64)).unwrap();
            let soft = net.soft_score_loss().unwrap().to_scalar::<f32>().unwrap();
            let in_phase = it < 3;
            assert_eq!(soft != 0.0, in_phase && !on_action, "{target:?} iteration {it}: soft-score term {soft}");
            let expected = if in_phase && on_action { 0.02 } else { 0.0 };
            assert_eq!(net.action_entropy_weight(), expected, "{target:?} iteration {it}");
        }
        net.end_task(&mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        // A finished task trained again (fine-tuning) has no entropy phase either way.
        start(&mut net, 0, &[], &cfg);
        net.begin_iteration(0, &mut ChaCha8Rng::seed_from_u64(0)).unwrap();
        assert_eq!(net.action_entropy_weight(), 0.0, "{target:?}: a repeat");
    }
}
