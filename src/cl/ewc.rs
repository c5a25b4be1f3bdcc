//! `ewc`: Elastic Weight Consolidation (Kirkpatrick et al. 2017), as
//! Continual World implements it for RL (Wolczyk et al. 2021,
//! `continualworld/methods/ewc.py`), on the dense network (METHOD.md 3).
//!
//! Penalty added to the loss of every later task:
//! `lambda * sum_i F_i (theta_i - theta*_i)^2` over the shared trunk
//! (`cl/quadratic_penalty.rs`), with theta* the values at the end of the last
//! task and F accumulated (summed) over the tasks so far.
//!
//! Fisher of the Gaussian policy at a task's end, per parameter, averaged over
//! `fisher_samples` rows of the task's last rollout:
//! `F_i = mean_x sum_k ((d mu_k / d theta_i)^2 + 2 (d sigma_k / d theta_i)^2) / sigma_k^2`.
//! sigma is state-independent and per task here (not a trunk parameter), so
//! its term is zero and `F_i = mean_x sum_k (d (mu_k / sigma_k) / d theta_i)^2`,
//! one backward per sample and action dimension.
//!
//! Settings: `[method.ewc]` `lambda` (1e4, Continual World's value),
//! `fisher_samples` (1024).

use super::method::ContinualMethod;
use super::quadratic_penalty::{is_regularised, QuadraticPenalty};
use crate::config::bounds::{self, NON_NEGATIVE};
use crate::config::ppo::MAX_ROLLOUT;
use crate::nn::{NetworkKind, Param, TaskId};
use crate::rl::{Metrics, OutputSample, PolicyProbe, UpdateHooks};
use candle_core::Tensor;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `[method.ewc]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EwcConfig {
    /// Weight lambda of the penalty.
    pub lambda: f64,
    /// Rollout rows the Fisher is averaged over at a task's end (evenly spaced).
    pub fisher_samples: usize,
}

impl Default for EwcConfig {
    fn default() -> Self {
        Self { lambda: 1e4, fisher_samples: 1024 }
    }
}

impl EwcConfig {
    /// Errors name the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        bounds::check("[method.ewc] lambda", self.lambda, NON_NEGATIVE)?;
        bounds::check_count("[method.ewc] fisher_samples", self.fisher_samples, 1, MAX_ROLLOUT)
    }
}

/// The method `ewc`.
#[derive(Debug, Clone)]
pub struct Ewc {
    pub cfg: EwcConfig,
}

impl ContinualMethod for Ewc {
    fn name(&self) -> &str {
        "ewc"
    }

    fn network_kind(&self) -> NetworkKind {
        NetworkKind::Dense
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.cfg).unwrap_or_default()
    }

    fn update_hooks(&self) -> Box<dyn UpdateHooks> {
        Box::new(EwcHooks { cfg: self.cfg.clone(), penalty: QuadraticPenalty::default() })
    }
}

/// EWC's state: the accumulated Fisher and the anchor.
#[derive(Debug, Clone)]
pub struct EwcHooks {
    cfg: EwcConfig,
    penalty: QuadraticPenalty,
}

impl EwcHooks {
    /// Hooks with these settings and no task learned.
    pub fn new(cfg: EwcConfig) -> Self {
        Self { cfg, penalty: QuadraticPenalty::default() }
    }

    /// The accumulated importances and anchors.
    pub fn penalty(&self) -> &QuadraticPenalty {
        &self.penalty
    }
}

/// The diagonal Fisher of every regularised parameter in `params`, averaged over `samples`
/// rows of `sample` spread evenly over it: `mean_x sum_k (d out_k / d theta)^2`.
pub fn diagonal_fisher(
    params: &[Param],
    sample: &dyn OutputSample,
    samples: usize,
) -> anyhow::Result<BTreeMap<String, Tensor>> {
    let chosen: Vec<&Param> = params.iter().filter(|p| is_regularised(&p.name)).collect();
    let mut sums: Vec<Tensor> =
        chosen.iter().map(|p| p.var.as_tensor().zeros_like()).collect::<candle_core::Result<_>>()?;
    let n = samples.min(sample.len());
    anyhow::ensure!(n > 0, "no sample to compute the Fisher from");
    for j in 0..n {
        let i = j * sample.len() / n;
        let out = sample.scaled_output(i)?;
        for k in 0..out.dim(0)? {
            let grads = out.get(k)?.backward()?;
            for (sum, p) in sums.iter_mut().zip(&chosen) {
                if let Some(g) = grads.get(p.var.as_tensor()) {
                    *sum = sum.add(&g.sqr()?)?;
                }
            }
        }
    }
    chosen.iter().zip(sums).map(|(p, s)| Ok((p.name.clone(), s.affine(1.0 / n as f64, 0.0)?))).collect()
}

impl UpdateHooks for EwcHooks {
    fn extra_loss(&mut self, params: &[Param], _probe: &dyn PolicyProbe) -> anyhow::Result<Option<(Tensor, Metrics)>> {
        self.penalty.extra_loss(params, self.cfg.lambda, "losses/ewc_penalty")
    }

    fn on_task_end(&mut self, _task: TaskId, params: &[Param], sample: &dyn OutputSample) -> anyhow::Result<()> {
        let fisher = diagonal_fisher(params, sample, self.cfg.fisher_samples)?;
        for p in params.iter().filter(|p| fisher.contains_key(&p.name)) {
            self.penalty.accumulate(&p.name, fisher[&p.name].clone(), p.var.as_tensor().copy()?.detach())?;
        }
        Ok(())
    }

    fn state(&self) -> anyhow::Result<BTreeMap<String, Tensor>> {
        Ok(self.penalty.state("ewc"))
    }

    fn load_state(&mut self, state: &BTreeMap<String, Tensor>) -> anyhow::Result<()> {
        self.penalty = QuadraticPenalty::from_state("ewc", state)?;
        Ok(())
    }
}
