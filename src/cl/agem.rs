//! `agem`: Averaged Gradient Episodic Memory (Chaudhry et al., ICLR 2019;
//! `facebookresearch/agem`), on the dense network (METHOD.md 3). The episodic
//! memory is ER's (`cl/replay.rs`: per finished task its inputs and the
//! policy's Gaussian on them). Each optimiser step draws a replay batch of
//! `batch_size` rows over the earlier tasks and takes the gradient g_ref of
//! its behaviour-cloning loss; when the task gradient g points against it
//! (g . g_ref < 0), g is projected onto the half-space where it does not:
//! `g <- g - (g . g_ref / g_ref . g_ref) g_ref`, so that (to first order) the
//! step does not increase the earlier tasks' loss. Nothing is added to the loss.
//!
//! Settings: `[method.agem]` `buffer_size` (1000 rows per task), `batch_size`
//! (256); `beta` is read but unused (A-GEM has no loss weight).

use super::er::ErConfig;
use super::method::ContinualMethod;
use super::replay::ReplayBuffers;
use crate::nn::{NetworkKind, Param, TaskId};
use crate::rl::{OutputSample, PolicyProbe, UpdateHooks};
use candle_core::backprop::GradStore;
use candle_core::Tensor;
use std::collections::BTreeMap;

/// The method `agem`.
#[derive(Debug, Clone)]
pub struct Agem {
    pub cfg: ErConfig,
}

impl ContinualMethod for Agem {
    fn name(&self) -> &str {
        "agem"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::json!({"buffer_size": self.cfg.buffer_size, "batch_size": self.cfg.batch_size})
    }

    fn network_kind(&self) -> NetworkKind {
        NetworkKind::Dense
    }

    fn update_hooks(&self) -> Box<dyn UpdateHooks> {
        Box::new(AgemHooks::new(self.cfg.clone()))
    }
}

/// A-GEM's state: the episodic memory, and how many steps were projected.
#[derive(Debug, Clone)]
pub struct AgemHooks {
    cfg: ErConfig,
    replay: ReplayBuffers,
    /// Optimiser steps whose gradient was projected (this process).
    pub projected: usize,
}

impl AgemHooks {
    /// Hooks with these settings and no task learned.
    pub fn new(cfg: ErConfig) -> Self {
        Self { cfg, replay: ReplayBuffers::default(), projected: 0 }
    }
}

/// sum over `params` of a . b of their tensors in `a` and `b`.
fn dot(params: &[Param], a: &GradStore, b: &GradStore) -> anyhow::Result<f64> {
    let mut total = 0.0;
    for p in params {
        if let (Some(x), Some(y)) = (a.get(p.var.as_tensor()), b.get(p.var.as_tensor())) {
            total += f64::from(x.mul(y)?.sum_all()?.to_scalar::<f32>()?);
        }
    }
    Ok(total)
}

/// A-GEM's projection of `grads` against `reference`, in place; whether it projected.
pub fn project(params: &[Param], grads: &mut GradStore, reference: &GradStore) -> anyhow::Result<bool> {
    let along = dot(params, grads, reference)?;
    if along >= 0.0 {
        return Ok(false);
    }
    let norm = dot(params, reference, reference)?;
    if norm <= 0.0 {
        return Ok(false);
    }
    for p in params {
        let t = p.var.as_tensor();
        if let Some(r) = reference.get(t) {
            let r = r.affine(along / norm, 0.0)?;
            let g = match grads.get(t) {
                Some(g) => g.sub(&r)?,
                None => r.neg()?,
            };
            grads.insert(t, g);
        }
    }
    Ok(true)
}

impl UpdateHooks for AgemHooks {
    fn on_task_start(&mut self, task: TaskId, _params: &[Param]) -> anyhow::Result<()> {
        self.replay.start(task);
        Ok(())
    }

    fn adjust_gradients(
        &mut self,
        params: &[Param],
        grads: &mut GradStore,
        probe: &dyn PolicyProbe,
    ) -> anyhow::Result<()> {
        let Some(loss) = self.replay.batch_loss(probe, self.cfg.batch_size)? else { return Ok(()) };
        if project(params, grads, &loss.backward()?)? {
            self.projected += 1;
        }
        Ok(())
    }

    fn after_step(&mut self, _params: &[Param]) -> anyhow::Result<()> {
        self.replay.stepped();
        Ok(())
    }

    fn on_task_end(&mut self, task: TaskId, _params: &[Param], sample: &dyn OutputSample) -> anyhow::Result<()> {
        self.replay.end(task, sample, self.cfg.buffer_size)
    }

    fn state(&self) -> anyhow::Result<BTreeMap<String, Tensor>> {
        self.replay.state("agem")
    }

    fn load_state(&mut self, state: &BTreeMap<String, Tensor>) -> anyhow::Result<()> {
        self.replay = ReplayBuffers::from_state("agem", state)?;
        Ok(())
    }
}
