//! Plasticity diagnostics (issue 31): how much of each network still responds
//! and how much of it the task may still change, measured once per training
//! iteration on the rollout it just collected, as `plasticity/*` metrics:
//!
//! - `plasticity/dormant/NET`: the share of NET's hidden units that are dormant
//!   (ReDo, Sokar et al. 2023): unit i of a hidden layer is dormant when its mean
//!   |activation| over the sample, s_i, is at most 0.1 of the layer's mean s
//!   (all of a layer's units are, when that mean is 0). Over all hidden units of NET.
//!   With ELU (the default) a unit saturated at -1 has |h| = 1 and counts as
//!   alive, though it passes almost no gradient: the measure is ReLU's.
//! - `plasticity/effective_rank/NET`: the effective rank of NET's last hidden
//!   layer's features F (rows, d) (Roy & Vetterli 2007, as in Dohare et al. 2024's
//!   study of plasticity loss): exp of the entropy of the normalised singular values
//!   p_k = sigma_k / sum sigma, between 1 (rank-one features) and d (d orthogonal
//!   directions of equal weight); 0 for all-zero features, NaN (left out of the
//!   curves) for non-finite ones. Singular values below 1e-5 of the largest are
//!   taken as 0 (round-off); they are the square roots of the eigenvalues of
//!   F^T F (d x d, f64).
//! - `plasticity/selected_abs_w/LAYER`, `plasticity/trainable_share/LAYER`: see
//!   [`crate::nn::SelectedWeights`].
//!
//! The sample: at most [`MAX_ROWS`] rows of the rollout, evenly spaced (row
//! floor(i N / MAX_ROWS)), through one extra forward with the weights the
//! rollout acted with (the iteration's masks); the inputs are the rollout's own
//! (normalised observations, privileged observations, histories, and the CENet
//! context the actor saw, which is also the decoder's input). Nothing here reads
//! a random stream or changes a network: the training numbers are those without it.

use super::agent::{matrix, Agent};
use super::metrics::{names, Metrics};
use super::rollout::RolloutBuffer;
use crate::nn::{FrozenWeights, Network};
use candle_core::{DType, Device, Tensor};
use rayon::prelude::*;

/// The most rollout rows the diagnostics run on.
pub const MAX_ROWS: usize = 256;
/// A unit whose mean |activation| is at most this share of its layer's mean is dormant (ReDo's tau).
pub const DORMANT_THRESHOLD: f64 = 0.1;
/// Singular values below this share of the largest are round-off, not directions.
const RANK_TOLERANCE: f64 = 1e-5;

/// The dormant units of one layer's outputs h (rows, width), row-major.
pub fn dormant_units(h: &[f32], width: usize) -> usize {
    let rows = h.len() / width.max(1);
    if rows == 0 || width == 0 {
        return 0;
    }
    let mut score = vec![0.0f64; width];
    for row in h.chunks_exact(width) {
        score.iter_mut().zip(row).for_each(|(s, v)| *s += f64::from(v.abs()));
    }
    score.iter_mut().for_each(|s| *s /= rows as f64);
    let mean = score.iter().sum::<f64>() / width as f64;
    score.iter().filter(|&&s| s <= DORMANT_THRESHOLD * mean).count()
}

/// The share of dormant units over every layer of `layers`, each (outputs (rows, width), width).
pub fn dormant_fraction(layers: &[(&[f32], usize)]) -> f64 {
    let units: usize = layers.iter().map(|(_, w)| w).sum();
    let dormant: usize = layers.iter().map(|(h, w)| dormant_units(h, *w)).sum();
    dormant as f64 / units.max(1) as f64
}

/// The effective rank (Roy & Vetterli; see the module doc) of features (rows, width), row-major.
pub fn effective_rank(features: &[f32], width: usize) -> anyhow::Result<f64> {
    let rows = features.len() / width.max(1);
    if rows == 0 || width == 0 {
        return Ok(0.0);
    }
    // A diverged network's features have no spectrum (and the eigen solver would not converge).
    if !features.iter().all(|v| v.is_finite()) {
        return Ok(f64::NAN);
    }
    let f = Tensor::from_slice(&features[..rows * width], (rows, width), &Device::Cpu)?.to_dtype(DType::F64)?;
    let gram = f.t()?.matmul(&f)?.flatten_all()?.to_vec1::<f64>()?; // (width, width)
    let eigen = nalgebra::DMatrix::from_row_slice(width, width, &gram).symmetric_eigenvalues();
    let sigma: Vec<f64> = eigen.iter().map(|l| l.max(0.0).sqrt()).collect();
    let largest = sigma.iter().copied().fold(0.0, f64::max);
    if largest <= 0.0 {
        return Ok(0.0);
    }
    let kept: Vec<f64> = sigma.into_iter().filter(|s| *s > RANK_TOLERANCE * largest).collect();
    let total: f64 = kept.iter().sum();
    let entropy: f64 = kept.iter().map(|s| s / total).map(|p| -p * p.ln()).sum();
    Ok(entropy.exp())
}

/// At most `max_rows` rows of `data` (rows of `width`), evenly spaced: row floor(i N / max_rows).
pub fn subsample_rows(data: &[f32], width: usize, max_rows: usize) -> Vec<f32> {
    let rows = data.len() / width.max(1);
    if rows <= max_rows {
        return data[..rows * width].to_vec();
    }
    (0..max_rows).flat_map(|i| &data[i * rows / max_rows * width..][..width]).copied().collect()
}

/// One network's diagnostics on inputs x (batch, in) with `weights` (from its
/// `frozen_weights`): `plasticity/dormant/NET`, `plasticity/effective_rank/NET`, and per
/// layer `plasticity/selected_abs_w/LAYER` and (masked layers) `plasticity/trainable_share/LAYER`.
pub fn network_plasticity(net: &Network, weights: &FrozenWeights, x: &Tensor) -> anyhow::Result<Metrics> {
    let mut m = Metrics::new();
    let hidden = net.hidden_outputs(weights, x)?;
    let widths = &net.sizes()[1..net.sizes().len() - 1];
    let layers: Vec<(&[f32], usize)> = hidden.iter().map(Vec::as_slice).zip(widths.iter().copied()).collect();
    let name = net.name();
    m.insert(format!("{}/{name}", names::DORMANT), dormant_fraction(&layers));
    if let Some((last, width)) = layers.last() {
        m.insert(format!("{}/{name}", names::EFFECTIVE_RANK), effective_rank(last, *width)?);
    }
    for (layer, s) in net.selected_weights()? {
        m.insert(format!("{}/{layer}", names::SELECTED_ABS_W), s.mean_abs);
        if let Some(share) = s.trainable_share {
            m.insert(format!("{}/{layer}", names::TRAINABLE_SHARE), share);
        }
    }
    Ok(m)
}

impl Agent {
    /// Every network's diagnostics (module doc) on the sample of `rollout`, with the weights
    /// it acted with: actor, critic, and with the CENet its encoder and decoder.
    pub(crate) fn plasticity_metrics(&self, rollout: &RolloutBuffer) -> anyhow::Result<Metrics> {
        let (d, filled) = (rollout.dims, rollout.len * rollout.num_envs);
        let sample = |data: &[f32], width: usize| -> anyhow::Result<Tensor> {
            Ok(matrix(&subsample_rows(&data[..filled * width], width, MAX_ROWS), width)?)
        };
        if filled == 0 {
            return Ok(Metrics::new());
        }
        let obs = sample(&rollout.obs, d.obs)?;
        let mut inputs: Vec<(&Network, Tensor)> =
            vec![(&self.critic, sample(&rollout.privileged_obs, d.privileged_obs)?)];
        if self.use_cenet {
            let context = sample(&rollout.context, d.context)?;
            inputs.push((&self.actor, self.actor_input(&obs, &context)?));
            inputs.push((&self.encoder, sample(&rollout.obs_history, d.obs_history)?));
            inputs.push((&self.decoder, context));
        } else {
            inputs.push((&self.actor, obs));
        }
        let task = self.recall.then_some(self.task);
        // The networks on both cores (each one's figures depend on it alone).
        let per_network: Vec<anyhow::Result<Metrics>> =
            inputs.into_par_iter().map(|(net, x)| network_plasticity(net, &net.frozen_weights(task)?, &x)).collect();
        let mut m = Metrics::new();
        for figures in per_network {
            m.extend(figures?);
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn all_dead_units_are_dormant_and_all_equally_alive_ones_are_not() {
        let dead = vec![0.0f32; 6 * 4];
        assert_eq!(dormant_fraction(&[(&dead, 4)]), 1.0, "a layer of zeros: every unit dormant");
        let alive: Vec<f32> = (0..6 * 4).map(|i| if i % 2 == 0 { 0.7 } else { -0.7 }).collect();
        assert_eq!(dormant_fraction(&[(&alive, 4)]), 0.0, "equal |activation| everywhere: none dormant");
    }

    #[test]
    fn a_unit_at_or_below_a_tenth_of_its_layers_mean_is_dormant() {
        // Layer 1, 4 units over 2 rows: mean |h| per unit 1, 1, 1.5, 0.05; layer mean 0.8875,
        // cut 0.08875: one dormant. Layer 2, 2 units: 2 and 0.1 (cut 0.105): one dormant.
        let first = [1.0f32, -1.0, 1.0, 0.1, -1.0, 1.0, 2.0, 0.0];
        let second = [2.0f32, 0.1, -2.0, -0.1];
        assert_eq!(dormant_units(&first, 4), 1);
        assert_eq!(dormant_units(&second, 2), 1);
        assert_eq!(dormant_fraction(&[(&first, 4), (&second, 2)]), 2.0 / 6.0);
    }

    #[test]
    fn rank_one_features_have_effective_rank_one_and_orthogonal_ones_full_rank() {
        // F = u v^T (16 x 8).
        let (u, v): (Vec<f32>, Vec<f32>) =
            ((0..16).map(|i| 0.5 + i as f32).collect(), (0..8).map(|j| 1.0 - 0.3 * j as f32).collect());
        let rank_one: Vec<f32> = u.iter().flat_map(|a| v.iter().map(move |b| a * b)).collect();
        let r = effective_rank(&rank_one, 8).unwrap();
        assert!(close(r, 1.0), "rank one: {r}");
        // The identity (8 x 8), and 3 times it stacked (24 x 8): 8 equal singular values.
        let identity: Vec<f32> = (0..64).map(|i| if i % 9 == 0 { 1.0 } else { 0.0 }).collect();
        assert!(close(effective_rank(&identity, 8).unwrap(), 8.0));
        assert!(close(effective_rank(&identity.repeat(3), 8).unwrap(), 8.0));
        assert_eq!(effective_rank(&[0.0; 32], 8).unwrap(), 0.0, "no direction at all");
        assert!(effective_rank(&[1.0, f32::NAN, 0.0, 1.0], 2).unwrap().is_nan(), "diverged: no figure");
    }

    #[test]
    fn the_effective_rank_is_the_exponential_of_the_singular_values_entropy() {
        // Singular values 3 and 1: p = (0.75, 0.25).
        let f = [3.0f32, 0.0, 0.0, 0.0, 1.0, 0.0];
        let want = (-(0.75f64 * 0.75f64.ln() + 0.25 * 0.25f64.ln())).exp();
        let got = effective_rank(&f, 3).unwrap();
        assert!(close(got, want), "{got} vs {want}");
    }

    #[test]
    fn the_sample_takes_evenly_spaced_rows_and_small_rollouts_whole() {
        let data: Vec<f32> = (0..10 * 2).map(|i| i as f32).collect();
        assert_eq!(subsample_rows(&data, 2, 16), data);
        // Rows 0, 2, 5, 7 of 10 (floor(i * 10 / 4)).
        assert_eq!(subsample_rows(&data, 2, 4), vec![0.0, 1.0, 4.0, 5.0, 10.0, 11.0, 14.0, 15.0]);
    }
}
