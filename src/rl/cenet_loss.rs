//! The context estimator's (CENet, DreamWaQ, Nahrendra et al. 2023) output
//! split, reparameterised latent sample and beta-VAE loss, as functions over
//! candle tensors.
//!
//! Encoder output (B, 3 + 2L): `[velocity (3) | latent mean (L) | latent logvar (L)]`.
//! Loss: `MSE(v_est, v_true) + MSE(decoder(v_est, z), o_{t+1}) + beta * KL(q(z|h) || N(0, I))`,
//! where the KL is summed over latent dims and averaged over the batch.

use candle_core::{Tensor, D};

/// The encoder's output split into its three parts, each (B, width).
#[derive(Debug, Clone)]
pub struct CenetEstimate {
    /// Estimated base linear velocity (B, 3), in the privileged obs's scaling.
    pub velocity: Tensor,
    /// Latent mean (B, L).
    pub latent_mean: Tensor,
    /// Latent log-variance (B, L), clamped for numerical safety.
    pub latent_logvar: Tensor,
}

/// Splits an encoder output (B, 3 + 2L) into velocity, latent mean and
/// clamped log-variance.
pub fn split_encoder_output(out: &Tensor, latent_dim: usize, logvar_clamp: f64) -> anyhow::Result<CenetEstimate> {
    let width = out.dim(D::Minus1)?;
    anyhow::ensure!(
        width == 3 + 2 * latent_dim,
        "CENet encoder output has width {width}, expected 3 + 2 * {latent_dim}"
    );
    Ok(CenetEstimate {
        velocity: out.narrow(D::Minus1, 0, 3)?,
        latent_mean: out.narrow(D::Minus1, 3, latent_dim)?,
        latent_logvar: out.narrow(D::Minus1, 3 + latent_dim, latent_dim)?.clamp(-logvar_clamp, logvar_clamp)?,
    })
}

/// Reparameterised sample `z = mean + exp(logvar / 2) * noise`; `noise` is
/// standard normal of the same shape (B, L), drawn by the caller from its
/// seeded stream so runs are reproducible.
pub fn reparameterize(mean: &Tensor, logvar: &Tensor, noise: &Tensor) -> candle_core::Result<Tensor> {
    mean.add(&logvar.affine(0.5, 0.0)?.exp()?.mul(noise)?)
}

/// KL(N(mean, exp(logvar)) || N(0, I)) summed over the latent and averaged
/// over the batch: `mean_b[-0.5 * sum_l (1 + logvar - mean^2 - exp(logvar))]`.
pub fn latent_kl(mean: &Tensor, logvar: &Tensor) -> candle_core::Result<Tensor> {
    let per_dim = logvar.affine(1.0, 1.0)?.sub(&mean.sqr()?)?.sub(&logvar.exp()?)?;
    per_dim.sum(D::Minus1)?.affine(-0.5, 0.0)?.mean_all()
}

/// The three terms of the CENet loss and their weighted total (scalars).
#[derive(Debug, Clone)]
pub struct CenetLoss {
    pub velocity_mse: Tensor,
    pub reconstruction_mse: Tensor,
    pub kl: Tensor,
    /// `velocity_mse + reconstruction_mse + beta * kl`.
    pub total: Tensor,
}

/// The beta-VAE loss from the estimate, its velocity target (B, 3), the
/// decoder's reconstruction and the next observation it should match (B, obs).
pub fn cenet_loss(
    estimate: &CenetEstimate,
    true_velocity: &Tensor,
    reconstruction: &Tensor,
    next_obs: &Tensor,
    beta: f64,
) -> candle_core::Result<CenetLoss> {
    let velocity_mse = estimate.velocity.sub(true_velocity)?.sqr()?.mean_all()?;
    let reconstruction_mse = reconstruction.sub(next_obs)?.sqr()?.mean_all()?;
    let kl = latent_kl(&estimate.latent_mean, &estimate.latent_logvar)?;
    let total = velocity_mse.add(&reconstruction_mse)?.add(&kl.affine(beta, 0.0)?)?;
    Ok(CenetLoss { velocity_mse, reconstruction_mse, kl, total })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rl::test_tensors::{close, scalar, t2};

    #[test]
    fn encoder_output_splits_into_velocity_mean_and_clamped_logvar() {
        // L = 1: [v0 v1 v2 | mu | logvar]
        let out = t2(&[1.0, 2.0, 3.0, 4.0, 50.0], 1);
        let est = split_encoder_output(&out, 1, 10.0).unwrap();
        assert_eq!(est.velocity.to_vec2::<f32>().unwrap(), vec![vec![1.0, 2.0, 3.0]]);
        assert_eq!(est.latent_mean.to_vec2::<f32>().unwrap(), vec![vec![4.0]]);
        assert_eq!(est.latent_logvar.to_vec2::<f32>().unwrap(), vec![vec![10.0]]);
        assert!(split_encoder_output(&out, 2, 10.0).is_err());
    }

    /// mean 1, logvar ln 4 (std 2), noise 0.5: z = 1 + 2 * 0.5 = 2.
    #[test]
    fn reparameterised_sample_by_hand() {
        let z = reparameterize(&t2(&[1.0], 1), &t2(&[4f32.ln()], 1), &t2(&[0.5], 1)).unwrap();
        close(f64::from(z.to_vec2::<f32>().unwrap()[0][0]), 2.0);
    }

    /// Two samples, L = 2.
    /// sample 1: mean (0, 0), logvar (0, 0) -> KL 0.
    /// sample 2: mean (1, 0), logvar (0, ln 2):
    ///   -0.5 * [(1 + 0 - 1 - 1) + (1 + ln2 - 0 - 2)] = -0.5 * (-1 - 0.3068528) = 0.6534264
    /// batch mean = 0.3267132.
    #[test]
    fn latent_kl_by_hand() {
        let mean = t2(&[0.0, 0.0, 1.0, 0.0], 2);
        let logvar = t2(&[0.0, 0.0, 0.0, 2f32.ln()], 2);
        close(scalar(&latent_kl(&mean, &logvar).unwrap()), 0.326_713_2);
    }

    /// One sample, L = 1: velocity (1, 0, 0) vs (0, 0, 0): MSE 1/3;
    /// reconstruction (1, 3) vs (1, 1): MSE 2; mean 1, logvar 0: KL 0.5;
    /// beta 0.5: total = 1/3 + 2 + 0.25.
    #[test]
    fn cenet_loss_terms_by_hand() {
        let est = split_encoder_output(&t2(&[1.0, 0.0, 0.0, 1.0, 0.0], 1), 1, 10.0).unwrap();
        let loss = cenet_loss(&est, &t2(&[0.0, 0.0, 0.0], 1), &t2(&[1.0, 3.0], 1), &t2(&[1.0, 1.0], 1), 0.5).unwrap();
        close(scalar(&loss.velocity_mse), 1.0 / 3.0);
        close(scalar(&loss.reconstruction_mse), 2.0);
        close(scalar(&loss.kl), 0.5);
        close(scalar(&loss.total), 1.0 / 3.0 + 2.0 + 0.25);
    }
}
