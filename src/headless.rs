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
struct TensorBoardObserver {
    root: PathBuf,
    /// The run's iterations so far (the sequence axis: the last one's step).
    done: i64,
    sequence: ScalarLog,
    task: Option<ScalarLog>,
    /// The first failure, reported once (training goes on: the curves are a record, not a result).
    failed: bool,
}

impl TensorBoardObserver {
    /// `done` iterations of the run are complete (a resume starts there).
    fn open(root: &Path, done: usize) -> anyhow::Result<Self> {
        let sequence = ScalarLog::after(&root.join("sequence"), done)?;
        Ok(Self { root: root.to_path_buf(), done: done as i64, sequence, task: None, failed: false })
    }

    fn handle(&mut self, event: &Event) -> anyhow::Result<()> {
        match event {
            Event::TaskStarted { step, name, .. } => {
                // A task redone after a resume starts its folder anew.
                let dir = self.root.join(format!("{step:02}-{}", task_file_name(name)));
                self.task = Some(ScalarLog::create(&dir)?);
            }
            Event::Iteration { iteration, metrics, .. } => {
                let scalars = || metrics.iter().map(|(k, v)| (k.as_str(), *v));
                if let Some(task) = &mut self.task {
                    task.write(*iteration as i64, scalars())?;
                }
                self.done += 1;
                self.sequence.write(self.done, scalars())?;
            }
            Event::TaskEnded { .. } => {
                self.sequence.flush()?;
                if let Some(task) = &mut self.task {
                    task.flush()?;
                }
            }
            Event::Evaluated { evaluation, .. } => {
                let name = &evaluation.report.task;
                let tags = [
                    (format!("eval/{name}/performance"), evaluation.performance),
                    (format!("eval/{name}/lin_vel_err"), evaluation.report.lin_vel_err),
                    (format!("eval/{name}/ang_vel_err"), evaluation.report.ang_vel_err),
                    (format!("eval/{name}/fall_rate"), evaluation.report.fall_rate),
                ];
                self.sequence.write(self.done, tags.iter().map(|(t, v)| (t.as_str(), *v)))?;
            }
            Event::Measures { summary, .. } => {
                let measures = [
                    ("eval/average_performance", summary.average_performance),
                    ("eval/forgetting", summary.forgetting),
                    ("eval/plasticity", summary.plasticity),
                    ("eval/forward_transfer", summary.forward_transfer_mean),
                ];
                self.sequence.write(self.done, measures.iter().filter_map(|(t, v)| v.map(|v| (*t, v))))?;
                self.sequence.flush()?;
            }
            _ => {}
        }
        Ok(())
    }
}

impl Observer for TensorBoardObserver {
    fn on_event(&mut self, event: &Event) {
        if let Err(e) = self.handle(event) {
            if !self.failed {
                tracing::warn!("{}: TensorBoard logging stopped: {e:#}", self.root.display());
                self.failed = true;
            }
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
    Ok(runner.metrics())
}
