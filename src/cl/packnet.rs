//! `packnet`: PackNet (Mallya & Lazebnik, CVPR 2018) on the masked networks
//! (METHOD.md 3; the mechanics are `nn/masked/baselines.rs`). Each task
//! trains every free (vacant) weight while using the frozen weights of the
//! tasks before it; `retrain_iterations` before its budget ends its free
//! weights are pruned by magnitude to `keep` of them (the others are zeroed and
//! freed for later tasks), the rest of the budget retrains the kept ones, and
//! at the end they are frozen. A task's recall uses its own weights and the
//! earlier tasks' only, so it is bit-identical after any later task.
//!
//! Settings: `[method.packnet]` `keep` (0.5: half of the free weights per
//! task, the paper's 50 % pruning), `retrain_iterations` (a tenth of the
//! budget when 0, the default). No re-initialisation, entropy, private
//! elements or per-row quota: the run's switches do not apply.

use super::method::ContinualMethod;
use super::ours::Switches;
use crate::config::bounds::{self, POSITIVE_UNIT};
use crate::config::net::{MaskConfig, ScoreReinit, SelectionRule};
use crate::config::ppo::MAX_ITERATIONS;
use serde::{Deserialize, Serialize};

/// `[method.packnet]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PackNetConfig {
    /// The share of a task's free weights kept when it is pruned.
    pub keep: f64,
    /// Iterations at the end of each task that retrain the kept weights (0: a tenth of the budget).
    pub retrain_iterations: usize,
}

impl Default for PackNetConfig {
    fn default() -> Self {
        Self { keep: 0.5, retrain_iterations: 0 }
    }
}

impl PackNetConfig {
    /// Errors name the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        bounds::check("[method.packnet] keep", self.keep, POSITIVE_UNIT)?;
        bounds::check_count("[method.packnet] retrain_iterations", self.retrain_iterations, 0, MAX_ITERATIONS)
    }

    /// The iteration of a task of `iterations` from which it is pruned.
    pub fn prune_at(&self, iterations: usize) -> usize {
        let retrain = if self.retrain_iterations == 0 { iterations / 10 } else { self.retrain_iterations };
        iterations.saturating_sub(retrain)
    }
}

/// `base` with `rule` and none of `ours`' plasticity mechanisms (no private elements,
/// re-initialisation, entropy or transfer bonus): the mask baselines' common settings.
pub fn without_plasticity_mechanisms(base: &MaskConfig, rule: SelectionRule) -> MaskConfig {
    MaskConfig {
        rule,
        private_share: 0.0,
        reinit_weights: false,
        reinit_scores: ScoreReinit::None,
        entropy: false,
        entropy_fraction: None,
        entropy_iterations: Some(0),
        transfer_bonus: 0.0,
        ..base.clone()
    }
}

/// The method `packnet`.
#[derive(Debug, Clone)]
pub struct PackNet {
    pub cfg: PackNetConfig,
}

impl ContinualMethod for PackNet {
    fn name(&self) -> &str {
        "packnet"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.cfg).unwrap_or_default()
    }

    fn switches_in_force(&self, _switches: &Switches) -> Option<Switches> {
        None
    }

    fn task_mask_config(
        &self,
        base: &MaskConfig,
        _switches: &Switches,
        iterations: usize,
    ) -> anyhow::Result<MaskConfig> {
        let m = MaskConfig {
            capacity: 1.0,
            packnet_keep: self.cfg.keep,
            packnet_prune_at: Some(self.cfg.prune_at(iterations)),
            ..without_plasticity_mechanisms(base, SelectionRule::PackNet)
        };
        m.validate()?;
        Ok(m)
    }
}
