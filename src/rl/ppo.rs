//! The PPO learner, readable top to bottom (CleanRL's
//! `ppo_continuous_action.py` and rsl_rl's `PPO` are the models):
//!
//! 1. [`PpoLearner::collect_rollout`]: `steps_per_env` steps of every env
//!    with the current (stochastic) policy; observation statistics follow
//!    the data; GAE with time-out bootstrapping at the end.
//! 2. [`PpoLearner::update`]: `epochs` passes over the rollout in
//!    `minibatches` random minibatches. Per minibatch: adapt the learning rate
//!    from KL(old || new) (legged_gym), then minimise
//!    `surrogate + c_v * value_loss - c_e * entropy + c_cenet * cenet_loss`,
//!    clip the global gradient norm, one Adam step. Each term depends only on
//!    its own network's parameters, so actor, critic and CENet go forward and
//!    backward in parallel and their gradients are merged before the clip.
//!
//! A continual-learning method enters through [`UpdateHooks`] (`rl/update_hooks.rs`):
//! it sees and may change the task gradient, adds its loss' gradient before the
//! clip, and sees every step and the end of the task.
//!
//! Metrics are namespaced as in CleanRL: `charts/*`, `losses/*`, `time/*`.

use super::agent::{matrix, normal_tensor, Agent};
use super::cenet_loss::{cenet_loss, reparameterize, CenetLoss};
use super::env::{EpisodeSummary, TrainEnv};
use super::losses::{
    adapt_learning_rate, clip_fraction, clipped_surrogate_loss, gaussian_entropy, gaussian_kl, gaussian_log_prob,
    normalize_advantages, value_loss,
};
use super::metrics::{layer_metrics, names, Metrics};
use super::rollout::{gather_rows, minibatch_indices, RolloutBuffer, RolloutDims, RolloutRow};
use super::rollout_sample::{AgentProbe, RolloutSample};
use super::update_hooks::{apply_hooks, NoHooks, UpdateHooks};
use crate::config::PpoConfig;
use crate::nn::{AdamConfig, MaskedAdam};
use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::VecDeque;
use std::time::Instant;

/// Episodes kept for the episode statistics (`charts/episodic_return`, ...).
pub(crate) const EPISODE_WINDOW: usize = 100;

/// PPO over an [`Agent`], with its optimiser, rollout buffer and random stream.
pub struct PpoLearner {
    pub(crate) cfg: PpoConfig,
    pub(crate) agent: Agent,
    pub(crate) optimizer: MaskedAdam,
    buffer: RolloutBuffer,
    pub(crate) rng: ChaCha8Rng,
    /// (act,) the policy's log-std when the rollout was collected.
    rollout_log_std: Option<Tensor>,
    pub(crate) recent_episodes: VecDeque<EpisodeSummary>,
    /// Iterations completed.
    pub(crate) iteration: usize,
}

impl PpoLearner {
    /// A learner for an environment batch of `num_envs` with `agent`'s dims.
    pub fn new(cfg: PpoConfig, agent: Agent, num_envs: usize, seed: u64) -> anyhow::Result<Self> {
        cfg.validate()?;
        let d = agent.dims;
        let dims = RolloutDims {
            obs: d.obs,
            privileged_obs: d.privileged_obs,
            obs_history: d.history_len * d.obs,
            act: d.act,
            context: agent.context_dim(),
        };
        Ok(Self {
            optimizer: MaskedAdam::new(AdamConfig { learning_rate: cfg.learning_rate, ..AdamConfig::default() }),
            buffer: RolloutBuffer::new(dims, cfg.steps_per_env, num_envs),
            rng: ChaCha8Rng::seed_from_u64(seed),
            rollout_log_std: None,
            recent_episodes: VecDeque::new(),
            iteration: 0,
            cfg,
            agent,
        })
    }

    /// Ends the agent's task (final masks, frozen statistics), with the learner's random stream.
    pub fn end_task(&mut self) -> anyhow::Result<()> {
        self.end_task_with(&mut NoHooks)
    }

    /// [`Self::end_task`], telling `hooks` first (with the last rollout as the task's sample).
    pub fn end_task_with(&mut self, hooks: &mut dyn UpdateHooks) -> anyhow::Result<()> {
        let params = self.agent.params();
        hooks.on_task_end(self.agent.task, &params, &RolloutSample::new(&self.agent, &self.buffer))?;
        self.agent.end_task(&mut self.rng)
    }

    /// One training iteration: a rollout, then an update. Returns its metrics.
    pub fn train_iteration(&mut self, env: &mut dyn TrainEnv) -> anyhow::Result<Metrics> {
        self.train_iteration_with(env, &mut NoHooks)
    }

    /// [`Self::train_iteration`] with a method's hooks in the update.
    pub fn train_iteration_with(
        &mut self,
        env: &mut dyn TrainEnv,
        hooks: &mut dyn UpdateHooks,
    ) -> anyhow::Result<Metrics> {
        let start = Instant::now();
        self.agent.begin_iteration(self.iteration, &mut self.rng)?;
        let masks_s = start.elapsed().as_secs_f64();
        let mut metrics = self.collect_rollout(env)?;
        metrics.insert("time/masks_s".into(), masks_s);
        if let Some(churn) = self.agent.actor.mask_churn() {
            metrics.insert("charts/mask_churn_actor".into(), churn);
        }
        if let Some(churn) = self.agent.critic.mask_churn() {
            metrics.insert("charts/mask_churn_critic".into(), churn);
        }
        for net in [&self.agent.actor, &self.agent.critic, &self.agent.encoder, &self.agent.decoder] {
            metrics.extend(layer_metrics(&net.layer_stats()?));
        }
        // Observations only (`rl/plasticity.rs`): the rollout's weights, no random stream.
        let probe_start = Instant::now();
        metrics.extend(self.agent.plasticity_metrics(&self.buffer)?);
        metrics.insert("time/plasticity_s".into(), probe_start.elapsed().as_secs_f64());
        let rollout_s = start.elapsed().as_secs_f64();
        let update_start = Instant::now();
        metrics.extend(self.update_with(hooks)?);
        let update_s = update_start.elapsed().as_secs_f64();
        let total = start.elapsed().as_secs_f64();
        metrics.insert("time/rollout_s".into(), rollout_s);
        metrics.insert("time/update_s".into(), update_s);
        metrics.insert(names::SPS.into(), self.buffer.capacity() as f64 / total.max(1e-9));
        self.iteration += 1;
        metrics.insert("charts/iteration".into(), self.iteration as f64);
        Ok(metrics)
    }

    /// Runs the policy for `steps_per_env` steps of every env and computes
    /// advantages. Metrics: episode statistics and where the time went.
    pub fn collect_rollout(&mut self, env: &mut dyn TrainEnv) -> anyhow::Result<Metrics> {
        anyhow::ensure!(
            env.num_envs() == self.buffer.num_envs,
            "env has {} members, learner expects {}",
            env.num_envs(),
            self.buffer.num_envs
        );
        self.buffer.clear();
        self.rollout_log_std = Some(self.agent.log_std.as_tensor().copy()?);
        let (mut env_s, mut policy_s) = (0.0f64, 0.0f64);
        let mut physics_resets: Vec<(usize, String)> = Vec::new();
        // Nothing trains during the rollout: the effective weights are made once.
        let weights = self.agent.acting_weights()?;
        for _ in 0..self.cfg.steps_per_env {
            let policy_start = Instant::now();
            let raw_privileged = env.privileged_observations().to_vec();
            self.agent.observe_statistics(env.observations(), &raw_privileged)?;
            let obs = self.agent.normalize_obs(env.observations());
            let history = self.agent.normalize_obs(env.obs_histories());
            let privileged = self.agent.normalize_privileged(&raw_privileged);
            // The policy (encoder, actor) and the critic are independent: one core each.
            let (agent, rng) = (&self.agent, &mut self.rng);
            let (act, values) = rayon::join(
                || agent.act_with(&weights, &obs, &history, rng),
                || agent.values_with(&weights, &privileged),
            );
            let (act, values) = (act?, values?);
            let base_velocity = self.agent.base_velocity(&raw_privileged);
            policy_s += policy_start.elapsed().as_secs_f64();

            let env_start = Instant::now();
            let step = env.step(&act.actions)?;
            env_s += env_start.elapsed().as_secs_f64();

            let next_obs = self.agent.normalize_obs(&step.next_obs_before_reset);
            let rewards: Vec<f32> = if self.cfg.only_positive_rewards {
                step.reward.iter().map(|r| r.max(0.0)).collect()
            } else {
                step.reward.clone()
            };
            self.buffer.push(&RolloutRow {
                obs: &obs,
                privileged_obs: &privileged,
                obs_history: &history,
                context: &act.context,
                next_obs: &next_obs,
                base_velocity: &base_velocity,
                actions: &act.actions,
                action_means: &act.means,
                log_probs: &act.log_probs,
                values: &values,
                rewards: &rewards,
                terminated: &step.terminated,
                truncated: &step.truncated,
            })?;
            physics_resets.extend(step.physics_resets);
            for episode in step.finished {
                if self.recent_episodes.len() == EPISODE_WINDOW {
                    self.recent_episodes.pop_front();
                }
                self.recent_episodes.push_back(episode);
            }
        }
        let last_values =
            self.agent.values_with(&weights, &self.agent.normalize_privileged(env.privileged_observations()))?;
        self.buffer.compute_returns(&last_values, self.cfg.gamma as f32, self.cfg.gae_lambda as f32)?;

        check_physics_resets(
            &physics_resets,
            self.buffer.num_envs * self.cfg.steps_per_env,
            self.cfg.max_physics_reset_rate,
        )?;
        let mut m = Metrics::new();
        m.insert(names::PHYSICS_RESETS.into(), physics_resets.len() as f64);
        m.insert("time/env_s".into(), env_s);
        m.insert("time/policy_s".into(), policy_s);
        if !self.recent_episodes.is_empty() {
            let n = self.recent_episodes.len() as f64;
            let mean =
                |f: fn(&EpisodeSummary) -> f32| self.recent_episodes.iter().map(|e| f64::from(f(e))).sum::<f64>() / n;
            m.insert(names::EPISODIC_RETURN.into(), mean(|e| e.episode_return));
            m.insert("charts/episodic_length_s".into(), mean(|e| e.length_s));
            m.insert(names::LIN_VEL_ERR.into(), mean(|e| e.lin_vel_err));
            m.insert(names::ANG_VEL_ERR.into(), mean(|e| e.ang_vel_err));
            m.insert(names::FALL_RATE.into(), mean(|e| f32::from(u8::from(e.fell))));
        }
        let rewards = &self.buffer.rewards;
        m.insert(
            "charts/mean_step_reward".into(),
            rewards.iter().map(|&r| f64::from(r)).sum::<f64>() / rewards.len() as f64,
        );
        Ok(m)
    }

    /// The PPO update over the collected rollout; returns the loss metrics
    /// averaged over minibatches.
    pub fn update(&mut self) -> anyhow::Result<Metrics> {
        self.update_with(&mut NoHooks)
    }

    /// [`Self::update`] with a method's hooks around every optimiser step.
    pub fn update_with(&mut self, hooks: &mut dyn UpdateHooks) -> anyhow::Result<Metrics> {
        let b = &self.buffer;
        let d = b.dims;
        let rollout_log_std =
            self.rollout_log_std.clone().ok_or_else(|| anyhow::anyhow!("update called before any rollout"))?;
        let cfg = &self.cfg;
        // PPO's entropy bonus, plus beta_H in a new task's first E iterations when the
        // method's entropy term acts on the action distribution (METHOD 2.3, Figure 8's reading).
        let entropy_coef = cfg.entropy_coef + self.agent.actor.action_entropy_weight();
        let mut sums = Metrics::new();
        let mut count = 0.0;
        for _epoch in 0..cfg.epochs {
            for indices in minibatch_indices(b.capacity(), cfg.minibatches, &mut self.rng) {
                let rows = |data: &[f32], width: usize| matrix(&gather_rows(data, width, &indices), width);
                let column =
                    |data: &[f32]| Tensor::from_vec(gather_rows(data, 1, &indices), indices.len(), &Device::Cpu);
                let obs = rows(&b.obs, d.obs)?; // (B, obs)
                let context = rows(&b.context, d.context)?; // (B, context)
                let actions = rows(&b.actions, d.act)?; // (B, act)
                let old_means = rows(&b.action_means, d.act)?; // (B, act)
                let old_log_probs = column(&b.log_probs)?; // (B,)
                let old_values = column(&b.values)?; // (B,)
                let returns = column(&b.returns)?; // (B,)
                let mut advantages = column(&b.advantages)?; // (B,)
                if cfg.normalize_advantages {
                    advantages = normalize_advantages(&advantages)?;
                }

                // CENet noise first, from the learner's stream (the branches below run in parallel).
                let latent_noise = if self.agent.use_cenet {
                    Some(normal_tensor(&mut self.rng, indices.len(), self.agent.latent_dim)?)
                } else {
                    None
                };
                let agent = &self.agent;
                let optimizer = &mut self.optimizer;

                // Each network's loss term depends on its own parameters only (the actor's
                // context input is detached), so the gradient of the summed loss is the
                // union of the three branches' gradients: actor (with log_std), critic,
                // CENet, each forward and backward on its own thread.
                let actor_branch = || -> anyhow::Result<ActorTerms> {
                    // Policy: the new means under the rollout's context.
                    let means = agent.action_mean(&obs, &context)?;
                    let log_std = agent.log_std.as_tensor();
                    // KL(rollout policy || current policy), for the adaptive learning rate.
                    let kl = f64::from(
                        gaussian_kl(&old_means, &rollout_log_std, &means.detach(), &log_std.detach())?
                            .to_scalar::<f32>()?,
                    );
                    let new_log_probs = gaussian_log_prob(&actions, &means, log_std)?;
                    let policy_loss =
                        clipped_surrogate_loss(&new_log_probs, &old_log_probs, &advantages, cfg.clip_ratio)?;
                    let entropy = gaussian_entropy(log_std)?;
                    // The masks' soft-score entropy term (METHOD 2.3; 0 after E iterations).
                    let soft_score = agent.actor.soft_score_loss()?;
                    let loss = policy_loss.sub(&entropy.affine(entropy_coef, 0.0)?)?.add(&soft_score)?;
                    let grads = loss.backward()?;
                    let clipfrac = f64::from(clip_fraction(&new_log_probs, &old_log_probs, cfg.clip_ratio)?);
                    Ok(ActorTerms { kl, policy_loss, entropy, soft_score, clipfrac, grads })
                };
                let critic_branch = || -> anyhow::Result<(Tensor, Tensor, GradStore)> {
                    // Critic on the privileged observation.
                    let values = agent.value(&rows(&b.privileged_obs, d.privileged_obs)?)?;
                    let clip = cfg.clip_value_loss.then_some(cfg.clip_ratio);
                    let critic_loss = value_loss(&values, &old_values, &returns, clip)?;
                    let soft_score = agent.critic.soft_score_loss()?;
                    let grads = critic_loss.affine(cfg.value_loss_coef, 0.0)?.add(&soft_score)?.backward()?;
                    Ok((critic_loss, soft_score, grads))
                };
                let cenet_branch = || -> anyhow::Result<Option<(CenetLoss, Tensor, GradStore)>> {
                    let Some(noise) = &latent_noise else { return Ok(None) };
                    // CENet: beta-VAE on the history, velocity target, next observation.
                    let history = rows(&b.obs_history, d.obs_history)?;
                    let estimate = agent.estimate(&history)?;
                    let z = reparameterize(&estimate.latent_mean, &estimate.latent_logvar, noise)?;
                    let reconstruction = agent.decode(&Tensor::cat(&[&estimate.velocity, &z], 1)?)?;
                    let cenet = cenet_loss(
                        &estimate,
                        &rows(&b.base_velocity, 3)?,
                        &reconstruction,
                        &rows(&b.next_obs, d.obs)?,
                        cfg.cenet_beta,
                    )?;
                    let soft_score = agent.encoder.soft_score_loss()?.add(&agent.decoder.soft_score_loss()?)?;
                    let grads = cenet.total.affine(cfg.cenet_loss_coef, 0.0)?.add(&soft_score)?.backward()?;
                    Ok(Some((cenet, soft_score, grads)))
                };
                // The CENet (the smallest: about 13 ms of one core against 15-17 for the
                // actor and the critic at 1,536 rows) starts beside the actor and the critic
                // follows it, so the core the actor frees takes one of the two products of each
                // of the critic's backward layers (`rayon::join` in `nn/fused.rs`) rather than
                // waiting on the CENet's serial forward. The gradients are merged in the same
                // order either way. Measured (per-branch timers, 4 alternated runs of 8 base
                // iterations): the three branches took 27.1 ms a minibatch, now 26.5.
                let (actor, (cenet, critic)) = rayon::join(actor_branch, || rayon::join(cenet_branch, critic_branch));
                let (actor, (critic_loss, critic_soft_score, critic_grads)) = (actor?, critic?);
                let mut grads = actor.grads;
                grads.extend(critic_grads)?;
                let mut soft_score = actor.soft_score.add(&critic_soft_score)?;
                if let Some((cenet, cenet_soft_score, cenet_grads)) = cenet? {
                    grads.extend(cenet_grads)?;
                    soft_score = soft_score.add(&cenet_soft_score)?;
                    add(&mut sums, "losses/cenet_velocity", &cenet.velocity_mse)?;
                    add(&mut sums, "losses/cenet_reconstruction", &cenet.reconstruction_mse)?;
                    add(&mut sums, "losses/cenet_kl", &cenet.kl)?;
                }
                add(&mut sums, "losses/soft_score", &soft_score)?;
                // The method sees the task gradient, then adds its own loss' gradient.
                let params = agent.params();
                for (k, v) in apply_hooks(hooks, &params, &mut grads, &AgentProbe::new(agent))? {
                    *sums.entry(k).or_default() += v;
                }

                // The learning rate adapts to this minibatch's KL before its step (legged_gym).
                let kl = actor.kl;
                if cfg.adaptive_lr {
                    let lr = adapt_learning_rate(
                        optimizer.learning_rate(),
                        kl,
                        cfg.desired_kl,
                        cfg.lr_factor,
                        cfg.min_lr,
                        cfg.max_lr,
                    );
                    optimizer.set_learning_rate(lr);
                }

                // Clip the global norm of the networks' gradients. The soft-score
                // sigmas ("{layer}.log_sigma") are left out: their entropy gradient
                // (beta_H * n on log_sigma, over 10 for a 512x256 layer at beta_H 1e-4)
                // would otherwise swamp the norm and shrink every PPO gradient; Adam is
                // per-element scale-free, so log_sigma needs no clipping.
                let clipped: Vec<_> = params.iter().filter(|p| !p.name.ends_with("sigma")).cloned().collect();
                let grad_norm = optimizer.clip_grad_norm(&clipped, &mut grads, cfg.max_grad_norm)?;
                optimizer.step(&params, &grads)?;
                hooks.after_step(&params)?;

                add(&mut sums, "losses/policy_loss", &actor.policy_loss)?;
                add(&mut sums, "losses/value_loss", &critic_loss)?;
                add(&mut sums, "losses/entropy", &actor.entropy)?;
                *sums.entry("losses/approx_kl".into()).or_default() += kl;
                *sums.entry("losses/clipfrac".into()).or_default() += actor.clipfrac;
                *sums.entry("losses/grad_norm".into()).or_default() += grad_norm;
                count += 1.0;
            }
        }
        let mut m: Metrics = sums.into_iter().map(|(k, v)| (k, v / count)).collect();
        m.insert("charts/learning_rate".into(), self.optimizer.learning_rate());
        let std = self.agent.log_std.as_tensor().exp()?.mean_all()?.to_scalar::<f32>()?;
        m.insert("charts/action_std".into(), f64::from(std));
        Ok(m)
    }
}

/// What the actor's branch of a minibatch update returns.
struct ActorTerms {
    /// KL(rollout policy || current policy) before the step.
    kl: f64,
    policy_loss: Tensor,
    entropy: Tensor,
    /// The actor's soft-score loss term.
    soft_score: Tensor,
    clipfrac: f64,
    grads: GradStore,
}

/// Adds a scalar tensor's value to `sums[name]`.
fn add(sums: &mut Metrics, name: &str, value: &Tensor) -> anyhow::Result<()> {
    *sums.entry(name.into()).or_default() += f64::from(value.to_scalar::<f32>()?);
    Ok(())
}

/// Errors when more than `max_rate` of an iteration's `env_steps` ended in a
/// physics blow-up (each already reset its env); the error says how many, the
/// limit's key and what the last one was.
pub fn check_physics_resets(resets: &[(usize, String)], env_steps: usize, max_rate: f64) -> anyhow::Result<()> {
    let rate = resets.len() as f64 / env_steps.max(1) as f64;
    match resets.last() {
        Some((_, last)) if rate > max_rate => anyhow::bail!(
            "the physics blew up in {} of this iteration's {env_steps} env steps ({:.2} %, more than \
             ppo.max_physics_reset_rate = {max_rate}); the last: {last}",
            resets.len(),
            100.0 * rate
        ),
        _ => Ok(()),
    }
}
