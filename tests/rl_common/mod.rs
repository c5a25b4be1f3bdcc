//! Shared by the rl integration tests: a PPO configuration small enough for
//! the toy environment.

use quadcl::config::{Config, PpoConfig};

/// 32 envs x 16 steps, 32-32 actor and critic, a 16-wide CENet with a 2-wide
/// latent, exploration N(0, 0.5), and capacity 1: these tests check PPO, not
/// the capacity, so every weight may be used.
pub fn small_ppo_config() -> Config {
    let mut cfg = Config {
        ppo: PpoConfig {
            num_envs: 32,
            steps_per_env: 16,
            cenet_decoder_hidden: vec![16],
            cenet_latent_dim: 2,
            init_action_std: 0.5,
            ..PpoConfig::default()
        },
        ..Config::default()
    };
    cfg.net.actor.hidden = vec![32, 32];
    cfg.net.critic.hidden = vec![32, 32];
    cfg.net.cenet.hidden = vec![16];
    cfg.net.mask.capacity = 1.0;
    cfg
}
