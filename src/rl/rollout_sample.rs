//! The last rollout as an [`OutputSample`]: how a method probes the policy of
//! the task that is ending (EWC's Fisher, METHOD.md 3). Sample i is the
//! rollout's i-th row: its normalised observation (obs,) and history
//! (H * obs,) go through the CENet encoder and the actor as a deployed
//! policy runs them (latent = its mean), differentiable in both networks'
//! training parameters; the action means are divided by the policy's sigma.
//!
//! Shapes: one row at a time, (1, obs) and (1, H * obs) -> (act,).

use super::agent::{matrix, Agent};
use super::rollout::RolloutBuffer;
use super::update_hooks::OutputSample;
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
}
