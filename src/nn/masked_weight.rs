//! A masked layer's training effective weight as one candle op (CPU, f32),
//! with the straight-through estimator of METHOD.md 2.1 as its backward.
//!
//! Inputs: the base weight W (out, in), the soft-score means mu (out, in)
//! and log sigma (1,); held by the op: this iteration's hard mask M
//! (out, in) of 0/1 and the noise eps (out, in) it was drawn with
//! (S = mu + sigma * eps). Output: W * M (out, in).
//!
//! Backward, for the upstream gradient g (out, in):
//! - dW = g * M (only selected elements receive a gradient);
//! - dmu = g * W (the straight-through estimator: M is taken as S);
//! - d log sigma = sigma * sum(g * W * eps), summed in fixed blocks in a
//!   fixed order (f64), so it does not depend on the thread count.
//!
//! Without noise (a repeat of a learned task, whose mask is fixed) only W
//! receives a gradient. This is exactly what the chain of stock candle ops
//! `W * (M + S - detach(S))` computes (`forward_matches_the_stock_ops...`
//! below), in one pass each way instead of about five element-wise kernels
//! and their gradient buffers per layer.

use super::activation::{contiguous_f32, with_f32_slice};
use super::wide::wide;
use candle_core::{CpuStorage, CustomOp3, Layout, Shape, Tensor};
use rayon::prelude::*;

/// Elements per rayon task (and per partial sum of d log sigma).
const CHUNK: usize = 1 << 14;

/// The op; holds the iteration's mask and noise.
struct MaskedWeight {
    mask: Tensor,
    noise: Option<Tensor>,
}

impl CustomOp3 for MaskedWeight {
    fn name(&self) -> &'static str {
        "masked-weight"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        _s2: &CpuStorage,
        _l2: &Layout,
        _s3: &CpuStorage,
        _l3: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let w = contiguous_f32(s1, l1, self.name())?;
        let out = with_f32_slice(&self.mask, "mask", |m| {
            let mut out = vec![0f32; w.len()];
            out.par_chunks_mut(CHUNK)
                .zip(w.par_chunks(CHUNK).zip(m.par_chunks(CHUNK)))
                .for_each(|(o, (w, m))| wide(|| o.iter_mut().zip(w).zip(m).for_each(|((o, w), m)| *o = w * m)));
            out
        })?;
        Ok((CpuStorage::F32(out), l1.shape().clone()))
    }

    fn bwd(
        &self,
        weight: &Tensor,
        _score_mean: &Tensor,
        log_sigma: &Tensor,
        _res: &Tensor,
        grad_res: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>, Option<Tensor>)> {
        let g = grad_res.contiguous()?;
        let shape = weight.shape().clone();
        let grad_weight = with_f32_slice(&g, "gradient", |g| {
            with_f32_slice(&self.mask, "mask", |m| {
                let mut out = vec![0f32; g.len()];
                out.par_chunks_mut(CHUNK)
                    .zip(g.par_chunks(CHUNK).zip(m.par_chunks(CHUNK)))
                    .for_each(|(o, (g, m))| wide(|| o.iter_mut().zip(g).zip(m).for_each(|((o, g), m)| *o = g * m)));
                out
            })
        })??;
        let grad_weight = Tensor::from_vec(grad_weight, shape.clone(), weight.device())?;
        let Some(noise) = &self.noise else { return Ok((Some(grad_weight), None, None)) };
        let w = weight.contiguous()?;
        let (grad_mu, noise_sum) = with_f32_slice(&g, "gradient", |g| {
            with_f32_slice(&w, "weight", |w| {
                with_f32_slice(noise, "noise", |eps| {
                    let mut out = vec![0f32; g.len()];
                    let partial: Vec<f64> = out
                        .par_chunks_mut(CHUNK)
                        .zip(g.par_chunks(CHUNK).zip(w.par_chunks(CHUNK)).zip(eps.par_chunks(CHUNK)))
                        .map(|(o, ((g, w), e))| {
                            wide(|| {
                                let mut sum = 0f64;
                                for (((o, g), w), e) in o.iter_mut().zip(g).zip(w).zip(e) {
                                    *o = g * w;
                                    sum += f64::from(*o * e);
                                }
                                sum
                            })
                        })
                        .collect();
                    (out, partial.iter().sum::<f64>())
                })
            })
        })???;
        let sigma = log_sigma.exp()?;
        let grad_log_sigma = sigma.affine(noise_sum, 0.0)?;
        Ok((Some(grad_weight), Some(Tensor::from_vec(grad_mu, shape, weight.device())?), Some(grad_log_sigma)))
    }
}

/// W * M (out, in), differentiable in W, mu and log sigma (straight-through,
/// see the module header) when `track` is true; `noise` None: in W only.
pub fn masked_weight(
    weight: &Tensor,
    score_mean: &Tensor,
    log_sigma: &Tensor,
    mask: &Tensor,
    noise: Option<&Tensor>,
    track: bool,
) -> candle_core::Result<Tensor> {
    if mask.shape() != weight.shape() || noise.is_some_and(|n| n.shape() != weight.shape()) {
        candle_core::bail!("masked-weight: mask and noise must have the weight's shape {:?}", weight.shape());
    }
    let op = MaskedWeight { mask: mask.contiguous()?, noise: noise.map(Tensor::contiguous).transpose()? };
    let weight = weight.contiguous()?;
    if track {
        weight.apply_op3(score_mean, log_sigma, op)
    } else {
        weight.apply_op3_no_bwd(score_mean, log_sigma, &op)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Var};

    fn bits(t: &Tensor) -> Vec<u32> {
        t.flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn forward_matches_the_stock_ops_bit_for_bit_and_gradients_agree() {
        let dev = Device::Cpu;
        let (out, inp) = (37, 29);
        let weight = Var::from_tensor(&Tensor::randn(0f32, 1.0, (out, inp), &dev).unwrap()).unwrap();
        let mu = Var::from_tensor(&Tensor::randn(0f32, 0.3, (out, inp), &dev).unwrap()).unwrap();
        let log_sigma = Var::from_slice(&[0.05f32.ln()], 1, &dev).unwrap();
        let eps = Tensor::randn(0f32, 1.0, (out, inp), &dev).unwrap();
        let mask = Tensor::randn(0f32, 1.0, (out, inp), &dev)
            .unwrap()
            .gt(0.0)
            .unwrap()
            .to_dtype(candle_core::DType::F32)
            .unwrap();
        let upstream = Tensor::randn(0f32, 1.0, (out, inp), &dev).unwrap();

        let fused =
            masked_weight(weight.as_tensor(), mu.as_tensor(), log_sigma.as_tensor(), &mask, Some(&eps), true).unwrap();
        let sample = mu.as_tensor().add(&eps.broadcast_mul(&log_sigma.as_tensor().exp().unwrap()).unwrap()).unwrap();
        let stock = weight.as_tensor().mul(&mask.add(&sample.sub(&sample.detach()).unwrap()).unwrap()).unwrap();
        assert_eq!(bits(&fused), bits(&stock), "forward values differ");

        let gf = fused.mul(&upstream).unwrap().sum_all().unwrap().backward().unwrap();
        let gs = stock.mul(&upstream).unwrap().sum_all().unwrap().backward().unwrap();
        for (var, name) in [(&weight, "weight"), (&mu, "score mean")] {
            let (a, b) = (gf.get(var.as_tensor()).unwrap(), gs.get(var.as_tensor()).unwrap());
            assert_eq!(bits(a), bits(b), "{name} gradient differs");
        }
        let a = gf.get(log_sigma.as_tensor()).unwrap().to_vec1::<f32>().unwrap()[0];
        let b = gs.get(log_sigma.as_tensor()).unwrap().to_vec1::<f32>().unwrap()[0];
        // A sum of out * in terms taken in another order: the tolerance scales with the terms'
        // absolute sum, not with the result (which cancellation can bring near 0 for random inputs).
        let terms = weight.as_tensor().mul(&upstream).unwrap().mul(&eps).unwrap().abs().unwrap();
        let scale = terms.sum_all().unwrap().to_scalar::<f32>().unwrap() * 0.05;
        assert!((a - b).abs() <= 1e-5 * scale, "log sigma gradient {a} vs {b} (terms' absolute sum {scale})");
        assert!(a != 0.0, "log sigma received no gradient");
    }

    #[test]
    fn without_noise_only_the_weight_gets_a_gradient() {
        let dev = Device::Cpu;
        let weight = Var::from_tensor(&Tensor::randn(0f32, 1.0, (4, 3), &dev).unwrap()).unwrap();
        let mu = Var::from_tensor(&Tensor::zeros((4, 3), candle_core::DType::F32, &dev).unwrap()).unwrap();
        let log_sigma = Var::from_slice(&[0f32], 1, &dev).unwrap();
        let mask = Tensor::from_vec((0..12).map(|i| (i % 2) as f32).collect(), (4, 3), &dev).unwrap();
        let y = masked_weight(weight.as_tensor(), mu.as_tensor(), log_sigma.as_tensor(), &mask, None, true).unwrap();
        let grads = y.sum_all().unwrap().backward().unwrap();
        assert_eq!(bits(grads.get(weight.as_tensor()).unwrap()), bits(&mask), "dW must be the mask");
        assert!(grads.get(mu.as_tensor()).is_none() && grads.get(log_sigma.as_tensor()).is_none());
    }
}
