//! What the engine tells its observers, and what observers may ask of it.
//! The headless progress bar and (later) the TUI and recorders are all
//! [`Observer`]s: they receive owned-or-borrowed [`Event`]s and never compute
//! a metric themselves. Commands come back through a [`CommandSender`]
//! (a channel, so a UI thread can pause a session that runs elsewhere).
//! [`ChannelObserver`] forwards every event to a channel (a UI on another thread).

use super::learner::Evaluation;
use super::results::Summary;
use crate::cl::{EvalMatrix, SwitchOverrides, Switches, TaskSpec, TransferInit};
use crate::nn::{LayerLift, LayerView, MaskReport, TaskId};
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
        /// The switches in force (none for a method without masks).
        switches: Option<Switches>,
        related: Vec<TaskId>,
        /// A repeat of a finished task (METHOD.md 2.5).
        repeat: bool,
    },
    /// One training iteration finished.
    Iteration { step: usize, task: TaskId, iteration: usize, iterations: usize, metrics: Metrics },
    /// The training step ended (masks chosen, per-task state frozen).
    TaskEnded {
        step: usize,
        task: TaskId,
        name: String,
        /// How its selection used the masked networks (none for a dense method).
        #[serde(skip_serializing_if = "Option::is_none")]
        capacity: Option<super::results::StepCapacity>,
    },
    /// A finished task was evaluated after training step `after_step`.
    Evaluated { after_step: usize, evaluation: Evaluation },
    /// Mask statistics after training step `after_step`.
    MaskStats { after_step: usize, report: MaskReport },
    /// The summary measures (METHOD.md 4) after training step `after_step`.
    Measures { after_step: usize, eval_matrix: EvalMatrix, summary: Summary },
    /// Every element of every layer as task `task` sees it ([`Command::WatchMasks`]);
    /// `iteration` is set while the task trains (its live selection).
    MaskViews { task: TaskId, iteration: Option<usize>, layers: Vec<LayerView> },
    /// A finished task evaluated on request ([`Command::Evaluate`]), outside the matrix.
    EvaluatedNow { evaluation: Evaluation },
    /// The elements the transfer bonus would lift for step `step` starting with `related` and
    /// `init`: `lifted_from` the tasks it resolves to (drawn, for `random`), none for a repeat.
    TransferPreview {
        step: usize,
        related: Vec<String>,
        init: TransferInit,
        lifted_from: Vec<String>,
        repeat: bool,
        layers: Vec<LayerLift>,
    },
    /// A task was added at the end of the sequence (as step `step`).
    TaskAppended { step: usize, spec: TaskSpec },
    /// A command could not be carried out; the session goes on unchanged.
    CommandRejected { command: String, error: String },
    /// Training failed; the session stops (completed steps are kept).
    Failed { error: String },
    /// The session was stopped ([`Command::Stop`]).
    Stopped { step: usize, iteration: usize },
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
    /// Evaluate a finished task now (answered by [`Event::EvaluatedNow`]).
    Evaluate(String),
    /// Report the element views of a task now, after each task, and every few
    /// iterations while it trains (answered by [`Event::MaskViews`]).
    WatchMasks(String),
    /// Preview the transfer bonus of the next step with these related tasks and mode
    /// (answered by [`Event::TransferPreview`]).
    PreviewTransfer { related: Vec<String>, init: TransferInit },
    /// Add a task at the end of the sequence (validated as a run file's entry).
    AppendTask(TaskSpec),
    /// Write the results now (a runner's business; see `engine::Runner`).
    Save,
    /// Pause after each task ends (true: step through the sequence) or run on (false).
    PauseAfterEachTask(bool),
    /// Stop: the task in progress is abandoned (a resume retrains it from its start).
    Stop,
}

/// The sending end of a session's command channel.
pub type CommandSender = std::sync::mpsc::Sender<Command>;

/// Forwards every event to a channel; a receiver that has gone is ignored.
pub struct ChannelObserver(pub std::sync::mpsc::Sender<Event>);

impl Observer for ChannelObserver {
    fn on_event(&mut self, event: &Event) {
        let _ = self.0.send(event.clone());
    }
}

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
