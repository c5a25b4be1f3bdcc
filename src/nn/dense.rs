//! DenseMlp: the network of the non-mask baselines (METHOD.md 3; Continual
//! World's multi-head setup, as the paper evaluates them). The hidden layers
//! are one dense trunk that every task trains (nothing is frozen: a method
//! protects old tasks through its loss, gradients or replay); the output
//! layer is one head per task.
//!
//! Shapes: trunk layer i: weight (sizes[i+1], sizes[i]), bias (sizes[i+1],);
//! head of task t: weight (out, sizes[last-1]), bias (out,); x (batch, in) ->
//! (batch, out). Forward for task t runs trunk + head t through the fused op
//! (`nn/fused.rs`), the same kernels as [`super::MaskedMlp`].
//!
//! A new task's head starts as a copy of the head of the task that ended last
//! (the policy it continues from, as a new task of `ours` starts from its
//! selected old weights), or of the network's initial head before any task
//! ended. Parameter names: "{name}.l{i}.weight" / ".bias" for the trunk,
//! "{name}.head.weight" / ".bias" for the head in training.

use super::fused::fused_mlp_checked;
use super::mlp::FrozenWeights;
use super::state::TaskId;
use super::Param;
use crate::config::net::Activation;
use anyhow::Context;
use candle_core::{Device, Tensor, Var};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Uniform};
use std::collections::BTreeMap;

/// One dense layer's weight (out, in) and bias (out,).
#[derive(Debug, Clone)]
pub struct DenseLayer {
    pub weight: Var,
    pub bias: Var,
}

impl DenseLayer {
    /// A layer with these values.
    pub fn from_values(weight: Vec<f32>, bias: Vec<f32>, out_dim: usize, in_dim: usize) -> anyhow::Result<Self> {
        Ok(Self {
            weight: Var::from_tensor(&Tensor::from_vec(weight, (out_dim, in_dim), &Device::Cpu)?)?,
            bias: Var::from_tensor(&Tensor::from_vec(bias, out_dim, &Device::Cpu)?)?,
        })
    }

    /// A detached copy (new variables).
    pub fn deep_copy(&self) -> anyhow::Result<Self> {
        Ok(Self {
            weight: Var::from_tensor(&self.weight.as_tensor().copy()?)?,
            bias: Var::from_tensor(&self.bias.as_tensor().copy()?)?,
        })
    }
}

/// A shared dense trunk with one output head per task.
#[derive(Debug)]
pub struct DenseMlp {
    pub(crate) name: String,
    pub(crate) sizes: Vec<usize>,
    pub(crate) activation: Activation,
    /// The hidden layers, input first (sizes.len() - 2 of them).
    pub(crate) trunk: Vec<DenseLayer>,
    /// Every task's head (a task in progress has one too).
    pub(crate) heads: BTreeMap<TaskId, DenseLayer>,
    /// The head a new task starts from when no task has ended yet.
    pub(crate) initial_head: DenseLayer,
    /// The task in progress.
    pub(crate) current: Option<TaskId>,
    /// Tasks that have finished at least once, in the order they first ended.
    pub(crate) finish_order: Vec<TaskId>,
    /// The task whose head a new task copies (the one that ended last).
    pub(crate) last_ended: Option<TaskId>,
}

fn uniform_layer(out_dim: usize, in_dim: usize, gain: f64, rng: &mut ChaCha8Rng) -> anyhow::Result<DenseLayer> {
    let bound = (gain / in_dim as f64).sqrt() as f32;
    let dist = Uniform::new_inclusive(-bound, bound);
    let w = (0..out_dim * in_dim).map(|_| dist.sample(rng)).collect();
    DenseLayer::from_values(w, vec![0.0; out_dim], out_dim, in_dim)
}

fn values(var: &Var) -> anyhow::Result<Vec<f32>> {
    Ok(var.as_tensor().flatten_all()?.to_vec1::<f32>()?)
}

impl DenseMlp {
    /// `sizes` = [in, hidden.., out]; W ~ U(-b, b) with b = sqrt(6 / in) (He) on hidden layers
    /// and sqrt(3 / in) on the output, biases 0; from `seed` alone.
    pub fn new(name: &str, sizes: &[usize], activation: Activation, seed: u64) -> anyhow::Result<Self> {
        anyhow::ensure!(sizes.len() >= 2, "{name}: an MLP needs at least an input and an output size, got {sizes:?}");
        anyhow::ensure!(sizes.iter().all(|s| *s > 0), "{name}: a zero size in {sizes:?}");
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let relu_like = matches!(activation, Activation::Elu | Activation::Relu);
        let trunk = sizes[..sizes.len() - 1]
            .windows(2)
            .map(|w| uniform_layer(w[1], w[0], if relu_like { 6.0 } else { 3.0 }, &mut rng))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let n = sizes.len();
        let initial_head = uniform_layer(sizes[n - 1], sizes[n - 2], 3.0, &mut rng)?;
        Ok(Self::from_parts(name, sizes, activation, trunk, initial_head))
    }

    /// A network with these layers and no task.
    pub(crate) fn from_parts(
        name: &str,
        sizes: &[usize],
        activation: Activation,
        trunk: Vec<DenseLayer>,
        initial_head: DenseLayer,
    ) -> Self {
        Self {
            name: name.to_string(),
            sizes: sizes.to_vec(),
            activation,
            trunk,
            heads: BTreeMap::new(),
            initial_head,
            current: None,
            finish_order: Vec::new(),
            last_ended: None,
        }
    }

    /// The dense network a masked one becomes (a base policy for a baseline): the trunk takes
    /// the effective weights W * M_t and biases of `trunk_task`, every finished task keeps its
    /// own output layer as its head. Without finished tasks: the raw weights, zero biases.
    pub fn from_masked(net: &super::MaskedMlp, trunk_task: Option<TaskId>) -> anyhow::Result<Self> {
        let sizes = net.sizes().to_vec();
        let layer_of = |i: usize, task: Option<TaskId>| -> anyhow::Result<DenseLayer> {
            let l = &net.layers()[i];
            let (out_dim, in_dim) = l.shape();
            match task {
                Some(t) => {
                    let (w, b) = l.recall_weight(t)?;
                    DenseLayer::from_values(w.flatten_all()?.to_vec1()?, b.to_vec1()?, out_dim, in_dim)
                }
                None => DenseLayer::from_values(l.weight_values()?, vec![0.0; out_dim], out_dim, in_dim),
            }
        };
        let last = sizes.len() - 2;
        let trunk = (0..last).map(|i| layer_of(i, trunk_task)).collect::<anyhow::Result<Vec<_>>>()?;
        let mut dense = Self::from_parts(net.name(), &sizes, net.activation(), trunk, layer_of(last, trunk_task)?);
        for &t in net.finished_tasks() {
            dense.heads.insert(t, layer_of(last, Some(t))?);
        }
        dense.finish_order = net.finished_tasks().to_vec();
        dense.last_ended = trunk_task.or(dense.finish_order.last().copied());
        Ok(dense)
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

    /// The shared hidden layers, input first.
    pub fn trunk(&self) -> &[DenseLayer] {
        &self.trunk
    }

    /// Task `task`'s head, if it has one.
    pub fn head(&self, task: TaskId) -> Option<&DenseLayer> {
        self.heads.get(&task)
    }

    /// The task in progress, if any.
    pub fn current_task(&self) -> Option<TaskId> {
        self.current
    }

    /// Tasks that have finished at least once, in the order they first ended.
    pub fn finished_tasks(&self) -> &[TaskId] {
        &self.finish_order
    }

    /// Scales the initial head's weights (a small initial policy output); only before the first task.
    pub fn scale_output_init(&mut self, factor: f32) -> anyhow::Result<()> {
        anyhow::ensure!(self.heads.is_empty(), "{}: the initial head is scaled before any task", self.name);
        let w = self.initial_head.weight.as_tensor().affine(f64::from(factor), 0.0)?;
        self.initial_head.weight.set(&w)?;
        Ok(())
    }

    /// Starts training `task`: a finished task trains its own head again; a new one gets a copy
    /// of the head of the task that ended last. `related` is not used (the trunk is shared).
    pub fn begin_task(&mut self, task: TaskId) -> anyhow::Result<()> {
        if let Some(current) = self.current {
            anyhow::bail!("{}: begin_task({task}) while task {current} is still in progress", self.name);
        }
        if !self.heads.contains_key(&task) {
            let source = match self.last_ended.and_then(|t| self.heads.get(&t)) {
                Some(head) => head,
                None => &self.initial_head,
            };
            self.heads.insert(task, source.deep_copy()?);
        }
        self.current = Some(task);
        Ok(())
    }

    /// Ends the task in progress; its head stays as it is.
    pub fn end_task(&mut self) -> anyhow::Result<()> {
        let task =
            self.current.take().with_context(|| format!("{}: end_task without a task in progress", self.name))?;
        if !self.finish_order.contains(&task) {
            self.finish_order.push(task);
        }
        self.last_ended = Some(task);
        Ok(())
    }

    fn theta(&self, head: &DenseLayer, track: bool) -> anyhow::Result<Tensor> {
        let mut parts = Vec::with_capacity(2 * self.sizes.len());
        for l in self.trunk.iter().chain(std::iter::once(head)) {
            let (w, b) = (l.weight.as_tensor(), l.bias.as_tensor());
            let (w, b) = if track { (w.clone(), b.clone()) } else { (w.detach(), b.detach()) };
            parts.push(w.flatten_all()?);
            parts.push(b);
        }
        Ok(Tensor::cat(&parts, 0)?)
    }

    fn head_of(&self, task: TaskId) -> anyhow::Result<&DenseLayer> {
        self.heads.get(&task).with_context(|| format!("{}: task {task} has no head (never trained)", self.name))
    }

    fn training_head(&self) -> anyhow::Result<&DenseLayer> {
        let task = self.current.with_context(|| format!("{}: no task in progress (call begin_task)", self.name))?;
        self.head_of(task)
    }

    fn run(&self, x: &Tensor, theta: &Tensor, track: bool) -> anyhow::Result<Tensor> {
        fused_mlp_checked(&self.name, &self.sizes, self.activation, x, theta, track)
    }

    /// Training forward with the task in progress' head, differentiable in trunk and head.
    pub fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        self.run(x, &self.theta(self.training_head()?, true)?, true)
    }

    /// Task `task` with today's trunk and its head (what an evaluation of it sees), no gradient.
    pub fn forward_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        self.run(x, &self.theta(self.head_of(task)?, false)?, false)
    }

    /// Task `task`'s forward (its head, today's trunk), differentiable in both: how a
    /// rehearsal loss pulls the shared trunk back towards an earlier task's outputs.
    pub fn forward_of_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        self.run(x, &self.theta(self.head_of(task)?, true)?, true)
    }

    /// The weights of [`Self::forward`] (`None`) or [`Self::forward_task`], detached.
    pub fn frozen_weights(&self, task: Option<TaskId>) -> anyhow::Result<FrozenWeights> {
        let head = match task {
            Some(t) => self.head_of(t)?,
            None => self.training_head()?,
        };
        Ok(FrozenWeights::new(&self.name, self.theta(head, false)?))
    }

    /// The forward with weights from [`Self::frozen_weights`]: the same values, no gradient.
    pub fn forward_weights(&self, weights: &FrozenWeights, x: &Tensor) -> anyhow::Result<Tensor> {
        anyhow::ensure!(
            weights.network() == self.name,
            "weights of {} given to network {}",
            weights.network(),
            self.name
        );
        self.run(x, weights.theta(), false)
    }

    /// Every trainable variable: the trunk, then the head of the task in progress (none between tasks).
    pub fn params(&self) -> Vec<Param> {
        let Some(head) = self.current.and_then(|t| self.heads.get(&t)) else { return Vec::new() };
        let p = |name: String, var: &Var| Param::free(name, var);
        let mut out = Vec::with_capacity(2 * self.sizes.len());
        for (i, l) in self.trunk.iter().enumerate() {
            out.push(p(format!("{}.l{i}.weight", self.name), &l.weight));
            out.push(p(format!("{}.l{i}.bias", self.name), &l.bias));
        }
        out.push(p(format!("{}.head.weight", self.name), &head.weight));
        out.push(p(format!("{}.head.bias", self.name), &head.bias));
        out
    }

    /// Every value of the trunk, layer by layer (weight then bias): for tests and statistics.
    pub fn trunk_values(&self) -> anyhow::Result<Vec<f32>> {
        let mut out = Vec::new();
        for l in &self.trunk {
            out.extend(values(&l.weight)?);
            out.extend(values(&l.bias)?);
        }
        Ok(out)
    }
}
