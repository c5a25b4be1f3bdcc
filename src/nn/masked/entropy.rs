//! The plasticity entropy term of a [`MaskedLinear`] (METHOD.md 2.3): during a new
//! task's first E iterations, -beta_H * H on the soft scores (sigma widens, so the
//! sampled masks explore), or beta_H handed to the learner to add to its
//! action-distribution entropy bonus (`entropy_target = "action"`, Figure 8's
//! caption). After E iterations sigma decays (`iteration.rs`).

use super::MaskedLinear;
use crate::config::net::EntropyTarget;
use candle_core::{DType, Device, Tensor};

impl MaskedLinear {
    /// Whether the plasticity entropy term is on this iteration: a new task's first E
    /// iterations, the switch on (METHOD 2.3); whichever distribution it acts on.
    fn entropy_phase(&self) -> bool {
        matches!(&self.training, Some(t) if !t.repeat && self.cfg.entropy && t.iteration < self.cfg.resolved_entropy_iterations())
    }

    /// beta_H while the entropy term acts on the action distribution (`entropy_target =
    /// "action"`) in this iteration, else 0: the learner adds it to its own entropy bonus.
    pub fn action_entropy_weight(&self) -> f64 {
        let on_action = self.cfg.entropy_target == EntropyTarget::Action;
        if on_action && self.entropy_phase() {
            self.cfg.entropy_weight
        } else {
            0.0
        }
    }

    /// -beta_H * H with H = sum over the layer's scores of 0.5 ln(2 pi e sigma^2)
    /// = n * (log_sigma + 0.5 ln(2 pi e)) (2.3); 0 when off, after E iterations, or when the
    /// term acts on the action distribution. Finite for every finite log_sigma; its gradient on
    /// log_sigma is the constant -beta_H * n. (Under `sigma_scale = "score_gap"` the scores'
    /// standard deviation is sigma * g_row: ln g_row is a constant of the iteration, left out.)
    pub fn soft_score_loss(&self) -> anyhow::Result<Tensor> {
        if !self.entropy_phase() || self.cfg.entropy_target != EntropyTarget::SoftScores {
            return Ok(Tensor::zeros((), DType::F32, &Device::Cpu)?);
        }
        let n = (self.out_dim * self.in_dim) as f64;
        let h =
            ((self.log_sigma.as_tensor() * n)? + n * 0.5 * (2.0 * std::f64::consts::PI * std::f64::consts::E).ln())?;
        Ok((h * -self.cfg.entropy_weight)?.sum_all()?)
    }
}
