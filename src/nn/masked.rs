//! MaskedLinear: one linear layer of the method (METHOD.md section 2).
//!
//! Shapes: base weights W (out, in), shared by every task; one
//! [`ElementState`] per element; per finished task t a bit-packed mask M_t
//! (out * in bits) and its own bias b_t (out,). While task n trains: soft
//! score means mu (out, in), one sigma per layer, a hard mask M drawn once
//! per iteration from S = mu + sigma * eps, and the bias b_n (out,).
//!
//! sigma is trained through its logarithm: the variable is log_sigma and
//! sigma = exp(log_sigma) wherever it is used, so no optimiser step can make
//! it zero or negative (a raw sigma Var went negative within one PPO update,
//! which made ln sigma NaN and flipped the sign of the sampled scores).
//!
//! Forward for task t: y = x (W * M_t)^T + b_t, x (batch, in) -> (batch, out).
//!
//! Gradients (2.2): the training forward uses M_ste = M + (S - stop_grad(S)),
//! whose value is exactly M, so dL/dW = dL/dWeff * M and
//! dL/dmu = dL/dM = dL/dWeff * W for every element (straight-through);
//! dL/dlog_sigma = sigma * sum(dL/dM * eps). Which elements may actually move is the
//! optimiser's update mask: W where selected AND vacant, mu where selectable,
//! log_sigma only during the first E iterations (after that it decays, 2.3), at its own
//! fixed learning rate (`sigma_learning_rate`). Under `sigma_scale = "score_gap"` sigma
//! is in units of each row's score gap at the top-k cut (`masked/score_gap.rs`).

use super::bitmask::BitMask;
use super::masked_weight::masked_weight;
use super::select::{select_mask, SelectionParams};
use super::state::{ElementState, TaskId};
use super::Param;
use crate::config::net::{BiasStart, MaskConfig, ReinitRange, ScoreReinit, SelectionRule};
use anyhow::Context;
use candle_core::{Device, Tensor, Var};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal, Uniform};
use std::collections::BTreeMap;

mod baselines;
mod entropy;
mod iteration;
mod score_gap;

pub use iteration::LayerIteration;

/// The task being trained and its per-iteration tensors.
#[derive(Debug, Clone)]
pub(crate) struct Training {
    pub task: TaskId,
    /// A finished task trained again: only PRIVATE(task) weights and its bias move (2.5, 2.7).
    pub repeat: bool,
    pub iteration: usize,
    pub bias: Var,
    /// (out, in) 0/1 hard mask of this iteration; None until `begin_iteration`.
    pub mask: Option<Tensor>,
    /// (out, in) eps of this iteration.
    pub noise: Option<Tensor>,
    pub weight_update: Option<Tensor>,
    pub score_update: Option<Tensor>,
    /// The previous iteration's hard mask, to measure how much of it this iteration replaced.
    pub previous_selection: Option<Vec<bool>>,
    /// Fraction of this iteration's selected elements that the previous iteration had not selected.
    pub mask_churn: Option<f64>,
    /// The rows' mean score gap at the cut this iteration (`sigma_scale = "score_gap"`).
    pub score_gap: Option<f64>,
}

impl Training {
    /// Training of `task` at `iteration` with its bias variable; no iteration drawn yet.
    pub(crate) fn new(task: TaskId, repeat: bool, iteration: usize, bias: Var) -> Self {
        Self {
            task,
            repeat,
            iteration,
            bias,
            mask: None,
            noise: None,
            weight_update: None,
            score_update: None,
            previous_selection: None,
            mask_churn: None,
            score_gap: None,
        }
    }
}

/// A linear layer with per-task binary masks over shared base weights.
#[derive(Debug)]
pub struct MaskedLinear {
    pub(crate) name: String,
    pub(crate) out_dim: usize,
    pub(crate) in_dim: usize,
    pub(crate) cfg: MaskConfig,
    /// Half-width of the uniform initialiser of W: sqrt(g / (c F)), He for the effective fan-in.
    pub(crate) init_bound: f32,
    /// Half-width of the layer's initialiser over its full fan-in F, sqrt(g / F) (times the same
    /// init scale): the range of `reinit_range = "initial"`.
    pub(crate) full_fan_in_bound: f32,
    pub(crate) weight: Var,
    pub(crate) score_mean: Var,
    /// ln sigma, shape (1,); sigma = exp(log_sigma) is always > 0.
    pub(crate) log_sigma: Var,
    pub(crate) states: Vec<ElementState>,
    pub(crate) masks: BTreeMap<TaskId, BitMask>,
    pub(crate) biases: BTreeMap<TaskId, Vec<f32>>,
    /// Finished tasks in the order they first ended (for from_vacant / from_occupied statistics).
    pub(crate) finish_order: Vec<TaskId>,
    pub(crate) training: Option<Training>,
}

fn var_from(values: Vec<f32>, shape: &[usize]) -> anyhow::Result<Var> {
    Ok(Var::from_tensor(&Tensor::from_vec(values, shape, &Device::Cpu)?)?)
}

fn set_var(var: &Var, values: Vec<f32>) -> anyhow::Result<()> {
    let shape = var.as_tensor().dims().to_vec();
    var.set(&Tensor::from_vec(values, shape, &Device::Cpu)?)?;
    Ok(())
}

pub(crate) fn var_values(var: &Var) -> anyhow::Result<Vec<f32>> {
    Ok(var.as_tensor().flatten_all()?.to_vec1::<f32>()?)
}

fn mask_tensor(bits: impl Iterator<Item = bool>, out_dim: usize, in_dim: usize) -> anyhow::Result<Tensor> {
    let v: Vec<f32> = bits.map(|b| if b { 1.0 } else { 0.0 }).collect();
    Ok(Tensor::from_vec(v, (out_dim, in_dim), &Device::Cpu)?)
}

impl MaskedLinear {
    /// A fresh layer: every element vacant, W ~ U(-b, b) with b = sqrt(6 / (c * in)) (He for the
    /// effective fan-in of a masked row; sqrt(3 / (c * in)) when `gain_relu` is false), mu ~ N(0, score_init_std).
    /// Re-initialised vacant weights draw from sqrt(g / in) or this range (`reinit_range`).
    pub fn new(
        name: &str,
        in_dim: usize,
        out_dim: usize,
        gain_relu: bool,
        cfg: &MaskConfig,
        rng: &mut impl Rng,
    ) -> anyhow::Result<Self> {
        cfg.validate()?;
        anyhow::ensure!(in_dim > 0 && out_dim > 0, "{name}: layer shape ({out_dim}, {in_dim}) must be non-empty");
        cfg.check_selects_in(name, out_dim, in_dim)?;
        let eff_fan_in = (cfg.capacity * in_dim as f64).max(1.0);
        let gain = if gain_relu { 6.0 } else { 3.0 };
        let init_bound = (gain / eff_fan_in).sqrt() as f32;
        let full_fan_in_bound = (gain / in_dim as f64).sqrt() as f32;
        let n = out_dim * in_dim;
        let dist = Uniform::new_inclusive(-init_bound, init_bound);
        let w: Vec<f32> = (0..n).map(|_| dist.sample(rng)).collect();
        let mu = Self::draw_scores(n, cfg.score_init_std, rng);
        Ok(Self {
            name: name.to_string(),
            out_dim,
            in_dim,
            cfg: cfg.clone(),
            init_bound,
            full_fan_in_bound,
            weight: var_from(w, &[out_dim, in_dim])?,
            score_mean: var_from(mu, &[out_dim, in_dim])?,
            log_sigma: var_from(vec![(cfg.sigma_init as f32).ln()], &[1])?,
            states: vec![ElementState::Vacant; n],
            masks: BTreeMap::new(),
            biases: BTreeMap::new(),
            finish_order: Vec::new(),
            training: None,
        })
    }

    fn draw_scores(n: usize, std: f64, rng: &mut impl Rng) -> Vec<f32> {
        (0..n)
            .map(|_| {
                let e: f64 = StandardNormal.sample(rng);
                (std * e) as f32
            })
            .collect()
    }

    /// The layer's parameter name, e.g. "actor.l0".
    pub fn name(&self) -> &str {
        &self.name
    }

    /// (out, in).
    pub fn shape(&self) -> (usize, usize) {
        (self.out_dim, self.in_dim)
    }

    /// Element states, row-major.
    pub fn states(&self) -> &[ElementState] {
        &self.states
    }

    /// The base weights W, row-major (out * in).
    pub fn weight_values(&self) -> anyhow::Result<Vec<f32>> {
        var_values(&self.weight)
    }

    /// The soft-score means mu, row-major (out * in).
    pub fn score_values(&self) -> anyhow::Result<Vec<f32>> {
        var_values(&self.score_mean)
    }

    /// Scales the initial weights and the re-initialisation range by
    /// `factor`, e.g. for a policy head that starts near zero (CleanRL's
    /// actor-mean init). Only on a fresh layer: no task started or ended.
    pub fn scale_init(&mut self, factor: f32) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.masks.is_empty() && self.training.is_none(),
            "{}: the initial weights can only be scaled before the first task starts",
            self.name
        );
        anyhow::ensure!(
            factor.is_finite() && factor > 0.0,
            "{}: init scale must be finite and > 0, got {factor}",
            self.name
        );
        set_var(&self.weight, var_values(&self.weight)?.into_iter().map(|w| w * factor).collect())?;
        self.init_bound *= factor;
        self.full_fan_in_bound *= factor;
        Ok(())
    }

    /// The current soft-score sigma of the layer (exp of the trained log_sigma).
    pub fn sigma(&self) -> anyhow::Result<f32> {
        Ok(self.log_sigma()?.exp())
    }

    /// The current ln sigma of the layer (the trained variable).
    pub fn log_sigma(&self) -> anyhow::Result<f32> {
        Ok(var_values(&self.log_sigma)?[0])
    }

    /// The hard mask (out, in) of the current training iteration, if one was drawn.
    pub fn iteration_mask(&self) -> Option<&Tensor> {
        self.training.as_ref().and_then(|t| t.mask.as_ref())
    }

    /// The stored bias (out,) of a finished task.
    pub fn task_bias(&self, task: TaskId) -> Option<&[f32]> {
        self.biases.get(&task).map(Vec::as_slice)
    }

    /// The bias (out,) of the task being trained, if any.
    pub fn training_bias(&self) -> anyhow::Result<Option<Vec<f32>>> {
        self.training.as_ref().map(|t| var_values(&t.bias)).transpose()
    }

    /// The stored mask of a finished task.
    pub fn task_mask(&self, task: TaskId) -> Option<&BitMask> {
        self.masks.get(&task)
    }

    fn params(&self) -> SelectionParams {
        SelectionParams { capacity: self.cfg.capacity, vacant_share: self.cfg.vacant_share, rule: self.cfg.rule }
    }

    /// A new task's starting bias: the mean of its related tasks' biases (zero without any).
    fn related_bias(&self, related: &[TaskId]) -> anyhow::Result<Vec<f32>> {
        let mut bias = vec![0.0f32; self.out_dim];
        for r in related {
            let b = self.biases.get(r).with_context(|| format!("{}: related task {r} has not finished", self.name))?;
            bias.iter_mut().zip(b).for_each(|(acc, v)| *acc += v / related.len() as f32);
        }
        Ok(bias)
    }

    /// A new task's starting bias under `bias_start` (METHOD.md 2.4 step 6): the bias of the task
    /// that ended last (`previous`: the last of the finish order, since a repeat only continues a
    /// task; zero before any), the related tasks' mean, or zero.
    fn start_bias(&self, related: &[TaskId]) -> anyhow::Result<Vec<f32>> {
        Ok(match self.cfg.bias_start {
            BiasStart::Previous => match self.finish_order.last() {
                Some(last) => self.biases[last].clone(),
                None => vec![0.0; self.out_dim],
            },
            BiasStart::Related => self.related_bias(related)?,
            BiasStart::Zero => vec![0.0; self.out_dim],
        })
    }

    /// Starts training `task`: repeat mode if it already finished (its own bias), otherwise a
    /// new task: its bias from `bias_start`, sigma back to its initial value, and mu += delta on
    /// the elements of related tasks' masks (2.6).
    pub fn begin_task(&mut self, task: TaskId, related: &[TaskId]) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.training.is_none(),
            "{}: begin_task({task}) while task {} is still in progress",
            self.name,
            self.training.as_ref().map_or(0, |t| t.task)
        );
        let repeat = self.masks.contains_key(&task);
        let bias = match self.biases.get(&task) {
            Some(b) => b.clone(),
            None => self.start_bias(related)?,
        };
        let bias = var_from(bias, &[self.out_dim])?;
        if !repeat && self.cfg.rule == SelectionRule::Piggyback {
            self.piggyback_start_scores()?;
        } else if !repeat {
            set_var(&self.log_sigma, vec![(self.cfg.sigma_init as f32).ln()])?;
            let mut mu = var_values(&self.score_mean)?;
            let delta = (self.cfg.transfer_bonus * self.cfg.score_init_std) as f32;
            let mut bonus = vec![false; mu.len()];
            for r in related {
                let m =
                    self.masks.get(r).with_context(|| format!("{}: related task {r} has not finished", self.name))?;
                (0..mu.len()).filter(|&i| m.get(i)).for_each(|i| bonus[i] = true);
            }
            mu.iter_mut().zip(&bonus).filter(|(_, b)| **b).for_each(|(m, _)| *m += delta);
            set_var(&self.score_mean, mu)?;
        }
        self.training = Some(Training::new(task, repeat, 0, bias));
        Ok(())
    }

    fn training_ready(&self) -> anyhow::Result<&Training> {
        let t =
            self.training.as_ref().with_context(|| format!("{}: no task in progress (call begin_task)", self.name))?;
        anyhow::ensure!(t.mask.is_some(), "{}: call begin_iteration before forward", self.name);
        Ok(t)
    }

    /// The training effective weight W * M_ste (out, in) and the current bias (out,), both differentiable.
    /// The straight-through estimator (M taken as S = mu + sigma * eps) is the backward of
    /// `nn/masked_weight.rs`'s op.
    pub fn training_weight(&self) -> anyhow::Result<(Tensor, Tensor)> {
        self.effective_training_weight(true)
    }

    /// [`Self::training_weight`], differentiable only when `track` is true.
    pub(crate) fn effective_training_weight(&self, track: bool) -> anyhow::Result<(Tensor, Tensor)> {
        let t = self.training_ready()?;
        let mask = t.mask.as_ref().expect("checked by training_ready");
        let effective = masked_weight(
            self.weight.as_tensor(),
            self.score_mean.as_tensor(),
            self.log_sigma.as_tensor(),
            mask,
            t.noise.as_ref(),
            track,
        )?;
        let bias = if track { t.bias.as_tensor().clone() } else { t.bias.as_tensor().detach() };
        Ok((effective, bias))
    }

    /// Training forward with the current task's hard mask (batch, in) -> (batch, out), differentiable.
    pub fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        let (effective, bias) = self.training_weight()?;
        Ok(x.matmul(&effective.t()?)?.broadcast_add(&bias)?)
    }

    /// Effective weights W * M_t of a finished task, with exact zeros outside the mask.
    pub fn recall_weight(&self, task: TaskId) -> anyhow::Result<(Tensor, Tensor)> {
        let m =
            self.masks.get(&task).with_context(|| format!("{}: task {task} has not finished (no mask)", self.name))?;
        let w = var_values(&self.weight)?;
        let eff: Vec<f32> = w.iter().enumerate().map(|(i, &w)| if m.get(i) { w } else { 0.0 }).collect();
        let eff = Tensor::from_vec(eff, (self.out_dim, self.in_dim), &Device::Cpu)?;
        let bias = Tensor::from_slice(&self.biases[&task], self.out_dim, &Device::Cpu)?;
        Ok((eff, bias))
    }

    /// Recall of a finished task: x (W * M_t)^T + b_t, not differentiable, bit-identical forever.
    pub fn forward_task(&self, task: TaskId, x: &Tensor) -> anyhow::Result<Tensor> {
        let (eff, bias) = self.recall_weight(task)?;
        Ok(x.matmul(&eff.t()?)?.broadcast_add(&bias)?)
    }

    /// Trainable variables with their update masks: weight, score, log_sigma (named "{layer}.log_sigma"),
    /// bias (a repeat: weight and bias only).
    pub fn parameters(&self) -> Vec<Param> {
        let Some(t) = &self.training else { return Vec::new() };
        let p = |suffix: &str, var: &Var, m: Option<&Tensor>| Param {
            name: format!("{}.{suffix}", self.name),
            var: var.clone(),
            update_mask: m.cloned(),
            fixed_learning_rate: None,
        };
        let mut out = vec![p("weight", &self.weight, t.weight_update.as_ref())];
        if !t.repeat {
            // The soft-score means step at their own fixed rate where one is set (the paper's Adam
            // 1e-3; Piggyback's, Mallya et al.'s mask rate), apart from PPO's KL-adapted one.
            let fixed_learning_rate = self.cfg.score_rate();
            out.push(Param { fixed_learning_rate, ..p("score", &self.score_mean, t.score_update.as_ref()) });
            if t.iteration < self.cfg.resolved_entropy_iterations() {
                let rate = self.cfg.sigma_learning_rate;
                let fixed_learning_rate = (rate > 0.0).then_some(rate);
                out.push(Param { fixed_learning_rate, ..p("log_sigma", &self.log_sigma, None) });
            }
        }
        out.push(p("bias", &t.bias, None));
        out
    }

    /// End of task (2.4): final mask from mu, private elements, states, re-initialisation.
    pub fn end_task(&mut self, rng: &mut impl Rng) -> anyhow::Result<()> {
        let t = self.training.take().with_context(|| format!("{}: end_task without a task in progress", self.name))?;
        self.biases.insert(t.task, var_values(&t.bias)?);
        if t.repeat {
            return Ok(());
        }
        let (out_dim, in_dim, n) = (self.out_dim, self.in_dim, self.out_dim * self.in_dim);
        let mu = var_values(&self.score_mean)?;
        let selected = if self.cfg.rule.is_baseline() {
            self.baseline_final_mask()?
        } else {
            select_mask(&mu, &self.states, out_dim, in_dim, t.task, &self.params())
        };
        let mut fresh: Vec<usize> = (0..n).filter(|&i| selected[i] && self.states[i] == ElementState::Vacant).collect();
        fresh.sort_by(|&a, &b| mu[b].total_cmp(&mu[a]).then(a.cmp(&b)));
        let n_private = ((self.cfg.private_share * n as f64).round() as usize).min(fresh.len());
        for (rank, &i) in fresh.iter().enumerate() {
            let to = if rank < n_private { ElementState::Private(t.task) } else { ElementState::Occupied };
            self.states[i] = self.states[i].transition(to).with_context(|| format!("{} element {i}", self.name))?;
        }
        self.masks.insert(t.task, BitMask::from_bools(&selected));
        self.finish_order.push(t.task);
        self.reinitialise(rng)
    }

    /// METHOD.md 2.4 step 4: the weights still VACANT redrawn from `reinit_range` times
    /// `reinit_scale` (`reinit_weights`), then the soft-score means `reinit_scores` names redrawn
    /// from N(0, score_init_std). One weight is drawn per vacant element and one mean per element
    /// whatever is kept, so every reading consumes the random stream alike (`all` with `he_effective`
    /// draws exactly what the layer drew before issue 31).
    fn reinitialise(&mut self, rng: &mut impl Rng) -> anyhow::Result<()> {
        if self.cfg.reinit_weights {
            self.redraw_vacant_weights(self.cfg.reinit_range, self.cfg.reinit_scale, rng)?;
        }
        let redraw = |s: &ElementState| match self.cfg.reinit_scores {
            ScoreReinit::All => true,
            ScoreReinit::Vacant => *s == ElementState::Vacant,
            ScoreReinit::None => false,
        };
        if self.cfg.reinit_weights || self.cfg.reinit_scores != ScoreReinit::None {
            let fresh = Self::draw_scores(self.states.len(), self.cfg.score_init_std, rng);
            let mut mu = var_values(&self.score_mean)?;
            for ((m, f), s) in mu.iter_mut().zip(fresh).zip(&self.states) {
                if redraw(s) {
                    *m = f;
                }
            }
            set_var(&self.score_mean, mu)?;
        }
        Ok(())
    }

    /// Every VACANT weight redrawn uniformly from `range` times `scale` (0: zero), one draw per
    /// vacant element in row-major order; occupied and private weights are untouched, so every
    /// learned task recalls as before. The end of a task's `reinit_weights`, and a base policy's
    /// vacant weights at a run's start (`[run] base_vacant = "redrawn"`, docs/method.md).
    pub fn redraw_vacant_weights(&mut self, range: ReinitRange, scale: f64, rng: &mut impl Rng) -> anyhow::Result<()> {
        let range = match range {
            ReinitRange::Initial => self.full_fan_in_bound,
            ReinitRange::HeEffective => self.init_bound,
        };
        let bound = range * scale as f32;
        let dist = Uniform::new_inclusive(-bound, bound);
        let mut w = var_values(&self.weight)?;
        for (w, s) in w.iter_mut().zip(&self.states) {
            if *s == ElementState::Vacant {
                *w = dist.sample(rng);
            }
        }
        set_var(&self.weight, w)
    }

    /// The rule in use (for statistics).
    pub fn rule(&self) -> SelectionRule {
        self.cfg.rule
    }
}
