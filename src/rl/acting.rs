//! Acting with frozen weights: the policy and critic forwards of rollouts,
//! evaluations and the robot view. [`Agent::acting_weights`] makes each
//! network's effective weights once (training masks, or the task's in recall
//! mode); the `*_with` forwards run the fused op on them without a graph, so
//! the many steps of a rollout do not rebuild W * M at every step.
//!
//! Shapes: N envs; obs (N, obs), histories (N, H * obs), privileged (N, priv),
//! actions and means (N, act), values and log-probabilities (N,).

use super::agent::{matrix, normal_tensor, Agent};
use super::cenet_loss::{reparameterize, split_encoder_output};
use super::losses::gaussian_log_prob;
use crate::nn::FrozenWeights;
use candle_core::{Device, Tensor};
use rand::Rng;

/// The acting networks' weights frozen at one moment ([`Agent::acting_weights`]): valid
/// until the next optimiser step, mask draw or end of task, which change them.
#[derive(Debug, Clone)]
pub struct ActingWeights {
    actor: FrozenWeights,
    critic: FrozenWeights,
    /// None without a CENet.
    encoder: Option<FrozenWeights>,
}

/// What the policy did at one step of all environments (row-major, N rows).
#[derive(Debug, Clone)]
pub struct ActOutput {
    /// (N, act) sampled actions.
    pub actions: Vec<f32>,
    /// (N, act) the Gaussian means.
    pub means: Vec<f32>,
    /// (N,) log-probabilities of the sampled actions.
    pub log_probs: Vec<f32>,
    /// (N, context) the CENet estimate the actor saw.
    pub context: Vec<f32>,
}

impl Agent {
    /// The acting networks' weights as they are now (training masks, or the task's in recall
    /// mode), computed once for the many batches of a rollout or an evaluation.
    pub fn acting_weights(&self) -> anyhow::Result<ActingWeights> {
        let task = self.recall.then_some(self.task);
        Ok(ActingWeights {
            actor: self.actor.frozen_weights(task)?,
            critic: self.critic.frozen_weights(task)?,
            encoder: if self.use_cenet { Some(self.encoder.frozen_weights(task)?) } else { None },
        })
    }

    /// The actor's context from normalised histories (B, H * obs) with frozen weights:
    /// `[v_est | z]` with z sampled using `noise` (B, L), or z = mean when `noise` is None
    /// (deployment). (B, context); (B, 0) without CENet.
    fn context_with(&self, w: &ActingWeights, history: &Tensor, noise: Option<&Tensor>) -> anyhow::Result<Tensor> {
        let batch = history.dim(0)?;
        let Some(encoder) = &w.encoder else {
            return Ok(Tensor::zeros((batch, 0), candle_core::DType::F32, &Device::Cpu)?);
        };
        let est =
            split_encoder_output(&self.encoder.forward_weights(encoder, history)?, self.latent_dim, self.logvar_clamp)?;
        let z = match noise {
            Some(noise) => reparameterize(&est.latent_mean, &est.latent_logvar, noise)?,
            None => est.latent_mean.clone(),
        };
        Ok(Tensor::cat(&[&est.velocity, &z], 1)?)
    }

    /// Action means (as [`Self::action_mean`]) with frozen weights.
    fn action_mean_with(&self, w: &ActingWeights, obs: &Tensor, context: &Tensor) -> anyhow::Result<Tensor> {
        self.actor.forward_weights(&w.actor, &self.actor_input(obs, context)?)
    }

    /// Samples actions for normalised obs (N, obs) and histories (N, H * obs).
    pub fn act(&self, obs: &[f32], history: &[f32], rng: &mut impl Rng) -> anyhow::Result<ActOutput> {
        self.act_with(&self.acting_weights()?, obs, history, rng)
    }

    /// [`Self::act`] with weights from [`Self::acting_weights`] (the same numbers).
    pub fn act_with(
        &self,
        w: &ActingWeights,
        obs: &[f32],
        history: &[f32],
        rng: &mut impl Rng,
    ) -> anyhow::Result<ActOutput> {
        let n = obs.len() / self.dims.obs;
        let noise = normal_tensor(rng, n, self.latent_dim)?;
        let context = self.context_with(w, &matrix(history, self.dims.history_len * self.dims.obs)?, Some(&noise))?;
        let mean = self.action_mean_with(w, &matrix(obs, self.dims.obs)?, &context)?;
        let action_noise = normal_tensor(rng, n, self.dims.act)?;
        let actions = mean.add(&action_noise.broadcast_mul(&self.log_std.as_tensor().exp()?)?)?;
        let log_probs = gaussian_log_prob(&actions, &mean, self.log_std.as_tensor())?;
        Ok(ActOutput {
            actions: actions.flatten_all()?.to_vec1()?,
            means: mean.flatten_all()?.to_vec1()?,
            log_probs: log_probs.to_vec1()?,
            context: context.flatten_all()?.to_vec1()?,
        })
    }

    /// Deterministic actions (the means, latent = its mean) for raw obs and
    /// histories: what a deployed policy does. (N, act).
    pub fn act_deterministic(&self, raw_obs: &[f32], raw_history: &[f32]) -> anyhow::Result<Vec<f32>> {
        self.act_deterministic_with(&self.acting_weights()?, raw_obs, raw_history)
    }

    /// [`Self::act_deterministic`] with weights from [`Self::acting_weights`] (the same numbers).
    pub fn act_deterministic_with(
        &self,
        w: &ActingWeights,
        raw_obs: &[f32],
        raw_history: &[f32],
    ) -> anyhow::Result<Vec<f32>> {
        let obs = self.normalize_obs(raw_obs);
        let history = self.normalize_obs(raw_history);
        let context = self.context_with(w, &matrix(&history, self.dims.history_len * self.dims.obs)?, None)?;
        let mean = self.action_mean_with(w, &matrix(&obs, self.dims.obs)?, &context)?;
        Ok(mean.flatten_all()?.to_vec1()?)
    }

    /// Values (N,) for normalised privileged observations, with weights from
    /// [`Self::acting_weights`].
    pub fn values_with(&self, w: &ActingWeights, privileged: &[f32]) -> anyhow::Result<Vec<f32>> {
        let x = matrix(privileged, self.dims.privileged_obs)?;
        Ok(self.critic.forward_weights(&w.critic, &x)?.squeeze(1)?.to_vec1()?)
    }
}
