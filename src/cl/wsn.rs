//! `wsn`: Winning SubNetworks (Kang et al., ICML 2022), as the paper compares
//! it (METHOD.md 3). It is `ours` with three mechanisms off, so it shares all
//! of `ours`' code (the masked networks) and only sets the mask rules:
//!
//! - one top-k over the whole layer (the `per-layer` lambda mode), which
//!   reuses occupied weights freely: no vacant / occupied split per row;
//! - no re-initialisation of vacant weights or scores, no soft-score entropy,
//!   no private elements (`reinit_weights`, `entropy` off, `reinit_scores`
//!   none, `private_share` 0);
//! - deterministic scores: sigma is 1e-6 of the 0.3 score spread and never
//!   trains (`entropy_iterations` 0), so the mask is the top-k of the score
//!   means, straight-through as in WSN.
//!
//! Capacity c (the share of each layer a task selects) is the run's.

use super::method::ContinualMethod;
use super::ours::{LambdaMode, Switches};
use crate::config::net::{MaskConfig, ScoreReinit, SigmaScale};

/// The method `wsn`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Wsn;

/// Sigma of the scores' sampling noise under `wsn` (against a score spread of about 0.3).
pub const WSN_SIGMA: f64 = 1e-6;

/// The run's switches with WSN's rules: only the capacity is the run's.
fn wsn_switches(switches: &Switches) -> Switches {
    Switches {
        reinit_weights: false,
        reinit_scores: ScoreReinit::None,
        entropy: false,
        lambda: LambdaMode::PerLayer,
        private_share: 0.0,
        ..*switches
    }
}

impl ContinualMethod for Wsn {
    fn name(&self) -> &str {
        "wsn"
    }

    fn switches_in_force(&self, switches: &Switches) -> Option<Switches> {
        Some(wsn_switches(switches))
    }

    fn task_mask_config(
        &self,
        base: &MaskConfig,
        switches: &Switches,
        _iterations: usize,
    ) -> anyhow::Result<MaskConfig> {
        let mut m = wsn_switches(switches).apply(base)?;
        // WSN draws no noise: sigma is a tie-break in score units, as before issue 13.
        m.sigma_scale = SigmaScale::Absolute;
        m.sigma_init = WSN_SIGMA;
        m.sigma_floor = m.sigma_floor.min(WSN_SIGMA);
        m.entropy_fraction = None;
        m.entropy_iterations = Some(0);
        // One optimiser for weights and scores (Kang et al.), as its committed runs trained.
        m.score_learning_rate = 0.0;
        m.validate()?;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::net::SelectionRule;

    #[test]
    fn wsn_is_ours_with_the_per_layer_rule_and_every_plasticity_mechanism_off() {
        let switches = Switches { capacity: 0.3, ..Switches::default() };
        let m = Wsn.task_mask_config(&MaskConfig::default(), &switches, 10).unwrap();
        assert_eq!(
            (m.rule, m.reinit_weights, m.reinit_scores, m.entropy, m.private_share, m.capacity, m.entropy_iterations),
            (SelectionRule::PerLayer, false, ScoreReinit::None, false, 0.0, 0.3, Some(0))
        );
        assert_eq!(m.score_rate(), None, "WSN's scores step with the weights, at the optimiser's rate");
        assert!(m.sigma_init <= WSN_SIGMA && m.sigma_floor <= WSN_SIGMA);
        assert_eq!(m.score_init_std, MaskConfig::default().score_init_std, "the rest is the run's");
    }
}
