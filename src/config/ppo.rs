//! Settings of PPO and the context estimator (CENet).
//!
//! Defaults follow legged_gym's `LeggedRobotCfgPPO` (rsl_rl) and DreamWaQ
//! (Nahrendra et al. 2023) for the CENet; every key can be set from the
//! `[ppo]` table of a TOML file under `scenes/`.

use super::bounds::{self, Interval, NON_NEGATIVE, POSITIVE, POSITIVE_UNIT, UNIT};
use super::net::{check_widths, MAX_WIDTH};
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
/// The most passes over one rollout per update (legged_gym uses 5).
pub const MAX_EPOCHS: usize = 1000;

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
    /// Write a metrics row (and refresh the progress bar) every this many iterations (at least 1).
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

    /// Checks the settings that would make training meaningless or panic, or that cannot fit
    /// in memory. Errors name the key and the expectation.
    pub fn validate(&self) -> anyhow::Result<()> {
        check_env_count("ppo.num_envs", self.num_envs)?;
        bounds::check_count("ppo.steps_per_env", self.steps_per_env, 1, MAX_ROLLOUT)?;
        anyhow::ensure!(
            self.batch_size() <= MAX_ROLLOUT,
            "ppo.num_envs * ppo.steps_per_env = {} transitions: at most {MAX_ROLLOUT} (about 1.8 KB each)",
            self.batch_size()
        );
        for (key, value, lo, hi) in [
            // A training of 0 iterations reports results of an untrained policy.
            ("iterations", self.iterations, 1, MAX_ITERATIONS),
            ("epochs", self.epochs, 1, MAX_EPOCHS),
            ("minibatches", self.minibatches, 1, self.batch_size()),
            ("cenet_latent_dim", self.cenet_latent_dim, 1, MAX_WIDTH),
            ("log_every", self.log_every, 1, MAX_ITERATIONS),
            ("checkpoint_every", self.checkpoint_every, 0, MAX_ITERATIONS),
        ] {
            bounds::check_count(&format!("ppo.{key}"), value, lo, hi)?;
        }
        check_widths("ppo.cenet_decoder_hidden", &self.cenet_decoder_hidden)?;
        let rate = Interval::OpenClosed(0.0, 1.0);
        for (key, value, interval) in [
            ("gamma", self.gamma, UNIT),
            ("gae_lambda", self.gae_lambda, UNIT),
            ("clip_ratio", self.clip_ratio, POSITIVE_UNIT),
            ("value_loss_coef", self.value_loss_coef, NON_NEGATIVE),
            ("entropy_coef", self.entropy_coef, NON_NEGATIVE),
            ("max_grad_norm", self.max_grad_norm, POSITIVE),
            ("learning_rate", self.learning_rate, rate),
            ("min_lr", self.min_lr, rate),
            ("max_lr", self.max_lr, rate),
            ("desired_kl", self.desired_kl, POSITIVE),
            ("lr_factor", self.lr_factor, Interval::Above(1.0)),
            ("init_action_std", self.init_action_std, POSITIVE),
            ("actor_output_init_scale", self.actor_output_init_scale, POSITIVE),
            ("obs_clip", self.obs_clip, POSITIVE),
            ("max_physics_reset_rate", self.max_physics_reset_rate, UNIT),
            ("cenet_beta", self.cenet_beta, NON_NEGATIVE),
            ("cenet_loss_coef", self.cenet_loss_coef, NON_NEGATIVE),
            ("cenet_logvar_clamp", self.cenet_logvar_clamp, POSITIVE),
        ] {
            bounds::check(&format!("ppo.{key}"), value, interval)?;
        }
        anyhow::ensure!(
            self.min_lr <= self.learning_rate && self.learning_rate <= self.max_lr,
            "ppo learning rates must satisfy 0 < min_lr <= learning_rate <= max_lr, got {} <= {} <= {}",
            self.min_lr,
            self.learning_rate,
            self.max_lr
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
