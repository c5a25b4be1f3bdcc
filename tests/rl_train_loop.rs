//! `rl::train` end to end on the toy environment: files written, policy
//! directory round trip through `nn::checkpoint`, evaluation.

mod rl_common;
use quadcl::config::Config;
use quadcl::rl::{evaluate, load_policy, save_policy, train, Agent, ToyEnv, TrainEnv};
use rl_common::small_ppo_config;

fn toy_config(iterations: usize) -> Config {
    let mut cfg = small_ppo_config();
    cfg.seed = 5;
    cfg.ppo.iterations = iterations;
    cfg
}

#[test]
fn training_writes_config_metrics_and_a_policy_that_reloads_bit_identically() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(3);
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, 1);
    let summary = train(&cfg, "none", &mut env, dir.path(), false).unwrap();
    assert_eq!(summary.iterations, 3);
    assert_eq!(summary.env_steps, 3 * 32 * 16);

    let text = std::fs::read_to_string(dir.path().join("metrics.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 3);
    assert!(lines[2]["losses/approx_kl"].is_number() && lines[2]["charts/SPS"].is_number());
    assert_eq!(Config::load(&dir.path().join("config.toml")).unwrap(), cfg);

    let loaded = load_policy(&dir.path().join("policy"), None).unwrap();
    assert_eq!(loaded.tasks, vec!["none".to_string()]);
    assert_eq!(loaded.info.iterations, 3);
    assert!(loaded.agent.in_recall() && loaded.agent.obs_normalizer().is_frozen());
    save_policy(&loaded.agent, &loaded.tasks, &loaded.info, &dir.path().join("again")).unwrap();
    for file in ["model.safetensors", "masks.safetensors"] {
        assert_eq!(
            std::fs::read(dir.path().join("policy").join(file)).unwrap(),
            std::fs::read(dir.path().join("again").join(file)).unwrap(),
            "{file} changed across a load/save round trip"
        );
    }
    let reloaded = load_policy(&dir.path().join("again"), Some("none")).unwrap();
    let env = ToyEnv::new(8, 10, 4);
    let a = loaded.agent.act_deterministic(env.observations(), env.obs_histories()).unwrap();
    let b = reloaded.agent.act_deterministic(env.observations(), env.obs_histories()).unwrap();
    assert_eq!(a, b);
}

#[test]
fn asking_for_an_unknown_task_names_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(1);
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, 1);
    train(&cfg, "none", &mut env, dir.path(), false).unwrap();
    let err = format!("{:#}", load_policy(&dir.path().join("policy"), Some("crash:FL")).unwrap_err());
    assert!(err.contains("crash:FL") && err.contains("none"), "{err}");
}

#[test]
fn a_trained_toy_policy_evaluates_better_than_an_untrained_one() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(30);
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, 1);
    train(&cfg, "none", &mut env, dir.path(), false).unwrap();
    let trained = load_policy(&dir.path().join("policy"), None).unwrap().agent;
    let mut untrained = Agent::new(env.dims(), &cfg, 99).unwrap();
    untrained.begin_task(0, &[]).unwrap();
    untrained.begin_iteration(0, &mut <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1)).unwrap();
    let eval = |agent: &Agent| evaluate(agent, &mut ToyEnv::new(64, 10, 3), "none", 3, 100).unwrap();
    let (good, bad) = (eval(&trained), eval(&untrained));
    assert_eq!(good.episodes, 64);
    assert!(good.lin_vel_err < 0.15 && good.lin_vel_err < bad.lin_vel_err, "{good:?} vs {bad:?}");
    assert_eq!(eval(&trained), good, "evaluation is deterministic");
}
