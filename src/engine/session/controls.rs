//! What observers and a UI ask of a running session, between iterations:
//! pause and resume, and the next task's switches and forward-transfer
//! initialisation (queued: the task in progress keeps its settings). Commands
//! sent on the session's channel arrive here too.

use super::Session;
use crate::cl::{SwitchOverrides, Switches, TransferInit};
use crate::engine::events::{Command, Event};

impl Session {
    /// The switches the next task to start will use (its sequence entry and queued changes applied).
    pub fn next_switches(&self) -> Option<Switches> {
        let spec = self.sequence.tasks.get(self.completed_steps() + usize::from(self.in_progress.is_some()))?;
        Some(self.switches.with(&spec.switches.merged(&self.queued)))
    }

    /// Stops at the next iteration boundary.
    pub fn pause(&mut self) {
        if !self.paused {
            self.paused = true;
            let (step, iteration) = self.position();
            self.emit(Event::Paused { step, iteration });
        }
    }

    /// Continues after [`Session::pause`].
    pub fn resume(&mut self) {
        if self.paused {
            self.paused = false;
            let (step, iteration) = self.position();
            self.emit(Event::Resumed { step, iteration });
        }
    }

    /// Queues switch changes for the next task to start (merged with earlier queued ones).
    /// The task in progress keeps its settings. An invalid value is an error now.
    pub fn set_next_switches(&mut self, overrides: SwitchOverrides) -> anyhow::Result<()> {
        let merged = self.queued.merged(&overrides);
        self.switches.with(&merged).apply(&self.base_mask)?;
        self.queued = merged;
        self.emit(Event::SwitchesQueued { overrides });
        Ok(())
    }

    /// Replaces the next task's related tasks and initialisation (METHOD.md 2.6).
    /// The related tasks must be learned already (checked now). Ignored if the next
    /// task is a repeat (a repeat has no initialisation).
    pub fn set_next_transfer(&mut self, related: Vec<String>, init: TransferInit) -> anyhow::Result<()> {
        for name in &related {
            let id = self.results.tasks.iter().position(|t| t == name);
            anyhow::ensure!(
                id.is_some_and(|t| self.finished[t]),
                "related task {name:?} has not been learned (learned: {:?})",
                self.learned_names()
            );
        }
        anyhow::ensure!(
            init != TransferInit::Random || !related.is_empty(),
            "init = random draws as many tasks as are named, and none is"
        );
        self.emit(Event::TransferQueued { related: related.clone(), init });
        self.queued_transfer = Some((related, init));
        Ok(())
    }

    pub(super) fn learned_names(&self) -> Vec<String> {
        (0..self.finished.len()).filter(|&t| self.finished[t]).map(|t| self.results.tasks[t].clone()).collect()
    }

    pub(super) fn position(&self) -> (usize, usize) {
        self.in_progress.as_ref().map_or((self.completed_steps(), 0), |p| (p.record.step, p.iteration))
    }

    pub(super) fn drain_commands(&mut self) -> anyhow::Result<()> {
        while let Ok(c) = self.commands.try_recv() {
            match c {
                Command::Pause => self.pause(),
                Command::Resume => self.resume(),
                Command::SetNextSwitches(o) => self.set_next_switches(o)?,
                Command::SetNextTransfer { related, init } => self.set_next_transfer(related, init)?,
            }
        }
        Ok(())
    }
}
