//! The last rollout as an [`OutputSample`]: how a method probes the policy of
//! the task that is ending (EWC's Fisher, ER's and A-GEM's rehearsal data,
//! METHOD.md 3); and the agent as a [`PolicyProbe`], running an earlier
//! task's policy on such data while a later task trains. Sample i is the
//! rollout's i-th row: its normalised observation (obs,) and history
//! (H * obs,) go through the CENet encoder and the actor as a deployed
//! policy runs them (latent = its mean), differentiable in both networks'
//! training parameters; the action means are divided by the policy's sigma.
//!
//! Shapes: one row at a time, (1, obs) and (1, H * obs) -> (act,). A replay
//! row is `[obs | history]` (obs + H * obs,), normalised as the task saw it.

use super::agent::{matrix, Agent};
use super::rollout::RolloutBuffer;
use super::update_hooks::{OutputSample, PolicyProbe};
use crate::nn::TaskId;
use candle_core::Tensor;

/// The rows of one rollout, seen through an agent in training mode.
pub struct RolloutSample<'a> {
    agent: &'a Agent,
    buffer: &'a RolloutBuffer,
}

impl<'a> RolloutSample<'a> {
    /// The rows `buffer` holds, probed through `agent`.
    pub fn new(agent: &'a Agent, buffer: &'a RolloutBuffer) -> Self {
        Self { agent, buffer }
    }
}

impl OutputSample for RolloutSample<'_> {
    fn len(&self) -> usize {
        self.buffer.len * self.buffer.num_envs
    }

    fn scaled_output(&self, i: usize) -> anyhow::Result<Tensor> {
        anyhow::ensure!(i < self.len(), "sample {i} of a rollout of {} rows", self.len());
        let d = self.buffer.dims;
        let obs = matrix(&self.buffer.obs[i * d.obs..(i + 1) * d.obs], d.obs)?;
        let context = if d.context > 0 {
            let h = d.obs_history;
            let estimate = self.agent.estimate(&matrix(&self.buffer.obs_history[i * h..(i + 1) * h], h)?)?;
            Tensor::cat(&[&estimate.velocity, &estimate.latent_mean], 1)?
        } else {
            Tensor::zeros((1, 0), candle_core::DType::F32, &candle_core::Device::Cpu)?
        };
        let mean = self.agent.action_mean(&obs, &context)?.squeeze(0)?;
        let sigma = self.agent.log_std.as_tensor().detach().exp()?;
        Ok(mean.div(&sigma)?)
    }

    fn replay_row(&self, i: usize) -> anyhow::Result<(Vec<f32>, Vec<f32>)> {
        let d = self.buffer.dims;
        let mut input = self.buffer.obs[i * d.obs..(i + 1) * d.obs].to_vec();
        input.extend_from_slice(&self.buffer.obs_history[i * d.obs_history..(i + 1) * d.obs_history]);
        let sigma = self.sigma()?;
        let scaled: Vec<f32> = self.scaled_output(i)?.detach().to_vec1()?;
        Ok((input, scaled.iter().zip(&sigma).map(|(m, s)| m * s).collect()))
    }

    fn sigma(&self) -> anyhow::Result<Vec<f32>> {
        Ok(self.agent.log_std.as_tensor().exp()?.to_vec1()?)
    }
}

/// The agent running any trained task's policy (its heads, today's trunks), differentiably.
pub struct AgentProbe<'a> {
    agent: &'a Agent,
}

impl<'a> AgentProbe<'a> {
    /// A probe of `agent`.
    pub fn new(agent: &'a Agent) -> Self {
        Self { agent }
    }
}

impl PolicyProbe for AgentProbe<'_> {
    fn outputs(&self, task: TaskId, inputs: &[f32], rows: usize) -> anyhow::Result<Tensor> {
        let a = self.agent;
        let (obs_w, hist_w) = (a.dims.obs, a.dims.history_len * a.dims.obs);
        anyhow::ensure!(inputs.len() == rows * (obs_w + hist_w), "{} values for {rows} replay rows", inputs.len());
        let (mut obs, mut history) = (Vec::with_capacity(rows * obs_w), Vec::with_capacity(rows * hist_w));
        for row in inputs.chunks_exact(obs_w + hist_w) {
            obs.extend_from_slice(&row[..obs_w]);
            history.extend_from_slice(&row[obs_w..]);
        }
        let obs = matrix(&obs, obs_w)?;
        let context = if a.use_cenet {
            let out = a.encoder.forward_of_task(task, &matrix(&history, hist_w)?)?;
            let estimate = super::cenet_loss::split_encoder_output(&out, a.latent_dim, a.logvar_clamp)?;
            Tensor::cat(&[&estimate.velocity, &estimate.latent_mean], 1)?
        } else {
            Tensor::zeros((rows, 0), candle_core::DType::F32, &candle_core::Device::Cpu)?
        };
        a.actor.forward_of_task(task, &a.actor_input(&obs, &context)?)
    }
}
