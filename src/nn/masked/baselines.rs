//! The mask baselines' rules on a [`MaskedLinear`] (METHOD.md 3), chosen by
//! `MaskConfig::rule`; the method's own rules are in `masked.rs` and
//! `iteration.rs`.
//!
//! - PackNet (Mallya & Lazebnik 2018): a task trains every vacant weight and
//!   uses every occupied one. From iteration `packnet_prune_at` (or at its
//!   end) its vacant weights are pruned by magnitude: the `packnet_keep`
//!   share with the largest |W| is kept, the others are set to 0 and stay
//!   vacant for later tasks; the rest of the task retrains only the kept ones.
//!   At its end the kept weights become occupied (frozen) and its mask is every
//!   weight occupied then, so its recall never sees a later task's weights.
//!   Pruning is idempotent (zeroed weights rank last), so it is simply applied
//!   at every iteration from `packnet_prune_at` on, and a resumed task prunes
//!   the same elements.
//! - Piggyback (Mallya et al. 2018): no weight trains. Every task learns a
//!   real-valued score per occupied weight (the frozen base), starting at
//!   `piggyback_init`; the mask is `score > piggyback_threshold`, with the
//!   straight-through gradient. Vacant weights are never used.
//!
//! Neither draws mask noise: the straight-through op gets eps = 0.

use super::{mask_tensor, set_var, var_values, MaskedLinear};
use crate::config::net::SelectionRule;
use crate::nn::state::ElementState;
use anyhow::Context;
use candle_core::{DType, Device, Tensor};

impl MaskedLinear {
    /// PackNet's pruning of the vacant weights: keeps the `packnet_keep` share with the largest
    /// |W| (ties to the lower index), zeroes the others; returns the kept elements.
    pub(super) fn packnet_prune(&mut self) -> anyhow::Result<Vec<bool>> {
        let mut w = var_values(&self.weight)?;
        let mut vacant: Vec<usize> = (0..w.len()).filter(|&i| self.states[i] == ElementState::Vacant).collect();
        let keep = (self.cfg.packnet_keep * vacant.len() as f64).round() as usize;
        vacant.sort_by(|&a, &b| w[b].abs().total_cmp(&w[a].abs()).then(a.cmp(&b)));
        let mut kept = vec![false; w.len()];
        for (rank, &i) in vacant.iter().enumerate() {
            if rank < keep {
                kept[i] = true;
            } else {
                w[i] = 0.0;
            }
        }
        set_var(&self.weight, w)?;
        Ok(kept)
    }

    /// The elements a baseline's task selects now and which of them may move: (selected,
    /// weight update, score update).
    fn baseline_masks(&mut self, iteration: usize) -> anyhow::Result<(Vec<bool>, Vec<bool>, Vec<bool>)> {
        let n = self.states.len();
        let occupied: Vec<bool> = self.states.iter().map(|s| *s == ElementState::Occupied).collect();
        Ok(match self.cfg.rule {
            SelectionRule::PackNet => {
                let fresh = match self.cfg.packnet_prune_at {
                    Some(at) if iteration >= at => self.packnet_prune()?,
                    _ => self.states.iter().map(|s| *s == ElementState::Vacant).collect(),
                };
                let selected = (0..n).map(|i| fresh[i] || occupied[i]).collect();
                (selected, fresh, vec![false; n])
            }
            SelectionRule::Piggyback => {
                let mu = var_values(&self.score_mean)?;
                let threshold = self.cfg.piggyback_threshold as f32;
                let selected = (0..n).map(|i| occupied[i] && mu[i] > threshold).collect();
                (selected, vec![false; n], occupied)
            }
            other => anyhow::bail!("{}: {other:?} is not a baseline's rule", self.name),
        })
    }

    /// A baseline's iteration: its masks (see the module header), no noise, no sigma schedule.
    pub(super) fn begin_baseline_iteration(&mut self, iteration: usize) -> anyhow::Result<()> {
        let (out_dim, in_dim) = (self.out_dim, self.in_dim);
        let (selected, weight_update, score_update) = self.baseline_masks(iteration)?;
        let t = self.training.as_mut().with_context(|| format!("{}: begin_iteration without begin_task", self.name))?;
        t.iteration = iteration;
        t.mask = Some(mask_tensor(selected.iter().copied(), out_dim, in_dim)?);
        t.noise = Some(Tensor::zeros((out_dim, in_dim), DType::F32, &Device::Cpu)?);
        t.weight_update = Some(mask_tensor(weight_update.into_iter(), out_dim, in_dim)?);
        t.score_update = Some(mask_tensor(score_update.into_iter(), out_dim, in_dim)?);
        t.previous_selection = Some(selected);
        Ok(())
    }

    /// A baseline task's final mask at its end (PackNet: pruned now if not yet; Piggyback: its
    /// thresholded scores).
    pub(super) fn baseline_final_mask(&mut self) -> anyhow::Result<Vec<bool>> {
        let occupied: Vec<bool> = self.states.iter().map(|s| *s == ElementState::Occupied).collect();
        Ok(match self.cfg.rule {
            SelectionRule::PackNet => {
                let kept = self.packnet_prune()?;
                kept.iter().zip(&occupied).map(|(k, o)| *k || *o).collect()
            }
            _ => {
                let mu = var_values(&self.score_mean)?;
                let threshold = self.cfg.piggyback_threshold as f32;
                occupied.iter().zip(&mu).map(|(o, m)| *o && *m > threshold).collect()
            }
        })
    }

    /// Piggyback's fresh scores for a new task: `piggyback_init` everywhere.
    pub(super) fn piggyback_start_scores(&mut self) -> anyhow::Result<()> {
        set_var(&self.score_mean, vec![self.cfg.piggyback_init as f32; self.out_dim * self.in_dim])
    }
}
