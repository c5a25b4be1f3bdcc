//! The whole MLP as one candle custom op (CPU, f32): the speed path of
//! [`crate::nn::MaskedMlp`] (`quadcl bench`: actor train step).
//!
//! Inputs: x (batch, sizes[0]) and theta, every layer's effective weight
//! (out, in) row-major followed by its bias (out,), concatenated in layer
//! order: theta (sum over layers of out * in + out,). Output: (batch, sizes[last]).
//! Hidden layers apply the activation; the output layer is linear.
//!
//! Forward: per layer z = h W^T + b (gemm on slices, bias pre-filled), then
//! the activation in place (rayon over chunks, a vectorisable exp for ELU).
//! The hidden activations are kept inside the op instance for its backward,
//! which computes grad_theta (and grad_x when x needs it) in one pass:
//! g <- g * act'(h); dW = g^T h_prev; db = column sums of g (fixed-size row
//! blocks summed in a fixed order: thread-count independent); g <- g W.
//! candle's autograd sees a single node, so none of its per-node gradient
//! buffers are made for the (batch, 512) activations.

use super::activation::{contiguous_f32, with_f32_slice};
use super::product::{parallelism, MatrixProduct};
use super::wide::wide;
use crate::config::net::Activation;
use candle_core::{CpuStorage, CustomOp2, Layout, Shape, Tensor};
use gemm::Parallelism;
use rayon::prelude::*;
use std::sync::Mutex;

const CHUNK: usize = 1 << 14;
const ROW_BLOCK: usize = 256;

/// e^x for x <= 0 (and moderately positive x), ~2 ulp, branch-free so it vectorises.
#[inline(always)]
fn fast_exp(x: f32) -> f32 {
    let x = x.clamp(-87.0, 88.0);
    // Round to nearest by the 1.5 * 2^23 trick (no libm call, so the loop vectorises):
    // the low mantissa bits of `biased` hold n itself, read without a (saturating,
    // hence scalar) float-to-int cast.
    let biased = x * std::f32::consts::LOG2_E + 12_582_912.0;
    let n = biased - 12_582_912.0;
    let n_int = biased.to_bits().wrapping_sub(12_582_912f32.to_bits()) as i32;
    let r = x - n * 0.693_145_75 - n * 1.428_606_8e-6;
    let p = 1.0
        + r * (1.0 + r * (0.5 + r * (0.166_666_67 + r * (0.041_666_668 + r * (0.008_333_334 + r * 0.001_388_889)))));
    f32::from_bits((n_int.wrapping_add(127) << 23) as u32) * p
}

/// e^x - 1, accurate near 0 (Taylor below |x| < 0.125). Both branches are
/// computed and one is selected, so loops over it vectorise.
#[inline(always)]
pub(crate) fn fast_expm1(x: f32) -> f32 {
    let taylor = x * (1.0 + x * (0.5 + x * (0.166_666_67 + x * (0.041_666_668 + x * 0.008_333_334))));
    let shifted = fast_exp(x) - 1.0;
    if x.abs() < 0.125 {
        taylor
    } else {
        shifted
    }
}

/// ELU (alpha 1), branch-free: y = x for x > 0, e^x - 1 otherwise.
#[inline(always)]
pub(crate) fn elu(x: f32) -> f32 {
    let negative = fast_expm1(x);
    if x > 0.0 {
        x
    } else {
        negative
    }
}

/// The activation applied in place. One loop per activation (a `match`
/// inside the loop compiled to a jump per element, not vector code).
fn activate_in_place(act: Activation, v: &mut [f32]) {
    match act {
        Activation::Elu => v.par_chunks_mut(CHUNK).for_each(|c| wide(|| c.iter_mut().for_each(|v| *v = elu(*v)))),
        Activation::Relu => v.par_chunks_mut(CHUNK).for_each(|c| wide(|| c.iter_mut().for_each(|v| *v = v.max(0.0)))),
        Activation::Tanh => v.par_chunks_mut(CHUNK).for_each(|c| c.iter_mut().for_each(|v| *v = v.tanh())),
        Activation::Identity => {}
    }
}

/// g <- g * act'(y) where y is the activation's output; one loop per activation, as above.
fn activation_grad_in_place(act: Activation, g: &mut [f32], y: &[f32]) {
    fn apply(g: &mut [f32], y: &[f32], derivative: impl Fn(f32) -> f32 + Sync) {
        g.par_chunks_mut(CHUNK).zip(y.par_chunks(CHUNK)).for_each(|(g, y)| {
            wide(|| {
                for (g, &y) in g.iter_mut().zip(y) {
                    *g *= derivative(y);
                }
            })
        });
    }
    match act {
        // ELU: 1 for y > 0, y + 1 otherwise (y = e^x - 1).
        Activation::Elu => apply(g, y, |y| if y > 0.0 { 1.0 } else { y + 1.0 }),
        Activation::Relu => apply(g, y, |y| if y > 0.0 { 1.0 } else { 0.0 }),
        Activation::Tanh => apply(g, y, |y| 1.0 - y * y),
        Activation::Identity => {}
    }
}

/// A new (batch, width) row-major matrix whose every row is `bias`, written once
/// (not zeroed first), rows in parallel.
fn bias_rows(bias: &[f32], batch: usize) -> Vec<f32> {
    let width = bias.len();
    let mut z = Vec::<f32>::with_capacity(batch * width);
    z.spare_capacity_mut()[..batch * width].par_chunks_mut(width.max(1) * ROW_BLOCK).for_each(|rows| {
        rows.chunks_mut(width.max(1)).for_each(|row| {
            row.iter_mut().zip(bias).for_each(|(z, b)| {
                z.write(*b);
            })
        })
    });
    // SAFETY: every one of the batch * width elements was written just above.
    unsafe { z.set_len(batch * width) };
    z
}

/// Offsets of each layer's weight and bias in theta.
fn offsets(sizes: &[usize]) -> (Vec<(usize, usize)>, usize) {
    let mut at = 0;
    let offs = sizes
        .windows(2)
        .map(|w| {
            let o = (at, at + w[0] * w[1]);
            at += w[0] * w[1] + w[1];
            o
        })
        .collect();
    (offs, at)
}

/// The number of elements of theta for these sizes.
pub fn theta_len(sizes: &[usize]) -> usize {
    offsets(sizes).1
}

/// What a forward keeps for its backward: every hidden layer's output (the input and theta
/// are the op's arguments, which the backward is handed again).
type Saved = Vec<Vec<f32>>;

/// The fused MLP op; one instance per forward call (it keeps that call's activations).
pub struct FusedMlp {
    sizes: Vec<usize>,
    activation: Activation,
    /// The hidden outputs after activation of the forward, for backward.
    saved: Mutex<Option<Saved>>,
}

impl FusedMlp {
    fn run(&self, x: &[f32], theta: &[f32], keep: bool) -> Vec<f32> {
        let batch = x.len() / self.sizes[0];
        let (offs, _) = offsets(&self.sizes);
        let last = offs.len() - 1;
        let mut hidden: Vec<Vec<f32>> = Vec::with_capacity(last);
        let mut out = Vec::new();
        for (l, &(w_at, b_at)) in offs.iter().enumerate() {
            let (fan_in, width) = (self.sizes[l], self.sizes[l + 1]);
            let h = if l == 0 { x } else { &hidden[l - 1] };
            let bias = &theta[b_at..b_at + width];
            let mut z = bias_rows(bias, batch);
            // z (batch, width) += h (batch, fan_in) . W^T, W (width, fan_in) row-major.
            MatrixProduct::new((batch, width, fan_in), h, (1, fan_in), &theta[w_at..], (fan_in, 1))
                .add_to(&mut z, parallelism());
            if l < last {
                activate_in_place(self.activation, &mut z);
                hidden.push(z);
            } else {
                out = z;
            }
        }
        if keep {
            *self.saved.lock().expect("fused MLP lock") = Some(hidden);
        }
        out
    }
}

/// [`fused_mlp`] after checking that `x` is (batch, sizes[0]); the error names `network`.
pub(crate) fn fused_mlp_checked(
    network: &str,
    sizes: &[usize],
    activation: Activation,
    x: &Tensor,
    theta: &Tensor,
    track: bool,
) -> anyhow::Result<Tensor> {
    let dims = x.dims();
    anyhow::ensure!(
        dims.len() == 2 && dims[1] == sizes[0],
        "{network}: input shape {dims:?}, expected (batch, {})",
        sizes[0]
    );
    Ok(fused_mlp(sizes, activation, x, theta, track)?)
}

/// Runs the MLP: differentiable in x and theta when `track` is true.
pub fn fused_mlp(
    sizes: &[usize],
    activation: Activation,
    x: &Tensor,
    theta: &Tensor,
    track: bool,
) -> candle_core::Result<Tensor> {
    let op = FusedMlp { sizes: sizes.to_vec(), activation, saved: Mutex::new(None) };
    let (x, theta) = (x.contiguous()?, theta.contiguous()?);
    if track {
        x.apply_op2(&theta, op)
    } else {
        x.apply_op2_no_bwd(&theta, &op)
    }
}

/// Every hidden layer's output (after the activation) of the forward on x (batch, sizes[0])
/// with `theta` as [`fused_mlp`] takes it: one row-major (batch, sizes[l + 1]) vector per
/// hidden layer, the values the forward computes (same kernels); no graph. What the
/// plasticity diagnostics read (`rl/plasticity.rs`). The error names `network`.
pub(crate) fn fused_mlp_hidden(
    network: &str,
    sizes: &[usize],
    activation: Activation,
    x: &Tensor,
    theta: &Tensor,
) -> anyhow::Result<Vec<Vec<f32>>> {
    let dims = x.dims();
    anyhow::ensure!(
        dims.len() == 2 && dims[1] == sizes[0],
        "{network}: input shape {dims:?}, expected (batch, {})",
        sizes[0]
    );
    anyhow::ensure!(
        theta.elem_count() == theta_len(sizes),
        "{network}: theta has {} elements, sizes {sizes:?} need {}",
        theta.elem_count(),
        theta_len(sizes)
    );
    let op = FusedMlp { sizes: sizes.to_vec(), activation, saved: Mutex::new(None) };
    let (x, theta) = (x.contiguous()?, theta.contiguous()?);
    with_f32_slice(&x, "fused-mlp hidden", |x| {
        with_f32_slice(&theta, "fused-mlp hidden", |theta| op.run(x, theta, true))
    })??;
    let hidden = op.saved.into_inner().map_err(|_| anyhow::anyhow!("{network}: fused MLP lock poisoned"))?;
    hidden.ok_or_else(|| anyhow::anyhow!("{network}: the forward kept no hidden outputs"))
}

impl CustomOp2 for FusedMlp {
    fn name(&self) -> &'static str {
        "fused-mlp"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let (x, theta) = (contiguous_f32(s1, l1, self.name())?, contiguous_f32(s2, l2, self.name())?);
        let dims = l1.dims();
        if dims.len() != 2 || dims[1] != self.sizes[0] {
            candle_core::bail!("fused-mlp: input shape {dims:?}, expected (batch, {})", self.sizes[0]);
        }
        if theta.len() != theta_len(&self.sizes) {
            candle_core::bail!(
                "fused-mlp: theta has {} elements, sizes {:?} need {}",
                theta.len(),
                self.sizes,
                theta_len(&self.sizes)
            );
        }
        let out = self.run(x, theta, true);
        Ok((CpuStorage::F32(out), Shape::from((dims[0], *self.sizes.last().expect("sizes checked")))))
    }

    fn bwd(
        &self,
        arg1: &Tensor,
        arg2: &Tensor,
        _res: &Tensor,
        grad_res: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        let guard = self.saved.lock().expect("fused MLP lock");
        let Some(hidden) = guard.as_ref() else { candle_core::bail!("fused-mlp: backward without forward") };
        let g = grad_res.contiguous()?.flatten_all()?.to_vec1::<f32>()?;
        let need_x = arg1.track_op();
        let (x, theta) = (arg1.contiguous()?, arg2.contiguous()?);
        let (grad_x, grad_theta) = with_f32_slice(&x, self.name(), |x| {
            with_f32_slice(&theta, self.name(), |theta| self.backward(x, theta, hidden, g, need_x))
        })??;
        let batch = x.dims()[0];
        let grad_x = match grad_x {
            Some(g) => Some(Tensor::from_vec(g, (batch, self.sizes[0]), &candle_core::Device::Cpu)?),
            None => None,
        };
        let total = grad_theta.len();
        Ok((grad_x, Some(Tensor::from_vec(grad_theta, total, &candle_core::Device::Cpu)?)))
    }
}

impl FusedMlp {
    /// The backward pass on slices: x (batch, sizes[0]) and theta as the forward had them,
    /// its hidden outputs, and g the output's gradient (batch, sizes[last]). Returns
    /// (grad_x when `need_x`, grad_theta).
    fn backward(
        &self,
        x: &[f32],
        theta: &[f32],
        hidden: &[Vec<f32>],
        mut g: Vec<f32>,
        need_x: bool,
    ) -> (Option<Vec<f32>>, Vec<f32>) {
        let batch = x.len() / self.sizes[0];
        let (offs, total) = offsets(&self.sizes);
        let mut grad_theta = vec![0f32; total];
        for l in (0..offs.len()).rev() {
            let (fan_in, width) = (self.sizes[l], self.sizes[l + 1]);
            let (w_at, b_at) = offs[l];
            if l < offs.len() - 1 {
                activation_grad_in_place(self.activation, &mut g, &hidden[l]);
            }
            let h: &[f32] = if l == 0 { x } else { &hidden[l - 1] };
            let need_prev = l > 0 || need_x;
            let (dw, db) = grad_theta[w_at..b_at + width].split_at_mut(width * fan_in);
            let g_now = &g;
            // dW and db, then (when needed) g_prev: two independent products, each on
            // one thread when both run, so small layers keep both cores busy.
            let mut weight_and_bias = |par: Parallelism| {
                // dW (width, fan_in) = g^T (width, batch) . h (batch, fan_in).
                MatrixProduct::new((width, fan_in, batch), g_now, (width, 1), h, (1, fan_in)).write_to(dw, par);
                // db: column sums of g over fixed row blocks, added in block order.
                for rows in g_now.chunks(width * ROW_BLOCK) {
                    let mut s = vec![0f32; width];
                    rows.chunks(width).for_each(|r| s.iter_mut().zip(r).for_each(|(s, v)| *s += v));
                    db.iter_mut().zip(&s).for_each(|(d, v)| *d += v);
                }
            };
            let previous = |par: Parallelism| {
                // g_prev (batch, fan_in) = g (batch, width) . W (width, fan_in).
                MatrixProduct::new((batch, fan_in, width), g_now, (1, width), &theta[w_at..], (1, fan_in))
                    .to_matrix(par)
            };
            if need_prev {
                let ((), prev) = rayon::join(|| weight_and_bias(Parallelism::None), || previous(Parallelism::None));
                g = prev;
            } else {
                weight_and_bias(parallelism());
            }
        }
        (need_x.then_some(g), grad_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::super::activation::activate;
    use super::*;
    use candle_core::{Device, Var};

    #[test]
    fn fast_exp_reads_the_exponent_as_the_float_to_int_cast_did() {
        for i in 0..200_000 {
            let x = (-87.0f32 + i as f32 * 0.000_875).min(88.0);
            let n = (x * std::f32::consts::LOG2_E + 12_582_912.0) - 12_582_912.0;
            let r = x - n * 0.693_145_75 - n * 1.428_606_8e-6;
            let p = 1.0
                + r * (1.0
                    + r * (0.5 + r * (0.166_666_67 + r * (0.041_666_668 + r * (0.008_333_334 + r * 0.001_388_889)))));
            let cast = f32::from_bits(((n as i32 + 127) << 23) as u32) * p;
            assert_eq!(fast_exp(x).to_bits(), cast.to_bits(), "exp({x})");
        }
    }

    #[test]
    fn fast_exp_is_accurate() {
        for i in 0..2000 {
            let x = -20.0 + i as f32 * 0.0123;
            let (got, want) = (fast_expm1(x), x.exp_m1());
            assert!((got - want).abs() <= 2e-6 * want.abs().max(1e-3), "expm1({x}) = {got}, want {want}");
        }
    }

    #[test]
    fn fused_mlp_matches_candle_ops_in_value_and_gradient() {
        let sizes = [5, 7, 6, 3];
        for act in [Activation::Elu, Activation::Relu, Activation::Tanh] {
            let dev = Device::Cpu;
            let x = Var::from_tensor(&Tensor::randn(0f32, 1.0, (9, 5), &dev).unwrap()).unwrap();
            let theta = Var::from_tensor(&Tensor::randn(0f32, 0.5, theta_len(&sizes), &dev).unwrap()).unwrap();
            let fused = fused_mlp(&sizes, act, x.as_tensor(), theta.as_tensor(), true).unwrap();
            // The reference, with candle's own ops.
            let (offs, _) = offsets(&sizes);
            let mut h = x.as_tensor().clone();
            for (l, &(w_at, b_at)) in offs.iter().enumerate() {
                let w = theta
                    .as_tensor()
                    .narrow(0, w_at, sizes[l] * sizes[l + 1])
                    .unwrap()
                    .reshape((sizes[l + 1], sizes[l]))
                    .unwrap();
                let b = theta.as_tensor().narrow(0, b_at, sizes[l + 1]).unwrap();
                h = h.matmul(&w.t().unwrap()).unwrap().broadcast_add(&b).unwrap();
                if l + 1 < offs.len() {
                    h = activate(act, &h).unwrap();
                }
            }
            let close = |a: &Tensor, b: &Tensor, what: &str| {
                let (a, b) = (
                    a.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
                    b.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
                );
                for (i, (a, b)) in a.iter().zip(&b).enumerate() {
                    assert!((a - b).abs() < 1e-4 * (1.0 + b.abs()), "{act:?} {what}[{i}]: {a} vs {b}");
                }
            };
            close(&fused, &h, "output");
            let weights = Tensor::randn(0f32, 1.0, (9, 3), &dev).unwrap();
            let gf = fused.mul(&weights).unwrap().sum_all().unwrap().backward().unwrap();
            let gr = h.mul(&weights).unwrap().sum_all().unwrap().backward().unwrap();
            close(gf.get(theta.as_tensor()).unwrap(), gr.get(theta.as_tensor()).unwrap(), "grad theta");
            close(gf.get(x.as_tensor()).unwrap(), gr.get(x.as_tensor()).unwrap(), "grad x");
        }
    }
}
