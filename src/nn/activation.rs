//! Activations as fused candle custom ops (CPU, f32, rayon-parallel over
//! chunks). candle's stock ELU is a chain of element-wise kernels and made a
//! training step several times slower than PyTorch; here forward is one
//! pass and backward is one pass over (result, upstream gradient):
//!
//! ELU (alpha = 1): y = x if x > 0 else exp(x) - 1;  dy/dx = 1 if y > 0 else y + 1.

use crate::config::net::Activation;
use candle_core::{CpuStorage, CustomOp1, CustomOp2, Layout, Shape, Tensor};
use rayon::prelude::*;

/// Elements per rayon task: large enough that scheduling is negligible.
const CHUNK: usize = 1 << 14;

pub(super) fn contiguous_f32<'a>(s: &'a CpuStorage, l: &Layout, op: &str) -> candle_core::Result<&'a [f32]> {
    let data = s.as_slice::<f32>()?;
    match l.contiguous_offsets() {
        Some((a, b)) => Ok(&data[a..b]),
        None => candle_core::bail!("{op}: expects a contiguous f32 tensor"),
    }
}

/// Runs `f` on the contiguous f32 contents of a CPU tensor, without copying them.
pub(super) fn with_f32_slice<R>(t: &Tensor, what: &str, f: impl FnOnce(&[f32]) -> R) -> candle_core::Result<R> {
    let (storage, layout) = t.storage_and_layout();
    match &*storage {
        candle_core::Storage::Cpu(cpu) => Ok(f(contiguous_f32(cpu, layout, what)?)),
        _ => candle_core::bail!("{what}: expects a tensor on the CPU"),
    }
}

struct EluForward;

impl CustomOp1 for EluForward {
    fn name(&self) -> &'static str {
        "fused-elu"
    }

    fn cpu_fwd(&self, s: &CpuStorage, l: &Layout) -> candle_core::Result<(CpuStorage, Shape)> {
        let x = contiguous_f32(s, l, self.name())?;
        let mut y = vec![0f32; x.len()];
        y.par_chunks_mut(CHUNK).zip(x.par_chunks(CHUNK)).for_each(|(y, x)| {
            for (y, &x) in y.iter_mut().zip(x) {
                *y = super::fused::elu(x);
            }
        });
        Ok((CpuStorage::F32(y), l.shape().clone()))
    }

    fn bwd(&self, _arg: &Tensor, res: &Tensor, grad_res: &Tensor) -> candle_core::Result<Option<Tensor>> {
        Ok(Some(res.contiguous()?.apply_op2_no_bwd(&grad_res.contiguous()?, &EluBackward)?))
    }
}

struct EluBackward;

impl CustomOp2 for EluBackward {
    fn name(&self) -> &'static str {
        "fused-elu-backward"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let y = contiguous_f32(s1, l1, self.name())?;
        let g = contiguous_f32(s2, l2, self.name())?;
        if y.len() != g.len() {
            candle_core::bail!("{}: result and gradient sizes differ", self.name());
        }
        let mut dx = vec![0f32; y.len()];
        dx.par_chunks_mut(CHUNK).zip(y.par_chunks(CHUNK).zip(g.par_chunks(CHUNK))).for_each(|(dx, (y, g))| {
            for ((dx, &y), &g) in dx.iter_mut().zip(y).zip(g) {
                *dx = if y > 0.0 { g } else { g * (y + 1.0) };
            }
        });
        Ok((CpuStorage::F32(dx), l1.shape().clone()))
    }
}

/// Applies `activation` to `x` (differentiable).
pub fn activate(activation: Activation, x: &Tensor) -> candle_core::Result<Tensor> {
    match activation {
        Activation::Elu => x.contiguous()?.apply_op1(EluForward),
        Activation::Relu => x.relu(),
        Activation::Tanh => x.tanh(),
        Activation::Identity => Ok(x.clone()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Var};

    #[test]
    fn fused_elu_matches_the_formula_and_its_gradient() {
        let xs = [-3.0f32, -0.5, -1e-4, 0.0, 1e-4, 0.7, 2.0];
        let x = Var::from_slice(&xs, xs.len(), &Device::Cpu).unwrap();
        let y = activate(Activation::Elu, x.as_tensor()).unwrap();
        let got = y.to_vec1::<f32>().unwrap();
        for (&xi, &yi) in xs.iter().zip(&got) {
            let want = if xi > 0.0 { xi } else { xi.exp() - 1.0 };
            assert!((yi - want).abs() < 1e-6, "elu({xi}) = {yi}, want {want}");
        }
        let grads = (y.sqr().unwrap().sum_all().unwrap()).backward().unwrap();
        let g = grads.get(x.as_tensor()).unwrap().to_vec1::<f32>().unwrap();
        for ((&xi, &yi), &gi) in xs.iter().zip(&got).zip(&g) {
            let want = 2.0 * yi * if xi > 0.0 { 1.0 } else { xi.exp() };
            assert!((gi - want).abs() < 1e-5, "grad at {xi}: {gi}, want {want}");
        }
    }
}
