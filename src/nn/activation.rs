//! Activations as fused candle custom ops (CPU, f32, rayon-parallel over
//! chunks). candle's stock ELU is a chain of element-wise kernels and made a
//! training step several times slower than PyTorch; here forward is one
//! pass and backward is one pass over (result, upstream gradient):
//!
//! ELU (alpha = 1): y = x if x > 0 else exp(x) - 1;  dy/dx = 1 if y > 0 else y + 1.

use crate::config::net::Activation;
use candle_core::{CpuStorage, CustomOp1, CustomOp2, InplaceOp1, Layout, Shape, Tensor};
use rayon::prelude::*;
use std::sync::Mutex;

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

/// Runs `f` on the contiguous f32 contents of a CPU tensor in place, without copying
/// them out and back: the write lands in the tensor's storage, which every tensor
/// sharing it (a `Var` and its clones) sees, as `Var::set` would.
pub(super) fn with_f32_slice_mut<R>(t: &Tensor, what: &str, f: impl FnOnce(&mut [f32]) -> R) -> candle_core::Result<R> {
    let op = InPlace { what, f: Mutex::new(Some(f)), out: Mutex::new(None) };
    t.inplace_op1(&op)?;
    let out = op.out.into_inner().map_err(|_| candle_core::Error::Msg(format!("{what}: in-place op poisoned")))?;
    out.ok_or_else(|| candle_core::Error::Msg(format!("{what}: expects a tensor on the CPU")))
}

/// The candle op behind [`with_f32_slice_mut`]: hands the storage to `f` once.
struct InPlace<'a, F, R> {
    what: &'a str,
    f: Mutex<Option<F>>,
    out: Mutex<Option<R>>,
}

impl<F: FnOnce(&mut [f32]) -> R, R> InplaceOp1 for InPlace<'_, F, R> {
    fn name(&self) -> &'static str {
        "f32-in-place"
    }

    fn cpu_fwd(&self, s: &mut CpuStorage, l: &Layout) -> candle_core::Result<()> {
        let what = self.what;
        let CpuStorage::F32(data) = s else { candle_core::bail!("{what}: expects an f32 tensor") };
        let Some((a, b)) = l.contiguous_offsets() else { candle_core::bail!("{what}: expects a contiguous tensor") };
        let poisoned = || candle_core::Error::Msg(format!("{what}: in-place op poisoned"));
        let f = self.f.lock().map_err(|_| poisoned())?.take();
        let Some(f) = f else { candle_core::bail!("{what}: in-place op run twice") };
        *self.out.lock().map_err(|_| poisoned())? = Some(f(&mut data[a..b]));
        Ok(())
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
    fn a_write_in_place_is_seen_by_the_var_and_its_clones() {
        let var = Var::from_slice(&[1f32, 2.0, 3.0, 4.0, 5.0, 6.0], (2, 3), &Device::Cpu).unwrap();
        let clone = var.clone();
        let sum = with_f32_slice_mut(var.as_tensor(), "w", |w| {
            w.iter_mut().for_each(|v| *v *= 10.0);
            w.iter().sum::<f32>()
        })
        .unwrap();
        assert_eq!(sum, 210.0);
        assert_eq!(
            clone.as_tensor().flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            [10.0, 20.0, 30.0, 40.0, 50.0, 60.0]
        );
    }

    #[test]
    fn a_write_in_place_refuses_a_strided_view_and_names_it() {
        let t = Tensor::from_slice(&[1f32, 2.0, 3.0, 4.0, 5.0, 6.0], (2, 3), &Device::Cpu).unwrap().t().unwrap();
        let err = with_f32_slice_mut(&t, "actor.l0.weight", |_| ()).unwrap_err().to_string();
        assert!(err.contains("actor.l0.weight") && err.contains("contiguous"), "{err}");
        let ints = Tensor::from_slice(&[1u32, 2], 2, &Device::Cpu).unwrap();
        let err = with_f32_slice_mut(&ints, "step", |_| ()).unwrap_err().to_string();
        assert!(err.contains("step") && err.contains("f32"), "{err}");
    }

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
