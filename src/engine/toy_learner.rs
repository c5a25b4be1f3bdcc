//! A tiny learner with the real masked networks: one [`MaskedMlp`] regresses
//! a task-specific map x -> tanh(A_t x) (A_t drawn from the task's name), with
//! the masked Adam. It goes through the same task life cycle, recall and
//! checkpoints as the PPO agent, in milliseconds, so the session's behaviour
//! (pause, switches, resume, exact recall) is tested without a simulator.
//! The network is masked (`ours`) or dense (the baselines, whose update hooks
//! it calls as the PPO update does: `rl/update_hooks.rs`).
//!
//! Shapes: x (batch, 8) -> y (batch, 2); hidden [32] ELU.

use super::learner::{Evaluation, Learner, TaskStart};
use crate::config::net::{Activation, MaskConfig};
use crate::nn::{
    checkpoint, mask_report, mask_views, transfer_lift, AdamConfig, DenseMlp, LayerLift, LayerView, MaskReport,
    MaskedAdam, MaskedMlp, Network, NetworkKind, TaskId,
};
use crate::rl::{
    apply_hooks, layer_metrics, metric_names, network_plasticity, EvalReport, Metrics, NoHooks, OutputSample,
    PolicyProbe, UpdateHooks,
};
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
pub struct ToyLearner {
    net: Network,
    /// The method inside the update.
    hooks: Box<dyn UpdateHooks>,
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
        Self::new_of_kind(mask, seed, NetworkKind::Masked)
    }

    /// [`Self::new`] with a network of `kind` (dense: a shared trunk, one head per task).
    pub fn new_of_kind(mask: &MaskConfig, seed: u64, kind: NetworkKind) -> anyhow::Result<Self> {
        let sizes = [IN, 32, OUT];
        let net = match kind {
            NetworkKind::Masked => MaskedMlp::new("toy", &sizes, Activation::Elu, mask, seed)?.into(),
            NetworkKind::Dense => DenseMlp::new("toy", &sizes, Activation::Elu, seed)?.into(),
        };
        Ok(Self {
            net,
            hooks: Box::new(NoHooks),
            optimizer: MaskedAdam::new(AdamConfig { learning_rate: 1e-2, ..AdamConfig::default() }),
            rng: ChaCha8Rng::seed_from_u64(seed),
            current: None,
            iteration: 0,
        })
    }

    /// The learner with a method's update hooks (before any task or load).
    pub fn with_hooks(mut self, hooks: Box<dyn UpdateHooks>) -> Self {
        self.hooks = hooks;
        self
    }

    /// The network (for tests that inspect masks or weights).
    pub fn network(&self) -> &Network {
        &self.net
    }
}

impl Learner for ToyLearner {
    fn begin_task(&mut self, start: &TaskStart) -> anyhow::Result<()> {
        self.net.set_mask_config(&start.mask)?;
        self.net.begin_task(start.task, &start.related)?;
        self.hooks.on_task_start(start.task, &self.net.params())?;
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
        let layers = layer_metrics(&self.net.layer_stats()?);
        let x = inputs(&mut self.rng, BATCH);
        let y = targets(&a, &x);
        let xt = Tensor::from_vec(x, (BATCH, IN), &Device::Cpu)?;
        let yt = Tensor::from_vec(y, (BATCH, OUT), &Device::Cpu)?;
        // Observations only: the batch's activations with the iteration's masks.
        let plasticity = network_plasticity(&self.net, &self.net.frozen_weights(None)?, &xt)?;
        let mse = self.net.forward(&xt)?.sub(&yt)?.sqr()?.mean_all()?;
        let loss = mse.add(&self.net.soft_score_loss()?)?;
        let params = self.net.params();
        let mut grads = loss.backward()?;
        let mut m = apply_hooks(self.hooks.as_mut(), &params, &mut grads, &ToyProbe { net: &self.net })?;
        self.optimizer.step(&params, &grads)?;
        self.hooks.after_step(&params)?;
        self.iteration += 1;
        let mse = f64::from(mse.to_scalar::<f32>()?);
        m.extend(layers);
        m.extend(plasticity);
        m.insert("losses/mse".into(), mse);
        m.insert(metric_names::PERFORMANCE.into(), 1.0 / (1.0 + mse));
        m.insert(metric_names::EPISODIC_RETURN.into(), -mse);
        Ok(m)
    }

    fn end_task(&mut self) -> anyhow::Result<()> {
        let (task, _) = self.current.take().context("end_task without begin_task")?;
        let sample = ToySample { net: &self.net, x: inputs(&mut ChaCha8Rng::seed_from_u64(task as u64), EVAL_POINTS) };
        self.hooks.on_task_end(task, &self.net.params(), &sample)?;
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
        mask_views(&self.net.as_masked().into_iter().collect::<Vec<_>>(), task)
    }

    fn transfer_lift(&self, related: &[TaskId]) -> Vec<LayerLift> {
        transfer_lift(&self.net.as_masked().into_iter().collect::<Vec<_>>(), related)
    }

    fn save(&self, dir: &Path, tasks: &[String]) -> anyhow::Result<()> {
        anyhow::ensure!(self.current.is_none(), "the toy learner saves between tasks only");
        let extras: BTreeMap<String, Tensor> = self
            .hooks
            .state()?
            .into_iter()
            .map(|(k, v)| (format!("{}{k}", super::ppo_learner::METHOD_PREFIX), v))
            .collect();
        checkpoint::save_policy(dir, tasks, &[&self.net], &extras, &serde_json::json!({"learner": "toy"}))
    }

    fn load(&mut self, dir: &Path) -> anyhow::Result<Vec<String>> {
        let mut policy = checkpoint::load_policy(dir)?;
        anyhow::ensure!(
            policy.config.get("learner").and_then(|v| v.as_str()) == Some("toy"),
            "{}: not a toy-learner checkpoint",
            dir.display()
        );
        let mut net = policy.networks.pop().with_context(|| format!("{}: no network", dir.display()))?;
        if self.net.kind() == NetworkKind::Dense {
            net = net.into_dense()?; // a masked base policy starts a dense method as its dense equivalent
        }
        anyhow::ensure!(
            net.kind() == self.net.kind(),
            "{}: the network is {:?}, this run's method trains a {:?} one",
            dir.display(),
            net.kind(),
            self.net.kind()
        );
        anyhow::ensure!(
            net.sizes() == self.net.sizes(),
            "{}: network sizes {:?}, expected {:?}",
            dir.display(),
            net.sizes(),
            self.net.sizes()
        );
        self.hooks
            .load_state(&super::ppo_learner::method_state(&policy.extras))
            .with_context(|| format!("{}: the method's state", dir.display()))?;
        self.net = net;
        self.current = None;
        Ok(policy.tasks)
    }
}

/// Points of the task's input distribution through the network in training (sigma 1): the
/// sample a method probes the toy task's outputs with.
struct ToySample<'a> {
    net: &'a Network,
    /// (EVAL_POINTS, IN) row-major.
    x: Vec<f32>,
}

impl OutputSample for ToySample<'_> {
    fn len(&self) -> usize {
        self.x.len() / IN
    }

    fn scaled_output(&self, i: usize) -> anyhow::Result<Tensor> {
        anyhow::ensure!(i < self.len(), "sample {i} of {}", self.len());
        let x = Tensor::from_slice(&self.x[i * IN..(i + 1) * IN], (1, IN), &Device::Cpu)?;
        Ok(self.net.forward(&x)?.squeeze(0)?)
    }

    fn replay_row(&self, i: usize) -> anyhow::Result<(Vec<f32>, Vec<f32>)> {
        let out = self.scaled_output(i)?.detach().to_vec1()?;
        Ok((self.x[i * IN..(i + 1) * IN].to_vec(), out))
    }

    fn sigma(&self) -> anyhow::Result<Vec<f32>> {
        Ok(vec![1.0; OUT])
    }
}

/// The toy network running any trained task (its head, today's trunk), differentiably.
struct ToyProbe<'a> {
    net: &'a Network,
}

impl PolicyProbe for ToyProbe<'_> {
    fn outputs(&self, task: TaskId, inputs: &[f32], rows: usize) -> anyhow::Result<Tensor> {
        self.net.forward_of_task(task, &Tensor::from_slice(inputs, (rows, IN), &Device::Cpu)?)
    }
}
