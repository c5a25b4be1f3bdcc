//! TEMPORARY dense stand-ins for `nn::MaskedMlp`, `nn::Param` and
//! `nn::MaskedAdam` with the contract's method names, so the learner can be
//! built and tested while the masked networks (issue 3) are being written.
//! Replaced by the real `nn` types when they land on main; nothing outside
//! `rl/` uses this file.
//!
//! `DenseMlp`: y = ELU(... ELU(x W0^T + b0) ...) W_k^T + b_k, PyTorch's
//! default init U(-1/sqrt(fan_in), 1/sqrt(fan_in)) from a seeded stream.
//! `Adam`: Adam (beta 0.9/0.999, eps 1e-5, no weight decay), global-norm clip.

use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor, Var};
use rand::{Rng, SeedableRng};

/// A trainable tensor and its name (`{net}.l{i}.weight`).
#[derive(Debug, Clone)]
pub struct Param {
    pub name: String,
    pub var: Var,
    /// 1.0 where the element may move; `None`: every element may.
    pub update_mask: Option<Tensor>,
}

/// A dense MLP with ELU hidden activations and a linear output.
#[derive(Debug, Clone)]
pub struct DenseMlp {
    layers: Vec<(Var, Var)>,
    names: Vec<String>,
}

impl DenseMlp {
    /// `sizes` = [in, hidden.., out].
    pub fn new(name: &str, sizes: &[usize], seed: u64) -> anyhow::Result<Self> {
        anyhow::ensure!(sizes.len() >= 2, "MLP {name} needs at least input and output sizes, got {sizes:?}");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut layers = Vec::new();
        let mut names = Vec::new();
        for (i, w) in sizes.windows(2).enumerate() {
            let (fan_in, fan_out) = (w[0], w[1]);
            let bound = 1.0 / (fan_in as f32).sqrt();
            let weight: Vec<f32> = (0..fan_in * fan_out).map(|_| rng.gen_range(-bound..bound)).collect();
            let bias: Vec<f32> = (0..fan_out).map(|_| rng.gen_range(-bound..bound)).collect();
            let weight = Var::from_tensor(&Tensor::from_vec(weight, (fan_out, fan_in), &Device::Cpu)?)?;
            let bias = Var::from_tensor(&Tensor::from_vec(bias, fan_out, &Device::Cpu)?)?;
            layers.push((weight, bias));
            names.push(format!("{name}.l{i}"));
        }
        Ok(Self { layers, names })
    }

    /// (batch, in) -> (batch, out).
    pub fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        let mut h = x.clone();
        for (i, (w, b)) in self.layers.iter().enumerate() {
            h = h.matmul(&w.as_tensor().t()?)?.broadcast_add(b.as_tensor())?;
            if i + 1 < self.layers.len() {
                h = h.elu(1.0)?;
            }
        }
        Ok(h)
    }

    pub fn params(&self) -> Vec<Param> {
        let mut out = Vec::new();
        for ((w, b), name) in self.layers.iter().zip(&self.names) {
            out.push(Param { name: format!("{name}.weight"), var: w.clone(), update_mask: None });
            out.push(Param { name: format!("{name}.bias"), var: b.clone(), update_mask: None });
        }
        out
    }
}

/// Adam without weight decay, keyed by parameter name.
#[derive(Debug)]
pub struct Adam {
    lr: f64,
    step: i32,
    moments: std::collections::HashMap<String, (Tensor, Tensor)>,
}

impl Adam {
    pub fn new(lr: f64) -> Self {
        Self { lr, step: 0, moments: Default::default() }
    }
    pub fn set_learning_rate(&mut self, lr: f64) {
        self.lr = lr;
    }
    pub fn learning_rate(&self) -> f64 {
        self.lr
    }

    /// Scales the gradients so their global L2 norm is at most `max_norm`;
    /// returns the norm before clipping.
    pub fn clip_grad_norm(&self, params: &[Param], grads: &mut GradStore, max_norm: f64) -> anyhow::Result<f64> {
        let mut sum_sq = 0.0f64;
        for p in params {
            if let Some(g) = grads.get(p.var.as_tensor()) {
                sum_sq += f64::from(g.sqr()?.sum_all()?.to_scalar::<f32>()?);
            }
        }
        let norm = sum_sq.sqrt();
        if norm > max_norm {
            let scale = max_norm / (norm + 1e-6);
            for p in params {
                if let Some(g) = grads.remove(p.var.as_tensor()) {
                    grads.insert(p.var.as_tensor(), g.affine(scale, 0.0)?);
                }
            }
        }
        Ok(norm)
    }

    pub fn step(&mut self, params: &[Param], grads: &GradStore) -> anyhow::Result<()> {
        let (b1, b2, eps) = (0.9f64, 0.999f64, 1e-5f64);
        self.step += 1;
        let c1 = 1.0 - b1.powi(self.step);
        let c2 = 1.0 - b2.powi(self.step);
        for p in params {
            let Some(g) = grads.get(p.var.as_tensor()) else { continue };
            let (m, v) = match self.moments.get(&p.name) {
                Some((m, v)) => (m.clone(), v.clone()),
                None => (g.zeros_like()?, g.zeros_like()?),
            };
            let m = m.affine(b1, 0.0)?.add(&g.affine(1.0 - b1, 0.0)?)?;
            let v = v.affine(b2, 0.0)?.add(&g.sqr()?.affine(1.0 - b2, 0.0)?)?;
            let update = m.affine(1.0 / c1, 0.0)?.div(&v.affine(1.0 / c2, 0.0)?.sqrt()?.affine(1.0, eps)?)?;
            p.var.set(&p.var.as_tensor().sub(&update.affine(self.lr, 0.0)?)?)?;
            self.moments.insert(p.name.clone(), (m, v));
        }
        Ok(())
    }
}
