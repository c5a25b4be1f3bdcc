//! The rehearsal data ER and A-GEM share (METHOD.md 3): per finished task a
//! buffer of its inputs (as the learner encodes them, `OutputSample::replay_row`)
//! with the policy's means on them and its sigma when the task ended; and the
//! behaviour-cloning loss that pulls today's network back to them, the KL
//! from the stored Gaussian to the current one at the task's own sigma:
//! `KL = sum_k (mu_k(x) - mu*_k)^2 / (2 sigma*_k^2)`, averaged over rows and
//! then over tasks.
//!
//! Replay batches are drawn from a stream seeded by the step count alone, so
//! a resumed run draws the same rows without saving a random state.

use crate::nn::checkpoint::{integer_tensor, tensor_integer};
use crate::nn::TaskId;
use crate::rl::{OutputSample, PolicyProbe};
use candle_core::{Device, Tensor};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// One finished task's rehearsal data.
#[derive(Debug, Clone)]
pub struct TaskReplay {
    pub task: TaskId,
    /// (rows, width) row-major.
    pub inputs: Vec<f32>,
    /// (rows, outputs) row-major: the policy's means when the task ended.
    pub means: Vec<f32>,
    /// (outputs,) the policy's sigma when the task ended.
    pub sigma: Vec<f32>,
}

impl TaskReplay {
    /// The number of rows.
    pub fn rows(&self) -> usize {
        self.means.len() / self.sigma.len().max(1)
    }

    fn width(&self) -> usize {
        self.inputs.len() / self.rows().max(1)
    }
}

/// Every finished task's rehearsal data, the step count that seeds the batches, and the
/// task in training (whose own buffer, when it repeats, is not replayed).
#[derive(Debug, Clone, Default)]
pub struct ReplayBuffers {
    pub tasks: Vec<TaskReplay>,
    pub steps: usize,
    pub current: Option<TaskId>,
}

impl ReplayBuffers {
    /// A task starts training.
    pub fn start(&mut self, task: TaskId) {
        self.current = Some(task);
    }

    /// An optimiser step was taken (the next batch is another).
    pub fn stepped(&mut self) {
        self.steps += 1;
    }

    /// The task in training ends: up to `size` rows of `sample` are kept for it.
    pub fn end(&mut self, task: TaskId, sample: &dyn OutputSample, size: usize) -> anyhow::Result<()> {
        self.current = None;
        self.store(task, sample, size)
    }

    /// [`Self::clone_loss`] on a batch of `batch` rows, leaving out the task in training.
    pub fn batch_loss(&self, probe: &dyn PolicyProbe, batch: usize) -> anyhow::Result<Option<Tensor>> {
        self.clone_loss(probe, batch, self.current)
    }

    /// Keeps up to `size` rows of `sample`, evenly spaced, for `task` (replacing an older buffer of it).
    pub fn store(&mut self, task: TaskId, sample: &dyn OutputSample, size: usize) -> anyhow::Result<()> {
        let n = size.min(sample.len());
        anyhow::ensure!(n > 0, "no sample of task {task} to keep for rehearsal");
        let (mut inputs, mut means) = (Vec::new(), Vec::new());
        for j in 0..n {
            let (x, mu) = sample.replay_row(j * sample.len() / n)?;
            inputs.extend(x);
            means.extend(mu);
        }
        self.tasks.retain(|r| r.task != task);
        self.tasks.push(TaskReplay { task, inputs, means, sigma: sample.sigma()? });
        self.tasks.sort_by_key(|r| r.task); // the order batches are drawn in, as a restored state has it
        Ok(())
    }

    /// The behaviour-cloning loss on a batch of about `batch` rows spread over the tasks'
    /// buffers (`skip`: the task in training, if it repeats one); None without any buffer.
    pub fn clone_loss(
        &self,
        probe: &dyn PolicyProbe,
        batch: usize,
        skip: Option<TaskId>,
    ) -> anyhow::Result<Option<Tensor>> {
        let tasks: Vec<&TaskReplay> = self.tasks.iter().filter(|r| Some(r.task) != skip).collect();
        if tasks.is_empty() {
            return Ok(None);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0x5e_91a7 ^ self.steps as u64);
        let per_task = (batch / tasks.len()).max(1);
        let mut total: Option<Tensor> = None;
        for r in &tasks {
            let (rows, width, outs) = (r.rows(), r.width(), r.sigma.len());
            let picked: Vec<usize> = (0..per_task).map(|_| rng.gen_range(0..rows)).collect();
            let inputs: Vec<f32> =
                picked.iter().flat_map(|&i| r.inputs[i * width..(i + 1) * width].iter().copied()).collect();
            let target: Vec<f32> =
                picked.iter().flat_map(|&i| r.means[i * outs..(i + 1) * outs].iter().copied()).collect();
            let target = Tensor::from_vec(target, (per_task, outs), &Device::Cpu)?;
            let scale: Vec<f32> = r.sigma.iter().map(|s| 1.0 / (2.0 * s * s)).collect();
            let scale = Tensor::from_vec(scale, (1, outs), &Device::Cpu)?;
            let mu = probe.outputs(r.task, &inputs, per_task)?;
            let kl = mu.sub(&target)?.sqr()?.broadcast_mul(&scale)?.sum(1)?.mean_all()?;
            total = Some(match total {
                Some(t) => t.add(&kl)?,
                None => kl,
            });
        }
        Ok(total.map(|t| t.affine(1.0 / tasks.len() as f64, 0.0)).transpose()?)
    }

    /// The buffers and step count as named tensors under `prefix`.
    pub fn state(&self, prefix: &str) -> anyhow::Result<BTreeMap<String, Tensor>> {
        let mut out = BTreeMap::new();
        for r in &self.tasks {
            let (rows, outs) = (r.rows(), r.sigma.len());
            let t = r.task;
            out.insert(
                format!("{prefix}.t{t}.inputs"),
                Tensor::from_slice(&r.inputs, (rows, r.width()), &Device::Cpu)?,
            );
            out.insert(format!("{prefix}.t{t}.means"), Tensor::from_slice(&r.means, (rows, outs), &Device::Cpu)?);
            out.insert(format!("{prefix}.t{t}.sigma"), Tensor::from_slice(&r.sigma, outs, &Device::Cpu)?);
        }
        out.insert(format!("{prefix}.steps"), integer_tensor(self.steps as u64)?);
        Ok(out)
    }

    /// The buffers [`Self::state`] wrote under `prefix`; errors name the tensor.
    pub fn from_state(prefix: &str, state: &BTreeMap<String, Tensor>) -> anyhow::Result<Self> {
        let mut tasks = Vec::new();
        let head = format!("{prefix}.t");
        for key in state.keys() {
            let Some(t) = key.strip_prefix(&head).and_then(|k| k.strip_suffix(".sigma")) else { continue };
            let task: TaskId = t.parse().map_err(|_| anyhow::anyhow!("{key}: not a task's replay"))?;
            let get = |what: &str| -> anyhow::Result<&Tensor> {
                state
                    .get(&format!("{head}{task}.{what}"))
                    .ok_or_else(|| anyhow::anyhow!("{key} has no {what} beside it"))
            };
            let (inputs, means, sigma) = (get("inputs")?, get("means")?, &state[key]);
            let flat = |t: &Tensor| -> anyhow::Result<Vec<f32>> { Ok(t.flatten_all()?.to_vec1()?) };
            let replay = TaskReplay { task, inputs: flat(inputs)?, means: flat(means)?, sigma: flat(sigma)? };
            anyhow::ensure!(
                means.dims().len() == 2
                    && means.dims()[1] == replay.sigma.len()
                    && inputs.dims().first() == means.dims().first(),
                "{key}: the replay of task {task} has inputs {:?}, means {:?}, sigma {:?}",
                inputs.dims(),
                means.dims(),
                sigma.dims()
            );
            tasks.push(replay);
        }
        let key = format!("{prefix}.steps");
        let steps = state.get(&key).map(|t| tensor_integer(t, &key)).transpose()?.unwrap_or(0) as usize;
        tasks.sort_by_key(|r| r.task);
        Ok(Self { tasks, steps, current: None })
    }
}
