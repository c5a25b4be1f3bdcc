//! Shared by the nn integration tests: ten synthetic regression tasks (random
//! linear targets y = A_t x) and a small training loop over a MaskedMlp; and,
//! for the tests of the mask rules on a 6-in, 3-out MaskedMlp, a fixed input
//! batch and a few steps of a task towards a constant target.
#![allow(dead_code)]

use candle_core::{Device, Tensor};
use quadcl::nn::{Activation, AdamConfig, MaskConfig, MaskedAdam, MaskedMlp, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

pub const IN: usize = 8;
pub const OUT: usize = 4;

/// A regression task: y = A x with A (OUT, IN) ~ N(0, 1/IN).
pub struct LinearTask {
    pub a: Tensor,
}

pub fn tasks(n: usize, seed: u64) -> Vec<LinearTask> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let a: Vec<f32> =
                (0..IN * OUT).map(|_| rng.sample::<f32, _>(StandardNormal) / (IN as f32).sqrt()).collect();
            LinearTask { a: Tensor::from_vec(a, (OUT, IN), &Device::Cpu).unwrap() }
        })
        .collect()
}

pub fn inputs(batch: usize, rng: &mut impl Rng) -> Tensor {
    let x: Vec<f32> = (0..batch * IN).map(|_| rng.sample(StandardNormal)).collect();
    Tensor::from_vec(x, (batch, IN), &Device::Cpu).unwrap()
}

pub fn targets(task: &LinearTask, x: &Tensor) -> Tensor {
    x.matmul(&task.a.t().unwrap()).unwrap()
}

pub fn mse(a: &Tensor, b: &Tensor) -> f32 {
    a.sub(b).unwrap().sqr().unwrap().mean_all().unwrap().to_scalar::<f32>().unwrap()
}

pub fn small_mlp(cfg: &MaskConfig, seed: u64) -> MaskedMlp {
    MaskedMlp::new("net", &[IN, 64, 64, OUT], Activation::Elu, cfg, seed).unwrap()
}

/// Trains `task` for `steps` iterations (begin_task .. end_task); returns the recall loss on a probe batch.
pub fn train_task(
    net: &mut MaskedMlp,
    id: TaskId,
    task: &LinearTask,
    steps: usize,
    lr: f64,
    rng: &mut ChaCha8Rng,
) -> f32 {
    net.begin_task(id, &[]).unwrap();
    let mut opt = MaskedAdam::new(AdamConfig { learning_rate: lr, ..AdamConfig::default() });
    for it in 0..steps {
        net.begin_iteration(it, rng).unwrap();
        let x = inputs(64, rng);
        let y = targets(task, &x);
        let loss = net.forward(&x).unwrap().sub(&y).unwrap().sqr().unwrap().mean_all().unwrap();
        let loss = loss.add(&net.soft_score_loss().unwrap()).unwrap();
        let params = net.params();
        let grads = loss.backward().unwrap();
        opt.step(&params, &grads).unwrap();
    }
    net.end_task(rng).unwrap();
    let x = inputs(256, &mut ChaCha8Rng::seed_from_u64(999));
    mse(&net.forward_task(id, &x).unwrap(), &targets(task, &x))
}

pub fn probe() -> Tensor {
    inputs(32, &mut ChaCha8Rng::seed_from_u64(12345))
}

pub fn bits(t: &Tensor) -> Vec<u32> {
    t.flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()).collect()
}

/// A (8, 6) batch in [-1, 1) from `seed`.
pub fn input(seed: u64) -> Tensor {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let v: Vec<f32> = (0..8 * 6).map(|_| rng.gen_range(-1.0f32..1.0)).collect();
    Tensor::from_vec(v, (8, 6), &Device::Cpu).unwrap()
}

/// `iterations` Adam steps of a squared loss towards `task + 1` on the task in progress of a
/// 6-in, 3-out network, the masks drawn from `rng`.
pub fn train_steps(net: &mut MaskedMlp, task: usize, iterations: usize, rng: &mut ChaCha8Rng) {
    let mut adam = MaskedAdam::new(Default::default());
    for it in 0..iterations {
        net.begin_iteration(it, rng).unwrap();
        let target = Tensor::full(task as f32 + 1.0, (8, 3), &Device::Cpu).unwrap();
        let loss = net.forward(&input(it as u64)).unwrap().sub(&target).unwrap().sqr().unwrap().mean_all().unwrap();
        adam.step(&net.params(), &loss.backward().unwrap()).unwrap();
    }
}
