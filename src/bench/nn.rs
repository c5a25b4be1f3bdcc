//! Masked network throughput: one PPO-sized training step of the paper's
//! actor (64 -> 512 -> 256 -> 128 -> 12, ELU) at batch 4096: forward,
//! backward and optimiser step, masked (a MaskedMlp mid-task, with the
//! straight-through soft scores) and dense (the same sizes as plain
//! weights, the reference PyTorch runs in 40-60 ms on the 2-core machine).
//!
//! Keys: `actor_train_step_ms_dense`, `actor_train_step_ms_masked` (median
//! over the steps that fit in the time budget) and their `_fastest` step (on
//! a machine shared with other work the median wanders, the fastest less),
//! the split of the masked step into `actor_masked_forward_ms`,
//! `actor_masked_backward_ms`, `actor_masked_optimiser_ms`, the once-per-
//! iteration `actor_masked_begin_iteration_ms`, `actor_recall_forward_ms`
//! (forward_task of a finished task, no gradient: rollouts and evaluation),
//! and `nn_threads`.

use candle_core::{Device, Tensor, Var};
use quadcl::nn::{fused_mlp, Activation, AdamConfig, MaskConfig, MaskedAdam, MaskedMlp, Param};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::time::Instant;

pub const BATCH: usize = 4096;
pub const SIZES: [usize; 5] = [64, 512, 256, 128, 12];

fn randn(shape: (usize, usize), scale: f32, rng: &mut ChaCha8Rng) -> anyhow::Result<Tensor> {
    let v: Vec<f32> = (0..shape.0 * shape.1).map(|_| rng.sample::<f32, _>(StandardNormal) * scale).collect();
    Ok(Tensor::from_vec(v, shape, &Device::Cpu)?)
}

/// The dense reference: plain weights and biases, the same fused ELU, the same Adam.
struct DenseMlp {
    layers: Vec<(Var, Var)>,
}

impl DenseMlp {
    fn new(rng: &mut ChaCha8Rng) -> anyhow::Result<Self> {
        let layers = SIZES
            .windows(2)
            .map(|w| {
                Ok((
                    Var::from_tensor(&randn((w[1], w[0]), (1.0 / w[0] as f32).sqrt(), rng)?)?,
                    Var::zeros(w[1], candle_core::DType::F32, &Device::Cpu)?,
                ))
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(Self { layers })
    }

    fn forward(&self, x: &Tensor) -> anyhow::Result<Tensor> {
        let parts: Vec<Tensor> = self
            .layers
            .iter()
            .flat_map(|(w, b)| [w.as_tensor().flatten_all(), Ok(b.as_tensor().clone())])
            .collect::<candle_core::Result<_>>()?;
        Ok(fused_mlp(&SIZES, Activation::Elu, x, &Tensor::cat(&parts, 0)?, true)?)
    }

    fn params(&self) -> Vec<Param> {
        self.layers
            .iter()
            .enumerate()
            .flat_map(|(i, (w, b))| [Param::free(format!("l{i}.weight"), w), Param::free(format!("l{i}.bias"), b)])
            .collect()
    }
}

/// Milliseconds of (forward, backward, optimiser) for one step.
fn timed_step(
    forward: impl Fn(&Tensor) -> anyhow::Result<Tensor>,
    params: &[Param],
    opt: &mut MaskedAdam,
    x: &Tensor,
    y: &Tensor,
) -> anyhow::Result<[f64; 3]> {
    let t0 = Instant::now();
    let loss = forward(x)?.sub(y)?.sqr()?.mean_all()?;
    let t1 = Instant::now();
    let grads = loss.backward()?;
    let t2 = Instant::now();
    opt.step(params, &grads)?;
    let t3 = Instant::now();
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    Ok([ms(t0, t1), ms(t1, t2), ms(t2, t3)])
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn minimum(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Runs steps for about `seconds` (at least 3 after one warm-up) and returns per-phase medians
/// and the fastest whole step (the figure least disturbed by other work on a shared machine).
fn measure_steps(seconds: f64, mut step: impl FnMut() -> anyhow::Result<[f64; 3]>) -> anyhow::Result<([f64; 4], f64)> {
    step()?;
    let start = Instant::now();
    let mut phases: [Vec<f64>; 4] = Default::default();
    while phases[0].len() < 3 || start.elapsed().as_secs_f64() < seconds {
        let p = step()?;
        for i in 0..3 {
            phases[i].push(p[i]);
        }
        phases[3].push(p.iter().sum());
    }
    let fastest = minimum(&phases[3]);
    let [a, b, c, d] = phases;
    Ok(([median(a), median(b), median(c), median(d)], fastest))
}

/// Adds the network figures to `report`.
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let x = randn((BATCH, SIZES[0]), 1.0, &mut rng)?;
    let y = randn((BATCH, SIZES[4]), 1.0, &mut rng)?;

    let dense = DenseMlp::new(&mut rng)?;
    let dense_params = dense.params();
    let mut opt = MaskedAdam::new(AdamConfig::default());
    let ([_, _, _, dense_ms], dense_min) =
        measure_steps(seconds, || timed_step(|x| dense.forward(x), &dense_params, &mut opt, &x, &y))?;

    let mut masked = MaskedMlp::new("actor", &SIZES, Activation::Elu, &MaskConfig::default(), 0)?;
    masked.begin_task(0, &[])?;
    let mut opt = MaskedAdam::new(AdamConfig::default());
    let mut iteration = 0;
    let mut mask_rng = ChaCha8Rng::seed_from_u64(1);
    // begin_iteration runs once per PPO iteration (many minibatch steps), so it is timed apart.
    let t = Instant::now();
    masked.begin_iteration(iteration, &mut mask_rng)?;
    let begin_iteration_ms = t.elapsed().as_secs_f64() * 1e3;
    let ([fwd, bwd, optim, masked_ms], masked_min) = measure_steps(seconds, || {
        iteration += 1;
        let params = masked.params();
        timed_step(|x| masked.forward(x), &params, &mut opt, &x, &y)
    })?;
    masked.end_task(&mut mask_rng)?;
    let mut recall = Vec::new();
    let start = Instant::now();
    while recall.len() < 3 || start.elapsed().as_secs_f64() < seconds / 4.0 {
        let t = Instant::now();
        masked.forward_task(0, &x)?;
        recall.push(t.elapsed().as_secs_f64() * 1e3);
    }

    let r = |v: f64| serde_json::Value::from((v * 100.0).round() / 100.0);
    report.insert("actor_train_step_ms_dense".into(), r(dense_ms));
    report.insert("actor_train_step_ms_masked".into(), r(masked_ms));
    report.insert("actor_train_step_ms_dense_fastest".into(), r(dense_min));
    report.insert("actor_train_step_ms_masked_fastest".into(), r(masked_min));
    report.insert("actor_recall_forward_ms".into(), r(median(recall)));
    report.insert("actor_masked_forward_ms".into(), r(fwd));
    report.insert("actor_masked_backward_ms".into(), r(bwd));
    report.insert("actor_masked_optimiser_ms".into(), r(optim));
    report.insert("actor_masked_begin_iteration_ms".into(), r(begin_iteration_ms));
    report.insert("nn_threads".into(), serde_json::Value::from(candle_core::utils::get_num_threads()));
    Ok(())
}
