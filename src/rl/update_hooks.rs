//! How a continual-learning method reaches into a learner's update
//! (Avalanche's plugins, Continual World's `sac.py` hooks): [`UpdateHooks`],
//! every hook doing nothing by default ([`NoHooks`] is `ours` and `finetune`).
//! The PPO update (`rl/ppo.rs`) and the toy learner (`engine/toy_learner.rs`)
//! call them in this order per optimiser step:
//!
//! 1. the learner's own loss is differentiated: the task gradient g;
//! 2. [`UpdateHooks::adjust_gradients`] sees g (SI records it, A-GEM projects it);
//! 3. [`UpdateHooks::extra_loss`] (EWC's and SI's penalties, ER's rehearsal loss):
//!    its gradient is added to g;
//! 4. the learner clips the global norm and steps the optimiser;
//! 5. [`UpdateHooks::after_step`] sees the moved parameters.
//!
//! Around a task: [`UpdateHooks::on_task_start`] once its parameters exist,
//! [`UpdateHooks::on_task_end`] before they freeze, with an [`OutputSample`]
//! of the task's data (the last rollout's observations) to compute
//! importances from or to keep for rehearsal. While a later task trains, a
//! [`PolicyProbe`] runs an earlier task's policy on kept inputs,
//! differentiably (ER's loss, A-GEM's reference gradient). The method's state travels in checkpoints through
//! [`UpdateHooks::state`] / [`UpdateHooks::load_state`], so `--resume` goes on
//! exactly.

use super::metrics::Metrics;
use crate::nn::{Param, TaskId};
use candle_core::backprop::GradStore;
use candle_core::Tensor;
use std::collections::BTreeMap;

/// Samples of a task's inputs with which a method probes the policy (EWC's Fisher).
pub trait OutputSample {
    /// The number of samples.
    fn len(&self) -> usize;

    /// Whether there is none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample `i`'s policy output over its standard deviation, mu(x_i) / sigma: (outputs,),
    /// differentiable in the parameters that train. For a Gaussian policy with a
    /// state-independent sigma the Fisher of a parameter is sum_k (d(mu_k / sigma_k))^2.
    fn scaled_output(&self, i: usize) -> anyhow::Result<Tensor>;

    /// Sample `i` as a [`PolicyProbe`] takes it (the learner's own encoding of one input row),
    /// and the policy's output mu(x_i) on it now, for rehearsal.
    fn replay_row(&self, _i: usize) -> anyhow::Result<(Vec<f32>, Vec<f32>)> {
        anyhow::bail!("this learner keeps no inputs for rehearsal")
    }

    /// The policy's standard deviation per output (1 for a regression).
    fn sigma(&self) -> anyhow::Result<Vec<f32>> {
        anyhow::bail!("this learner has no policy standard deviation")
    }
}

/// Runs an earlier task's policy while a later one trains.
pub trait PolicyProbe {
    /// The means of task `task`'s policy (its own head, today's trunk) on `rows` inputs encoded
    /// as [`OutputSample::replay_row`] gives them: (rows, outputs), differentiable in the
    /// parameters that train.
    fn outputs(&self, task: TaskId, inputs: &[f32], rows: usize) -> anyhow::Result<Tensor>;
}

/// A probe for hooks that need none (tests; a learner without rehearsal).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProbe;

impl PolicyProbe for NoProbe {
    fn outputs(&self, _task: TaskId, _inputs: &[f32], _rows: usize) -> anyhow::Result<Tensor> {
        anyhow::bail!("this learner cannot run an earlier task's policy")
    }
}

/// The hooks of one continual-learning method; every hook defaults to nothing.
pub trait UpdateHooks: Send {
    /// A task's first iteration is about to run; `params` are the ones that train it.
    fn on_task_start(&mut self, _task: TaskId, _params: &[Param]) -> anyhow::Result<()> {
        Ok(())
    }

    /// The task gradient `grads` of `params`, before any penalty: record it or change it.
    fn adjust_gradients(
        &mut self,
        _params: &[Param],
        _grads: &mut GradStore,
        _probe: &dyn PolicyProbe,
    ) -> anyhow::Result<()> {
        Ok(())
    }

    /// A scalar loss of the parameters whose gradient joins the task gradient, and what it is
    /// worth as metrics (e.g. `losses/ewc_penalty`); None adds nothing.
    fn extra_loss(&mut self, _params: &[Param], _probe: &dyn PolicyProbe) -> anyhow::Result<Option<(Tensor, Metrics)>> {
        Ok(None)
    }

    /// The optimiser has stepped `params`.
    fn after_step(&mut self, _params: &[Param]) -> anyhow::Result<()> {
        Ok(())
    }

    /// The task is about to end; `params` still hold its final values, `sample` probes its policy.
    fn on_task_end(&mut self, _task: TaskId, _params: &[Param], _sample: &dyn OutputSample) -> anyhow::Result<()> {
        Ok(())
    }

    /// Everything the method accumulated, as named f32 tensors (saved with a checkpoint).
    fn state(&self) -> anyhow::Result<BTreeMap<String, Tensor>> {
        Ok(BTreeMap::new())
    }

    /// Restores [`Self::state`]'s tensors.
    fn load_state(&mut self, _state: &BTreeMap<String, Tensor>) -> anyhow::Result<()> {
        Ok(())
    }
}

/// No hooks: the learner's loss alone.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHooks;

impl UpdateHooks for NoHooks {}

/// Steps 2 and 3 of the order above on a learner's task gradient: the method adjusts `grads`,
/// then its extra loss' gradient is added. Returns the extra loss' metrics.
pub fn apply_hooks(
    hooks: &mut dyn UpdateHooks,
    params: &[Param],
    grads: &mut GradStore,
    probe: &dyn PolicyProbe,
) -> anyhow::Result<Metrics> {
    hooks.adjust_gradients(params, grads, probe)?;
    match hooks.extra_loss(params, probe)? {
        Some((loss, metrics)) => {
            grads.extend(loss.backward()?)?;
            Ok(metrics)
        }
        None => Ok(Metrics::new()),
    }
}
