//! Headless runs (`quadcl run`): a run file trained to the end with a
//! progress bar on stderr, results written into the output folder after
//! every task, `--resume` from the last completed task. The folder is the
//! engine's business ([`Runner`]); this adds two observers: the progress bar,
//! and TensorBoard events with a CSV of the same scalars in `OUT/tb/`
//! ([`crate::log`]): one folder per task (`tb/NN-TASK/`, step = the task's
//! iteration, from 1) and `tb/sequence/` (step = the iteration counted over the
//! run; the continual measures under `eval/` at each task's last iteration).

use crate::engine::{task_file_name, Event, MetricsFile, Observer, OpenMode, Runner};
use crate::log::ScalarLog;
use crate::rl::{iteration_summary, progress_bar};
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};

/// A progress bar over every iteration of the sequence.
struct ProgressObserver {
    bar: ProgressBar,
}

impl Observer for ProgressObserver {
    fn on_event(&mut self, event: &Event) {
        match event {
            Event::TaskStarted { step, name, .. } => self.bar.set_prefix(format!("step {step} {name}")),
            Event::Iteration { metrics, .. } => {
                self.bar.inc(1);
                self.bar.set_message(iteration_summary(metrics));
            }
            Event::SequenceFinished { .. } => self.bar.finish(),
            _ => {}
        }
    }
}

/// Every iteration's metrics and the measures after each task as TensorBoard runs.
///
/// A write that fails is said once per folder, with what happens next: a task's folder
/// that cannot be written loses that task's curves only (its writer is closed before the
/// next task's opens, so no task's curves go into another's folder); `tb/sequence` that
/// cannot be written stops the sequence's curves for the rest of the run. Training goes on
/// either way: the curves are a record, `metrics.json` holds the results.
struct TensorBoardObserver {
    root: PathBuf,
    /// The run's iterations so far (the sequence axis: the last one's step).
    done: i64,
    /// None once a write to it failed.
    sequence: Option<ScalarLog>,
    /// The task in progress's writer; None before the first task, or when its folder failed.
    task: Option<ScalarLog>,
    /// The task in progress's folder (named in a warning).
    task_dir: PathBuf,
}

impl TensorBoardObserver {
    /// `done` iterations of the run are complete (a resume starts there).
    fn open(root: &Path, done: usize) -> anyhow::Result<Self> {
        let sequence = ScalarLog::after(&root.join("sequence"), done)?;
        Ok(Self {
            root: root.to_path_buf(),
            done: done as i64,
            sequence: Some(sequence),
            task: None,
            task_dir: root.into(),
        })
    }

    /// The task in progress's writer failed: its curves stop until the next task.
    fn task_failed(&mut self, e: &anyhow::Error) {
        if self.task.take().is_some() {
            tracing::warn!(
                "{}: TensorBoard curves of this task stopped ({}); the next task writes its own folder again",
                self.task_dir.display(),
                crate::util::text::error_text(e)
            );
        }
    }

    /// The sequence's writer failed: its curves stop for the rest of the run.
    fn sequence_failed(&mut self, e: &anyhow::Error) {
        if self.sequence.take().is_some() {
            tracing::warn!(
                "{}: TensorBoard curves of the whole sequence stopped for the rest of the run ({}); each task's \
                 folder goes on",
                self.root.join("sequence").display(),
                crate::util::text::error_text(e)
            );
        }
    }

    /// Writes to the sequence's log while it works.
    fn write_sequence(&mut self, write: impl FnOnce(&mut ScalarLog) -> anyhow::Result<()>) {
        if let Some(sequence) = &mut self.sequence {
            if let Err(e) = write(sequence) {
                self.sequence_failed(&e);
            }
        }
    }

    /// Writes to the task in progress's log while it works.
    fn write_task(&mut self, write: impl FnOnce(&mut ScalarLog) -> anyhow::Result<()>) {
        if let Some(task) = &mut self.task {
            if let Err(e) = write(task) {
                self.task_failed(&e);
            }
        }
    }
}

impl Observer for TensorBoardObserver {
    fn on_event(&mut self, event: &Event) {
        match event {
            Event::TaskStarted { step, name, .. } => {
                // The previous task's writer is flushed and closed before this one opens.
                self.write_task(|t| t.flush());
                self.task = None;
                // A task redone after a resume starts its folder anew.
                self.task_dir = self.root.join(format!("{step:02}-{}", task_file_name(name)));
                match ScalarLog::create(&self.task_dir) {
                    Ok(log) => self.task = Some(log),
                    Err(e) => tracing::warn!(
                        "{}: cannot write this task's TensorBoard curves ({}); the next task writes its own folder again",
                        self.task_dir.display(),
                        crate::util::text::error_text(&e)
                    ),
                }
            }
            Event::Iteration { iteration, metrics, .. } => {
                let scalars = || metrics.iter().map(|(k, v)| (k.as_str(), *v));
                self.write_task(|t| t.write(*iteration as i64, scalars()));
                self.done += 1;
                let done = self.done;
                self.write_sequence(|s| s.write(done, scalars()));
            }
            Event::TaskEnded { .. } => {
                self.write_sequence(|s| s.flush());
                self.write_task(|t| t.flush());
            }
            Event::Evaluated { evaluation, .. } => {
                let name = &evaluation.report.task;
                let tags = [
                    (format!("eval/{name}/performance"), evaluation.performance),
                    (format!("eval/{name}/lin_vel_err"), evaluation.report.lin_vel_err),
                    (format!("eval/{name}/ang_vel_err"), evaluation.report.ang_vel_err),
                    (format!("eval/{name}/fall_rate"), evaluation.report.fall_rate),
                ];
                let done = self.done;
                self.write_sequence(|s| s.write(done, tags.iter().map(|(t, v)| (t.as_str(), *v))));
            }
            Event::Measures { summary, .. } => {
                let measures = [
                    ("eval/average_performance", summary.average_performance),
                    ("eval/forgetting", summary.forgetting),
                    ("eval/plasticity", summary.plasticity),
                    ("eval/forward_transfer", summary.forward_transfer_mean),
                ];
                let done = self.done;
                self.write_sequence(|s| {
                    s.write(done, measures.iter().filter_map(|(t, v)| v.map(|v| (*t, v))))?;
                    s.flush()
                });
            }
            _ => {}
        }
    }
}

/// How a headless run goes.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Continue the run already in the output folder from its last completed task (or start
    /// it, when the folder holds none yet).
    pub resume: bool,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Stop after this many more completed tasks (the rest can be `resume`d later).
    pub stop_after: Option<usize>,
    /// Record one evaluation episode of every learned task after each task (`DIR/episodes/`).
    pub record: Option<crate::record::RecordFormat>,
    /// Train with this method instead of the run file's (`--method`).
    pub method: Option<String>,
    /// Write no TensorBoard events or CSV (`OUT/tb/`).
    pub no_tensorboard: bool,
}

/// Runs (or, with `resume`, continues) the run file `config` into `out`.
/// Every check (config, existing results, checkpoint) happens before anything is written.
pub fn run(config: &Path, out: &Path, options: RunOptions) -> anyhow::Result<MetricsFile> {
    run_then(config, out, options, |_| {})
}

/// [`run`], then `after` with the results while the run still holds its folder's lock (so
/// that what it writes there, the figures of `quadcl run`, is not raced by a second process).
pub fn run_then(
    config: &Path,
    out: &Path,
    options: RunOptions,
    after: impl FnOnce(&MetricsFile),
) -> anyhow::Result<MetricsFile> {
    let RunOptions { resume, progress, stop_after, record, method, no_tensorboard } = options;
    // A folder that holds no run yet (never started, or killed before its first record) starts
    // it: a Slurm array task or a sweep cell is always started with --resume.
    let mode = if resume { OpenMode::ResumeOrNew } else { OpenMode::New };
    let mut runner = Runner::open_with_method(config, out, mode, !progress, method.as_deref())?;
    runner.record_episodes(record)?;
    let session = runner.session();
    let sequence = session.sequence();
    let total: usize = (0..sequence.tasks.len()).map(|i| sequence.iterations_of(i)).sum();
    let done: usize = (0..session.completed_steps()).map(|i| sequence.iterations_of(i)).sum();
    let bar = progress_bar(total, progress);
    bar.set_position(done as u64);
    runner.session_mut().add_observer(Box::new(ProgressObserver { bar }));
    if !no_tensorboard {
        let tb = TensorBoardObserver::open(&out.join("tb"), done)?;
        runner.session_mut().add_observer(Box::new(tb));
    }
    runner.train(stop_after)?;
    let metrics = runner.metrics();
    after(&metrics);
    Ok(metrics)
}
