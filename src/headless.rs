//! Headless runs (`quadcl run`): a run file trained to the end with a
//! progress bar on stderr, results written into the output folder after
//! every task, `--resume` from the last completed task. The folder is the
//! engine's business ([`Runner`]); this adds the progress bar, an observer.

use crate::engine::{Event, MetricsFile, Observer, OpenMode, Runner};
use crate::rl::{iteration_summary, progress_bar};
use indicatif::ProgressBar;
use std::path::Path;

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
}

/// Runs (or, with `resume`, continues) the run file `config` into `out`.
/// Every check (config, existing results, checkpoint) happens before anything is written.
pub fn run(config: &Path, out: &Path, options: RunOptions) -> anyhow::Result<MetricsFile> {
    let RunOptions { resume, progress, stop_after, record, method } = options;
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
    runner.train(stop_after)?;
    Ok(runner.metrics())
}
