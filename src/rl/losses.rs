//! The pieces of the PPO loss (Schulman et al. 2017, as in rsl_rl /
//! legged_gym and CleanRL's `ppo_continuous_action.py`), each a function over
//! candle tensors so it can be tested against hand-computed values; and the
//! adaptive learning-rate rule of legged_gym.
//!
//! The policy is a diagonal Gaussian with a state-independent learned
//! log-std: `a ~ N(mean(s), diag(exp(log_std))^2)`.
//! Shapes: `B` = batch, `A` = action width.

use candle_core::{Tensor, D};

/// `0.5 * ln(2 pi)`.
const HALF_LN_2PI: f64 = 0.918_938_533_204_672_7;

/// Log-density of `actions` (B, A) under `N(mean (B, A), exp(log_std (A,)))`,
/// summed over the action dimensions: (B,).
pub fn gaussian_log_prob(actions: &Tensor, mean: &Tensor, log_std: &Tensor) -> candle_core::Result<Tensor> {
    let inv_std = log_std.neg()?.exp()?; // (A,)
    let z = actions.sub(mean)?.broadcast_mul(&inv_std)?; // (B, A)
    let per_dim = z.sqr()?.affine(-0.5, -HALF_LN_2PI)?.broadcast_sub(log_std)?; // (B, A)
    per_dim.sum(D::Minus1)
}

/// Entropy of the Gaussian policy, the same for every state:
/// `sum_a (0.5 + 0.5 ln(2 pi) + log_std_a)`, a scalar.
pub fn gaussian_entropy(log_std: &Tensor) -> candle_core::Result<Tensor> {
    log_std.affine(1.0, 0.5 + HALF_LN_2PI)?.sum_all()
}

/// PPO's clipped surrogate, as a loss to minimise (a scalar):
/// `mean(max(-A * r, -A * clip(r, 1 - eps, 1 + eps)))` with
/// `r = exp(new_log_prob - old_log_prob)`. All inputs (B,).
pub fn clipped_surrogate_loss(
    new_log_prob: &Tensor,
    old_log_prob: &Tensor,
    advantages: &Tensor,
    clip: f64,
) -> candle_core::Result<Tensor> {
    let ratio = new_log_prob.sub(old_log_prob)?.exp()?;
    let unclipped = advantages.neg()?.mul(&ratio)?;
    let clipped = advantages.neg()?.mul(&ratio.clamp(1.0 - clip, 1.0 + clip)?)?;
    unclipped.maximum(&clipped)?.mean_all()
}

/// Fraction of the batch whose ratio left `[1 - eps, 1 + eps]` (a diagnostic).
pub fn clip_fraction(new_log_prob: &Tensor, old_log_prob: &Tensor, clip: f64) -> candle_core::Result<f32> {
    let ratio = new_log_prob.sub(old_log_prob)?.exp()?;
    let outside = ratio.affine(1.0, -1.0)?.abs()?.gt(clip)?.to_dtype(candle_core::DType::F32)?;
    outside.mean_all()?.to_scalar::<f32>()
}

/// The critic's loss (a scalar), legged_gym's form without the 1/2:
/// `mean((V - R)^2)`, or with clipping
/// `mean(max((V - R)^2, (V_old + clip(V - V_old, -eps, eps) - R)^2))`.
/// All inputs (B,).
pub fn value_loss(
    values: &Tensor,
    old_values: &Tensor,
    returns: &Tensor,
    clip: Option<f64>,
) -> candle_core::Result<Tensor> {
    let unclipped = values.sub(returns)?.sqr()?;
    match clip {
        None => unclipped.mean_all(),
        Some(eps) => {
            let clipped_values = old_values.add(&values.sub(old_values)?.clamp(-eps, eps)?)?;
            let clipped = clipped_values.sub(returns)?.sqr()?;
            unclipped.maximum(&clipped)?.mean_all()
        }
    }
}

/// KL(old || new) between diagonal Gaussians, summed over actions and
/// averaged over the batch (legged_gym's adaptive-lr statistic):
/// `sum_a [ls_new - ls_old + (s_old^2 + (m_old - m_new)^2) / (2 s_new^2) - 1/2]`.
/// Means (B, A), log-stds (A,). Returns a scalar.
pub fn gaussian_kl(
    old_mean: &Tensor,
    old_log_std: &Tensor,
    new_mean: &Tensor,
    new_log_std: &Tensor,
) -> candle_core::Result<Tensor> {
    let old_var = old_log_std.affine(2.0, 0.0)?.exp()?; // (A,)
    let new_var = new_log_std.affine(2.0, 0.0)?.exp()?; // (A,)
    let mean_diff_sq = old_mean.sub(new_mean)?.sqr()?; // (B, A)
    let numerator = mean_diff_sq.broadcast_add(&old_var)?;
    let per_dim = numerator
        .broadcast_div(&new_var.affine(2.0, 0.0)?)?
        .broadcast_add(&new_log_std.sub(old_log_std)?)?
        .affine(1.0, -0.5)?; // (B, A)
    per_dim.sum(D::Minus1)?.mean_all()
}

/// legged_gym's adaptive learning rate: divide by `factor` when the KL is
/// above twice the target, multiply when below half of it, then clamp.
pub fn adapt_learning_rate(lr: f64, kl: f64, desired_kl: f64, factor: f64, min_lr: f64, max_lr: f64) -> f64 {
    let next = if kl > 2.0 * desired_kl {
        lr / factor
    } else if kl < desired_kl / 2.0 && kl > 0.0 {
        lr * factor
    } else {
        lr
    };
    next.clamp(min_lr, max_lr)
}

/// Zero-mean, unit-std advantages (std with Bessel's correction, as torch's
/// `std()`), plus 1e-8 in the denominator. Input and output (B,).
pub fn normalize_advantages(advantages: &Tensor) -> candle_core::Result<Tensor> {
    let n = advantages.dim(0)?;
    let mean = advantages.mean_all()?;
    let centred = advantages.broadcast_sub(&mean)?;
    let denom = (n.max(2) - 1) as f64;
    let std = centred.sqr()?.sum_all()?.affine(1.0 / denom, 0.0)?.sqrt()?;
    centred.broadcast_div(&std.affine(1.0, 1e-8)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    fn t(v: &[f32]) -> Tensor {
        Tensor::new(v, &Device::Cpu).unwrap()
    }
    use crate::rl::test_tensors::{close, scalar, t2};

    /// a = (1, 0), mean = (0, 0), log_std = (0, ln 2):
    /// dim 0: -0.5 * 1 - 0 - 0.9189385 = -1.4189385
    /// dim 1: -0 - ln 2 - 0.9189385 = -1.6120857
    #[test]
    fn log_prob_matches_the_gaussian_density_by_hand() {
        let lp = gaussian_log_prob(&t2(&[1.0, 0.0], 1), &t2(&[0.0, 0.0], 1), &t(&[0.0, 2f32.ln()])).unwrap();
        let got = lp.to_vec1::<f32>().unwrap();
        close(f64::from(got[0]), -1.418_938_5 - 1.612_085_7);
    }

    /// Two dims, log_std (0, 1): 2 * 1.4189385 + 1 = 3.837877.
    #[test]
    fn entropy_matches_hand_value() {
        close(scalar(&gaussian_entropy(&t(&[0.0, 1.0])).unwrap()), 3.837_877);
    }

    /// Ratios e^0.5 = 1.6487 (A = 1) and e^-0.5 = 0.6065 (A = -2), clip 0.2:
    /// sample 1: max(-1.6487, -1.2) = -1.2;  sample 2: max(1.2131, 1.6) = 1.6;
    /// mean = 0.2.
    #[test]
    fn surrogate_clips_both_ways_by_hand() {
        let loss = clipped_surrogate_loss(&t(&[0.5, -0.5]), &t(&[0.0, 0.0]), &t(&[1.0, -2.0]), 0.2).unwrap();
        close(scalar(&loss), 0.2);
        let frac = clip_fraction(&t(&[0.5, 0.1]), &t(&[0.0, 0.0]), 0.2).unwrap();
        close(f64::from(frac), 0.5);
    }

    /// V = (1.5, 0), V_old = (1, 0), R = (2, 1), eps 0.2:
    /// unclipped (0.25, 1); clipped V = (1.2, 0) -> (0.64, 1); max -> (0.64, 1); mean 0.82.
    #[test]
    fn value_loss_clipped_and_unclipped_by_hand() {
        let (v, old, r) = (t(&[1.5, 0.0]), t(&[1.0, 0.0]), t(&[2.0, 1.0]));
        close(scalar(&value_loss(&v, &old, &r, Some(0.2)).unwrap()), 0.82);
        close(scalar(&value_loss(&v, &old, &r, None).unwrap()), 0.625);
    }

    /// One dim: old N(0, 1), new N(1, 2): ln 2 + (1 + 1) / 8 - 0.5 = 0.4431472.
    /// Identical distributions give 0.
    #[test]
    fn kl_matches_closed_form_by_hand() {
        let kl = gaussian_kl(&t2(&[0.0], 1), &t(&[0.0]), &t2(&[1.0], 1), &t(&[2f32.ln()])).unwrap();
        close(scalar(&kl), 0.443_147_2);
        let same = gaussian_kl(&t2(&[0.3, -1.0], 1), &t(&[0.1, 0.2]), &t2(&[0.3, -1.0], 1), &t(&[0.1, 0.2])).unwrap();
        close(scalar(&same), 0.0);
    }

    #[test]
    fn learning_rate_adapts_to_kl_within_its_clamps() {
        close(adapt_learning_rate(1e-3, 0.05, 0.01, 1.5, 1e-5, 1e-2), 1e-3 / 1.5);
        close(adapt_learning_rate(1e-3, 0.001, 0.01, 1.5, 1e-5, 1e-2), 1.5e-3);
        close(adapt_learning_rate(1e-3, 0.01, 0.01, 1.5, 1e-5, 1e-2), 1e-3);
        close(adapt_learning_rate(1e-2, 0.0001, 0.01, 1.5, 1e-5, 1e-2), 1e-2);
        close(adapt_learning_rate(1e-5, 1.0, 0.01, 1.5, 1e-5, 1e-2), 1e-5);
    }

    /// (1, 2, 3): mean 2, sample std 1 -> (-1, 0, 1).
    #[test]
    fn advantages_normalise_to_zero_mean_unit_sample_std() {
        let out = normalize_advantages(&t(&[1.0, 2.0, 3.0])).unwrap().to_vec1::<f32>().unwrap();
        for (a, b) in out.iter().zip([-1.0, 0.0, 1.0]) {
            close(f64::from(*a), b);
        }
    }
}
