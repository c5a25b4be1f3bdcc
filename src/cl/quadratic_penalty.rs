//! The quadratic penalty EWC and SI share (METHOD.md 3):
//! `weight * sum_i Omega_i (theta_i - theta*_i)^2` over the regularised
//! parameters, with an importance Omega (EWC: the Fisher; SI: the path
//! integral's score) accumulated over tasks and the anchor theta* the values
//! when the last task ended.
//!
//! Which parameters are regularised: the shared trunk of the networks the
//! policy acts with (the actor, the CENet encoder; the toy learner's only
//! network). Not per-task heads (`*.head.*`, a task's own), not `log_std`
//! (per task), not the critic or the CENet decoder (only training uses them).

use crate::nn::Param;
use candle_core::{Device, Tensor};
use std::collections::BTreeMap;

/// Whether a parameter is part of the shared trunk a penalty protects.
pub fn is_regularised(name: &str) -> bool {
    !name.contains(".head.")
        && name != "log_std"
        && !name.starts_with("critic.")
        && !name.starts_with("cenet_decoder.")
        && !name.ends_with(".score")
        && !name.ends_with(".log_sigma")
}

/// One parameter's importance and anchor, shaped like the parameter.
#[derive(Debug, Clone)]
struct Term {
    importance: Tensor,
    anchor: Tensor,
}

/// Importances and anchors per parameter name.
#[derive(Debug, Clone, Default)]
pub struct QuadraticPenalty {
    terms: BTreeMap<String, Term>,
}

impl QuadraticPenalty {
    /// Whether no task has added an importance yet.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Adds `importance` to the parameter's accumulated importance and makes `anchor` its anchor.
    pub fn accumulate(&mut self, name: &str, importance: Tensor, anchor: Tensor) -> anyhow::Result<()> {
        // Both are constants of the penalty: detached, so that no gradient flows back through
        // how they were computed (an importance computed from a copy of the live parameter
        // would otherwise pass a gradient to it, unlike the same importance read from a checkpoint).
        let importance = importance.detach();
        let importance = match self.terms.get(name) {
            Some(t) => {
                anyhow::ensure!(
                    t.importance.dims() == importance.dims(),
                    "{name}: importance of shape {:?}, the accumulated one is {:?}",
                    importance.dims(),
                    t.importance.dims()
                );
                t.importance.add(&importance)?.detach()
            }
            None => importance,
        };
        self.terms.insert(name.to_string(), Term { importance, anchor: anchor.detach() });
        Ok(())
    }

    /// Makes `importance` the parameter's importance (not added to the old one) and `anchor` its anchor.
    pub fn replace(&mut self, name: &str, importance: Tensor, anchor: Tensor) -> anyhow::Result<()> {
        self.terms.remove(name);
        self.accumulate(name, importance, anchor)
    }

    /// The accumulated importance of a parameter.
    pub fn importance(&self, name: &str) -> Option<&Tensor> {
        self.terms.get(name).map(|t| &t.importance)
    }

    /// The anchor of a parameter.
    pub fn anchor(&self, name: &str) -> Option<&Tensor> {
        self.terms.get(name).map(|t| &t.anchor)
    }

    /// `weight * sum Omega (theta - theta*)^2` over `params` that have a term, differentiable in
    /// them; None when none has.
    pub fn loss(&self, params: &[Param], weight: f64) -> anyhow::Result<Option<Tensor>> {
        let mut total: Option<Tensor> = None;
        for p in params {
            let Some(t) = self.terms.get(&p.name) else { continue };
            let theta = p.var.as_tensor();
            anyhow::ensure!(
                theta.dims() == t.anchor.dims(),
                "{}: the parameter has shape {:?}, its anchor {:?}",
                p.name,
                theta.dims(),
                t.anchor.dims()
            );
            let term = theta.sub(&t.anchor)?.sqr()?.mul(&t.importance)?.sum_all()?;
            total = Some(match total {
                Some(s) => s.add(&term)?,
                None => term,
            });
        }
        Ok(match total {
            Some(t) => Some(t.affine(weight, 0.0)?),
            None => None,
        })
    }

    /// [`Self::loss`] with its value as the metric `name` (an [`crate::rl::UpdateHooks::extra_loss`]).
    pub fn extra_loss(
        &self,
        params: &[Param],
        weight: f64,
        name: &str,
    ) -> anyhow::Result<Option<(Tensor, crate::rl::Metrics)>> {
        let Some(loss) = self.loss(params, weight)? else { return Ok(None) };
        let value = f64::from(loss.to_scalar::<f32>()?);
        Ok(Some((loss, crate::rl::Metrics::from([(name.to_string(), value)]))))
    }

    /// The terms as named tensors: "{prefix}.{param}.importance" and ".anchor".
    pub fn state(&self, prefix: &str) -> BTreeMap<String, Tensor> {
        let mut out = BTreeMap::new();
        for (name, t) in &self.terms {
            out.insert(format!("{prefix}.{name}.importance"), t.importance.clone());
            out.insert(format!("{prefix}.{name}.anchor"), t.anchor.clone());
        }
        out
    }

    /// The terms [`Self::state`] wrote under `prefix` (other keys are ignored).
    pub fn from_state(prefix: &str, state: &BTreeMap<String, Tensor>) -> anyhow::Result<Self> {
        let mut terms = BTreeMap::new();
        let head = format!("{prefix}.");
        for (key, importance) in state {
            let Some(name) = key.strip_prefix(&head).and_then(|k| k.strip_suffix(".importance")) else { continue };
            let anchor = state
                .get(&format!("{head}{name}.anchor"))
                .ok_or_else(|| anyhow::anyhow!("{key} has no {head}{name}.anchor beside it"))?;
            anyhow::ensure!(
                anchor.dims() == importance.dims(),
                "{key} has shape {:?}, its anchor {:?}",
                importance.dims(),
                anchor.dims()
            );
            let to_cpu = |t: &Tensor| t.to_device(&Device::Cpu);
            terms.insert(name.to_string(), Term { importance: to_cpu(importance)?, anchor: to_cpu(anchor)? });
        }
        Ok(Self { terms })
    }
}
