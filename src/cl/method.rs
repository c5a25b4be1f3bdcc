//! A continual-learning method as a set of hooks (Avalanche's plugins,
//! Continual World's `sac.py` hooks), each doing nothing by default, at two
//! levels: around a task's training loop ([`ContinualMethod`], held by the
//! engine's session), and inside the learner's update ([`UpdateHooks`] of
//! `rl/update_hooks.rs`, which the method hands to the learner). `ours` needs
//! only [`ContinualMethod::task_mask_config`] (everything else happens in the
//! masked networks); EWC and SI train dense networks and add a penalty
//! through their update hooks.
//!
//! The methods' settings are the run file's `[method.NAME]` tables
//! ([`MethodSettings`]); every table parses whatever the method, so a run
//! switches method by changing one word.

use super::agem::Agem;
use super::er::{Er, ErConfig};
use super::ewc::{Ewc, EwcConfig};
use super::finetune::Finetune;
use super::ours::{Ours, Switches};
use super::packnet::{PackNet, PackNetConfig};
use super::piggyback::{Piggyback, PiggybackConfig};
use super::rwalk::{Rwalk, RwalkConfig};
use super::si::{Si, SiConfig};
use super::wsn::Wsn;
use crate::config::net::MaskConfig;
use crate::nn::{NetworkKind, TaskId};
use crate::rl::{NoHooks, UpdateHooks};
use serde::{Deserialize, Serialize};

/// The implemented methods' names.
pub const METHODS: [&str; 10] = ["ours", "wsn", "packnet", "piggyback", "finetune", "ewc", "si", "rwalk", "er", "agem"];

/// Every method's settings: `[method.NAME]` for ewc, si, rwalk, er, agem, packnet, piggyback (`ours`' switches are `[method]`'s own keys).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MethodSettings {
    pub ewc: EwcConfig,
    pub si: SiConfig,
    pub rwalk: RwalkConfig,
    pub er: ErConfig,
    pub agem: ErConfig,
    pub packnet: PackNetConfig,
    pub piggyback: PiggybackConfig,
}

impl MethodSettings {
    /// Errors name the table and key.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.ewc.validate()?;
        self.si.validate()?;
        self.rwalk.validate()?;
        self.er.validate("er")?;
        self.agem.validate("agem")?;
        self.packnet.validate()?;
        self.piggyback.validate()
    }
}

/// Hooks the engine calls around a task's training; all default to nothing.
pub trait ContinualMethod: Send {
    /// The name written into `metrics.json` (`ours`, `finetune`, ...).
    fn name(&self) -> &str;

    /// The mask settings the learner's networks use for the next task, from
    /// the run's `base` settings, the switches in force for that task and its budget.
    fn task_mask_config(
        &self,
        base: &MaskConfig,
        _switches: &Switches,
        _iterations: usize,
    ) -> anyhow::Result<MaskConfig> {
        Ok(base.clone())
    }

    /// The switches as they act on the networks, for the task records: as given for a masked
    /// method, none for a dense one (nothing reads them).
    fn switches_in_force(&self, switches: &Switches) -> Option<Switches> {
        (self.network_kind() == NetworkKind::Masked).then(|| switches.clone())
    }

    /// The method's settings as JSON (`metrics.json`); null when it has none.
    fn settings(&self) -> serde_json::Value {
        serde_json::Value::Null
    }

    /// The networks the method trains: masked (`ours`) or dense (the other baselines).
    fn network_kind(&self) -> NetworkKind {
        NetworkKind::Masked
    }

    /// The hooks the learner calls inside its update (fresh state: nothing learned yet).
    fn update_hooks(&self) -> Box<dyn UpdateHooks> {
        Box::new(NoHooks)
    }

    /// Called before a task's first iteration.
    fn on_task_start(&mut self, _task: TaskId, _name: &str) -> anyhow::Result<()> {
        Ok(())
    }

    /// Called after every training iteration with its metrics.
    fn after_iteration(&mut self, _task: TaskId, _metrics: &crate::rl::Metrics) -> anyhow::Result<()> {
        Ok(())
    }

    /// Called after the learner ended the task.
    fn on_task_end(&mut self, _task: TaskId, _name: &str) -> anyhow::Result<()> {
        Ok(())
    }
}

/// The method named in a run file, with its settings; an unknown name is an error listing the known ones.
pub fn method_by_name(name: &str, settings: &MethodSettings) -> anyhow::Result<Box<dyn ContinualMethod>> {
    match name {
        "ours" => Ok(Box::new(Ours)),
        "wsn" => Ok(Box::new(Wsn)),
        "packnet" => Ok(Box::new(PackNet { cfg: settings.packnet.clone() })),
        "piggyback" => Ok(Box::new(Piggyback { cfg: settings.piggyback.clone() })),
        "finetune" => Ok(Box::new(Finetune)),
        "ewc" => Ok(Box::new(Ewc { cfg: settings.ewc.clone() })),
        "si" => Ok(Box::new(Si { cfg: settings.si.clone() })),
        "rwalk" => Ok(Box::new(Rwalk { cfg: settings.rwalk.clone() })),
        "er" => Ok(Box::new(Er { cfg: settings.er.clone() })),
        "agem" => Ok(Box::new(Agem { cfg: settings.agem.clone() })),
        other => anyhow::bail!("unknown method {other:?}: the implemented methods are {METHODS:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_method_is_an_error_listing_the_known_ones() {
        let settings = MethodSettings::default();
        let err = method_by_name("hat", &settings).err().unwrap().to_string();
        assert!(err.contains("hat") && err.contains("ours") && err.contains("packnet"), "{err}");
        for name in METHODS {
            assert_eq!(method_by_name(name, &settings).unwrap().name(), name);
        }
    }

    #[test]
    fn only_the_mask_methods_train_masked_networks() {
        let settings = MethodSettings::default();
        for name in METHODS {
            let kind = method_by_name(name, &settings).unwrap().network_kind();
            assert_eq!(kind == NetworkKind::Masked, ["ours", "wsn", "packnet", "piggyback"].contains(&name), "{name}");
        }
    }
}
