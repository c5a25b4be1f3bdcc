//! MaskedAdam: Adam (eps 1e-5, no weight decay by default) that never moves a
//! frozen element (METHOD.md 2.2). Where a parameter's update mask is 0 the
//! element, its first and its second moment are all left untouched, so a
//! frozen element stays bit-identical however many steps run (candle's AdamW
//! would keep moving it through momentum and weight decay).
//!
//! The update is element-wise (rayon over parameters), so the result does not
//! depend on the number of threads.

use super::activation::{with_f32_slice, with_f32_slice_mut};
use super::Param;
use candle_core::backprop::GradStore;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Adam's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdamConfig {
    /// Learning rate.
    pub learning_rate: f64,
    /// Decay of the first moment.
    pub beta1: f64,
    /// Decay of the second moment.
    pub beta2: f64,
    /// Added to the root of the second moment.
    pub eps: f64,
    /// Decoupled weight decay (AdamW style), applied only to elements that may move.
    pub weight_decay: f64,
}

impl Default for AdamConfig {
    fn default() -> Self {
        Self { learning_rate: 1e-3, beta1: 0.9, beta2: 0.999, eps: 1e-5, weight_decay: 0.0 }
    }
}

/// One parameter's Adam state: first and second moments and the steps taken
/// (what a training checkpoint keeps so that a resumed run steps alike).
#[derive(Debug, Clone, PartialEq)]
pub struct Moments {
    pub m: Vec<f32>,
    pub v: Vec<f32>,
    pub step: i32,
}

/// Adam over [`Param`]s, respecting their update masks.
#[derive(Debug)]
pub struct MaskedAdam {
    cfg: AdamConfig,
    moments: HashMap<String, Moments>,
}

/// A parameter's gradient and update mask, read in place; None when it has no gradient.
fn with_grad_and_mask<R>(
    p: &Param,
    grads: &GradStore,
    f: impl FnOnce(&[f32], Option<&[f32]>) -> R,
) -> anyhow::Result<Option<R>> {
    let Some(g) = grads.get(p.var.as_tensor()) else { return Ok(None) };
    let g = g.contiguous()?;
    Ok(Some(with_f32_slice(&g, &p.name, |g| match &p.update_mask {
        Some(m) => {
            let m = m.contiguous()?;
            with_f32_slice(&m, &p.name, |m| f(g, Some(m)))
        }
        None => Ok(f(g, None)),
    })??))
}

/// Lanes of [`square_sum`]: independent accumulators, so the loop is not one long
/// chain of dependent f64 additions.
const LANES: usize = 8;

/// Sum of squares in f64 of the elements whose mask is not 0 (all without a mask):
/// element i goes to lane i mod 8, the lanes are added in order.
fn square_sum(g: &[f32], mask: Option<&[f32]>) -> f64 {
    match mask {
        Some(mask) => masked_square_sum(g, &mask[..g.len()]),
        None => full_square_sum(g),
    }
}

super::wide::wide_fn!(
    /// [`square_sum`] of every element, at full vector width.
    fn full_square_sum(g: &[f32]) -> f64 => full_square_sum_body
);

#[inline(always)]
fn full_square_sum_body(g: &[f32]) -> f64 {
    let chunks = g.chunks_exact(LANES);
    let tail = chunks.remainder();
    let mut lanes = [0f64; LANES];
    for chunk in chunks {
        for j in 0..LANES {
            let v = f64::from(chunk[j]);
            lanes[j] += v * v;
        }
    }
    for (j, &v) in tail.iter().enumerate() {
        lanes[j] += f64::from(v) * f64::from(v);
    }
    lanes.iter().sum()
}

super::wide::wide_fn!(
    /// [`square_sum`] of the elements whose mask (as long as g) is not 0, at full vector width.
    fn masked_square_sum(g: &[f32], mask: &[f32]) -> f64 => masked_square_sum_body
);

/// Chunks of 8 of g and of its mask side by side, each lane's element kept or zeroed by a
/// bit mask: no index, bounds check or branch inside the loop, so it compiles to vector code.
/// (Indexing the mask by position kept it scalar, a branch per element: 2 % of an iteration.)
#[inline(always)]
fn masked_square_sum_body(g: &[f32], mask: &[f32]) -> f64 {
    let (chunks, mask_chunks) = (g.chunks_exact(LANES), mask[..g.len()].chunks_exact(LANES));
    let (tail, mask_tail) = (chunks.remainder(), mask_chunks.remainder());
    let mut lanes = [0f64; LANES];
    for (chunk, moves) in chunks.zip(mask_chunks) {
        for j in 0..LANES {
            // All ones where the element moves, else 0: an AND, not a select, which LLVM
            // turned back into a branch per element.
            let keep = u32::from(moves[j] != 0.0).wrapping_neg();
            let v = f64::from(f32::from_bits(chunk[j].to_bits() & keep));
            lanes[j] += v * v;
        }
    }
    for (j, (&v, &moves)) in tail.iter().zip(mask_tail).enumerate() {
        let v = if moves != 0.0 { f64::from(v) } else { 0.0 };
        lanes[j] += v * v;
    }
    lanes.iter().sum()
}

/// The constants of one Adam step of one parameter.
#[derive(Clone, Copy)]
struct StepConstants {
    beta1: f32,
    beta2: f32,
    /// lr / (1 - beta1^t).
    step_size: f32,
    /// sqrt(1 - beta2^t).
    bc2_sqrt: f32,
    eps: f32,
    /// lr * weight_decay.
    decay: f32,
}

super::wide::wide_fn!(
    /// [`adam_elements`] at full vector width.
    fn adam_step(
        w: &mut [f32],
        m: &mut [f32],
        v: &mut [f32],
        g: &[f32],
        mask: Option<&[f32]>,
        c: StepConstants,
    ) => adam_elements
);

/// One Adam step over a parameter's elements in place. A frozen element (mask 0), its moments
/// included, keeps its bits (METHOD 2.2): its step is computed and discarded, a select rather
/// than a branch. Inlined into [`adam_step`]'s target-feature functions, with every constant a
/// local value and the slices of one length, so the loop compiles to full-width vector code.
#[inline(always)]
fn adam_elements(w: &mut [f32], m: &mut [f32], v: &mut [f32], g: &[f32], mask: Option<&[f32]>, c: StepConstants) {
    let n = w.len();
    let (m, v, g) = (&mut m[..n], &mut v[..n], &g[..n]);
    let StepConstants { beta1: b1, beta2: b2, step_size, bc2_sqrt, eps, decay } = c;
    let stepped = |w: f32, m: f32, v: f32, g: f32| {
        let m = b1 * m + (1.0 - b1) * g;
        let v = b2 * v + (1.0 - b2) * g * g;
        let w = w - decay * w;
        (w - step_size * m / (v.sqrt() / bc2_sqrt + eps), m, v)
    };
    match mask {
        Some(mask) => {
            let mask = &mask[..n];
            for i in 0..n {
                let (w1, m1, v1) = stepped(w[i], m[i], v[i], g[i]);
                let frozen = mask[i] == 0.0;
                w[i] = if frozen { w[i] } else { w1 };
                m[i] = if frozen { m[i] } else { m1 };
                v[i] = if frozen { v[i] } else { v1 };
            }
        }
        None => {
            for i in 0..n {
                (w[i], m[i], v[i]) = stepped(w[i], m[i], v[i], g[i]);
            }
        }
    }
}

impl MaskedAdam {
    /// A new optimiser with empty moments.
    pub fn new(cfg: AdamConfig) -> Self {
        Self { cfg, moments: HashMap::new() }
    }

    /// Forgets every moment: call at the start of each task (a new task's bias is a new
    /// variable under the same name, and old moments must not push the new task).
    pub fn reset(&mut self) {
        self.moments.clear();
    }

    /// Every parameter's moments, by parameter name.
    pub fn moments(&self) -> &HashMap<String, Moments> {
        &self.moments
    }

    /// Replaces every moment (from a training checkpoint); a moment whose two vectors differ
    /// in length is an error, and one whose size no longer fits its parameter errors at the next step.
    pub fn restore_moments(&mut self, moments: HashMap<String, Moments>) -> anyhow::Result<()> {
        for (name, mom) in &moments {
            anyhow::ensure!(
                mom.m.len() == mom.v.len(),
                "{name}: Adam moments of {} and {} elements",
                mom.m.len(),
                mom.v.len()
            );
            anyhow::ensure!(mom.step >= 0, "{name}: Adam step count {}", mom.step);
        }
        self.moments = moments;
        Ok(())
    }

    /// Sets the learning rate (for schedules).
    pub fn set_learning_rate(&mut self, lr: f64) {
        self.cfg.learning_rate = lr;
    }

    /// The current learning rate.
    pub fn learning_rate(&self) -> f64 {
        self.cfg.learning_rate
    }

    /// Scales all gradients so their global L2 norm is at most `max_norm`. The norm counts only
    /// elements that may move (update mask 1); it is returned as it was before clipping.
    /// Each parameter's square sum is taken in a fixed order (8 f64 lanes), and the sums in
    /// parameter order, so the norm does not depend on the thread count.
    pub fn clip_grad_norm(&self, params: &[Param], grads: &mut GradStore, max_norm: f64) -> anyhow::Result<f64> {
        let square_sums =
            params.par_iter().map(|p| with_grad_and_mask(p, grads, square_sum)).collect::<anyhow::Result<Vec<_>>>()?;
        let norm = square_sums.into_iter().flatten().sum::<f64>().sqrt();
        if norm > max_norm && norm.is_finite() {
            let scale = max_norm / (norm + 1e-6);
            for p in params {
                if let Some(g) = grads.get(p.var.as_tensor()) {
                    let scaled = (g * scale)?;
                    grads.insert(p.var.as_tensor(), scaled);
                }
            }
        }
        Ok(norm)
    }

    /// One Adam step on every parameter that has a gradient (the parameters in parallel), each
    /// at its [`Param::fixed_learning_rate`] where it has one, at the optimiser's rate otherwise.
    pub fn step(&mut self, params: &[Param], grads: &GradStore) -> anyhow::Result<()> {
        let c = self.cfg.clone();
        for p in params {
            if grads.get(p.var.as_tensor()).is_some() {
                let n = p.var.as_tensor().elem_count();
                let mom = self.moments.entry(p.name.clone()).or_insert_with(|| Moments {
                    m: vec![0.0; n],
                    v: vec![0.0; n],
                    step: 0,
                });
                anyhow::ensure!(mom.m.len() == n, "{}: parameter changed size between steps", p.name);
            }
        }
        // One moment entry per parameter with a gradient, handed out as disjoint borrows.
        let mut by_name: HashMap<&str, &mut Moments> = self.moments.iter_mut().map(|(k, v)| (k.as_str(), v)).collect();
        let work: Vec<(&Param, &mut Moments)> = params
            .iter()
            .filter(|p| grads.get(p.var.as_tensor()).is_some())
            .filter_map(|p| by_name.remove(p.name.as_str()).map(|m| (p, m)))
            .collect();
        work.into_par_iter().try_for_each(|(p, mom)| -> anyhow::Result<()> {
            mom.step += 1;
            let lr = p.fixed_learning_rate.unwrap_or(c.learning_rate);
            let constants = StepConstants {
                beta1: c.beta1 as f32,
                beta2: c.beta2 as f32,
                step_size: (lr / (1.0 - c.beta1.powi(mom.step))) as f32,
                bc2_sqrt: (1.0 - c.beta2.powi(mom.step)).sqrt() as f32,
                eps: c.eps as f32,
                decay: (lr * c.weight_decay) as f32,
            };
            // The parameter is stepped in its own storage (no copy out and back).
            let stepped = with_grad_and_mask(p, grads, |g, mask| {
                with_f32_slice_mut(p.var.as_tensor(), &p.name, |w| -> anyhow::Result<()> {
                    anyhow::ensure!(
                        g.len() == w.len(),
                        "{}: gradient has {} elements, parameter {}",
                        p.name,
                        g.len(),
                        w.len()
                    );
                    anyhow::ensure!(
                        mask.is_none_or(|m| m.len() == w.len()),
                        "{}: update mask differs in size from the parameter",
                        p.name
                    );
                    adam_step(w, &mut mom.m, &mut mom.v, g, mask, constants);
                    Ok(())
                })
            })?;
            // None: no gradient. Otherwise the in-place op's error, then the step's own.
            if let Some(stepped) = stepped {
                stepped??;
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::masked::var_values;
    use super::*;
    use candle_core::Tensor;
    use candle_core::{Device, Var};

    #[test]
    fn frozen_elements_stay_bit_identical_over_many_steps() {
        let init: Vec<f32> = (0..64).map(|i| (i as f32 * 0.37).sin()).collect();
        let var = Var::from_slice(&init, (8, 8), &Device::Cpu).unwrap();
        let mask: Vec<f32> = (0..64).map(|i| if i % 3 == 0 { 1.0 } else { 0.0 }).collect();
        let mut opt = MaskedAdam::new(AdamConfig { weight_decay: 0.01, ..AdamConfig::default() });
        let mut at_freeze = Vec::new();
        for step in 0..300 {
            // Alternate the mask so moments exist for elements that are later frozen.
            let m = if step < 50 { vec![1.0; 64] } else { mask.clone() };
            let p = Param {
                name: "w".into(),
                var: var.clone(),
                update_mask: Some(Tensor::from_vec(m, (8, 8), &Device::Cpu).unwrap()),
                fixed_learning_rate: None,
            };
            let loss = var.as_tensor().sqr().unwrap().sum_all().unwrap();
            let grads = loss.backward().unwrap();
            if step == 50 {
                at_freeze = var_values(&var).unwrap();
            }
            opt.step(&[p], &grads).unwrap();
        }
        let end = var_values(&var).unwrap();
        for i in 0..64 {
            if mask[i] == 0.0 {
                assert_eq!(end[i].to_bits(), at_freeze[i].to_bits(), "element {i} moved");
            } else {
                assert!(end[i].abs() < at_freeze[i].abs() || at_freeze[i] == 0.0, "element {i} did not train");
            }
        }
    }

    #[test]
    fn a_fixed_learning_rate_ignores_the_optimisers_rate() {
        // Adam's first step moves every element by its learning rate (sign of the gradient).
        let step = |fixed: Option<f64>, optimiser_lr: f64| {
            let var = Var::from_slice(&[1.0f32, -2.0], 2, &Device::Cpu).unwrap();
            let p = Param { fixed_learning_rate: fixed, ..Param::free("log_sigma", &var) };
            let grads = var.as_tensor().sqr().unwrap().sum_all().unwrap().backward().unwrap();
            let mut opt = MaskedAdam::new(AdamConfig { learning_rate: optimiser_lr, ..AdamConfig::default() });
            opt.step(&[p], &grads).unwrap();
            var_values(&var).unwrap()
        };
        for lr in [1e-4, 1e-2] {
            let moved = step(Some(1e-3), lr);
            assert!((moved[0] - (1.0 - 1e-3)).abs() < 1e-6 && (moved[1] - (-2.0 + 1e-3)).abs() < 1e-6, "{moved:?}");
            let at_optimiser = step(None, lr);
            assert!((at_optimiser[0] - (1.0 - lr as f32)).abs() < 1e-6, "{at_optimiser:?}");
        }
    }

    #[test]
    fn clipping_scales_to_max_norm_and_reports_the_norm_before() {
        let var = Var::from_slice(&[3.0f32, 4.0], 2, &Device::Cpu).unwrap();
        let p = Param::free("w", &var);
        let mut grads = (var.as_tensor().sqr().unwrap().sum_all().unwrap() * 0.5).unwrap().backward().unwrap();
        let opt = MaskedAdam::new(AdamConfig::default());
        let norm = opt.clip_grad_norm(std::slice::from_ref(&p), &mut grads, 1.0).unwrap();
        assert!((norm - 5.0).abs() < 1e-6);
        let g = grads.get(var.as_tensor()).unwrap().to_vec1::<f32>().unwrap();
        assert!(((g[0] * g[0] + g[1] * g[1]).sqrt() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn clipping_norm_counts_only_elements_that_may_move() {
        let var = Var::from_slice(&[3.0f32, 4.0, 100.0], 3, &Device::Cpu).unwrap();
        let mask = Tensor::from_slice(&[1.0f32, 1.0, 0.0], 3, &Device::Cpu).unwrap();
        let p = Param { update_mask: Some(mask), ..Param::free("w", &var) };
        let mut grads = (var.as_tensor().sqr().unwrap().sum_all().unwrap() * 0.5).unwrap().backward().unwrap();
        let norm =
            MaskedAdam::new(AdamConfig::default()).clip_grad_norm(std::slice::from_ref(&p), &mut grads, 10.0).unwrap();
        assert!((norm - 5.0).abs() < 1e-6, "norm {norm}");
    }

    #[test]
    fn square_sums_add_each_lane_in_order_and_skip_frozen_elements_even_when_not_finite() {
        for len in [0usize, 5, 8, 61, 1000] {
            let g: Vec<f32> = (0..len).map(|i| ((i * 7919) % 1000) as f32 / 97.0 - 5.0).collect();
            let mask: Vec<f32> = (0..len).map(|i| if i % 3 == 0 { 0.0 } else { 1.0 }).collect();
            // A frozen element's gradient never counts, NaN included.
            let g_nan: Vec<f32> = g.iter().zip(&mask).map(|(&v, &m)| if m == 0.0 { f32::NAN } else { v }).collect();
            // The reference: element i into lane i mod 8, in f64, lanes summed in order.
            let reference = |keep: &dyn Fn(usize) -> bool| {
                let mut lanes = [0f64; LANES];
                (0..len).filter(|&i| keep(i)).for_each(|i| lanes[i % LANES] += f64::from(g[i]) * f64::from(g[i]));
                lanes.iter().sum::<f64>()
            };
            assert_eq!(full_square_sum(&g).to_bits(), reference(&|_| true).to_bits(), "len {len}");
            assert_eq!(
                masked_square_sum(&g_nan, &mask).to_bits(),
                reference(&|i| mask[i] != 0.0).to_bits(),
                "len {len}"
            );
        }
    }
}
