//! A continual-learning method as a set of hooks around one training loop
//! (Avalanche's plugins, Continual World's `sac.py` hooks): each hook does
//! nothing by default. `ours` needs only [`ContinualMethod::task_mask_config`]
//! (everything else happens in the masked networks); a baseline such as EWC
//! will add a penalty (a loss hook and its own state, not here yet) and
//! compute importances in [`ContinualMethod::on_task_end`].

use super::ours::{Ours, Switches};
use crate::config::net::MaskConfig;
use crate::nn::TaskId;

/// Hooks the engine calls around a task's training; all default to nothing.
pub trait ContinualMethod: Send {
    /// The name written into `metrics.json` (`ours`, `finetune`, ...).
    fn name(&self) -> &str;

    /// The mask settings the learner's networks use for the next task, from
    /// the run's `base` settings and the switches in force for that task.
    fn task_mask_config(&self, base: &MaskConfig, _switches: &Switches) -> anyhow::Result<MaskConfig> {
        Ok(base.clone())
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

/// The method named in a run file. Only `ours` exists so far; the error lists what does.
pub fn method_by_name(name: &str) -> anyhow::Result<Box<dyn ContinualMethod>> {
    match name {
        "ours" => Ok(Box::new(Ours)),
        other => anyhow::bail!("unknown method {other:?}: the implemented methods are [\"ours\"]"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_method_is_an_error_listing_the_known_ones() {
        let err = method_by_name("ewc").err().unwrap().to_string();
        assert!(err.contains("ewc") && err.contains("ours"), "{err}");
        assert_eq!(method_by_name("ours").unwrap().name(), "ours");
    }
}
