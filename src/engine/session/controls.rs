//! What observers and a UI ask of a running session, between iterations:
//! pause and resume, stop, the next task's switches and forward-transfer
//! initialisation (queued: the task in progress keeps its settings), a task
//! added at the end, an evaluation or the element views of a task now.
//! Commands sent on the session's channel arrive here too; one that cannot be
//! carried out is announced ([`Event::CommandRejected`]) and changes nothing.
//! While paused, [`Session::wait_for_command`] blocks on the channel.

use super::Session;
use crate::cl::{KnownBefore, SwitchOverrides, Switches, TaskSpec, TransferInit};
use crate::engine::events::{Command, Event};
use crate::nn::TaskId;
use crate::util::{derive_seed, Stream};
use anyhow::Context;
use serde::{Deserialize, Serialize};

/// What a UI chose for the step to train next, beyond its run-file entry: kept in the run
/// folder, so a step interrupted (or not yet started) is trained as chosen after a reopen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChosenSettings {
    /// The step they are for.
    pub step: usize,
    /// Switch changes.
    pub switches: SwitchOverrides,
    /// Related tasks and mode replacing the entry's.
    pub transfer: Option<(Vec<String>, TransferInit)>,
}

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

    /// Switch changes queued for the next task to start.
    pub fn queued_switches(&self) -> &SwitchOverrides {
        &self.queued
    }

    /// Related tasks and mode queued for the next task to start.
    pub fn queued_transfer(&self) -> Option<&(Vec<String>, TransferInit)> {
        self.queued_transfer.as_ref()
    }

    /// The settings of the step in progress (as it started), or the changes queued for the
    /// next one; None when the next step is exactly its run-file entry.
    pub fn chosen_settings(&self) -> Option<ChosenSettings> {
        if let Some(p) = &self.in_progress {
            let s = p.record.switches.clone().unwrap_or_else(|| self.switches.clone());
            let switches = SwitchOverrides {
                reinit_weights: Some(s.reinit_weights),
                reinit_scores: Some(s.reinit_scores),
                reinit_range: Some(s.reinit_range),
                bias_start: Some(s.bias_start),
                entropy: Some(s.entropy),
                lambda: Some(s.lambda),
                capacity: Some(s.capacity),
                private_share: Some(s.private_share),
            };
            // The drawn related tasks (random mode already resolved) give the same start as related.
            let names = p.record.related.iter().map(|t| self.results.tasks[*t].clone()).collect();
            let transfer = (!p.record.repeat).then_some((names, TransferInit::Related));
            return Some(ChosenSettings { step: p.record.step, switches, transfer });
        }
        let untouched = self.queued == SwitchOverrides::default() && self.queued_transfer.is_none();
        (!untouched).then(|| ChosenSettings {
            step: self.completed_steps(),
            switches: self.queued.clone(),
            transfer: self.queued_transfer.clone(),
        })
    }

    /// Queues `chosen` again if it is for the next step to start (else it is stale and ignored).
    pub fn apply_chosen(&mut self, chosen: ChosenSettings) -> anyhow::Result<()> {
        if chosen.step != self.completed_steps() || self.in_progress.is_some() {
            return Ok(());
        }
        self.set_next_switches(chosen.switches)?;
        if let Some((related, init)) = chosen.transfer {
            self.set_next_transfer(related, init)?;
        }
        Ok(())
    }

    /// Stops: nothing more trains; the task in progress is abandoned.
    pub fn stop(&mut self) {
        if !self.stopped {
            self.stopped = true;
            let (step, iteration) = self.position();
            self.emit(Event::Stopped { step, iteration });
        }
    }

    /// Pause when each task has ended (step through the sequence), or run on.
    pub fn set_pause_after_each_task(&mut self, on: bool) {
        self.pause_after_task = on;
    }

    /// Whether the session was stopped (or failed).
    pub fn is_stopped(&self) -> bool {
        self.stopped
    }

    /// Whether a [`Command::Save`] came since the last call (a runner writes then).
    pub fn take_save_request(&mut self) -> bool {
        std::mem::take(&mut self.save_requested)
    }

    /// Blocks until the next command arrives on the channel and carries it out
    /// (a paused UI session waits here, not in a polling loop).
    pub fn wait_for_command(&mut self) {
        if let Ok(c) = self.commands.recv() {
            self.apply(c);
        }
        self.drain_commands();
    }

    /// Adds a task at the end of the sequence: its name must parse and its related
    /// tasks be learned or earlier in the sequence. A new name gets the next task id.
    pub fn append_task(&mut self, spec: TaskSpec) -> anyhow::Result<()> {
        let mut sequence = self.sequence.clone();
        sequence.tasks.push(spec.clone());
        let known: Vec<String> =
            (0..self.finished.len()).filter(|&t| self.finished[t]).map(|t| self.results.tasks[t].clone()).collect();
        sequence.validate_with(KnownBefore::Tasks(known))?;
        if !self.results.tasks.contains(&spec.name) {
            self.results.tasks.push(spec.name.clone());
            self.results.eval_matrix.tasks.push(spec.name.clone());
            self.results.eval_matrix.rows.iter_mut().for_each(|r| r.push(None));
            self.finished.push(false);
        }
        self.sequence = sequence;
        self.emit(Event::TaskAppended { step: self.sequence.tasks.len() - 1, spec });
        Ok(())
    }

    /// Starts reporting the element views of task `name` (now, after each task, while it trains).
    pub fn watch_masks(&mut self, name: &str) -> anyhow::Result<()> {
        let task = self.task_id(name)?;
        self.watched = Some(task);
        let live = self.in_progress.as_ref().filter(|p| p.record.task == task).map(|p| p.iteration);
        let layers = self.learner.mask_views(task);
        self.emit(Event::MaskViews { task, iteration: live, layers });
        Ok(())
    }

    /// Reports how many elements per layer the transfer bonus would lift for the next step to
    /// start with `related` and `init`, resolved as the step will resolve them (`random` draws
    /// with the step's seed from the tasks learned by then; a repeat gets no bonus).
    pub fn preview_transfer(&mut self, related: Vec<String>, init: TransferInit) -> anyhow::Result<()> {
        let step = self.completed_steps() + usize::from(self.in_progress.is_some());
        let spec = self.sequence.tasks.get(step).context("no step left to start: add a task first")?;
        let task = self.task_id(&spec.name)?;
        let mut learned = self.finished.clone();
        if let Some(p) = &self.in_progress {
            learned[p.record.task] = true;
        }
        let repeat = learned[task];
        let seed = derive_seed(self.seed, Stream::SequenceStep(step));
        let ids = if repeat { Vec::new() } else { self.resolve_related(&related, init, task, seed, &learned)? };
        let layers = if ids.is_empty() { Vec::new() } else { self.learner.transfer_lift(&ids) };
        let lifted_from = ids.iter().map(|t| self.results.tasks[*t].clone()).collect();
        self.emit(Event::TransferPreview { step, related, init, lifted_from, repeat, layers });
        Ok(())
    }

    fn evaluate_now(&mut self, name: &str) -> anyhow::Result<()> {
        // Mid-task too: the learner evaluates the recalled task on its own envs and restores the
        // training state exactly (tests/engine_smoke.rs checks the run's numbers do not move).
        let task = self.task_id(name)?;
        let evaluation = self.evaluate(task)?;
        self.emit(Event::EvaluatedNow { evaluation });
        Ok(())
    }

    fn task_id(&self, name: &str) -> anyhow::Result<TaskId> {
        self.results
            .tasks
            .iter()
            .position(|t| t == name)
            .with_context(|| format!("no task {name:?} in this run (tasks: {:?})", self.results.tasks))
    }

    fn apply(&mut self, c: Command) {
        let label = format!("{c:?}");
        let result = match c {
            Command::Pause => {
                self.pause();
                Ok(())
            }
            Command::Resume => {
                self.resume();
                Ok(())
            }
            Command::Stop => {
                self.stop();
                Ok(())
            }
            Command::PauseAfterEachTask(on) => {
                self.set_pause_after_each_task(on);
                Ok(())
            }
            Command::Save => {
                self.save_requested = true;
                Ok(())
            }
            Command::SetNextSwitches(o) => self.set_next_switches(o),
            Command::SetNextTransfer { related, init } => self.set_next_transfer(related, init),
            Command::Evaluate(name) => self.evaluate_now(&name),
            Command::WatchMasks(name) => self.watch_masks(&name),
            Command::PreviewTransfer { related, init } => self.preview_transfer(related, init),
            Command::AppendTask(spec) => self.append_task(spec),
        };
        if let Err(e) = result {
            self.emit(Event::CommandRejected { command: label, error: format!("{e:#}") });
        }
    }

    pub(super) fn drain_commands(&mut self) {
        while let Ok(c) = self.commands.try_recv() {
            self.apply(c);
        }
    }
}
