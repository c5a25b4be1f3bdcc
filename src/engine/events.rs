//! What the engine tells its observers, and what observers may ask of it.
//! The headless progress bar and (later) the TUI and recorders are all
//! [`Observer`]s: they receive owned-or-borrowed [`Event`]s and never compute
//! a metric themselves. Commands come back through a [`CommandSender`]
//! (a channel, so a UI thread can pause a session that runs elsewhere).

use super::learner::Evaluation;
use crate::cl::{SwitchOverrides, Switches, TransferInit};
use crate::nn::{MaskReport, TaskId};
use crate::rl::Metrics;
use serde::Serialize;

/// Something that happened in a session.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum Event {
    /// A training step begins.
    TaskStarted {
        step: usize,
        task: TaskId,
        name: String,
        iterations: usize,
        switches: Switches,
        related: Vec<TaskId>,
        /// A repeat of a finished task (METHOD.md 2.5).
        repeat: bool,
    },
    /// One training iteration finished.
    Iteration { step: usize, task: TaskId, iteration: usize, iterations: usize, metrics: Metrics },
    /// The training step ended (masks chosen, per-task state frozen).
    TaskEnded { step: usize, task: TaskId, name: String },
    /// A finished task was evaluated after training step `after_step`.
    Evaluated { after_step: usize, evaluation: Evaluation },
    /// Mask statistics after training step `after_step`.
    MaskStats { after_step: usize, report: MaskReport },
    /// The session paused (between or inside tasks).
    Paused { step: usize, iteration: usize },
    /// The session resumed.
    Resumed { step: usize, iteration: usize },
    /// Switch changes were queued for the next task to start.
    SwitchesQueued { overrides: SwitchOverrides },
    /// Related tasks / init mode were queued for the next task to start.
    TransferQueued { related: Vec<String>, init: TransferInit },
    /// Every step of the sequence is done.
    SequenceFinished { steps: usize },
}

/// Receives a session's events.
pub trait Observer: Send {
    fn on_event(&mut self, event: &Event);
}

/// What an observer (or anyone holding a [`CommandSender`]) may ask.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Stop at the next iteration boundary.
    Pause,
    /// Continue.
    Resume,
    /// Change switches for the next task to start (not the one in progress).
    SetNextSwitches(SwitchOverrides),
    /// Change the next task's related tasks and initialisation (METHOD.md 2.6).
    SetNextTransfer { related: Vec<String>, init: TransferInit },
}

/// The sending end of a session's command channel.
pub type CommandSender = std::sync::mpsc::Sender<Command>;

/// Collects every event (tests, recorders that write at the end).
#[derive(Debug, Default, Clone)]
pub struct EventLog {
    events: std::sync::Arc<std::sync::Mutex<Vec<Event>>>,
}

impl EventLog {
    /// A copy of the events so far.
    pub fn snapshot(&self) -> Vec<Event> {
        self.events.lock().map(|e| e.clone()).unwrap_or_default()
    }
}

impl Observer for EventLog {
    fn on_event(&mut self, event: &Event) {
        if let Ok(mut events) = self.events.lock() {
            events.push(event.clone());
        }
    }
}
