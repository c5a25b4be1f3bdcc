//! Network: one of the learner's networks, masked ([`MaskedMlp`], the paper's
//! method and the mask baselines) or dense ([`DenseMlp`], the shared trunk with
//! per-task heads of the regularisation and rehearsal baselines). The agent,
//! checkpoints and statistics take either; what only masks have (soft scores,
//! per-iteration mask draws, switches) does nothing on a dense network.
//!
//! Shapes: x (batch, sizes[0]) -> (batch, sizes[last]) either way.

use super::dense::DenseMlp;
use super::masked::LayerIteration;
use super::mlp::{FrozenWeights, MaskedMlp};
use super::state::TaskId;
use super::Param;
use crate::config::net::{Activation, MaskConfig, NetworkKind};
use candle_core::{DType, Device, Tensor};
use rand::Rng;

/// A masked or a dense network.
#[derive(Debug)]
pub enum Network {
    Masked(MaskedMlp),
    Dense(DenseMlp),
}

/// The noise one iteration's mask draw needs, per layer (empty for a dense network).
pub type IterationNoise = Vec<Option<Vec<f32>>>;

impl Network {
    /// Which kind it is.
    pub fn kind(&self) -> NetworkKind {
        match self {
            Self::Masked(_) => NetworkKind::Masked,
            Self::Dense(_) => NetworkKind::Dense,
        }
    }

    /// The masked network, if it is one.
    pub fn as_masked(&self) -> Option<&MaskedMlp> {
        match self {
            Self::Masked(n) => Some(n),
            Self::Dense(_) => None,
        }
    }

    /// The dense network, if it is one.
    pub fn as_dense(&self) -> Option<&DenseMlp> {
        match self {
            Self::Masked(_) => None,
            Self::Dense(n) => Some(n),
        }
    }

    /// The dense network this becomes (a masked one: [`DenseMlp::from_masked`] with the
    /// task that ended last as the trunk); a dense one stays as it is.
    pub fn into_dense(self) -> anyhow::Result<Self> {
        match self {
            Self::Masked(n) => {
                let last = n.finished_tasks().last().copied();
                Ok(Self::Dense(DenseMlp::from_masked(&n, last)?))
            }
            dense => Ok(dense),
        }
    }

    /// The network's name ("actor", "critic", ...).
    pub fn name(&self) -> &str {
        match self {
            Self::Masked(n) => n.name(),
            Self::Dense(n) => n.name(),
        }
    }

    /// [in, hidden.., out].
    pub fn sizes(&self) -> &[usize] {
        match self {
            Self::Masked(n) => n.sizes(),
            Self::Dense(n) => n.sizes(),
        }
    }

    /// The activation between hidden layers.
    pub fn activation(&self) -> Activation {
        match self {
            Self::Masked(n) => n.activation(),
            Self::Dense(n) => n.activation(),
        }
    }

    /// The task in progress, if any.
    pub fn current_task(&self) -> Option<TaskId> {
        match self {
            Self::Masked(n) => n.current_task(),
            Self::Dense(n) => n.current_task(),
        }
    }

    /// Tasks that have finished at least once, in the order they first ended.
    pub fn finished_tasks(&self) -> &[TaskId] {
        match self {
            Self::Masked(n) => n.finished_tasks(),
            Self::Dense(n) => n.finished_tasks(),
        }
    }

    /// The mask settings for the next task (nothing for a dense network).
    pub fn set_mask_config(&mut self, cfg: &MaskConfig) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.set_mask_config(cfg),
            Self::Dense(_) => Ok(()),
        }
    }

    /// End-of-task mask settings, also mid-task (nothing for a dense network).
    pub fn set_end_of_task(&mut self, cfg: &MaskConfig) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.set_end_of_task(cfg),
            Self::Dense(_) => Ok(()),
        }
    }

    /// Every vacant weight redrawn at `cfg`'s fresh-weight range ([`MaskedMlp::redraw_vacant_weights`]);
    /// a dense network has no vacant weights and refuses.
    pub fn redraw_vacant_weights(&mut self, cfg: &MaskConfig, rng: &mut impl rand::Rng) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.redraw_vacant_weights(cfg, rng),
            Self::Dense(n) => anyhow::bail!("{}: a dense network has no vacant weights to redraw", n.name()),
        }
    }

    /// Scales the output layer's (or initial head's) initial weights; only before the first task.
    pub fn scale_output_init(&mut self, factor: f32) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.scale_output_init(factor),
            Self::Dense(n) => n.scale_output_init(factor),
        }
    }

    /// Starts training `task` (`related` seeds a masked network's soft scores).
    pub fn begin_task(&mut self, task: TaskId, related: &[TaskId]) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.begin_task(task, related),
            Self::Dense(n) => n.begin_task(task),
        }
    }

    /// The noise of one iteration's mask draw, from `rng` in layer order (none for a dense network).
    pub fn draw_iteration_noise(&self, rng: &mut impl Rng) -> anyhow::Result<IterationNoise> {
        match self {
            Self::Masked(n) => n.draw_iteration_noise(rng),
            Self::Dense(_) => Ok(Vec::new()),
        }
    }

    /// Chooses the iteration's masks from `noise` (nothing for a dense network).
    pub fn begin_iteration_with_noise(&mut self, iteration: usize, noise: IterationNoise) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.begin_iteration_with_noise(iteration, noise),
            Self::Dense(_) => Ok(()),
        }
    }

    /// Once per training iteration: a masked network draws its masks.
    pub fn begin_iteration(&mut self, iteration: usize, rng: &mut impl Rng) -> anyhow::Result<()> {
        let noise = self.draw_iteration_noise(rng)?;
        self.begin_iteration_with_noise(iteration, noise)
    }

    /// The soft-score loss term (METHOD 2.3), a scalar; 0 for a dense network.
    pub fn soft_score_loss(&self) -> anyhow::Result<Tensor> {
        match self {
            Self::Masked(n) => n.soft_score_loss(),
            Self::Dense(_) => Ok(Tensor::zeros((), DType::F32, &Device::Cpu)?),
        }
    }

    /// Share of this iteration's selected elements new since the last (masked networks only).
    pub fn mask_churn(&self) -> Option<f64> {
        self.as_masked().and_then(MaskedMlp::mask_churn)
    }

    /// beta_H to add to the action-distribution entropy bonus this iteration (masked networks
    /// with `entropy_target = "action"` in a new task's first E iterations; 0 otherwise).
    pub fn action_entropy_weight(&self) -> f64 {
        self.as_masked().map_or(0.0, MaskedMlp::action_entropy_weight)
    }

    /// Each masked layer's soft-score statistics of the iteration (none for a dense network).
    pub fn layer_stats(&self) -> anyhow::Result<Vec<(String, LayerIteration)>> {
        self.as_masked().map_or(Ok(Vec::new()), MaskedMlp::layer_stats)
    }

    /// Every trainable variable with its update mask.
    pub fn params(&self) -> Vec<Param> {
        match self {
            Self::Masked(n) => n.params(),
            Self::Dense(n) => n.params(),
        }
    }

    /// Training forward of the task in progress, differentiable.
    pub fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        match self {
            Self::Masked(n) => n.forward(x),
            Self::Dense(n) => n.forward(x),
        }
    }

    /// Finished (or trained) task `task`'s forward, no gradient. Masked: bit-identical
    /// forever; dense: with today's trunk (which later tasks may have moved).
    pub fn forward_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        match self {
            Self::Masked(n) => n.forward_task(task, x),
            Self::Dense(n) => n.forward_task(task, x),
        }
    }

    /// Task `task`'s forward, differentiable in what trains (dense: the shared trunk and the
    /// task's head); a masked network's recall, which nothing moves, is a constant.
    pub fn forward_of_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        match self {
            Self::Masked(n) => n.forward_task(task, x),
            Self::Dense(n) => n.forward_of_task(task, x),
        }
    }

    /// The weights of the training forward (`None`) or of `task`'s, detached, to run many batches.
    pub fn frozen_weights(&self, task: Option<TaskId>) -> anyhow::Result<FrozenWeights> {
        match self {
            Self::Masked(n) => n.frozen_weights(task),
            Self::Dense(n) => n.frozen_weights(task),
        }
    }

    /// The forward with weights from [`Self::frozen_weights`].
    pub fn forward_weights(&self, weights: &FrozenWeights, x: &Tensor) -> anyhow::Result<Tensor> {
        match self {
            Self::Masked(n) => n.forward_weights(weights, x),
            Self::Dense(n) => n.forward_weights(weights, x),
        }
    }

    /// Ends the task in progress (a masked network: METHOD 2.4).
    pub fn end_task(&mut self, rng: &mut impl Rng) -> anyhow::Result<()> {
        match self {
            Self::Masked(n) => n.end_task(rng),
            Self::Dense(n) => n.end_task(),
        }
    }
}

/// A borrowed masked or dense network: what a checkpoint writes.
#[derive(Debug, Clone, Copy)]
pub enum NetworkRef<'a> {
    Masked(&'a MaskedMlp),
    Dense(&'a DenseMlp),
}

/// Anything a checkpoint can write as a network.
pub trait AsNetworkRef {
    /// The network, borrowed.
    fn as_network_ref(&self) -> NetworkRef<'_>;
}

impl AsNetworkRef for Network {
    fn as_network_ref(&self) -> NetworkRef<'_> {
        match self {
            Self::Masked(n) => NetworkRef::Masked(n),
            Self::Dense(n) => NetworkRef::Dense(n),
        }
    }
}

impl AsNetworkRef for MaskedMlp {
    fn as_network_ref(&self) -> NetworkRef<'_> {
        NetworkRef::Masked(self)
    }
}

impl AsNetworkRef for DenseMlp {
    fn as_network_ref(&self) -> NetworkRef<'_> {
        NetworkRef::Dense(self)
    }
}

impl From<MaskedMlp> for Network {
    fn from(n: MaskedMlp) -> Self {
        Self::Masked(n)
    }
}

impl From<DenseMlp> for Network {
    fn from(n: DenseMlp) -> Self {
        Self::Dense(n)
    }
}
