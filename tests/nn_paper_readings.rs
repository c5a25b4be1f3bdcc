//! The paper's readings as switches (docs/method.md, "The paper's experiments and ours"):
//! the soft-score means step at their own fixed Adam rate whatever the optimiser's
//! (KL-adapted) rate does, and at the optimiser's when that rate is 0; a first task from the
//! intact network selects only vacant elements, c of each row, and trains exactly them.

mod nn_common;
use nn_common::*;
use quadcl::config::net::row_quota;
use quadcl::nn::{AdamConfig, ElementState, MaskConfig, MaskedAdam, MaskedMlp};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A layer's (score means before, after, weights before, after) one step.
type Step = (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>);

/// One Adam step of a fresh network's first task at the optimiser's rate `rate`, layer by layer.
fn one_step(cfg: &MaskConfig, rate: f64) -> Vec<Step> {
    let mut net = small_mlp(cfg, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    net.begin_task(0, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let before: Vec<_> = net.layers().iter().map(|l| (l.score_values().unwrap(), l.weight_values().unwrap())).collect();
    let x = inputs(64, &mut rng);
    let task = &tasks(1, 7)[0];
    let loss = net.forward(&x).unwrap().sub(&targets(task, &x)).unwrap().sqr().unwrap().mean_all().unwrap();
    let params = net.params();
    let mut opt = MaskedAdam::new(AdamConfig { learning_rate: rate, ..AdamConfig::default() });
    opt.step(&params, &loss.backward().unwrap()).unwrap();
    net.layers()
        .iter()
        .zip(before)
        .map(|(l, (s0, w0))| (s0, l.score_values().unwrap(), w0, l.weight_values().unwrap()))
        .collect()
}

fn largest_change(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

#[test]
fn soft_score_means_move_at_their_fixed_rate_whatever_the_optimisers_rate() {
    let paper = MaskConfig::default();
    assert_eq!(paper.score_learning_rate, 1e-3);
    // The KL rule moves the optimiser's rate between these; the means must not notice.
    let (slow, fast) = (one_step(&paper, 1e-5), one_step(&paper, 1e-2));
    for (i, ((s0, s_slow, w0, w_slow), (_, s_fast, _, w_fast))) in slow.iter().zip(&fast).enumerate() {
        assert_eq!(s_slow, s_fast, "layer {i}: the means moved alike at both optimiser rates");
        let step = largest_change(s0, s_slow);
        // Adam's first step is the rate times g / (|g| + eps): at most the rate, about it where |g| >> eps.
        assert!(step <= 1e-3 * 1.01 && step > 0.5e-3, "layer {i}: the means moved by up to {step}");
        assert!(
            largest_change(w0, w_fast) > 10.0 * largest_change(w0, w_slow),
            "layer {i}: the weights follow the optimiser"
        );
    }
    // Rate 0: the means at the optimiser's rate, as before issue 60.
    let at_ppo = MaskConfig { score_learning_rate: 0.0, ..MaskConfig::default() };
    let (slow, fast) = (one_step(&at_ppo, 1e-5), one_step(&at_ppo, 1e-2));
    for (i, ((s0, s_slow, ..), (_, s_fast, ..))) in slow.iter().zip(&fast).enumerate() {
        let (a, b) = (largest_change(s0, s_slow), largest_change(s0, s_fast));
        assert!(a <= 1e-5 * 1.01 && b > 0.5e-2, "layer {i}: means moved {a} at 1e-5 and {b} at 1e-2");
    }
}

#[test]
fn a_first_task_from_the_intact_network_selects_only_vacant_elements_and_trains_c_of_each_row() {
    let cfg = MaskConfig::default();
    let mut net: MaskedMlp = small_mlp(&cfg, 8);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    assert!(net.layers().iter().all(|l| l.states().iter().all(|s| *s == ElementState::Vacant)), "intact");
    net.begin_task(0, &[]).unwrap();
    net.begin_iteration(0, &mut rng).unwrap();
    let params = net.params();
    for layer in net.layers() {
        let (rows, cols) = layer.shape();
        let k = row_quota(cfg.capacity, cols);
        let mask: Vec<f32> = layer.iteration_mask().unwrap().flatten_all().unwrap().to_vec1().unwrap();
        for r in 0..rows {
            assert_eq!(
                mask[r * cols..(r + 1) * cols].iter().filter(|m| **m > 0.5).count(),
                k,
                "{} row {r}",
                layer.name()
            );
        }
        // What trains is exactly the selection: every selected element is vacant.
        let update = params.iter().find(|p| p.name == format!("{}.weight", layer.name())).unwrap();
        let update: Vec<f32> = update.update_mask.as_ref().unwrap().flatten_all().unwrap().to_vec1().unwrap();
        assert_eq!(update, mask, "{}: the weights that may move are the selected ones", layer.name());
    }
    // After the task, each row holds k elements of it (occupied, or private to it), the rest vacant.
    let mut net = small_mlp(&cfg, 8);
    train_task(&mut net, 0, &tasks(1, 10)[0], 5, 1e-3, &mut rng);
    for layer in net.layers() {
        let (rows, cols) = layer.shape();
        let k = row_quota(cfg.capacity, cols);
        for r in 0..rows {
            let taken = layer.states()[r * cols..(r + 1) * cols].iter().filter(|s| **s != ElementState::Vacant).count();
            assert_eq!(taken, k, "{} row {r}", layer.name());
        }
    }
}

#[test]
fn a_redraw_of_vacant_weights_changes_only_vacant_ones_and_keeps_every_recall_bit_for_bit() {
    let cfg = MaskConfig::default();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut net = small_mlp(&cfg, 12);
    train_task(&mut net, 0, &tasks(1, 13)[0], 5, 1e-3, &mut rng);
    let recall = bits(&net.forward_task(0, &probe()).unwrap());
    let before: Vec<Vec<f32>> = net.layers().iter().map(|l| l.weight_values().unwrap()).collect();
    for scale in [0.0, 0.1] {
        let run = MaskConfig { reinit_scale: scale, ..cfg.clone() };
        net.redraw_vacant_weights(&run, &mut rng).unwrap();
        assert_eq!(bits(&net.forward_task(0, &probe()).unwrap()), recall, "task 0 recalls as before at {scale}");
        for (layer, w0) in net.layers().iter().zip(&before) {
            let w = layer.weight_values().unwrap();
            // The initialiser's range over the full fan-in (`reinit_range = "initial"`), He-uniform.
            let bound = (6.0 / layer.shape().1 as f32).sqrt() * scale as f32;
            let mut vacant_nonzero = 0;
            for ((w, w0), s) in w.iter().zip(w0).zip(layer.states()) {
                if *s == ElementState::Vacant {
                    assert!(w.abs() <= bound * 1.0001, "{}: a vacant weight {w} beyond {bound}", layer.name());
                    vacant_nonzero += usize::from(*w != 0.0);
                } else {
                    assert_eq!(w.to_bits(), w0.to_bits(), "{}: a weight of task 0 moved", layer.name());
                }
            }
            assert_eq!(vacant_nonzero > 0, scale > 0.0, "{}: at scale {scale}", layer.name());
        }
    }
    // A task in progress keeps its weights: the redraw is for between tasks.
    net.begin_task(1, &[]).unwrap();
    assert!(net.redraw_vacant_weights(&cfg, &mut rng).is_err());
}
