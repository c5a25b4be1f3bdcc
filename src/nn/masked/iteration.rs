//! The per-iteration part of a [`MaskedLinear`]'s life cycle (METHOD.md 2.1,
//! 2.3): draw S = mu + sigma * eps (eps scaled per row by the score gap at the
//! cut under `sigma_scale = "score_gap"`, `score_gap.rs`), choose the hard mask,
//! set the update masks, decay sigma after E iterations, and measure the mask churn.

use super::score_gap::score_gaps;
use super::{mask_tensor, set_var, var_values, MaskedLinear};
use crate::config::net::SigmaScale;
use crate::nn::select::select_mask;
use crate::nn::state::ElementState;
use anyhow::Context;
use candle_core::{DType, Device, Tensor};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Fraction of the elements selected in `now` that were not selected in `before` (0 when none is selected).
fn churn(before: &[bool], now: &[bool]) -> f64 {
    let selected = now.iter().filter(|s| **s).count();
    let entered = now.iter().zip(before).filter(|(n, b)| **n && !**b).count();
    if selected == 0 {
        0.0
    } else {
        entered as f64 / selected as f64
    }
}

impl MaskedLinear {
    /// Once per training iteration: draw S = mu + sigma * eps, choose the hard mask, set the update masks.
    /// After E iterations sigma decays (x decay, floor); it is always kept in [floor, max].
    /// Both are done on log_sigma: + ln(decay), clamped to [ln floor, ln max].
    pub fn begin_iteration(&mut self, iteration: usize, rng: &mut impl Rng) -> anyhow::Result<()> {
        let noise = self.draw_iteration_noise(rng)?;
        self.begin_iteration_with_noise(iteration, noise)
    }

    /// The standard normal eps (out * in) of this iteration's S = mu + sigma * eps, from `rng`;
    /// None while fine-tuning a repeat (its mask is fixed). The only part of
    /// [`Self::begin_iteration`] that reads the random stream, so layers can draw in order
    /// and then choose their masks in parallel.
    pub(crate) fn draw_iteration_noise(&self, rng: &mut impl Rng) -> anyhow::Result<Option<Vec<f32>>> {
        let t = self.training.as_ref().with_context(|| format!("{}: begin_iteration without begin_task", self.name))?;
        Ok((!t.repeat).then(|| (0..self.out_dim * self.in_dim).map(|_| StandardNormal.sample(rng)).collect()))
    }

    /// [`Self::begin_iteration`] with the noise from [`Self::draw_iteration_noise`].
    pub(crate) fn begin_iteration_with_noise(
        &mut self,
        iteration: usize,
        noise: Option<Vec<f32>>,
    ) -> anyhow::Result<()> {
        let (out_dim, in_dim, n) = (self.out_dim, self.in_dim, self.out_dim * self.in_dim);
        let params = self.params();
        let t = self.training.as_mut().with_context(|| format!("{}: begin_iteration without begin_task", self.name))?;
        t.iteration = iteration;
        if t.repeat {
            let m = &self.masks[&t.task];
            t.mask = Some(mask_tensor((0..n).map(|i| m.get(i)), out_dim, in_dim)?);
            let own = ElementState::Private(t.task);
            t.weight_update = Some(mask_tensor(self.states.iter().map(|s| *s == own), out_dim, in_dim)?);
            t.score_update = Some(Tensor::zeros((out_dim, in_dim), DType::F32, &Device::Cpu)?);
            t.noise = None;
            return Ok(());
        }
        if self.cfg.rule.is_baseline() {
            return self.begin_baseline_iteration(iteration);
        }
        let mut log_sigma = var_values(&self.log_sigma)?[0];
        if iteration >= self.cfg.resolved_entropy_iterations() {
            log_sigma += (self.cfg.sigma_decay as f32).ln();
        }
        log_sigma = log_sigma.clamp((self.cfg.sigma_floor as f32).ln(), (self.cfg.sigma_max as f32).ln());
        set_var(&self.log_sigma, vec![log_sigma])?;
        let sigma = log_sigma.exp();
        let mu = var_values(&self.score_mean)?;
        let mut eps = noise.with_context(|| format!("{}: no noise drawn for the iteration", self.name))?;
        anyhow::ensure!(eps.len() == n, "{}: {} noise values for {n} elements", self.name, eps.len());
        // In score-gap units each row's noise is eps * g_row: the stored noise is the scaled
        // one, so the straight-through gradient of ln sigma (sigma * sum dL/dM * noise) stays exact.
        t.score_gap = match self.cfg.sigma_scale {
            SigmaScale::Absolute => None,
            SigmaScale::ScoreGap => {
                let gaps = score_gaps(&mu, &self.states, out_dim, in_dim, t.task, &params);
                eps.chunks_mut(in_dim).zip(&gaps).for_each(|(row, g)| row.iter_mut().for_each(|e| *e *= g));
                Some(gaps.iter().map(|g| f64::from(*g)).sum::<f64>() / out_dim as f64)
            }
        };
        let sample: Vec<f32> = mu.iter().zip(&eps).map(|(m, e)| m + sigma * e).collect();
        let selected = select_mask(&sample, &self.states, out_dim, in_dim, t.task, &params);
        t.mask_churn = t.previous_selection.as_ref().map(|previous| churn(previous, &selected));
        t.previous_selection = Some(selected.clone());
        t.mask = Some(mask_tensor(selected.iter().copied(), out_dim, in_dim)?);
        t.noise = Some(Tensor::from_vec(eps, (out_dim, in_dim), &Device::Cpu)?);
        let vacant = self.states.iter().map(|s| *s == ElementState::Vacant);
        t.weight_update = Some(mask_tensor(selected.iter().zip(vacant).map(|(s, v)| *s && v), out_dim, in_dim)?);
        let occupied_too = self.cfg.score_grad_occupied;
        let scores_move = |s: &ElementState| s.selectable_by(t.task) && (occupied_too || *s == ElementState::Vacant);
        t.score_update = Some(mask_tensor(self.states.iter().map(scores_move), out_dim, in_dim)?);
        Ok(())
    }

    /// The share of this iteration's hard mask that the previous iteration had not selected
    /// (None before a task's second iteration, and while fine-tuning, whose mask is fixed).
    pub fn mask_churn(&self) -> Option<f64> {
        self.training.as_ref().and_then(|t| t.mask_churn)
    }

    /// The previous iteration's hard mask (the reference of the churn), while a task trains.
    pub fn previous_selection(&self) -> Option<&[bool]> {
        self.training.as_ref().and_then(|t| t.previous_selection.as_deref())
    }

    /// Restores [`Self::previous_selection`] (from a training checkpoint): out * in flags.
    pub fn set_previous_selection(&mut self, selected: Vec<bool>) -> anyhow::Result<()> {
        let n = self.out_dim * self.in_dim;
        anyhow::ensure!(
            selected.len() == n,
            "{}: a previous selection of {} flags for {n} elements",
            self.name,
            selected.len()
        );
        let t = self.training.as_mut().with_context(|| format!("{}: no task in training", self.name))?;
        t.previous_selection = Some(selected);
        Ok(())
    }

    /// The iteration's sigma (in `sigma_scale` units), the rows' mean score gap at the cut
    /// (score units; None in absolute units) and the mask churn; None outside a new task's
    /// training (a repeat's mask is fixed) and for the mask baselines.
    pub fn iteration_stats(&self) -> anyhow::Result<Option<LayerIteration>> {
        match &self.training {
            Some(t) if !t.repeat && !self.cfg.rule.is_baseline() && t.mask.is_some() => Ok(Some(LayerIteration {
                sigma: f64::from(self.sigma()?),
                score_gap: t.score_gap,
                mask_churn: t.mask_churn,
            })),
            _ => Ok(None),
        }
    }
}

/// One layer's soft-score statistics of an iteration (see [`MaskedLinear::iteration_stats`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerIteration {
    /// sigma, in the layer's `sigma_scale` units.
    pub sigma: f64,
    /// The rows' mean score gap at the top-k cut (the unit of sigma under `score_gap`).
    pub score_gap: Option<f64>,
    /// The share of the hard mask the previous iteration had not selected.
    pub mask_churn: Option<f64>,
}
