//! The workbench engine: one learner trained on a sequence of tasks, step by
//! step, with every result kept and every change announced to observers.
//!
//! A UI drives it one iteration at a time ([`Session::step_iteration`]), a
//! script task by task ([`Session::train_next_task`]) or to the end
//! ([`Session::run`]). Pausing (a method call or a [`Command`] on the
//! channel) takes effect at the next iteration boundary, inside a task or
//! between tasks. Switch changes are queued for the NEXT task to start; the
//! task in progress keeps its settings. After each task every finished task
//! is evaluated (METHOD.md 4) with a seed that depends only on (master seed,
//! task), so the evaluation of a task recalled later is comparable bit for bit.
//!
//! Determinism across interruptions: each step's random streams come from
//! (master seed, step), never from a stream carried over, so a session
//! restored from a checkpoint after step k continues exactly as if it had
//! never stopped.

mod controls;
pub use controls::ChosenSettings;
mod restore;

use super::events::{Command, CommandSender, Event, Observer};
use super::learner::{Learner, TaskStart};
use super::results::{SessionResults, SoftScoreSettings, StepRecord, TaskCurve};
use crate::cl::{ContinualMethod, EvalMatrix, Sequence, SwitchOverrides, Switches, TransferInit};
use crate::config::net::MaskConfig;
use crate::nn::TaskId;
use crate::util::{derive_seed, Stream};
use anyhow::Context;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::sync::mpsc::{channel, Receiver};

/// What one call of [`Session::step_iteration`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// Nothing: the session is paused.
    Paused,
    /// One iteration of step `step` ran (`iteration` is 1-based); the task goes on.
    Iterated { step: usize, iteration: usize },
    /// The last iteration of step `step` ran, the task ended and was evaluated.
    TaskFinished { step: usize },
    /// Every step of the sequence is done.
    SequenceDone,
    /// The session was stopped ([`Command::Stop`]); nothing more trains.
    Stopped,
}

/// While a watched task trains, its element views are reported every this many iterations.
const MASK_VIEWS_EVERY: usize = 10;

struct InProgress {
    record: StepRecord,
    iteration: usize,
    curve: TaskCurve,
}

/// A learner, a sequence, the method and the results.
pub struct Session {
    learner: Box<dyn Learner>,
    method: Box<dyn ContinualMethod>,
    sequence: Sequence,
    base_mask: MaskConfig,
    switches: Switches,
    seed: u64,
    finished: Vec<bool>,
    in_progress: Option<InProgress>,
    queued: SwitchOverrides,
    /// Related tasks and init mode for the next task, replacing its sequence entry's.
    queued_transfer: Option<(Vec<String>, TransferInit)>,
    paused: bool,
    /// Set by [`Command::Stop`]: nothing more is trained.
    stopped: bool,
    /// [`Command::PauseAfterEachTask`]: pause when a task has ended.
    pause_after_task: bool,
    /// Set by [`Command::Save`] until a runner takes it.
    save_requested: bool,
    /// The task whose element views are reported ([`Command::WatchMasks`]).
    watched: Option<TaskId>,
    /// From-scratch curves by task name, for forward transfer in [`Event::Measures`].
    reference: std::collections::BTreeMap<String, Vec<f64>>,
    observers: Vec<Box<dyn Observer>>,
    commands: Receiver<Command>,
    sender: CommandSender,
    results: SessionResults,
}

impl Session {
    /// A session at the start of `sequence` (validated here). `base_mask`: the
    /// run's mask settings; `switches`: the method's switches for every task
    /// that does not change them; `seed`: the master seed.
    pub fn new(
        learner: Box<dyn Learner>,
        method: Box<dyn ContinualMethod>,
        sequence: Sequence,
        base_mask: MaskConfig,
        switches: Switches,
        seed: u64,
    ) -> anyhow::Result<Self> {
        sequence.validate()?;
        switches.apply(&base_mask)?;
        let tasks = sequence.distinct_tasks();
        let (sender, commands) = channel();
        let results = SessionResults {
            method: method.name().to_string(),
            method_settings: method.settings(),
            eval_matrix: EvalMatrix::new(tasks.clone()),
            tasks,
            ..Default::default()
        };
        Ok(Self {
            finished: vec![false; results.tasks.len()],
            learner,
            method,
            sequence,
            base_mask,
            switches,
            seed,
            in_progress: None,
            queued: SwitchOverrides::default(),
            queued_transfer: None,
            paused: false,
            stopped: false,
            pause_after_task: false,
            save_requested: false,
            watched: None,
            reference: Default::default(),
            observers: Vec::new(),
            commands,
            sender,
            results,
        })
    }

    /// Adds an observer; it receives every later event.
    pub fn add_observer(&mut self, observer: Box<dyn Observer>) {
        self.observers.push(observer);
    }

    /// A sender for commands (pause, resume, switches) from another thread or an observer.
    pub fn command_sender(&self) -> CommandSender {
        self.sender.clone()
    }

    /// The results so far.
    pub fn results(&self) -> &SessionResults {
        &self.results
    }

    /// The learner (for saving checkpoints, mask statistics, viewers).
    pub fn learner(&self) -> &dyn Learner {
        self.learner.as_ref()
    }

    /// The run's switches (every task that does not change them uses these).
    pub fn switches(&self) -> &Switches {
        &self.switches
    }

    /// The sequence being trained.
    pub fn sequence(&self) -> &Sequence {
        &self.sequence
    }

    /// Steps completed.
    pub fn completed_steps(&self) -> usize {
        self.results.steps.len()
    }

    /// (step, iterations done, budget) of the task in progress.
    pub fn progress(&self) -> Option<(usize, usize, usize)> {
        self.in_progress.as_ref().map(|p| (p.record.step, p.iteration, p.record.iterations))
    }

    /// True once every step is done.
    pub fn is_done(&self) -> bool {
        self.in_progress.is_none() && self.completed_steps() == self.sequence.tasks.len()
    }

    /// Whether the session is paused.
    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// Uses `reference` (from-scratch curves by task name) for forward transfer in [`Event::Measures`].
    pub fn set_reference(&mut self, reference: std::collections::BTreeMap<String, Vec<f64>>) {
        self.reference = reference;
    }

    /// The from-scratch curve of task `name` ([`Session::set_reference`]), if any.
    pub fn reference_curve(&self, name: &str) -> Option<Vec<f64>> {
        self.reference.get(name).cloned()
    }

    /// Tells every observer.
    fn emit(&mut self, event: Event) {
        for o in &mut self.observers {
            o.on_event(&event);
        }
    }

    /// Runs one training iteration (starting the next task first when none is in
    /// progress, ending and evaluating it after its last iteration).
    /// A failure is announced ([`Event::Failed`]) and stops the session; completed steps stay.
    pub fn step_iteration(&mut self) -> anyhow::Result<StepOutcome> {
        let outcome = self.try_step_iteration();
        if let Err(e) = &outcome {
            self.stopped = true;
            self.emit(Event::Failed { error: format!("{e:#}") });
        }
        outcome
    }

    fn try_step_iteration(&mut self) -> anyhow::Result<StepOutcome> {
        self.drain_commands();
        if self.stopped {
            return Ok(StepOutcome::Stopped);
        }
        if self.paused {
            return Ok(StepOutcome::Paused);
        }
        if self.in_progress.is_none() {
            if self.is_done() {
                return Ok(StepOutcome::SequenceDone);
            }
            self.start_task()?;
        }
        let p = self.in_progress.as_mut().expect("a task is in progress");
        let metrics = self.learner.train_iteration()?;
        p.iteration += 1;
        p.curve.push(&metrics);
        let (step, task, iteration, iterations) = (p.record.step, p.record.task, p.iteration, p.record.iterations);
        self.method.after_iteration(task, &metrics)?;
        self.emit(Event::Iteration { step, task, iteration, iterations, metrics });
        if self.watched == Some(task) && iteration % MASK_VIEWS_EVERY == 0 && iteration < iterations {
            let layers = self.learner.mask_views(task);
            self.emit(Event::MaskViews { task, iteration: Some(iteration), layers });
        }
        if iteration < iterations {
            return Ok(StepOutcome::Iterated { step, iteration });
        }
        self.finish_task()?;
        Ok(StepOutcome::TaskFinished { step })
    }

    /// Trains until the current (or next) task has finished, or the session pauses.
    pub fn train_next_task(&mut self) -> anyhow::Result<StepOutcome> {
        loop {
            match self.step_iteration()? {
                StepOutcome::Iterated { .. } => continue,
                other => return Ok(other),
            }
        }
    }

    /// Trains to the end of the sequence, or until the session pauses.
    /// `after_task` runs after each finished task (e.g. to write results).
    pub fn run(&mut self, after_task: &mut dyn FnMut(&Session) -> anyhow::Result<()>) -> anyhow::Result<StepOutcome> {
        loop {
            match self.train_next_task()? {
                StepOutcome::TaskFinished { .. } => after_task(self)?,
                other => return Ok(other),
            }
        }
    }

    fn start_task(&mut self) -> anyhow::Result<()> {
        let step = self.completed_steps();
        let spec = self.sequence.tasks[step].clone();
        let task = self.results.tasks.iter().position(|t| *t == spec.name).expect("distinct tasks cover the sequence");
        let switches = self.switches.with(&spec.switches.merged(&self.queued));
        let iterations = self.sequence.iterations_of(step);
        // The task's own settings: E resolved for its budget (a share of it unless a count is set).
        let mask = self.method.task_mask_config(&self.base_mask, &switches, iterations)?.for_budget(iterations);
        let repeat = self.finished[task];
        let seed = derive_seed(self.seed, Stream::SequenceStep(step));
        let (related_names, init) = self.queued_transfer.take().unwrap_or((spec.related.clone(), spec.init));
        let related =
            if repeat { Vec::new() } else { self.resolve_related(&related_names, init, task, seed, &self.finished)? };
        let start = TaskStart {
            step,
            task,
            name: spec.name.clone(),
            related: related.clone(),
            mask,
            iterations: self.sequence.iterations_of(step),
            seed,
        };
        self.learner.begin_task(&start)?;
        self.method.on_task_start(task, &spec.name)?;
        self.queued = SwitchOverrides::default();
        let record = StepRecord {
            step,
            task,
            name: spec.name.clone(),
            iterations: start.iterations,
            switches: self.method.switches_in_force(&switches),
            soft_scores: self.method.switches_in_force(&switches).map(|_| SoftScoreSettings::of(&start.mask)),
            related: related.clone(),
            repeat,
            capacity: None,
        };
        let curve = TaskCurve { step, task, name: spec.name.clone(), ..Default::default() };
        self.in_progress = Some(InProgress { record, iteration: 0, curve });
        self.emit(Event::TaskStarted {
            step,
            task,
            name: spec.name,
            iterations: start.iterations,
            switches: self.method.switches_in_force(&switches),
            related,
            repeat,
        });
        Ok(())
    }

    /// Task ids for the transfer initialisation (METHOD.md 2.6).
    /// `learned[t]`: task t is learned by the time the step starts (the pool `random` draws from).
    fn resolve_related(
        &self,
        names: &[String],
        init: TransferInit,
        task: TaskId,
        seed: u64,
        learned: &[bool],
    ) -> anyhow::Result<Vec<TaskId>> {
        let id = |n: &String| {
            self.results
                .tasks
                .iter()
                .position(|t| t == n)
                .with_context(|| format!("related task {n:?} is neither in the sequence nor learned before it"))
        };
        let named: Vec<TaskId> = names.iter().map(id).collect::<anyhow::Result<_>>()?;
        match init {
            TransferInit::Scratch => Ok(Vec::new()),
            TransferInit::Related => Ok(named),
            TransferInit::Random => {
                let learned: Vec<TaskId> = (0..learned.len()).filter(|&t| learned[t] && t != task).collect();
                let others: Vec<TaskId> = learned.iter().copied().filter(|t| !named.contains(t)).collect();
                let pool = if others.len() >= named.len() { others } else { learned };
                let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(seed, Stream::RandomRelated));
                let mut drawn: Vec<TaskId> = pool.choose_multiple(&mut rng, named.len()).copied().collect();
                drawn.sort_unstable();
                Ok(drawn)
            }
        }
    }

    fn finish_task(&mut self) -> anyhow::Result<()> {
        let mut p = self.in_progress.take().expect("a task is in progress");
        self.learner.end_task()?;
        let (step, task) = (p.record.step, p.record.task);
        self.finished[task] = true;
        self.method.on_task_end(task, &p.record.name)?;
        let report = self.learner.mask_report(&self.results.tasks);
        if self.method.network_kind() == crate::nn::NetworkKind::Masked {
            p.record.capacity = super::results::StepCapacity::from_report(&report, &p.record.name);
        }
        let capacity = p.record.capacity.clone();
        self.emit(Event::TaskEnded { step, task, name: p.record.name.clone(), capacity });
        let mut row = Vec::new();
        let mut evaluations = Vec::new();
        let learned: Vec<TaskId> = (0..self.finished.len()).filter(|&t| self.finished[t]).collect();
        for t in learned {
            let evaluation = self.evaluate(t)?;
            row.push((t, evaluation.performance));
            evaluations.push(evaluation.clone());
            self.emit(Event::Evaluated { after_step: step, evaluation });
        }
        self.results.eval_matrix.push_step(task, &row)?;
        self.results.evaluations.push(evaluations);
        self.results.curves.push(p.curve);
        self.results.steps.push(p.record);
        self.emit(Event::MaskStats { after_step: step, report });
        let reference = |name: &str| self.reference_curve(name);
        let (eval_matrix, summary) = (self.results.eval_matrix.clone(), self.results.summary(&reference));
        self.emit(Event::Measures { after_step: step, eval_matrix, summary });
        if let Some(t) = self.watched {
            let layers = self.learner.mask_views(t);
            self.emit(Event::MaskViews { task: t, iteration: None, layers });
        }
        if self.is_done() {
            self.emit(Event::SequenceFinished { steps: self.completed_steps() });
        }
        if self.pause_after_task {
            self.pause();
        }
        Ok(())
    }

    /// Evaluates finished task `task` with its recalled parameters and the
    /// task's fixed evaluation seed.
    pub fn evaluate(&mut self, task: TaskId) -> anyhow::Result<super::learner::Evaluation> {
        let name =
            self.results.tasks.get(task).cloned().ok_or_else(|| {
                anyhow::anyhow!("no task {task}: the sequence has {} tasks", self.results.tasks.len())
            })?;
        anyhow::ensure!(self.finished[task], "task {task} ({name}) has not been learned yet");
        self.learner.evaluate(task, &name, derive_seed(self.seed, Stream::SequenceEval(task)))
    }
}
