//! `rl::train` end to end on the toy environment: files written, policy
//! directory round trip, evaluation.

use quadcl::config::{Config, PpoConfig};
use quadcl::rl::toy_env::ToyEnv;
use quadcl::rl::{evaluate, load_policy, save_policy, train, Agent, TrainEnv};

fn toy_config(iterations: usize) -> Config {
    Config {
        seed: 5,
        ppo: PpoConfig {
            num_envs: 32,
            steps_per_env: 16,
            iterations,
            actor_hidden: vec![32, 32],
            critic_hidden: vec![32, 32],
            cenet_encoder_hidden: vec![16],
            cenet_decoder_hidden: vec![16],
            cenet_latent_dim: 2,
            init_action_std: 0.5,
            ..PpoConfig::default()
        },
        ..Config::default()
    }
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

    let (agent, manifest) = load_policy(&dir.path().join("policy")).unwrap();
    assert_eq!((manifest.task.as_str(), manifest.iterations), ("none", 3));
    assert!(agent.obs_normalizer.is_frozen());
    save_policy(&agent, &cfg, "none", 3, &dir.path().join("again")).unwrap();
    assert_eq!(
        std::fs::read(dir.path().join("policy/model.safetensors")).unwrap(),
        std::fs::read(dir.path().join("again/model.safetensors")).unwrap()
    );
}

#[test]
fn a_corrupted_weights_file_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(1);
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, 1);
    train(&cfg, "none", &mut env, dir.path(), false).unwrap();
    let weights = dir.path().join("policy/model.safetensors");
    let mut bytes = std::fs::read(&weights).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&weights, bytes).unwrap();
    let err = format!("{:#}", load_policy(&dir.path().join("policy")).unwrap_err());
    assert!(err.contains("model.safetensors") && err.contains("sha256"), "{err}");
}

#[test]
fn a_trained_toy_policy_evaluates_better_than_an_untrained_one() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = toy_config(30);
    let mut env = ToyEnv::new(cfg.ppo.num_envs, 10, 1);
    train(&cfg, "none", &mut env, dir.path(), false).unwrap();
    let (trained, _) = load_policy(&dir.path().join("policy")).unwrap();
    let untrained = Agent::new(env.dims(), &cfg.ppo, 99).unwrap();
    let eval = |agent: &Agent| evaluate(agent, &mut ToyEnv::new(64, 10, 3), "none", 3, 100).unwrap();
    let (good, bad) = (eval(&trained), eval(&untrained));
    assert_eq!(good.episodes, 64);
    assert!(good.lin_vel_err < 0.15 && good.lin_vel_err < bad.lin_vel_err, "{good:?} vs {bad:?}");
    assert_eq!(eval(&trained), good, "evaluation is deterministic");
}
