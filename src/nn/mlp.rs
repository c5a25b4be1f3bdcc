//! MaskedMlp: a stack of [`MaskedLinear`] layers with an activation between
//! them (the output layer is linear). Used for the actor (512-256-128 ELU by
//! default), the critic and the CENet. Layers are named "{name}.l0",
//! "{name}.l1", ...; their tensors "{name}.l0.weight", "{name}.l0.bias", ...
//!
//! Shapes: x (batch, sizes[0]) -> (batch, sizes[last]).

use super::activation::activate;
use super::fused::fused_mlp_checked;
use super::masked::{LayerIteration, MaskedLinear};
use super::state::TaskId;
use super::Param;
use crate::config::net::{Activation, MaskConfig};
use candle_core::Tensor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// A network's effective weights at one moment, detached (see [`MaskedMlp::frozen_weights`]).
#[derive(Debug, Clone)]
pub struct FrozenWeights {
    network: String,
    /// (sum over layers of out * in + out,): the fused op's theta.
    theta: Tensor,
}

impl FrozenWeights {
    /// The detached theta of `network`.
    pub(crate) fn new(network: &str, theta: Tensor) -> Self {
        Self { network: network.to_string(), theta }
    }

    /// The network these weights belong to.
    pub(crate) fn network(&self) -> &str {
        &self.network
    }

    /// The fused op's theta.
    pub(crate) fn theta(&self) -> &Tensor {
        &self.theta
    }
}

/// A multi-layer perceptron of masked layers sharing one task life cycle.
#[derive(Debug)]
pub struct MaskedMlp {
    pub(crate) name: String,
    pub(crate) sizes: Vec<usize>,
    pub(crate) activation: Activation,
    pub(crate) cfg: MaskConfig,
    pub(crate) layers: Vec<MaskedLinear>,
}

impl MaskedMlp {
    /// `sizes` = [in, hidden.., out]; the initial weights and scores come from `seed` alone.
    pub fn new(
        name: &str,
        sizes: &[usize],
        activation: Activation,
        cfg: &MaskConfig,
        seed: u64,
    ) -> anyhow::Result<Self> {
        anyhow::ensure!(sizes.len() >= 2, "{name}: an MLP needs at least an input and an output size, got {sizes:?}");
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let last = sizes.len() - 2;
        let layers = sizes
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let gain_relu = i < last && matches!(activation, Activation::Elu | Activation::Relu);
                MaskedLinear::new(&format!("{name}.l{i}"), w[0], w[1], gain_relu, cfg, &mut rng)
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(Self { name: name.to_string(), sizes: sizes.to_vec(), activation, cfg: cfg.clone(), layers })
    }

    /// The network's name ("actor", "critic", ...).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// [in, hidden.., out].
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// The activation between hidden layers.
    pub fn activation(&self) -> Activation {
        self.activation
    }

    /// The mask settings.
    pub fn mask_config(&self) -> &MaskConfig {
        &self.cfg
    }

    /// Replaces the mask settings (capacity, lambda rule, private share, entropy, re-initialisation, ...)
    /// of the network and every layer, for the NEXT task: only allowed between tasks, so a
    /// task in progress never sees its rules change. The layers' initialiser bounds stay.
    pub fn set_mask_config(&mut self, cfg: &MaskConfig) -> anyhow::Result<()> {
        cfg.validate()?;
        for l in &self.layers {
            cfg.check_selects_in(&l.name, l.out_dim, l.in_dim)?;
        }
        if let Some(current) = self.current_task() {
            anyhow::bail!("{}: mask settings changed while task {current} is in progress", self.name);
        }
        self.cfg = cfg.clone();
        self.layers.iter_mut().for_each(|l| l.cfg = cfg.clone());
        Ok(())
    }

    /// Takes `cfg`'s end-of-task settings ([`MaskConfig::with_end_of_task`]); allowed while a
    /// task is in progress, since training up to its end does not read them.
    pub fn set_end_of_task(&mut self, cfg: &MaskConfig) -> anyhow::Result<()> {
        let merged = self.cfg.with_end_of_task(cfg);
        merged.validate()?;
        self.layers.iter_mut().for_each(|l| l.cfg = l.cfg.with_end_of_task(cfg));
        self.cfg = merged;
        Ok(())
    }

    /// Scales the output layer's initial weights and re-initialisation range
    /// (see [`MaskedLinear::scale_init`]); only before the first task.
    pub fn scale_output_init(&mut self, factor: f32) -> anyhow::Result<()> {
        let name = self.name.clone();
        self.layers.last_mut().ok_or_else(|| anyhow::anyhow!("{name}: no layers"))?.scale_init(factor)
    }

    /// The layers, input first.
    pub fn layers(&self) -> &[MaskedLinear] {
        &self.layers
    }

    /// The task in progress, if any.
    pub fn current_task(&self) -> Option<TaskId> {
        self.layers[0].training.as_ref().map(|t| t.task)
    }

    /// Tasks that have finished at least once, in the order they first ended.
    pub fn finished_tasks(&self) -> &[TaskId] {
        &self.layers[0].finish_order
    }

    /// New task: fresh per-task bias, soft scores (+ forward-transfer bonus on related tasks' masks);
    /// an already finished task => repeat mode (only its private elements and bias train, METHOD.md 2.5).
    pub fn begin_task(&mut self, task: TaskId, related: &[TaskId]) -> anyhow::Result<()> {
        // Checked here first so that no layer starts when another would refuse.
        if let Some(current) = self.current_task() {
            anyhow::bail!(
                "{}: begin_task({task}) while task {current} is still in progress (call end_task first)",
                self.name
            );
        }
        if let Some(r) = related.iter().find(|r| !self.finished_tasks().contains(r)) {
            anyhow::bail!("{}: related task {r} has not finished (finished: {:?})", self.name, self.finished_tasks());
        }
        self.layers.iter_mut().try_for_each(|l| l.begin_task(task, related))
    }

    /// Once per training iteration: draw S = mu + sigma*eps, choose the hard masks, entropy schedule.
    pub fn begin_iteration(&mut self, iteration: usize, rng: &mut impl Rng) -> anyhow::Result<()> {
        let noise = self.draw_iteration_noise(rng)?;
        self.begin_iteration_with_noise(iteration, noise)
    }

    /// Every layer's noise for the iteration, drawn in layer order (see
    /// [`MaskedLinear::draw_iteration_noise`]).
    pub(crate) fn draw_iteration_noise(&self, rng: &mut impl Rng) -> anyhow::Result<Vec<Option<Vec<f32>>>> {
        self.layers.iter().map(|l| l.draw_iteration_noise(rng)).collect()
    }

    /// The layers choose their masks from `noise` in parallel (the draws were made in order,
    /// so the masks are those of drawing and choosing layer by layer).
    pub(crate) fn begin_iteration_with_noise(
        &mut self,
        iteration: usize,
        noise: Vec<Option<Vec<f32>>>,
    ) -> anyhow::Result<()> {
        anyhow::ensure!(noise.len() == self.layers.len(), "{}: noise for {} layers", self.name, noise.len());
        self.layers.par_iter_mut().zip(noise).try_for_each(|(l, n)| l.begin_iteration_with_noise(iteration, n))
    }

    /// Mask churn of the whole network: the share of this iteration's selected elements that
    /// the previous iteration had not selected, layers weighted by their size (None until a
    /// task's second iteration). Large values mean the sampled network changes under the
    /// policy between iterations, which PPO's KL does not see.
    pub fn mask_churn(&self) -> Option<f64> {
        let (mut sum, mut weight) = (0.0, 0.0);
        for l in &self.layers {
            let n = (l.out_dim * l.in_dim) as f64;
            sum += l.mask_churn()? * n;
            weight += n;
        }
        (weight > 0.0).then(|| sum / weight)
    }

    /// beta_H to add to the action-distribution entropy bonus this iteration (see
    /// [`MaskedLinear::action_entropy_weight`]; every layer has the same settings).
    pub fn action_entropy_weight(&self) -> f64 {
        self.layers.iter().map(MaskedLinear::action_entropy_weight).fold(0.0, f64::max)
    }

    /// Each layer's soft-score statistics of the iteration (METHOD 2.3), by layer name
    /// (layers outside a new task's training left out).
    pub fn layer_stats(&self) -> anyhow::Result<Vec<(String, LayerIteration)>> {
        let mut out = Vec::new();
        for l in &self.layers {
            if let Some(s) = l.iteration_stats()? {
                out.push((l.name().to_string(), s));
            }
        }
        Ok(out)
    }

    /// Every layer's (weight, bias) concatenated in layer order: the fused op's theta.
    fn theta(weights: Vec<(Tensor, Tensor)>) -> anyhow::Result<Tensor> {
        let mut parts = Vec::with_capacity(2 * weights.len());
        for (w, b) in weights {
            parts.push(w.flatten_all()?);
            parts.push(b);
        }
        Ok(Tensor::cat(&parts, 0)?)
    }

    /// Runs the fused op on `theta` (see [`Self::theta`]).
    fn run_theta(&self, x: &Tensor, theta: &Tensor, track: bool) -> anyhow::Result<Tensor> {
        fused_mlp_checked(&self.name, &self.sizes, self.activation, x, theta, track)
    }

    fn run(&self, x: &Tensor, weights: Vec<(Tensor, Tensor)>, track: bool) -> anyhow::Result<Tensor> {
        self.run_theta(x, &Self::theta(weights)?, track)
    }

    /// The weights [`Self::forward_no_grad`] uses (this iteration's masks), or with `task`
    /// those of [`Self::forward_task`], as one detached tensor to run many batches with
    /// [`Self::forward_weights`] while nothing trains (a rollout, an evaluation).
    pub fn frozen_weights(&self, task: Option<TaskId>) -> anyhow::Result<FrozenWeights> {
        let weights = match task {
            Some(task) => self.layers.iter().map(|l| l.recall_weight(task)).collect::<anyhow::Result<_>>()?,
            None => self.layers.iter().map(|l| l.effective_training_weight(false)).collect::<anyhow::Result<_>>()?,
        };
        Ok(FrozenWeights { network: self.name.clone(), theta: Self::theta(weights)?.detach() })
    }

    /// The forward with weights from [`Self::frozen_weights`]: the same values, no gradient.
    pub fn forward_weights(&self, weights: &FrozenWeights, x: &Tensor) -> anyhow::Result<Tensor> {
        anyhow::ensure!(weights.network == self.name, "weights of {} given to network {}", weights.network, self.name);
        self.run_theta(x, &weights.theta, false)
    }

    /// Training forward with the current task's masks, (batch, in) -> (batch, out), differentiable.
    pub fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        let weights = self.layers.iter().map(|l| l.training_weight()).collect::<anyhow::Result<_>>()?;
        self.run(x, weights, true)
    }

    /// The training forward's values without a gradient (no activations kept): for rollouts
    /// with the current iteration's masks.
    pub fn forward_no_grad(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        self.forward_weights(&self.frozen_weights(None)?, x)
    }

    /// Recall a finished task (W*M_t + b_t), bit-identical forever.
    pub fn forward_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        let weights = self.layers.iter().map(|l| l.recall_weight(task)).collect::<anyhow::Result<_>>()?;
        self.run(x, weights, false)
    }

    /// The same forward as [`MaskedMlp::forward`] with candle's stock ops, layer by layer
    /// (the reference the fused op is tested against).
    pub fn forward_unfused(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        let last = self.layers.len() - 1;
        let mut h = x.clone();
        for (i, l) in self.layers.iter().enumerate() {
            h = l.forward(&h)?;
            if i < last {
                h = activate(self.activation, &h)?;
            }
        }
        Ok(h)
    }

    /// Scalar -beta_H * H summed over layers (METHOD 2.3); 0 when off or after E iterations.
    pub fn soft_score_loss(&self) -> anyhow::Result<Tensor> {
        let mut total = self.layers[0].soft_score_loss()?;
        for l in &self.layers[1..] {
            total = total.add(&l.soft_score_loss()?)?;
        }
        Ok(total)
    }

    /// Every trainable Var with its current per-element update mask.
    pub fn params(&self) -> Vec<Param> {
        self.layers.iter().flat_map(|l| l.parameters()).collect()
    }

    /// Every layer's vacant weights redrawn ([`MaskedLinear::redraw_vacant_weights`]) at the
    /// range and scale `cfg` gives fresh weights (`reinit_range`, `reinit_scale`); between tasks only.
    pub fn redraw_vacant_weights(&mut self, cfg: &MaskConfig, rng: &mut impl Rng) -> anyhow::Result<()> {
        if let Some(current) = self.current_task() {
            anyhow::bail!("{}: vacant weights redrawn while task {current} is in progress", self.name);
        }
        self.layers.iter_mut().try_for_each(|l| l.redraw_vacant_weights(cfg.reinit_range, cfg.reinit_scale, rng))
    }

    /// End of task (METHOD 2.4).
    pub fn end_task(&mut self, rng: &mut impl Rng) -> anyhow::Result<()> {
        self.layers.iter_mut().try_for_each(|l| l.end_task(rng))
    }
}
