//! The gradient and life-cycle rules of a masked layer (METHOD.md 2.2 to 2.6):
//! which elements move, the straight-through score gradient, the entropy
//! schedule of sigma, forward transfer, and private fine-tuning.

mod nn_common;
use candle_core::Tensor;
use nn_common::*;
use quadcl::nn::{AdamConfig, ElementState, MaskConfig, MaskedAdam, MaskedMlp};
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
    let (gw, gs, w, m) = (grad("net.l1.weight"), grad("net.l1.score"), l.weight_values().unwrap(), flat(l.iteration_mask().unwrap()));
    let mut unselected_with_gradient = 0;
    for i in 0..w.len() {
        if m[i] == 1.0 {
            // dL/dmu = dL/dWeff * W and dL/dW = dL/dWeff * M = dL/dWeff where selected.
            assert!((gs[i] - gw[i] * w[i]).abs() <= 1e-6 * (1.0 + gs[i].abs()), "element {i}: {} vs {}", gs[i], gw[i] * w[i]);
        } else {
            assert_eq!(gw[i], 0.0, "unselected weight {i} has a gradient");
            unselected_with_gradient += (gs[i] != 0.0) as usize;
        }
    }
    assert!(unselected_with_gradient > w.len() / 2, "only {unselected_with_gradient} unselected scores got a gradient");
}

#[test]
fn entropy_term_widens_sigma_then_sigma_decays_to_its_floor() {
    let cfg = MaskConfig { entropy_iterations: 20, entropy_weight: 1.0, ..MaskConfig::default() };
    let (mut net, mut rng) = net_after(0, &cfg);
    net.begin_task(0, &[]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig::default());
    let mut sigmas = Vec::new();
    for it in 0..400 {
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
    assert_eq!(*sigmas.last().unwrap(), cfg.sigma_floor as f32);
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
    assert!(with > 0.97 && with > without + 0.05, "share of reused elements from related task 0: {with:.3} with bonus, {without:.3} without");
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
        assert!(moved.iter().all(|&i| states[i] == ElementState::Private(0)), "{}: a non-private element moved", l.name());
    }
}

#[test]
fn fused_forward_matches_the_layer_by_layer_forward() {
    let (mut net, mut rng) = net_after(1, &MaskConfig::default());
    net.begin_task(1, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let x = probe();
    let (a, b) = (flat(&net.forward(&x).unwrap()), flat(&net.forward_unfused(&x).unwrap()));
    for (a, b) in a.iter().zip(&b) {
        assert!((a - b).abs() < 1e-5 * (1.0 + b.abs()), "{a} vs {b}");
    }
}
