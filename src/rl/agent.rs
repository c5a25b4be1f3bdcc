//! The learner's networks and observation statistics: an asymmetric
//! actor-critic with DreamWaQ's context estimator (CENet).
//!
//! - encoder: history (B, H * obs) -> [velocity 3 | latent mean L | latent logvar L]
//! - decoder: [velocity 3 | latent sample L] -> next observation (B, obs)
//! - actor:   [obs | velocity estimate 3 | latent sample L] -> action means (B, act)
//! - critic:  privileged obs (B, priv) -> value (B, 1)
//! - `log_std` (act,): the Gaussian policy's state-independent log-std (per task).
//!
//! The four networks are `nn::Network`s of one kind. Masked (`ours`, METHOD 2):
//! while a task trains they run with the current task's sampled masks
//! ([`Agent::begin_iteration`]); after [`Agent::end_task`] (or when loaded from a
//! policy directory) they recall the task's frozen masks and biases,
//! bit-identically. Dense (the regularisation and rehearsal baselines, METHOD 3):
//! a shared trunk and one output head per task ([`Agent::into_dense`] turns a
//! masked base policy into one).
//!
//! The actor's CENet inputs are detached: the CENet learns only from its own
//! beta-VAE loss (DreamWaQ), the actor treats its estimate as an input.
//! Observations are normalised here (running statistics, frozen per task);
//! histories are normalised block by block with the observation statistics.
//! Acting (rollouts, evaluation) with weights frozen once is in `acting.rs`.

use super::cenet_loss::{split_encoder_output, CenetEstimate};
use super::env::EnvDims;
use super::normalizer::RunningNormalizer;
use crate::config::Config;
use crate::nn::{DenseMlp, MaskedMlp, Network, NetworkKind, Param, TaskId};
use candle_core::{Device, Tensor, Var};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// Networks, policy std and observation statistics of one learner.
#[derive(Debug)]
pub struct Agent {
    pub(crate) dims: EnvDims,
    /// Latent width L of the CENet (0 when the CENet is off).
    pub(crate) latent_dim: usize,
    pub(crate) use_cenet: bool,
    pub(crate) actor: Network,
    pub(crate) critic: Network,
    pub(crate) encoder: Network,
    pub(crate) decoder: Network,
    /// The task being trained, or recalled.
    pub(crate) task: TaskId,
    /// Recall mode: forward with the task's frozen masks (after `end_task`, or loaded).
    pub(crate) recall: bool,
    /// (act,) log standard deviation of the policy.
    pub(crate) log_std: Var,
    /// Statistics of the actor observation (also used for each history block).
    pub(crate) obs_normalizer: RunningNormalizer,
    /// Statistics of the privileged observation.
    pub(crate) privileged_normalizer: RunningNormalizer,
    normalize: bool,
    pub(crate) logvar_clamp: f64,
}

/// A (rows, cols) tensor of standard normal noise from `rng`.
pub fn normal_tensor(rng: &mut impl Rng, rows: usize, cols: usize) -> candle_core::Result<Tensor> {
    let data: Vec<f32> = (0..rows * cols).map(|_| rng.sample(StandardNormal)).collect();
    Tensor::from_vec(data, (rows, cols), &Device::Cpu)
}

/// A row-major slice as a (rows, width) tensor.
pub fn matrix(data: &[f32], width: usize) -> candle_core::Result<Tensor> {
    Tensor::from_slice(data, (data.len() / width.max(1), width), &Device::Cpu)
}

impl Agent {
    /// The widths of the environment the agent was built for.
    pub fn dims(&self) -> EnvDims {
        self.dims
    }

    /// The task being trained, or recalled.
    pub fn task(&self) -> TaskId {
        self.task
    }

    /// Whether the agent recalls a finished task's frozen masks (after `end_task`, or loaded).
    pub fn in_recall(&self) -> bool {
        self.recall
    }

    /// The actor network.
    pub fn actor(&self) -> &Network {
        &self.actor
    }

    /// Statistics of the actor observation.
    pub fn obs_normalizer(&self) -> &RunningNormalizer {
        &self.obs_normalizer
    }

    /// Fresh networks (of `config.net.kind`) for an environment with `dims`; `seed` seeds every
    /// initialiser. Sizes: `config.net` (actor, critic, CENet encoder),
    /// `config.ppo.cenet_decoder_hidden` (decoder, with the encoder's activation).
    pub fn new(dims: EnvDims, config: &Config, seed: u64) -> anyhow::Result<Self> {
        Self::new_of_kind(dims, config, seed, config.net.kind)
    }

    /// [`Self::new`] with networks of `kind` (dense: [`DenseMlp`]'s initialiser, same sizes and seeds).
    pub fn new_of_kind(dims: EnvDims, config: &Config, seed: u64, kind: NetworkKind) -> anyhow::Result<Self> {
        let (cfg, net) = (&config.ppo, &config.net);
        let latent_dim = if cfg.use_cenet { cfg.cenet_latent_dim } else { 0 };
        let context = if cfg.use_cenet { 3 + latent_dim } else { 0 };
        let build = |name: &str, input: usize, hidden: &[usize], output: usize, activation, seed| {
            let mut sizes = vec![input];
            sizes.extend_from_slice(hidden);
            sizes.push(output);
            Ok::<Network, anyhow::Error>(match kind {
                NetworkKind::Masked => MaskedMlp::new(name, &sizes, activation, &net.mask, seed)?.into(),
                NetworkKind::Dense => DenseMlp::new(name, &sizes, activation, seed)?.into(),
            })
        };
        let mut actor = build("actor", dims.obs + context, &net.actor.hidden, dims.act, net.actor.activation, seed)?;
        actor.scale_output_init(cfg.actor_output_init_scale as f32)?;
        let critic =
            build("critic", dims.privileged_obs, &net.critic.hidden, 1, net.critic.activation, seed.wrapping_add(1))?;
        let history = dims.history_len * dims.obs;
        let encoder = build(
            "cenet_encoder",
            history,
            &net.cenet.hidden,
            3 + 2 * cfg.cenet_latent_dim,
            net.cenet.activation,
            seed.wrapping_add(2),
        )?;
        let decoder = build(
            "cenet_decoder",
            3 + cfg.cenet_latent_dim,
            &cfg.cenet_decoder_hidden,
            dims.obs,
            net.cenet.activation,
            seed.wrapping_add(3),
        )?;
        let log_std = Var::from_tensor(&Tensor::from_vec(
            vec![cfg.init_action_std.ln() as f32; dims.act],
            dims.act,
            &Device::Cpu,
        )?)?;
        Ok(Self {
            dims,
            latent_dim,
            use_cenet: cfg.use_cenet,
            actor,
            critic,
            encoder,
            decoder,
            task: 0,
            recall: false,
            log_std,
            obs_normalizer: RunningNormalizer::new(dims.obs, cfg.obs_clip as f32),
            privileged_normalizer: RunningNormalizer::new(dims.privileged_obs, cfg.obs_clip as f32),
            normalize: cfg.normalize_observations,
            logvar_clamp: cfg.cenet_logvar_clamp,
        })
    }

    /// The four networks, in checkpoint order.
    pub fn networks(&self) -> [&Network; 4] {
        [&self.actor, &self.critic, &self.encoder, &self.decoder]
    }

    /// The four networks as a checkpoint writes them.
    pub fn saved_networks(&self) -> [&dyn crate::nn::AsNetworkRef; 4] {
        [&self.actor, &self.critic, &self.encoder, &self.decoder]
    }

    /// The networks that are masked (all four, or none for a dense agent).
    pub fn masked_networks(&self) -> Vec<&MaskedMlp> {
        self.networks().into_iter().filter_map(Network::as_masked).collect()
    }

    /// Which kind of networks the agent has.
    pub fn network_kind(&self) -> NetworkKind {
        self.actor.kind()
    }

    /// The same agent with dense networks ([`Network::into_dense`]: a masked policy's last
    /// finished task becomes the shared trunk, every finished task keeps its output layer as
    /// its head); only between tasks.
    pub fn into_dense(mut self) -> anyhow::Result<Self> {
        anyhow::ensure!(
            self.networks().iter().all(|n| n.current_task().is_none()),
            "an agent becomes dense between tasks only"
        );
        self.actor = self.actor.into_dense()?;
        self.critic = self.critic.into_dense()?;
        self.encoder = self.encoder.into_dense()?;
        self.decoder = self.decoder.into_dense()?;
        Ok(self)
    }

    /// The four networks, in checkpoint order, to change.
    pub(crate) fn networks_mut(&mut self) -> [&mut Network; 4] {
        [&mut self.actor, &mut self.critic, &mut self.encoder, &mut self.decoder]
    }

    /// The mask settings of every network from now on (a switch change for the next task, or
    /// end-of-task settings given on resume); nothing learned changes.
    pub fn set_mask_config(&mut self, mask: &crate::nn::MaskConfig) -> anyhow::Result<()> {
        self.networks_mut().into_iter().try_for_each(|net| net.set_mask_config(mask))
    }

    /// Every network takes `mask`'s end-of-task settings, also mid-task (a resumed run ended with another p).
    pub fn set_end_of_task(&mut self, mask: &crate::nn::MaskConfig) -> anyhow::Result<()> {
        self.networks_mut().into_iter().try_for_each(|net| net.set_end_of_task(mask))
    }

    /// Every network's vacant weights redrawn at `mask`'s fresh-weight range and scale, between
    /// tasks (`[run] base_vacant = "redrawn"`); what every learned task recalls is unchanged.
    pub fn redraw_vacant_weights(&mut self, mask: &crate::nn::MaskConfig, rng: &mut impl Rng) -> anyhow::Result<()> {
        self.networks_mut().into_iter().try_for_each(|net| net.redraw_vacant_weights(mask, rng))
    }

    /// Starts training `task` (METHOD 2.1; a finished task => fine-tuning).
    /// The observation statistics follow the data again.
    pub fn begin_task(&mut self, task: TaskId, related: &[TaskId]) -> anyhow::Result<()> {
        for net in self.networks_mut() {
            net.begin_task(task, related)?;
        }
        self.task = task;
        self.recall = false;
        self.obs_normalizer.unfreeze();
        self.privileged_normalizer.unfreeze();
        Ok(())
    }

    /// Once per training iteration: new soft-score samples and masks.
    /// The noise is drawn network by network in order, then the networks choose their masks
    /// in parallel: the same masks as one network after the other.
    pub fn begin_iteration(&mut self, iteration: usize, rng: &mut impl Rng) -> anyhow::Result<()> {
        let noise = self.networks().map(|net| net.draw_iteration_noise(rng));
        let nets: Vec<(&mut Network, anyhow::Result<_>)> = self.networks_mut().into_iter().zip(noise).collect();
        nets.into_par_iter().try_for_each(|(net, noise)| net.begin_iteration_with_noise(iteration, noise?))
    }

    /// Sum of the networks' soft-score losses (METHOD 2.3), a scalar.
    pub fn soft_score_loss(&self) -> anyhow::Result<Tensor> {
        let mut total = self.actor.soft_score_loss()?;
        for net in &self.networks()[1..] {
            total = total.add(&net.soft_score_loss()?)?;
        }
        Ok(total)
    }

    /// Ends the task (METHOD 2.4): final masks, frozen statistics, recall mode.
    pub fn end_task(&mut self, rng: &mut impl Rng) -> anyhow::Result<()> {
        for net in self.networks_mut() {
            net.end_task(rng)?;
        }
        self.obs_normalizer.freeze();
        self.privileged_normalizer.freeze();
        self.recall = true;
        Ok(())
    }

    /// Forward through `net`: training masks, or the task's frozen ones in recall mode.
    fn run(&self, net: &Network, x: &Tensor) -> anyhow::Result<Tensor> {
        if self.recall {
            net.forward_task(self.task, x)
        } else {
            net.forward(x)
        }
    }

    /// The decoder's reconstruction of the next observation from `[v_est | z]` (B, 3 + L).
    pub fn decode(&self, velocity_and_latent: &Tensor) -> anyhow::Result<Tensor> {
        self.run(&self.decoder, velocity_and_latent)
    }

    /// Width of the CENet context the actor sees (3 + L, or 0 without CENet).
    pub fn context_dim(&self) -> usize {
        if self.use_cenet {
            3 + self.latent_dim
        } else {
            0
        }
    }

    /// Every trainable parameter: actor, critic, CENet, then `log_std`.
    pub fn params(&self) -> Vec<Param> {
        let mut out = self.actor.params();
        out.extend(self.critic.params());
        if self.use_cenet {
            out.extend(self.encoder.params());
            out.extend(self.decoder.params());
        }
        if self.recall {
            return out; // nothing trains in recall mode
        }
        out.push(Param::free("log_std", &self.log_std));
        out
    }

    /// Updates the running statistics with raw observations (no-op when frozen).
    pub fn observe_statistics(&mut self, obs: &[f32], privileged: &[f32]) -> anyhow::Result<()> {
        if self.normalize {
            self.obs_normalizer.update(obs)?;
            self.privileged_normalizer.update(privileged)?;
        }
        Ok(())
    }

    /// Whether observations are normalised before the networks see them.
    pub fn normalizes(&self) -> bool {
        self.normalize
    }

    /// Normalised copy of raw actor observations (N, obs) or histories (N, H * obs).
    pub fn normalize_obs(&self, raw: &[f32]) -> Vec<f32> {
        if self.normalize {
            self.obs_normalizer.normalize(raw)
        } else {
            raw.to_vec()
        }
    }

    /// Normalised copy of raw privileged observations (N, priv).
    pub fn normalize_privileged(&self, raw: &[f32]) -> Vec<f32> {
        if self.normalize {
            self.privileged_normalizer.normalize(raw)
        } else {
            raw.to_vec()
        }
    }

    /// The CENet's estimate from normalised histories (B, H * obs).
    pub fn estimate(&self, history: &Tensor) -> anyhow::Result<CenetEstimate> {
        split_encoder_output(&self.run(&self.encoder, history)?, self.latent_dim, self.logvar_clamp)
    }

    /// Action means from normalised obs (B, obs) and context (B, context): (B, act).
    pub fn action_mean(&self, obs: &Tensor, context: &Tensor) -> anyhow::Result<Tensor> {
        self.run(&self.actor, &self.actor_input(obs, context)?)
    }

    /// The actor's input (B, obs + context): `[obs | context]`, or obs alone without CENet.
    pub(crate) fn actor_input(&self, obs: &Tensor, context: &Tensor) -> anyhow::Result<Tensor> {
        Ok(if self.use_cenet { Tensor::cat(&[obs, context], 1)? } else { obs.clone() })
    }

    /// Values from normalised privileged obs (B, priv): (B,).
    pub fn value(&self, privileged: &Tensor) -> anyhow::Result<Tensor> {
        Ok(self.run(&self.critic, privileged)?.squeeze(1)?)
    }

    /// Extracts the CENet's velocity target (N, 3) from raw privileged observations.
    pub fn base_velocity(&self, raw_privileged: &[f32]) -> Vec<f32> {
        let (width, off) = (self.dims.privileged_obs, self.dims.base_velocity_offset);
        raw_privileged.chunks_exact(width).flat_map(|row| row[off..off + 3].iter().copied()).collect()
    }
}
