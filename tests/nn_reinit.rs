//! The end of a task and the start of the next (METHOD.md 2.4 steps 4 and 6, issue 31):
//! which soft-score means survive (`reinit_scores`), the range fresh vacant weights are
//! drawn from (`reinit_range`), and where the next task's bias starts (`bias_start`).

mod nn_common;
use nn_common::*;
use quadcl::nn::{BiasStart, ElementState, MaskConfig, MaskedMlp, ReinitRange, ScoreReinit};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// No private elements, and a first-iteration mask that is the top-k of the means (sigma 1e-6
/// of the score gap), so the selection can be read off the means.
fn config(reinit_scores: ScoreReinit) -> MaskConfig {
    MaskConfig { private_share: 0.0, reinit_scores, sigma_init: 1e-6, sigma_floor: 1e-6, ..MaskConfig::default() }
}

/// Task 0 trained and ended; returns the network and each layer's means just before the end.
fn after_first_task(cfg: &MaskConfig) -> (MaskedMlp, Vec<Vec<f32>>) {
    let ts = tasks(1, 3);
    let mut net = small_mlp(cfg, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    net.begin_task(0, &[]).unwrap();
    train_steps_on(&mut net, &ts[0], 60, &mut rng);
    let before: Vec<Vec<f32>> = net.layers().iter().map(|l| l.score_values().unwrap()).collect();
    net.end_task(&mut rng).unwrap();
    (net, before)
}

fn train_steps_on(net: &mut MaskedMlp, task: &LinearTask, steps: usize, rng: &mut ChaCha8Rng) {
    let mut opt = quadcl::nn::MaskedAdam::new(quadcl::nn::AdamConfig { learning_rate: 1e-2, ..Default::default() });
    for it in 0..steps {
        net.begin_iteration(it, rng).unwrap();
        let x = inputs(64, rng);
        let loss = net.forward(&x).unwrap().sub(&targets(task, &x)).unwrap().sqr().unwrap().mean_all().unwrap();
        opt.step(&net.params(), &loss.backward().unwrap()).unwrap();
    }
}

/// Per layer, the share of elements in `state` whose mean is bit-identical to `before`.
fn kept_share(net: &MaskedMlp, before: &[Vec<f32>], state: ElementState) -> Vec<f64> {
    net.layers()
        .iter()
        .zip(before)
        .map(|(l, before)| {
            let after = l.score_values().unwrap();
            let idx: Vec<usize> = (0..after.len()).filter(|&i| l.states()[i] == state).collect();
            assert!(!idx.is_empty(), "{}: no {state:?} element", l.name());
            idx.iter().filter(|&&i| after[i].to_bits() == before[i].to_bits()).count() as f64 / idx.len() as f64
        })
        .collect()
}

#[test]
fn vacant_score_reinit_keeps_the_occupied_means_bit_identical_and_redraws_the_vacant_ones() {
    let (net, before) = after_first_task(&config(ScoreReinit::Vacant));
    assert!(kept_share(&net, &before, ElementState::Occupied).iter().all(|s| *s == 1.0));
    for (layer, kept) in kept_share(&net, &before, ElementState::Vacant).iter().enumerate() {
        assert!(*kept < 0.01, "layer {layer}: {kept} of the vacant means kept");
    }
}

#[test]
fn all_score_reinit_redraws_the_occupied_means_too_and_none_keeps_every_mean() {
    let (net, before) = after_first_task(&config(ScoreReinit::All));
    for kept in kept_share(&net, &before, ElementState::Occupied) {
        assert!(kept < 0.01, "{kept} of the occupied means kept under `all`");
    }
    let (net, before) = after_first_task(&config(ScoreReinit::None));
    for state in [ElementState::Occupied, ElementState::Vacant] {
        assert!(kept_share(&net, &before, state).iter().all(|s| *s == 1.0), "{state:?} under `none`");
    }
}

/// Per row of every layer, whether the next task's first mask takes its occupied quota from the
/// top of the previous task's ranking: the share of the occupied elements it selects that are
/// among the row's top k_o occupied means of `before`.
fn top_of_ranking_share(net: &MaskedMlp, before: &[Vec<f32>]) -> f64 {
    let (mut hits, mut total) = (0usize, 0usize);
    for (l, before) in net.layers().iter().zip(before) {
        let (out_dim, in_dim) = l.shape();
        let mask = l.iteration_mask().unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
        for row in 0..out_dim {
            let occupied: Vec<usize> =
                (row * in_dim..(row + 1) * in_dim).filter(|&i| l.states()[i] == ElementState::Occupied).collect();
            let chosen: Vec<usize> = occupied.iter().copied().filter(|&i| mask[i] == 1.0).collect();
            let mut ranked = occupied.clone();
            ranked.sort_by(|&a, &b| before[b].total_cmp(&before[a]).then(a.cmp(&b)));
            hits += chosen.iter().filter(|i| ranked[..chosen.len()].contains(i)).count();
            total += chosen.len();
        }
    }
    assert!(total > 0, "the next task selected no occupied element");
    hits as f64 / total as f64
}

#[test]
fn the_next_tasks_first_mask_keeps_the_top_of_the_previous_ranking_only_when_it_survives() {
    for (scores, expect_all) in [(ScoreReinit::Vacant, true), (ScoreReinit::All, false)] {
        let (mut net, before) = after_first_task(&config(scores));
        net.begin_task(1, &[]).unwrap();
        net.begin_iteration(0, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        let share = top_of_ranking_share(&net, &before);
        if expect_all {
            assert_eq!(share, 1.0, "{scores:?}");
        } else {
            assert!(share < 0.9, "{scores:?}: {share} of the occupied quota from the previous top");
        }
    }
}

#[test]
fn a_new_tasks_bias_starts_from_the_previous_task_the_related_ones_or_zero() {
    let ts = tasks(2, 4);
    for bias_start in [BiasStart::Previous, BiasStart::Related, BiasStart::Zero] {
        let cfg = MaskConfig { bias_start, ..MaskConfig::default() };
        let mut net = small_mlp(&cfg, 7);
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for (id, task) in ts.iter().enumerate() {
            train_task(&mut net, id, task, 30, 1e-2, &mut rng);
        }
        net.begin_task(2, &[0]).unwrap();
        for l in net.layers() {
            let start = l.training_bias().unwrap().unwrap();
            let (first, last) = (l.task_bias(0).unwrap(), l.task_bias(1).unwrap());
            assert_ne!(first, last, "{}: the two tasks learned different biases", l.name());
            let want = match bias_start {
                BiasStart::Previous => last.to_vec(),
                BiasStart::Related => first.to_vec(),
                BiasStart::Zero => vec![0.0; start.len()],
            };
            assert_eq!(start, want, "{bias_start:?} {}", l.name());
        }
    }
}

#[test]
fn fresh_vacant_weights_span_the_initialisers_range_over_the_full_or_the_effective_fan_in() {
    for range in [ReinitRange::Initial, ReinitRange::HeEffective] {
        let cfg = MaskConfig { reinit_range: range, ..config(ScoreReinit::Vacant) };
        let (net, _) = after_first_task(&cfg);
        for (i, l) in net.layers().iter().enumerate() {
            let (_, fan_in) = l.shape();
            let gain = if i + 1 < net.layers().len() { 6.0 } else { 3.0 };
            let fan = match range {
                ReinitRange::Initial => fan_in as f64,
                ReinitRange::HeEffective => (cfg.capacity * fan_in as f64).max(1.0),
            };
            let bound = (gain / fan).sqrt() as f32;
            let w = l.weight_values().unwrap();
            let vacant: Vec<f32> =
                (0..w.len()).filter(|&i| l.states()[i] == ElementState::Vacant).map(|i| w[i].abs()).collect();
            let largest = vacant.iter().copied().fold(0.0f32, f32::max);
            assert!(largest <= bound, "{range:?} {}: |w| up to {largest}, bound {bound}", l.name());
            assert!(largest > 0.8 * bound, "{range:?} {}: |w| only up to {largest}, bound {bound}", l.name());
        }
    }
}

#[test]
fn a_mask_configuration_saved_before_issue_31_reads_as_it_ran() {
    let mut old = serde_json::json!({ "capacity": 0.2, "reinit": true, "reinit_scale": 0.1 });
    MaskConfig::fill_in_pre_issue_31(&mut old);
    let m: MaskConfig = serde_json::from_value(old).unwrap();
    assert_eq!(
        (m.reinit_weights, m.reinit_scores, m.reinit_range, m.bias_start, m.reinit_scale),
        (true, ScoreReinit::All, ReinitRange::HeEffective, BiasStart::Related, 0.1)
    );
    let mut off = serde_json::json!({ "reinit": false, "bias_start": "zero" });
    MaskConfig::fill_in_pre_issue_31(&mut off);
    let m: MaskConfig = serde_json::from_value(off).unwrap();
    assert_eq!((m.reinit_weights, m.reinit_scores, m.bias_start), (false, ScoreReinit::None, BiasStart::Zero));
    // A configuration that names its readings keeps them.
    let mut new = serde_json::json!({ "reinit_weights": true, "reinit_scores": "vacant" });
    MaskConfig::fill_in_pre_issue_31(&mut new);
    let m: MaskConfig = serde_json::from_value(new).unwrap();
    assert_eq!(
        (m.reinit_scores, m.reinit_range, m.bias_start),
        (ScoreReinit::Vacant, ReinitRange::Initial, BiasStart::Previous)
    );
}
