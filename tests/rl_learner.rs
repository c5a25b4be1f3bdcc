//! The PPO learner end to end on the point-mass toy environment, with the
//! masked networks training their weights and masks together (task 0).

mod rl_common;
use quadcl::config::Config;
use quadcl::rl::{Agent, PpoLearner, ToyEnv, TrainEnv};
use rl_common::small_ppo_config;

fn run(cfg: &Config, iterations: usize, seed: u64) -> Vec<quadcl::rl::Metrics> {
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, seed);
    let mut agent = Agent::new(env.dims(), cfg, seed).unwrap();
    agent.begin_task(0, &[]).unwrap();
    let mut learner = PpoLearner::new(cfg.ppo.clone(), agent, cfg.ppo.num_envs, seed).unwrap();
    (0..iterations).map(|_| learner.train_iteration(&mut env).unwrap()).collect()
}

#[test]
fn one_iteration_reports_every_namespaced_metric() {
    let metrics = run(&small_ppo_config(), 1, 1);
    for key in [
        "charts/episodic_return",
        "charts/SPS",
        "charts/lin_vel_err",
        "charts/learning_rate",
        "losses/approx_kl",
        "losses/value_loss",
        "losses/policy_loss",
        "losses/entropy",
        "losses/soft_score",
        "losses/cenet_velocity",
        "losses/cenet_reconstruction",
        "losses/cenet_kl",
        "time/env_s",
        "time/update_s",
        "charts/sigma/actor.l0",
        "charts/score_gap/critic.l2",
        "charts/sigma/cenet_encoder.l0",
        "plasticity/dormant/actor",
        "plasticity/dormant/cenet_decoder",
        "plasticity/effective_rank/critic",
        "plasticity/selected_abs_w/actor.l0",
        "plasticity/trainable_share/cenet_encoder.l1",
        "time/plasticity_s",
        "time/masks_s",
    ] {
        let v = metrics[0].get(key).unwrap_or_else(|| panic!("missing {key}: {:?}", metrics[0].keys()));
        assert!(v.is_finite(), "{key} = {v}");
    }
}

#[test]
fn the_plasticity_diagnostics_of_a_first_task_are_in_range() {
    let metrics = run(&small_ppo_config(), 2, 3);
    for m in &metrics {
        for (key, v) in m.iter().filter(|(k, _)| k.starts_with("plasticity/")) {
            let ok = match key.split('/').nth(1) {
                // At most the last hidden layer's width (32 or 16 here).
                Some("effective_rank") => (1.0..=32.0).contains(v),
                Some("selected_abs_w") => *v > 0.0 && v.is_finite(),
                _ => (0.0..=1.0).contains(v),
            };
            assert!(ok, "{key} = {v}");
        }
        // A first task: every selected weight is vacant, so the task may change all of them.
        assert_eq!(m["plasticity/trainable_share/actor.l0"], 1.0);
    }
}

#[test]
fn ppo_learns_to_track_the_toy_command() {
    let cfg = small_ppo_config();
    let metrics = run(&cfg, 40, 2);
    let first = metrics[0]["charts/mean_step_reward"];
    let last = metrics[metrics.len() - 1]["charts/mean_step_reward"];
    // Perfect tracking gives 0.1 per step; an untrained policy with std 0.5 far less.
    assert!(last > first + 0.02 && last > 0.07, "mean step reward {first} -> {last}");
}

#[test]
fn same_seed_gives_the_same_training_curve() {
    let cfg = small_ppo_config();
    let strip = |ms: Vec<quadcl::rl::Metrics>| -> Vec<Vec<(String, f64)>> {
        ms.into_iter()
            .map(|m| m.into_iter().filter(|(k, _)| !k.starts_with("time/") && k != "charts/SPS").collect())
            .collect()
    };
    let a = strip(run(&cfg, 3, 7));
    let b = strip(run(&cfg, 3, 7));
    assert_eq!(a, b);
    let c = strip(run(&cfg, 3, 8));
    assert_ne!(a, c, "a different seed should give a different curve");
}

/// Largest |action mean| of a fresh agent (task 0 begun) on the standing robot's observations.
fn fresh_action_means_max(ppo: quadcl::config::PpoConfig) -> f32 {
    use quadcl::rl::SimTrainEnv;
    use rand::SeedableRng;
    let cfg = quadcl::config::Config { ppo, ..quadcl::config::Config::default() };
    let env = SimTrainEnv::new(&cfg.env, &quadcl::sim::Perturbation::none(), 8, 1).unwrap();
    let mut agent = quadcl::rl::Agent::new(env.dims(), &cfg, 1).unwrap();
    agent.begin_task(0, &[]).unwrap();
    agent.begin_iteration(0, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1)).unwrap();
    let means = agent.act_deterministic(env.observations(), env.obs_histories()).unwrap();
    means.iter().fold(0f32, |m, a| m.max(a.abs()))
}

#[test]
fn a_fresh_actor_starts_near_the_default_pose_not_at_a_random_offset() {
    let scaled = fresh_action_means_max(quadcl::config::PpoConfig::default());
    assert!(scaled < 0.1, "initial action means up to {scaled}: the policy would start folded over");
    let plain =
        fresh_action_means_max(quadcl::config::PpoConfig { actor_output_init_scale: 1.0, ..Default::default() });
    assert!(plain > 0.5, "without the scale the means reach {plain}; the test no longer shows what the scale is for");
}

/// Bit patterns of a value list, to compare forwards exactly.
fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn frozen_acting_weights_give_the_training_forwards_numbers_bit_for_bit() {
    use candle_core::{Device, Tensor};
    use rand::SeedableRng;
    let cfg = small_ppo_config();
    let env = ToyEnv::new(cfg.ppo.num_envs, 10, 3);
    let mut agent = Agent::new(env.dims(), &cfg, 3).unwrap();
    agent.begin_task(0, &[]).unwrap();
    agent.begin_iteration(0, &mut rand_chacha::ChaCha8Rng::seed_from_u64(5)).unwrap();
    let d = env.dims();
    let n = cfg.ppo.num_envs;
    let privileged = agent.normalize_privileged(env.privileged_observations());
    for recall in [false, true] {
        let weights = agent.acting_weights().unwrap();
        // The critic: the differentiable forward the update uses against the frozen one.
        let x = Tensor::from_vec(privileged.clone(), (n, d.privileged_obs), &Device::Cpu).unwrap();
        let tracked = agent.value(&x).unwrap().to_vec1::<f32>().unwrap();
        assert_eq!(bits(&tracked), bits(&agent.values_with(&weights, &privileged).unwrap()), "recall {recall}");
        // The actor with its CENet context: fresh weights each call against one frozen set.
        let fresh = agent.act_deterministic(env.observations(), env.obs_histories()).unwrap();
        let frozen = agent.act_deterministic_with(&weights, env.observations(), env.obs_histories()).unwrap();
        assert_eq!(bits(&fresh), bits(&frozen), "recall {recall}");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (obs, history) = (agent.normalize_obs(env.observations()), agent.normalize_obs(env.obs_histories()));
        let sampled = agent.act(&obs, &history, &mut rng).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let sampled_frozen = agent.act_with(&weights, &obs, &history, &mut rng).unwrap();
        assert_eq!(bits(&sampled.actions), bits(&sampled_frozen.actions), "recall {recall}");
        if !recall {
            agent.end_task(&mut rand_chacha::ChaCha8Rng::seed_from_u64(6)).unwrap();
        }
    }
}

/// With `entropy_target = "action"` the method's beta_H joins PPO's entropy bonus in a task's
/// first E iterations: the policy's action std grows where the soft-score reading leaves it.
#[test]
fn an_entropy_term_on_the_action_widens_the_policys_action_distribution() {
    let action_std = |target: quadcl::nn::EntropyTarget| -> f64 {
        let mut cfg = small_ppo_config();
        cfg.net.mask.entropy_target = target;
        cfg.net.mask.entropy_weight = 1.0;
        cfg.net.mask.entropy_iterations = Some(4);
        let metrics = run(&cfg, 4, 3);
        assert!(metrics
            .iter()
            .all(|m| (m["losses/soft_score"] == 0.0) == (target == quadcl::nn::EntropyTarget::Action)));
        metrics[3]["charts/action_std"]
    };
    let (on_scores, on_action) =
        (action_std(quadcl::nn::EntropyTarget::SoftScores), action_std(quadcl::nn::EntropyTarget::Action));
    assert!(on_action > on_scores * 1.02, "action std {on_action} with the term on the action, {on_scores} without");
}
