//! Settings of PPO and the context estimator (CENet).
//!
//! Defaults follow legged_gym's `LeggedRobotCfgPPO` (rsl_rl) and DreamWaQ
//! (Nahrendra et al. 2023) for the CENet; every key can be set from the
//! `[ppo]` table of a TOML file under `scenes/`.

use super::net::MAX_WIDTH;
use serde::{Deserialize, Serialize};

/// The most environments one batch may have (`ppo.num_envs`, `[eval] episodes`,
/// `quadcl eval --episodes`): each holds a rapier world and its buffers, about
/// 126 KB (measured: 64 envs 47 MB, 1024 envs 167 MB resident), so this is about 2 GB.
pub const MAX_ENVS: usize = 16_384;
/// The most transitions one rollout may hold (`num_envs * steps_per_env`):
/// about 1.8 KB each with the observation history, so about 1.9 GB.
pub const MAX_ROLLOUT: usize = 1 << 20;
/// The most iterations a training may ask for: the curves keep a row per
/// iteration, and at 0.1 s an iteration this is over eleven days.
pub const MAX_ITERATIONS: usize = 10_000_000;

/// Checks a count of environments (`what` names the key or option): at
/// least 1 and at most [`MAX_ENVS`]. Every place a batch size comes from
/// (`ppo.num_envs`, `[eval] episodes`, `quadcl eval --episodes`, a `VecEnv`)
/// checks it here.
pub fn check_env_count(what: &str, n: usize) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=MAX_ENVS).contains(&n),
        "{what} = {n}: expected at least 1 and at most {MAX_ENVS} (an env holds about 126 KB of physics state)"
    );
    Ok(())
}

/// PPO with a privileged critic and a context estimator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {
    /// Number of environments stepped in parallel.
    pub num_envs: usize,
    /// Control steps each environment takes per iteration (rollout length).
    pub steps_per_env: usize,
    /// Training iterations (one rollout + one update each).
    pub iterations: usize,
    /// Discount factor gamma.
    pub gamma: f64,
    /// GAE lambda.
    pub gae_lambda: f64,
    /// Passes over the rollout per update.
    pub epochs: usize,
    /// Minibatches per epoch (the rollout is split into this many).
    pub minibatches: usize,
    /// PPO ratio clip epsilon (surrogate objective).
    pub clip_ratio: f64,
    /// Clip the value loss around the rollout's value estimates (same epsilon as the ratio).
    pub clip_value_loss: bool,
    /// Weight of the value loss in the total loss.
    pub value_loss_coef: f64,
    /// Weight of the entropy bonus (subtracted from the loss).
    pub entropy_coef: f64,
    /// Normalise advantages per minibatch to zero mean, unit std.
    pub normalize_advantages: bool,
    /// Global gradient-norm clip.
    pub max_grad_norm: f64,
    /// Initial learning rate of the one Adam over actor, critic and CENet.
    pub learning_rate: f64,
    /// Adapt the learning rate from the approximate KL (legged_gym rule):
    /// divide by `lr_factor` when kl > 2 * desired_kl, multiply when kl < desired_kl / 2.
    pub adaptive_lr: bool,
    /// Target KL divergence between the rollout policy and the updated one.
    pub desired_kl: f64,
    /// Factor of one adaptive learning-rate change.
    pub lr_factor: f64,
    /// Lower clamp of the adaptive learning rate.
    pub min_lr: f64,
    /// Upper clamp of the adaptive learning rate.
    pub max_lr: f64,
    /// Clip each step's total reward at zero before the learner sees it
    /// (legged_gym's `only_positive_rewards`): with the Table 1 penalties the
    /// step reward is negative early on, and a learner that sees negative
    /// rewards learns to fall as fast as it can to end the episode. Measured:
    /// without it the base run's episodes shrank from 3.3 s to 0.27 s in 400
    /// iterations. Episode returns in the metrics are the env's, unclipped.
    pub only_positive_rewards: bool,
    /// Initial standard deviation of the Gaussian policy (state independent, learned, per task).
    pub init_action_std: f64,
    /// Observation normalisation: clip normalised values to +-this.
    pub obs_clip: f64,
    /// An env whose physics blows up (a non-finite state, a rapier failure) is
    /// reset and counted (`charts/physics_resets`); training stops with an
    /// error only when more than this fraction of an iteration's env steps did.
    pub max_physics_reset_rate: f64,
    /// Normalise observations with running statistics (frozen when a task ends).
    pub normalize_observations: bool,
    /// Factor on the actor's output-layer initial weights (and its
    /// re-initialisation range). The layers are initialised for unit-scale
    /// activations, which gives initial action means of about N(0, 1) per
    /// joint: a fixed 0.25 rad offset pattern that folds the robot over in
    /// about a second. CleanRL starts the actor mean at std 0.01 for the same
    /// reason.
    pub actor_output_init_scale: f64,
    /// Use the CENet (DreamWaQ); when off, the actor sees only the observation.
    pub use_cenet: bool,
    /// Size of the CENet latent context z.
    pub cenet_latent_dim: usize,
    /// Hidden layer sizes of the CENet decoder (velocity + latent -> next
    /// observation). The actor, critic and encoder sizes are in `[net]`.
    pub cenet_decoder_hidden: Vec<usize>,
    /// beta of the beta-VAE: weight of the KL term of the CENet loss.
    pub cenet_beta: f64,
    /// Weight of the whole CENet loss in the total loss.
    pub cenet_loss_coef: f64,
    /// Clamp of the latent log-variance, for numerical safety (+-this).
    pub cenet_logvar_clamp: f64,
    /// Write a metrics row (and refresh the progress bar) every this many iterations.
    pub log_every: usize,
    /// Save a checkpoint of the run in progress (`checkpoint/` in the output
    /// folder) every this many iterations, so `quadcl train --resume` can go
    /// on after an interruption; 0: never.
    pub checkpoint_every: usize,
}

impl Default for PpoConfig {
    fn default() -> Self {
        Self {
            num_envs: 256,
            steps_per_env: 24,
            iterations: 1500,
            gamma: 0.99,
            gae_lambda: 0.95,
            epochs: 5,
            minibatches: 4,
            clip_ratio: 0.2,
            clip_value_loss: true,
            value_loss_coef: 1.0,
            entropy_coef: 0.01,
            normalize_advantages: true,
            max_grad_norm: 1.0,
            learning_rate: 1e-3,
            adaptive_lr: true,
            desired_kl: 0.01,
            lr_factor: 1.5,
            min_lr: 1e-5,
            max_lr: 1e-2,
            only_positive_rewards: true,
            init_action_std: 1.0,
            actor_output_init_scale: 0.01,
            obs_clip: 5.0,
            max_physics_reset_rate: 0.01,
            normalize_observations: true,
            use_cenet: true,
            cenet_latent_dim: 16,
            cenet_decoder_hidden: vec![128, 256],
            cenet_beta: 1.0,
            cenet_loss_coef: 1.0,
            cenet_logvar_clamp: 10.0,
            log_every: 1,
            checkpoint_every: 25,
        }
    }
}

impl PpoConfig {
    /// Transitions in one rollout: `num_envs * steps_per_env`.
    pub fn batch_size(&self) -> usize {
        self.num_envs * self.steps_per_env
    }

    /// Transitions in one minibatch (the last may be smaller; see [`crate::rl`]).
    pub fn minibatch_size(&self) -> usize {
        self.batch_size().div_ceil(self.minibatches.max(1))
    }

    /// Checks the settings that would make training meaningless or panic.
    /// Errors name the key and the expectation.
    pub fn validate(&self) -> anyhow::Result<()> {
        check_env_count("ppo.num_envs", self.num_envs)?;
        let positive = [
            ("steps_per_env", self.steps_per_env),
            ("epochs", self.epochs),
            ("minibatches", self.minibatches),
            ("cenet_latent_dim", self.cenet_latent_dim),
        ];
        for (key, value) in positive {
            anyhow::ensure!(value > 0, "ppo.{key} must be > 0, got {value}");
        }
        anyhow::ensure!(
            self.batch_size() <= MAX_ROLLOUT,
            "ppo.num_envs * ppo.steps_per_env = {} transitions: at most {MAX_ROLLOUT} (about 1.8 KB each)",
            self.batch_size()
        );
        anyhow::ensure!(
            self.iterations <= MAX_ITERATIONS,
            "ppo.iterations = {}: at most {MAX_ITERATIONS}",
            self.iterations
        );
        anyhow::ensure!(
            self.cenet_decoder_hidden.iter().all(|&w| w > 0 && w <= MAX_WIDTH),
            "ppo.cenet_decoder_hidden = {:?}: every width must be in 1..={MAX_WIDTH}",
            self.cenet_decoder_hidden
        );
        anyhow::ensure!(
            self.cenet_latent_dim <= MAX_WIDTH,
            "ppo.cenet_latent_dim = {}: at most {MAX_WIDTH}",
            self.cenet_latent_dim
        );
        anyhow::ensure!(
            self.minibatches <= self.batch_size(),
            "ppo.minibatches ({}) must not exceed num_envs * steps_per_env ({})",
            self.minibatches,
            self.batch_size()
        );
        anyhow::ensure!((0.0..=1.0).contains(&self.gamma), "ppo.gamma must be in [0, 1], got {}", self.gamma);
        anyhow::ensure!(
            (0.0..=1.0).contains(&self.gae_lambda),
            "ppo.gae_lambda must be in [0, 1], got {}",
            self.gae_lambda
        );
        anyhow::ensure!(self.clip_ratio > 0.0, "ppo.clip_ratio must be > 0, got {}", self.clip_ratio);
        anyhow::ensure!(self.init_action_std > 0.0, "ppo.init_action_std must be > 0, got {}", self.init_action_std);
        anyhow::ensure!(
            self.actor_output_init_scale.is_finite() && self.actor_output_init_scale > 0.0,
            "ppo.actor_output_init_scale must be finite and > 0, got {}",
            self.actor_output_init_scale
        );
        anyhow::ensure!(
            self.min_lr > 0.0 && self.min_lr <= self.learning_rate && self.learning_rate <= self.max_lr,
            "ppo learning rates must satisfy 0 < min_lr <= learning_rate <= max_lr, got {} <= {} <= {}",
            self.min_lr,
            self.learning_rate,
            self.max_lr
        );
        anyhow::ensure!(self.lr_factor > 1.0, "ppo.lr_factor must be > 1, got {}", self.lr_factor);
        anyhow::ensure!(self.obs_clip > 0.0, "ppo.obs_clip must be > 0, got {}", self.obs_clip);
        anyhow::ensure!(
            (0.0..=1.0).contains(&self.max_physics_reset_rate),
            "ppo.max_physics_reset_rate must be in [0, 1], got {}",
            self.max_physics_reset_rate
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_match_legged_gym() {
        let cfg = PpoConfig::default();
        cfg.validate().unwrap();
        assert_eq!((cfg.epochs, cfg.minibatches, cfg.steps_per_env), (5, 4, 24));
        assert_eq!(cfg.batch_size(), 256 * 24);
        assert_eq!(cfg.minibatch_size(), 256 * 24 / 4);
    }

    #[test]
    fn sizes_that_cannot_fit_in_memory_are_errors_giving_the_limit() {
        for (key, cfg) in [
            ("ppo.num_envs", PpoConfig { num_envs: 100_000_000, ..PpoConfig::default() }),
            ("transitions", PpoConfig { num_envs: 4096, steps_per_env: 1_000_000, ..PpoConfig::default() }),
            ("ppo.iterations", PpoConfig { iterations: usize::MAX, ..PpoConfig::default() }),
            ("ppo.cenet_decoder_hidden", PpoConfig { cenet_decoder_hidden: vec![1 << 30], ..PpoConfig::default() }),
            ("ppo.cenet_decoder_hidden", PpoConfig { cenet_decoder_hidden: vec![0], ..PpoConfig::default() }),
        ] {
            let err = cfg.validate().unwrap_err().to_string();
            assert!(err.contains(key) && (err.contains("at most") || err.contains("1..=")), "{key}: {err}");
        }
    }

    #[test]
    fn zero_minibatches_is_an_error_naming_the_key() {
        let cfg = PpoConfig { minibatches: 0, ..PpoConfig::default() };
        let err = cfg.validate().unwrap_err().to_string();
        assert!(err.contains("ppo.minibatches"), "{err}");
    }
}
