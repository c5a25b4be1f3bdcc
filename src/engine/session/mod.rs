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

use super::events::{Command, CommandSender, Event, Observer};
use super::learner::{Learner, TaskStart};
use super::results::{SessionResults, StepRecord, TaskCurve};
use crate::cl::{ContinualMethod, EvalMatrix, KnownBefore, Sequence, SwitchOverrides, Switches, TransferInit};
use crate::config::net::MaskConfig;
use crate::nn::TaskId;
use crate::util::{derive_seed, Stream};
use anyhow::Context;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;
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
}

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
            observers: Vec::new(),
            commands,
            sender,
            results,
        })
    }

    /// Declares tasks the learner already knows before the sequence starts
    /// (a base policy's): they come first among the task ids and columns, count
    /// as finished (a sequence entry naming one repeats it, METHOD.md 2.5)
    /// and are evaluated after every step. Only before any training.
    pub fn with_learned_tasks(mut self, learned: &[String]) -> anyhow::Result<Self> {
        anyhow::ensure!(
            self.results.steps.is_empty() && self.in_progress.is_none(),
            "learned tasks are declared before training"
        );
        self.sequence.validate_with(KnownBefore::Tasks(learned.to_vec()))?;
        let mut tasks = learned.to_vec();
        for t in self.sequence.distinct_tasks() {
            if !tasks.contains(&t) {
                tasks.push(t);
            }
        }
        self.finished = (0..tasks.len()).map(|i| i < learned.len()).collect();
        self.results.eval_matrix = EvalMatrix::new(tasks.clone());
        self.results.tasks = tasks;
        Ok(self)
    }

    /// Continues from `results` (the steps completed so far) and the learner
    /// state saved after the last of them in `checkpoint`. Errors (a corrupt
    /// checkpoint, results from another sequence) leave the session untouched.
    pub fn restore(&mut self, results: SessionResults, checkpoint: &Path) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.in_progress.is_none() && self.results.steps.is_empty(),
            "restore: the session has already trained"
        );
        anyhow::ensure!(
            results.tasks == self.results.tasks,
            "the saved results are for tasks {:?}, the sequence has {:?}",
            results.tasks,
            self.results.tasks
        );
        let done = results.steps.len();
        anyhow::ensure!(
            done <= self.sequence.tasks.len(),
            "the saved results have {done} steps, the sequence only {}",
            self.sequence.tasks.len()
        );
        for (i, s) in results.steps.iter().enumerate() {
            anyhow::ensure!(
                s.step == i && s.name == self.sequence.tasks[i].name,
                "saved step {i} ({}) does not match the sequence ({})",
                s.name,
                self.sequence.tasks[i].name
            );
        }
        anyhow::ensure!(
            results.eval_matrix.rows.len() == done && results.curves.len() == done && results.evaluations.len() == done,
            "the saved results are inconsistent: {done} steps, {} matrix rows, {} curves, {} evaluation rows",
            results.eval_matrix.rows.len(),
            results.curves.len(),
            results.evaluations.len()
        );
        if done > 0 {
            let names = self.learner.load(checkpoint)?;
            anyhow::ensure!(
                names == self.results.tasks,
                "{}: checkpoint tasks {names:?} differ from the sequence's {:?}",
                checkpoint.display(),
                self.results.tasks
            );
        }
        results.steps.iter().for_each(|s| self.finished[s.task] = true);
        self.results = results;
        Ok(())
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

    /// Tells every observer.
    fn emit(&mut self, event: Event) {
        for o in &mut self.observers {
            o.on_event(&event);
        }
    }

    /// Runs one training iteration (starting the next task first when none is in
    /// progress, ending and evaluating it after its last iteration).
    pub fn step_iteration(&mut self) -> anyhow::Result<StepOutcome> {
        self.drain_commands()?;
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
        let mask = self.method.task_mask_config(&self.base_mask, &switches)?;
        let repeat = self.finished[task];
        let seed = derive_seed(self.seed, Stream::SequenceStep(step));
        let (related_names, init) = self.queued_transfer.take().unwrap_or((spec.related.clone(), spec.init));
        let related = if repeat { Vec::new() } else { self.resolve_related(&related_names, init, task, seed)? };
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
            switches: switches.clone(),
            related: related.clone(),
            repeat,
        };
        let curve = TaskCurve { step, task, name: spec.name.clone(), ..Default::default() };
        self.in_progress = Some(InProgress { record, iteration: 0, curve });
        self.emit(Event::TaskStarted {
            step,
            task,
            name: spec.name,
            iterations: start.iterations,
            switches,
            related,
            repeat,
        });
        Ok(())
    }

    /// Task ids for the transfer initialisation (METHOD.md 2.6).
    fn resolve_related(
        &self,
        names: &[String],
        init: TransferInit,
        task: TaskId,
        seed: u64,
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
                let learned: Vec<TaskId> =
                    (0..self.finished.len()).filter(|&t| self.finished[t] && t != task).collect();
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
        let p = self.in_progress.take().expect("a task is in progress");
        self.learner.end_task()?;
        let (step, task) = (p.record.step, p.record.task);
        self.finished[task] = true;
        self.method.on_task_end(task, &p.record.name)?;
        self.emit(Event::TaskEnded { step, task, name: p.record.name.clone() });
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
        let report = self.learner.mask_report(&self.results.tasks);
        self.emit(Event::MaskStats { after_step: step, report });
        if self.is_done() {
            self.emit(Event::SequenceFinished { steps: self.completed_steps() });
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
