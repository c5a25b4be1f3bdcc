//! A tiny learner with the real masked networks: one [`MaskedMlp`] regresses
//! a task-specific map x -> tanh(A_t x) (A_t drawn from the task's name), with
//! the masked Adam. It goes through the same task life cycle, recall and
//! checkpoints as the PPO agent, in milliseconds, so the session's behaviour
//! (pause, switches, resume, exact recall) is tested without a simulator.
//!
//! Shapes: x (batch, 8) -> y (batch, 2); hidden [32] ELU.

use super::learner::{Evaluation, Learner, TaskStart};
use crate::config::net::{Activation, MaskConfig};
use crate::nn::{
    checkpoint, mask_report, mask_views, transfer_lift, AdamConfig, LayerLift, LayerView, MaskReport, MaskedAdam,
    MaskedMlp, TaskId,
};
use crate::rl::{metric_names, EvalReport, Metrics};
use anyhow::Context;
use candle_core::{Device, Tensor};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::path::Path;

const IN: usize = 8;
const OUT: usize = 2;
const BATCH: usize = 32;
const EVAL_POINTS: usize = 64;

/// The toy regression learner.
#[derive(Debug)]
pub struct ToyLearner {
    net: MaskedMlp,
    optimizer: MaskedAdam,
    rng: ChaCha8Rng,
    /// (task id, its target matrix (OUT, IN) row-major) of the task in progress.
    current: Option<(TaskId, Vec<f32>)>,
    iteration: usize,
}

/// The task's target matrix A_t (OUT, IN), a pure function of its name.
fn target_matrix(name: &str) -> Vec<f32> {
    let digest = crate::util::sha256_hex(name.as_bytes());
    let seed = u64::from_str_radix(&digest[..16], 16).expect("hex digits");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..OUT * IN).map(|_| rng.gen_range(-1.5f32..1.5)).collect()
}

fn inputs(rng: &mut impl Rng, n: usize) -> Vec<f32> {
    (0..n * IN).map(|_| rng.gen_range(-1.0f32..1.0)).collect()
}

fn targets(a: &[f32], x: &[f32]) -> Vec<f32> {
    x.chunks_exact(IN)
        .flat_map(|row| (0..OUT).map(move |o| (0..IN).map(|i| a[o * IN + i] * row[i]).sum::<f32>().tanh()))
        .collect()
}

impl ToyLearner {
    /// A fresh network with `mask` settings, initialised from `seed`.
    pub fn new(mask: &MaskConfig, seed: u64) -> anyhow::Result<Self> {
        Ok(Self {
            net: MaskedMlp::new("toy", &[IN, 32, OUT], Activation::Elu, mask, seed)?,
            optimizer: MaskedAdam::new(AdamConfig { learning_rate: 1e-2, ..AdamConfig::default() }),
            rng: ChaCha8Rng::seed_from_u64(seed),
            current: None,
            iteration: 0,
        })
    }

    /// The network (for tests that inspect masks or weights).
    pub fn network(&self) -> &MaskedMlp {
        &self.net
    }
}

impl Learner for ToyLearner {
    fn begin_task(&mut self, start: &TaskStart) -> anyhow::Result<()> {
        self.net.set_mask_config(&start.mask)?;
        self.net.begin_task(start.task, &start.related)?;
        self.optimizer = MaskedAdam::new(AdamConfig { learning_rate: 1e-2, ..AdamConfig::default() });
        self.rng = ChaCha8Rng::seed_from_u64(start.seed);
        self.current = Some((start.task, target_matrix(&start.name)));
        self.iteration = 0;
        Ok(())
    }

    fn train_iteration(&mut self) -> anyhow::Result<Metrics> {
        let (_, a) = self.current.as_ref().context("train_iteration without begin_task")?;
        let a = a.clone();
        self.net.begin_iteration(self.iteration, &mut self.rng)?;
        let x = inputs(&mut self.rng, BATCH);
        let y = targets(&a, &x);
        let xt = Tensor::from_vec(x, (BATCH, IN), &Device::Cpu)?;
        let yt = Tensor::from_vec(y, (BATCH, OUT), &Device::Cpu)?;
        let mse = self.net.forward(&xt)?.sub(&yt)?.sqr()?.mean_all()?;
        let loss = mse.add(&self.net.soft_score_loss()?)?;
        let params = self.net.params();
        let grads = loss.backward()?;
        self.optimizer.step(&params, &grads)?;
        self.iteration += 1;
        let mse = f64::from(mse.to_scalar::<f32>()?);
        let mut m = Metrics::new();
        m.insert("losses/mse".into(), mse);
        m.insert(metric_names::PERFORMANCE.into(), 1.0 / (1.0 + mse));
        m.insert(metric_names::EPISODIC_RETURN.into(), -mse);
        Ok(m)
    }

    fn end_task(&mut self) -> anyhow::Result<()> {
        self.current.take().context("end_task without begin_task")?;
        self.net.end_task(&mut self.rng)
    }

    fn evaluate(&mut self, task: TaskId, name: &str, seed: u64) -> anyhow::Result<Evaluation> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let x = inputs(&mut rng, EVAL_POINTS);
        let y = targets(&target_matrix(name), &x);
        let pred: Vec<f32> = self
            .net
            .forward_task(task, &Tensor::from_vec(x, (EVAL_POINTS, IN), &Device::Cpu)?)?
            .flatten_all()?
            .to_vec1()?;
        let err: Vec<f64> = pred.iter().zip(&y).map(|(p, t)| f64::from(p - t)).collect();
        let mse = err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64;
        let abs_of = |o: usize| err.iter().skip(o).step_by(OUT).map(|e| e.abs()).sum::<f64>() / EVAL_POINTS as f64;
        let report = EvalReport {
            task: name.to_string(),
            episodes: EVAL_POINTS,
            mean_return: -mse,
            lin_vel_err: abs_of(0),
            ang_vel_err: abs_of(1),
            fall_rate: 0.0,
            survival_s: 0.0,
            return_std: None,
            seed,
            physics_resets: 0,
        };
        Ok(Evaluation { report, performance: 1.0 / (1.0 + mse) })
    }

    fn mask_report(&self, tasks: &[String]) -> MaskReport {
        mask_report(tasks, &[&self.net])
    }

    fn mask_views(&self, task: TaskId) -> Vec<LayerView> {
        mask_views(&[&self.net], task)
    }

    fn transfer_lift(&self, related: &[TaskId]) -> Vec<LayerLift> {
        transfer_lift(&[&self.net], related)
    }

    fn save(&self, dir: &Path, tasks: &[String]) -> anyhow::Result<()> {
        anyhow::ensure!(self.current.is_none(), "the toy learner saves between tasks only");
        checkpoint::save_policy(dir, tasks, &[&self.net], &BTreeMap::new(), &serde_json::json!({"learner": "toy"}))
    }

    fn load(&mut self, dir: &Path) -> anyhow::Result<Vec<String>> {
        let mut policy = checkpoint::load_policy(dir)?;
        anyhow::ensure!(
            policy.config.get("learner").and_then(|v| v.as_str()) == Some("toy"),
            "{}: not a toy-learner checkpoint",
            dir.display()
        );
        let net = policy.networks.pop().with_context(|| format!("{}: no network", dir.display()))?;
        anyhow::ensure!(
            net.sizes() == self.net.sizes(),
            "{}: network sizes {:?}, expected {:?}",
            dir.display(),
            net.sizes(),
            self.net.sizes()
        );
        self.net = net;
        self.current = None;
        Ok(policy.tasks)
    }
}
