//! The plasticity entropy phase moves the selection (METHOD.md 2.3, issue 13
//! item 2), on the toy learner: during a task's first E iterations the term
//! -beta_H * H widens sigma (in score-gap units, at its own fixed learning
//! rate), so the hard mask is redrawn measurably more than without the term;
//! every layer's sigma and churn are in each iteration's metrics and in the
//! task's curve.

use quadcl::config::net::MaskConfig;
use quadcl::engine::{Learner, TaskCurve, TaskStart, ToyLearner};
use quadcl::rl::Metrics;

const E: usize = 40;

/// The first E + 20 iterations of one toy task, entropy term on or off.
fn first_iterations(entropy: bool) -> Vec<Metrics> {
    // One Adam step per toy iteration: a rate of 0.05 lets ln sigma move by up to 2 in E
    // iterations (a PPO update takes 10 steps per iteration at the default 1e-3). The toy's
    // 8x32 and 32x2 layers have few scores, and its regression loss pushes sigma down about as
    // hard as beta_H = 1e-4 pushes it up (the term's gradient on ln sigma is beta_H per score;
    // a 512-wide PPO layer has 100 times as many): beta_H = 1e-2 here.
    let mask = MaskConfig {
        entropy,
        entropy_iterations: Some(E),
        entropy_weight: 1e-2,
        sigma_learning_rate: 0.05,
        ..MaskConfig::default()
    };
    let mut learner = ToyLearner::new(&mask, 3).unwrap();
    let start =
        TaskStart { step: 0, task: 0, name: "none".into(), related: vec![], mask, iterations: E + 20, seed: 11 };
    learner.begin_task(&start).unwrap();
    (0..E + 20).map(|_| learner.train_iteration().unwrap()).collect()
}

fn series(metrics: &[Metrics], key: &str) -> Vec<f64> {
    metrics.iter().filter_map(|m| m.get(key).copied()).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn the_entropy_phase_widens_sigma_and_redraws_more_of_the_mask_than_without_it() {
    let (with, without) = (first_iterations(true), first_iterations(false));
    for layer in ["toy.l0", "toy.l1"] {
        let sigma = |m: &[Metrics]| series(m, &format!("charts/sigma/{layer}"));
        let churn = |m: &[Metrics]| series(m, &format!("charts/mask_churn/{layer}"));
        let (s_with, s_without) = (sigma(&with), sigma(&without));
        assert_eq!(s_with.len(), E + 20, "{layer}: a sigma every iteration");
        assert_eq!(churn(&with).len(), E + 19, "{layer}: a churn from the second iteration");
        assert!(with.iter().all(|m| m.contains_key(&format!("charts/score_gap/{layer}"))), "{layer}: the score gap");
        // The term pushes ln sigma up by about the rate every step; without it only the
        // loss moves sigma.
        assert!(s_with[E - 1] > 3.0 * s_with[0], "{layer}: sigma {} -> {} with the term", s_with[0], s_with[E - 1]);
        assert!(
            s_with[E - 1] > 2.0 * s_without[E - 1],
            "{layer}: {} with, {} without",
            s_with[E - 1],
            s_without[E - 1]
        );
        // After E iterations sigma decays x0.99 per iteration.
        assert!((s_with[E + 5] / s_with[E + 4] - 0.99).abs() < 1e-4, "{layer}: no decay after E");
    }
    // The selection: the mean churn of the whole network over the second half of the phase.
    let phase_churn = |m: &[Metrics]| {
        let per_layer: Vec<f64> = ["toy.l0", "toy.l1"]
            .iter()
            .map(|l| mean(&series(&m[E / 2..E], &format!("charts/mask_churn/{l}"))))
            .collect();
        mean(&per_layer)
    };
    let (c_with, c_without) = (phase_churn(&with), phase_churn(&without));
    assert!(c_with > 0.05, "the entropy phase redrew only {c_with} of the mask per iteration");
    assert!(c_with > 1.5 * c_without, "churn {c_with} with the entropy term, {c_without} without");
}

#[test]
fn a_tasks_curve_keeps_each_layers_sigma_and_churn() {
    let metrics = first_iterations(true);
    let mut curve = TaskCurve::default();
    metrics.iter().for_each(|m| curve.push(m));
    assert_eq!(curve.sigma.keys().collect::<Vec<_>>(), ["toy.l0", "toy.l1"]);
    assert_eq!(curve.sigma["toy.l0"], series(&metrics, "charts/sigma/toy.l0"));
    assert_eq!(curve.mask_churn["toy.l1"], series(&metrics, "charts/mask_churn/toy.l1"));
    let json = serde_json::to_value(&curve).unwrap();
    assert!(json["sigma"]["toy.l0"].is_array() && json["mask_churn"]["toy.l0"].is_array(), "{json}");
    // A curve without layers (a dense method) writes neither key.
    let dense = serde_json::to_value(TaskCurve::default()).unwrap();
    assert!(dense.get("sigma").is_none() && dense.get("mask_churn").is_none(), "{dense}");
}

#[test]
fn the_entropy_phase_scales_with_the_tasks_budget() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("run.toml");
    let run = |phase: &str| {
        std::fs::write(
            &cfg,
            format!(
                "seed = 2\n[run]\nlearner = \"toy\"\n[net.mask]\n{phase}\n[[task]]\nname = \"crash:FL\"\n\
                 iterations = 20\n[[task]]\nname = \"invert:RR\"\niterations = 40\n"
            ),
        )
        .unwrap();
        let out = tmp.path().join(phase.replace([' ', '='], ""));
        let options = quadcl::headless::RunOptions { no_tensorboard: true, ..Default::default() };
        quadcl::headless::run(&cfg, &out, options).unwrap()
    };
    let share = run("entropy_fraction = 0.25");
    let phases: Vec<usize> = share.steps.iter().map(|s| s.soft_scores.unwrap().entropy_iterations).collect();
    assert_eq!(phases, [5, 10], "a quarter of 20 and of 40 iterations");
    assert!(share.steps.iter().all(|s| s.soft_scores.unwrap().score_learning_rate == 1e-3), "the paper's rate");
    for (curve, e) in share.curves.iter().zip([5, 10]) {
        let sigma = &curve.sigma["toy.l0"];
        let ratio = |i: usize| sigma[i] / sigma[i - 1];
        assert!((ratio(e - 1) - 0.99).abs() > 1e-4, "{}: sigma trains, not decays, inside the phase", curve.name);
        for i in e + 1..sigma.len() {
            assert!((ratio(i) - 0.99).abs() < 1e-4, "{}: no decay at iteration {i} after E = {e}", curve.name);
        }
    }
    // A count stays a count whatever the budget.
    let count = run("entropy_iterations = 5");
    let phases: Vec<usize> = count.steps.iter().map(|s| s.soft_scores.unwrap().entropy_iterations).collect();
    assert_eq!(phases, [5, 5]);
}
