//! The gradient and life-cycle rules of a masked layer (METHOD.md 2.2 to 2.6):
//! which elements move, the straight-through score gradient, the entropy
//! schedule of sigma, forward transfer, and private fine-tuning.

mod nn_common;
use candle_core::Tensor;
use nn_common::*;
use quadcl::nn::{AdamConfig, BiasStart, ElementState, MaskConfig, MaskedAdam, MaskedMlp, SigmaScale};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn flat(t: &Tensor) -> Vec<f32> {
    t.flatten_all().unwrap().to_vec1::<f32>().unwrap()
}

fn net_after(tasks_done: usize, cfg: &MaskConfig) -> (MaskedMlp, ChaCha8Rng) {
    let ts = tasks(tasks_done.max(1), 31);
    let mut net = small_mlp(cfg, 31);
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    for (id, t) in ts.iter().take(tasks_done).enumerate() {
        train_task(&mut net, id, t, 40, 1e-2, &mut rng);
    }
    (net, rng)
}

fn loss_of(net: &MaskedMlp, rng: &mut ChaCha8Rng) -> Tensor {
    let x = inputs(64, rng);
    let y = targets(&tasks(1, 77)[0], &x);
    net.forward(&x).unwrap().sub(&y).unwrap().sqr().unwrap().mean_all().unwrap()
}

#[test]
fn base_weights_move_only_where_selected_and_vacant() {
    let (mut net, mut rng) = net_after(2, &MaskConfig::default());
    net.begin_task(2, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let before: Vec<Vec<f32>> = net.layers().iter().map(|l| l.weight_values().unwrap()).collect();
    let params = net.params();
    let grads = loss_of(&net, &mut rng).backward().unwrap();
    MaskedAdam::new(AdamConfig::default()).step(&params, &grads).unwrap();
    for (l, before) in net.layers().iter().zip(before) {
        let after = l.weight_values().unwrap();
        let mask = flat(l.iteration_mask().unwrap());
        let mut moved = 0;
        for i in 0..after.len() {
            let may_move = mask[i] == 1.0 && l.states()[i] == ElementState::Vacant;
            if after[i].to_bits() != before[i].to_bits() {
                assert!(may_move, "{} element {i} moved: state {:?}, selected {}", l.name(), l.states()[i], mask[i]);
                moved += 1;
            }
        }
        assert!(moved > 0, "{}: no selected vacant weight trained", l.name());
    }
}

#[test]
fn scores_get_the_straight_through_gradient_even_where_unselected() {
    let (mut net, mut rng) = net_after(0, &MaskConfig::default());
    net.begin_task(0, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let params = net.params();
    let grads = loss_of(&net, &mut rng).backward().unwrap();
    let grad = |name: &str| flat(grads.get(params.iter().find(|p| p.name == name).unwrap().var.as_tensor()).unwrap());
    let l = &net.layers()[1];
    let (gw, gs, w, m) =
        (grad("net.l1.weight"), grad("net.l1.score"), l.weight_values().unwrap(), flat(l.iteration_mask().unwrap()));
    let cols = l.shape().1;
    let (mut live_rows, mut unselected_in_live_rows) = (0, 0);
    for row in 0..l.shape().0 {
        let elements = row * cols..(row + 1) * cols;
        // A row gets a gradient only if the next layer selects its neuron somewhere; with
        // 4 outputs selecting 13 of 64 inputs each, about 40 % of l1's neurons get none.
        let live = elements.clone().any(|i| m[i] == 1.0 && gw[i] != 0.0);
        live_rows += live as usize;
        for i in elements {
            if m[i] == 1.0 {
                // dL/dmu = dL/dWeff * W and dL/dW = dL/dWeff * M = dL/dWeff where selected.
                assert!(
                    (gs[i] - gw[i] * w[i]).abs() <= 1e-6 * (1.0 + gs[i].abs()),
                    "element {i}: {} vs {}",
                    gs[i],
                    gw[i] * w[i]
                );
            } else {
                assert_eq!(gw[i], 0.0, "unselected weight {i} has a gradient");
                if live {
                    assert_ne!(gs[i], 0.0, "unselected element {i} of a live row has no score gradient");
                    unselected_in_live_rows += 1;
                }
            }
        }
    }
    assert!(live_rows > 0 && unselected_in_live_rows > 0, "no row of l1 got a gradient");
}

#[test]
fn entropy_term_widens_sigma_then_sigma_decays_to_its_floor() {
    // The layer trains ln sigma at its own fixed rate, which Adam moves by about that rate per
    // step: with one step per iteration a large rate is needed to widen sigma visibly within
    // E = 20 iterations.
    let cfg = MaskConfig {
        entropy_iterations: Some(20),
        entropy_weight: 1.0,
        sigma_learning_rate: 0.05,
        ..MaskConfig::default()
    };
    let (mut net, mut rng) = net_after(0, &cfg);
    net.begin_task(0, &[]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig { learning_rate: 1e-3, ..AdamConfig::default() });
    let mut sigmas = Vec::new();
    for it in 0..1000 {
        net.begin_iteration(it, &mut rng).unwrap();
        sigmas.push(net.layers()[0].sigma().unwrap());
        let params = net.params();
        let loss = net.soft_score_loss().unwrap();
        if it < 20 {
            assert_ne!(loss.to_scalar::<f32>().unwrap(), 0.0, "entropy term missing at iteration {it}");
        } else {
            assert_eq!(loss.to_scalar::<f32>().unwrap(), 0.0, "entropy term still on at iteration {it}");
        }
        let grads = loss.add(&loss_of(&net, &mut rng).affine(0.0, 0.0).unwrap()).unwrap().backward().unwrap();
        opt.step(&params, &grads).unwrap();
    }
    assert!(sigmas[19] > sigmas[0] * 1.5, "sigma did not widen: {} -> {}", sigmas[0], sigmas[19]);
    assert!((sigmas[25] / sigmas[24] - 0.99).abs() < 1e-4, "no 0.99 decay after E");
    // The floor is applied to ln sigma, so exp(ln floor) matches the floor to f32 rounding only.
    let last = *sigmas.last().unwrap();
    assert!(
        (last / cfg.sigma_floor as f32 - 1.0).abs() < 1e-5,
        "sigma ends at {last}, not its floor {}",
        cfg.sigma_floor
    );
}

/// The bug: sigma was a raw variable, only clamped to [floor, max] once per iteration, and
/// the 10-20 Adam steps of one PPO update (each about lr = 1e-3, sigma starting at 0.005)
/// drove it negative: ln sigma in the soft-score loss became NaN and S = mu + sigma * eps
/// flipped sign. sigma is now exp(log_sigma): many Adam steps within one iteration, with a
/// large entropy weight and a loss that pushes sigma down, never give sigma <= 0 or a NaN.
#[test]
fn soft_score_sigma_stays_positive_and_finite_under_many_adam_steps() {
    let cfg = MaskConfig { entropy_iterations: Some(1000), entropy_weight: 10.0, ..MaskConfig::default() };
    let (mut net, mut rng) = net_after(0, &cfg);
    net.begin_task(0, &[]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig::default());
    let mut lowest = f32::INFINITY;
    for it in 0..3 {
        net.begin_iteration(it, &mut rng).unwrap();
        let start: Vec<f32> = net.layers().iter().map(|l| l.sigma().unwrap()).collect();
        for step in 0..1000 {
            let params = net.params();
            assert!(params.iter().any(|p| p.name.ends_with("sigma")), "sigma is not trained at iteration {it}");
            let soft = net.soft_score_loss().unwrap();
            let soft_value = soft.to_scalar::<f32>().unwrap();
            assert!(soft_value.is_finite(), "soft-score loss {soft_value} at iteration {it}, step {step}");
            // A penalty on the effective weights W * M_ste: its straight-through gradient on sigma
            // is sum(2 W^2 M eps), positive because the selected elements are those with large eps,
            // so it pushes sigma down, far harder than the entropy term pushes it up.
            let mut push = Tensor::zeros((), candle_core::DType::F32, &candle_core::Device::Cpu).unwrap();
            for l in net.layers() {
                let (w, _) = l.training_weight().unwrap();
                push = push.add(&w.sqr().unwrap().sum_all().unwrap()).unwrap();
            }
            let loss = soft.add(&(push * 1e6).unwrap()).unwrap();
            let grads = loss.backward().unwrap();
            opt.step(&params, &grads).unwrap();
            for (l, s0) in net.layers().iter().zip(&start) {
                let sigma = l.sigma().unwrap();
                assert!(
                    sigma.is_finite() && sigma > 0.0,
                    "{}: sigma = {sigma} at iteration {it}, step {step}",
                    l.name()
                );
                lowest = lowest.min(sigma / s0);
            }
        }
    }
    // The push really drove sigma down within an iteration (where the old raw sigma went negative).
    // A raw sigma moving about 1e-3 per step from 0.005 would have gone negative within 10 steps.
    assert!(lowest < 0.75, "sigma never fell well below its value at the start of an iteration ({lowest})");
}

#[test]
fn forward_transfer_bonus_favours_related_tasks_elements() {
    // Fraction of the selected non-vacant elements that belong to task 0's mask.
    let share_of_task0 = |related: &[usize]| {
        let (mut net, mut rng) = net_after(2, &MaskConfig::default());
        net.begin_task(2, related).unwrap();
        net.begin_iteration(0, &mut rng).unwrap();
        let (mut reused, mut from_task0) = (0, 0);
        for l in net.layers() {
            let m = flat(l.iteration_mask().unwrap());
            let t0 = l.task_mask(0).unwrap();
            for i in (0..m.len()).filter(|&i| m[i] == 1.0 && l.states()[i] != ElementState::Vacant) {
                reused += 1;
                from_task0 += t0.get(i) as usize;
            }
        }
        from_task0 as f64 / reused as f64
    };
    let (with, without) = (share_of_task0(&[0]), share_of_task0(&[]));
    // Measured: 0.99 with the bonus, 0.87 without (task 1 already reused much of task 0).
    assert!(
        with > 0.97 && with > without + 0.05,
        "share of reused elements from related task 0: {with:.3} with bonus, {without:.3} without"
    );
}

#[test]
fn fine_tuning_a_finished_task_moves_only_its_private_elements() {
    let (mut net, mut rng) = net_after(2, &MaskConfig::default());
    let states: Vec<Vec<ElementState>> = net.layers().iter().map(|l| l.states().to_vec()).collect();
    let before: Vec<Vec<f32>> = net.layers().iter().map(|l| l.weight_values().unwrap()).collect();
    net.begin_task(0, &[]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig::default());
    for it in 0..20 {
        net.begin_iteration(it, &mut rng).unwrap();
        let params = net.params();
        assert!(params.iter().all(|p| !p.name.ends_with(".score")), "scores train during fine-tuning");
        let grads = loss_of(&net, &mut rng).backward().unwrap();
        opt.step(&params, &grads).unwrap();
    }
    net.end_task(&mut rng).unwrap();
    for ((l, before), states) in net.layers().iter().zip(before).zip(states) {
        assert_eq!(l.states(), &states[..], "{}: states changed", l.name());
        let after = l.weight_values().unwrap();
        let moved: Vec<usize> = (0..after.len()).filter(|&i| after[i].to_bits() != before[i].to_bits()).collect();
        assert!(!moved.is_empty(), "{}: nothing moved", l.name());
        assert!(
            moved.iter().all(|&i| states[i] == ElementState::Private(0)),
            "{}: a non-private element moved",
            l.name()
        );
    }
}

#[test]
fn fused_forward_matches_the_layer_by_layer_forward() {
    let (mut net, mut rng) = net_after(1, &MaskConfig::default());
    net.begin_task(1, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let x = probe();
    let (a, b) = (flat(&net.forward(&x).unwrap()), flat(&net.forward_unfused(&x).unwrap()));
    assert_eq!(a, flat(&net.forward_no_grad(&x).unwrap()), "forward_no_grad differs from forward");
    for (a, b) in a.iter().zip(&b) {
        assert!((a - b).abs() < 1e-5 * (1.0 + b.abs()), "{a} vs {b}");
    }
}

#[test]
fn misuse_of_the_task_life_cycle_is_an_error_not_a_panic() {
    let (mut net, mut rng) = net_after(1, &MaskConfig::default());
    assert!(net.forward(&probe()).is_err(), "forward without a task in progress");
    assert!(net.forward_task(5, &probe()).is_err(), "recall of a task that never ran");
    let err = net.begin_task(1, &[3]).unwrap_err().to_string();
    assert!(err.contains("related task 3"), "{err}");
    net.begin_task(1, &[0]).unwrap();
    assert!(net.forward(&probe()).is_err(), "forward before begin_iteration");
    assert!(net.begin_task(2, &[]).is_err(), "two tasks at once");
    net.begin_iteration(0, &mut rng).unwrap();
    net.end_task(&mut rng).unwrap();
    assert!(net.end_task(&mut rng).is_err(), "end_task twice");
    let bad = MaskConfig { capacity: 1.5, ..MaskConfig::default() };
    let err = MaskedMlp::new("x", &[2, 2], quadcl::nn::Activation::Elu, &bad, 0).unwrap_err().to_string();
    assert!(err.contains("capacity"), "{err}");
}

#[test]
fn scaling_the_output_init_scales_its_weights_and_only_before_the_first_task() {
    let cfg = MaskConfig::default();
    let plain = MaskedMlp::new("net", &[6, 8, 3], quadcl::nn::Activation::Elu, &cfg, 4).unwrap();
    let mut scaled = MaskedMlp::new("net", &[6, 8, 3], quadcl::nn::Activation::Elu, &cfg, 4).unwrap();
    scaled.scale_output_init(0.01).unwrap();
    let w = |net: &MaskedMlp, l: usize| net.layers()[l].weight_values().unwrap();
    assert_eq!(w(&plain, 0), w(&scaled, 0), "hidden layers are untouched");
    for (a, b) in w(&plain, 1).iter().zip(w(&scaled, 1)) {
        assert_eq!(a * 0.01, b);
    }
    assert!(scaled.scale_output_init(0.0).is_err());
    scaled.begin_task(0, &[]).unwrap();
    let err = scaled.scale_output_init(0.5).unwrap_err().to_string();
    assert!(err.contains("before the first task"), "{err}");
}

#[test]
fn mask_churn_counts_the_selected_share_that_the_previous_draw_did_not_select() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    // sigma far below the spread of mu: the draw is nearly the ranking of mu; only
    // elements within about sigma of a row's k-th score can swap.
    // In score units (`absolute`), so that sigma compares with the spread of mu.
    let still = MaskConfig {
        score_init_std: 1.0,
        sigma_scale: SigmaScale::Absolute,
        sigma_init: 1e-3,
        sigma_floor: 1e-3,
        entropy: false,
        ..MaskConfig::default()
    };
    let mut net = small_mlp(&still, 5);
    net.begin_task(0, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    assert_eq!(net.mask_churn(), None, "no churn before a second draw");
    net.begin_iteration(1, &mut rng).unwrap();
    let churn = net.mask_churn().unwrap();
    assert!(churn < 0.01, "a still mask churned {churn}");

    // sigma far above the spread of mu: every draw is a fresh random top-k, so about 1 - c of it is new.
    let noisy = MaskConfig {
        score_init_std: 1e-3,
        sigma_scale: SigmaScale::Absolute,
        sigma_init: 0.05,
        sigma_max: 0.05,
        entropy: false,
        ..MaskConfig::default()
    };
    let mut net = small_mlp(&noisy, 5);
    net.begin_task(0, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let before: Vec<Vec<f32>> = net.layers().iter().map(|l| flat(l.iteration_mask().unwrap())).collect();
    net.begin_iteration(1, &mut rng).unwrap();
    for (l, before) in net.layers().iter().zip(&before) {
        let now = flat(l.iteration_mask().unwrap());
        let selected = now.iter().filter(|m| **m == 1.0).count();
        let entered = now.iter().zip(before).filter(|(n, b)| **n == 1.0 && **b == 0.0).count();
        assert_eq!(l.mask_churn(), Some(entered as f64 / selected as f64), "{}", l.name());
    }
    let churn = net.mask_churn().unwrap();
    assert!(churn > 0.6, "random redraws replaced only {churn} of the mask");
    let per_layer: Vec<f64> = net.layers().iter().map(|l| l.mask_churn().unwrap()).collect();
    let (lo, hi) = per_layer.iter().fold((f64::MAX, f64::MIN), |(a, b), &c| (a.min(c), b.max(c)));
    assert!((lo..=hi).contains(&churn), "network churn {churn} outside its layers' {per_layer:?}");
}

/// Under `sigma_scale = "score_gap"` sigma is measured in each row's score gap at the cut, so
/// the same sigma redraws about the same share of the mask whatever the scores' spread, and a
/// larger sigma redraws more; in score units the same sigma does nothing to widely spread scores.
#[test]
fn in_score_gap_units_the_churn_follows_sigma_not_the_scores_spread() {
    let churn = |score_init_std: f64, sigma: f64, sigma_scale: SigmaScale| -> f64 {
        let cfg = MaskConfig {
            score_init_std,
            sigma_scale,
            sigma_init: sigma,
            sigma_floor: sigma.min(1e-3),
            sigma_max: sigma.max(1.0),
            entropy: false,
            ..MaskConfig::default()
        };
        let mut net = small_mlp(&cfg, 5);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        net.begin_task(0, &[]).unwrap();
        // The mean churn of 20 redraws of the same scores (nothing trains in between).
        (0..21)
            .filter_map(|it| {
                net.begin_iteration(it, &mut rng).unwrap();
                net.mask_churn()
            })
            .sum::<f64>()
            / 20.0
    };
    let (narrow, wide) = (churn(1e-3, 1.0, SigmaScale::ScoreGap), churn(1.0, 1.0, SigmaScale::ScoreGap));
    assert!(narrow > 0.02 && wide > 0.02, "sigma 1 gap redraws part of the mask: {narrow}, {wide}");
    assert!((narrow / wide - 1.0).abs() < 0.35, "the spread of the scores changed the churn: {narrow} vs {wide}");
    let small = churn(1.0, 0.1, SigmaScale::ScoreGap);
    assert!(small < 0.5 * wide, "sigma 0.1 gap churned {small}, sigma 1 gap {wide}");
    let absolute = churn(1.0, 1e-3, SigmaScale::Absolute);
    assert!(absolute < 0.5 * small, "sigma 1e-3 in score units churned {absolute} of spread-1 scores");
}

#[test]
fn under_a_related_bias_start_a_new_task_starts_from_the_mean_bias_of_its_related_tasks() {
    let cfg = MaskConfig { bias_start: BiasStart::Related, ..MaskConfig::default() };
    let (mut net, _) = net_after(2, &cfg);
    let start_bias = |net: &mut MaskedMlp, related: &[usize]| -> Vec<Vec<f32>> {
        net.begin_task(2, related).unwrap();
        let b = net.layers().iter().map(|l| l.training_bias().unwrap().unwrap()).collect();
        // Back to between tasks without ending task 2.
        *net = net_after(2, &cfg).0;
        b
    };
    for (layer, bias) in start_bias(&mut net, &[]).iter().enumerate() {
        assert!(bias.iter().all(|b| *b == 0.0), "layer {layer}: a task with no related task starts from zero bias");
    }
    let both = start_bias(&mut net, &[0, 1]);
    let only_first = start_bias(&mut net, &[0]);
    for (k, l) in net.layers().iter().enumerate() {
        let (b0, b1) = (l.task_bias(0).unwrap(), l.task_bias(1).unwrap());
        assert!(b0.iter().zip(b1).any(|(a, b)| a != b), "{}: tasks 0 and 1 ended with the same bias", l.name());
        assert_eq!(only_first[k], b0, "{}", l.name());
        for i in 0..b0.len() {
            assert!((both[k][i] - (b0[i] + b1[i]) / 2.0).abs() <= 1e-6, "{} element {i}", l.name());
        }
    }
}

#[test]
fn a_task_that_takes_all_of_a_related_task_starts_as_it_when_fresh_weights_start_small() {
    // Task 0 keeps nothing private (p = 0). Task 1 names it as related and selects
    // c = 0.34 of a row: its occupied quota (0.75 of it) holds all of task 0's 0.2.
    // The rest of its selection is fresh vacant weights, re-initialised at
    // `reinit_scale` times the initialiser's range.
    let start_gap = |reinit_scale: f64| -> f32 {
        let cfg = MaskConfig { private_share: 0.0, reinit_scale, ..MaskConfig::default() };
        let (mut net, mut rng) = net_after(1, &cfg);
        for l in net.layers() {
            let w = l.weight_values().unwrap();
            let (bound, _) = w
                .iter()
                .zip(l.states())
                .filter(|(_, s)| **s == ElementState::Vacant)
                .fold((0.0f32, 0), |(m, n), (w, _)| (m.max(w.abs()), n + 1));
            let full = (6.0 / (0.2 * l.shape().1 as f32)).sqrt();
            assert!(
                bound <= reinit_scale as f32 * full + 1e-6,
                "{}: vacant |w| up to {bound}, range {full} x {reinit_scale}",
                l.name()
            );
        }
        net.set_mask_config(&MaskConfig { capacity: 0.34, ..cfg }).unwrap();
        net.begin_task(1, &[0]).unwrap();
        net.begin_iteration(0, &mut rng).unwrap();
        for l in net.layers() {
            let m = flat(l.iteration_mask().unwrap());
            let t0 = l.task_mask(0).unwrap();
            assert!(
                (0..m.len()).all(|i| !t0.get(i) || m[i] == 1.0),
                "{}: an element of task 0 is not selected",
                l.name()
            );
        }
        let x = inputs(32, &mut rng);
        let now = flat(&net.forward(&x).unwrap());
        let related = flat(&net.forward_task(0, &x).unwrap());
        let scale = related.iter().map(|v| v.abs()).fold(0.0f32, f32::max);
        now.iter().zip(&related).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max) / scale
    };
    let (zero, tenth, full) = (start_gap(0.0), start_gap(0.1), start_gap(1.0));
    // Measured: 0, 0.11 and 1.13 of the largest output.
    assert!(zero < 1e-5, "with zero fresh weights the first forward is task 0's (gap {zero})");
    assert!(tenth < 0.5 * full && full > 0.05, "largest output gap to task 0: {tenth} at scale 0.1, {full} at scale 1");
}
