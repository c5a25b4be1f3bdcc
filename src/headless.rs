//! Headless runs (`quadcl run`): a run file trained to the end with a
//! progress bar on stderr, results written into the output folder after
//! every task (see `engine::run_dir`), `--resume` from the last completed task.
//! The progress bar and the log are observers of the session's events.

use crate::engine::{
    Event, Learner, LearnerKind, MetricsFile, Observer, RunConfig, RunDir, Session, StepOutcome, ToyLearner, RUN_FILE,
};
use crate::rl::{iteration_summary, progress_bar, Metrics};
use anyhow::Context;
use indicatif::ProgressBar;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// The learner a run file asks for, with the base policy's tasks it already knows.
pub fn make_learner(cfg: &RunConfig) -> anyhow::Result<(Box<dyn Learner>, Vec<String>)> {
    let mask = cfg.switches.apply(&cfg.config.net.mask)?;
    match cfg.run.learner {
        LearnerKind::Toy => {
            let mut learner = ToyLearner::new(&mask, cfg.config.seed)?;
            let learned = match &cfg.run.base_policy {
                Some(dir) => learner.load(dir).with_context(|| format!("loading the base policy {}", dir.display()))?,
                None => Vec::new(),
            };
            Ok((Box::new(learner), learned))
        }
        LearnerKind::Ppo => crate::engine::make_ppo_learner(cfg),
    }
}

/// One line per task-level event, kept for `log.txt` (and echoed to stderr
/// when there is no progress bar, e.g. under nohup).
struct LogObserver {
    lines: Arc<Mutex<String>>,
    echo: bool,
}

/// Without a progress bar (under nohup), every this many iterations a line on stderr says
/// where training is, so a long run can be followed with `tail -f`.
const ECHO_EVERY: usize = 25;

impl Observer for LogObserver {
    fn on_event(&mut self, event: &Event) {
        let line = match event {
            Event::Iteration { step, iteration, iterations, metrics, .. } => {
                if self.echo && (iteration % ECHO_EVERY == 0 || iteration == iterations) {
                    eprintln!("{}", iteration_line(*step, *iteration, *iterations, metrics));
                }
                return;
            }
            Event::MaskStats { .. } => return,
            Event::Evaluated { after_step, evaluation: e } => format!(
                "after step {after_step}: {} performance {:.4} return {:.3} lin_vel_err {:.3} ang_vel_err {:.3} fall_rate {:.3}",
                e.report.task, e.performance, e.report.mean_return, e.report.lin_vel_err, e.report.ang_vel_err, e.report.fall_rate
            ),
            other => serde_json::to_string(other).unwrap_or_default(),
        };
        if self.echo {
            eprintln!("{line}");
        }
        if let Ok(mut l) = self.lines.lock() {
            l.push_str(&line);
            l.push('\n');
        }
    }
}

/// The echo line of iteration `iteration` (1-based) of `iterations`:
/// `step 0 iteration 25/500: return 3.21 lin_vel_err 0.410 ...` (see [`iteration_summary`]).
fn iteration_line(step: usize, iteration: usize, iterations: usize, metrics: &Metrics) -> String {
    format!("step {step} iteration {iteration}/{iterations}: {}", iteration_summary(metrics))
}

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
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    /// Continue the run already in the output folder from its last completed task.
    pub resume: bool,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Stop after this many more completed tasks (the rest can be `resume`d later).
    pub stop_after: Option<usize>,
}

/// Runs (or, with `resume`, continues) the run file `config` into `out`.
/// Every check (config, existing results, checkpoint) happens before anything is written.
pub fn run(config: &Path, out: &Path, options: RunOptions) -> anyhow::Result<MetricsFile> {
    let RunOptions { resume, progress, stop_after } = options;
    let cfg = RunConfig::load(config)?;
    let text = std::fs::read_to_string(config).with_context(|| format!("reading {}", config.display()))?;
    let dir = RunDir::new(out);
    let previous = if resume {
        let stored = RunConfig::load(&out.join(RUN_FILE))
            .with_context(|| format!("--resume: {} holds no readable run", out.display()))?;
        anyhow::ensure!(
            stored == cfg,
            "--resume: {} differs from the run in {} (its {RUN_FILE}); start a new --out instead",
            config.display(),
            out.display()
        );
        Some(MetricsFile::load(&dir.metrics_path())?)
    } else {
        anyhow::ensure!(
            !dir.has_run(),
            "{} already holds a run: use --resume to continue it, or another --out",
            out.display()
        );
        None
    };
    let reference = match &cfg.run.reference {
        Some(p) => Some(MetricsFile::load(p).context("the [run] reference")?),
        None => None,
    };
    let reference_curve = |name: &str| reference.as_ref().and_then(|r| r.reference_curve(name));
    let (learner, learned) = make_learner(&cfg)?;
    let method = crate::cl::method_by_name(&cfg.method)?;
    let mut session = Session::new(
        learner,
        method,
        cfg.sequence.clone(),
        cfg.config.net.mask.clone(),
        cfg.switches.clone(),
        cfg.config.seed,
    )?
    .with_learned_tasks(&learned)?;
    let total_steps = cfg.sequence.tasks.len();
    if let Some(prev) = &previous {
        let done = prev.completed_steps;
        let checkpoint = match done {
            0 => out.to_path_buf(),
            n => dir.checkpoint(n - 1, &prev.steps[n - 1].name),
        };
        session.restore(prev.results(), &checkpoint).context("--resume")?;
    } else {
        crate::util::write_atomic(&out.join(RUN_FILE), text.as_bytes())?;
        dir.write_metrics(&MetricsFile::new(session.results(), total_steps, &reference_curve))?;
    }

    let lines = Arc::new(Mutex::new(dir.read_log()));
    session.add_observer(Box::new(LogObserver { lines: lines.clone(), echo: !progress }));
    let total_iterations: usize = (0..total_steps).map(|i| cfg.sequence.iterations_of(i)).sum();
    let done_iterations: usize = (0..session.completed_steps()).map(|i| cfg.sequence.iterations_of(i)).sum();
    let bar = progress_bar(total_iterations, progress);
    bar.set_position(done_iterations as u64);
    session.add_observer(Box::new(ProgressObserver { bar }));

    let mut trained = 0;
    while stop_after != Some(trained) {
        match session.train_next_task()? {
            StepOutcome::TaskFinished { step } => {
                let name = &session.results().steps[step].name;
                dir.write_checkpoint(step, name, session.learner(), &session.results().tasks)?;
                dir.write_metrics(&MetricsFile::new(session.results(), total_steps, &reference_curve))?;
                if cfg.run.keep_last_checkpoint_only && step > 0 {
                    // Only after metrics.json names the new checkpoint as the last one.
                    let previous = dir.checkpoint(step - 1, &session.results().steps[step - 1].name);
                    if previous.exists() {
                        std::fs::remove_dir_all(&previous)
                            .with_context(|| format!("removing {}", previous.display()))?;
                    }
                }
                dir.write_log(&lines.lock().map(|l| l.clone()).unwrap_or_default())?;
                trained += 1;
            }
            _ => break,
        }
    }
    Ok(MetricsFile::new(session.results(), total_steps, &reference_curve))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_iteration_line_shows_missing_figures_as_a_dash() {
        let metrics =
            [("charts/episodic_return".to_string(), 3.214), ("charts/SPS".to_string(), 3301.7)].into_iter().collect();
        assert_eq!(
            iteration_line(1, 25, 500, &metrics),
            "step 1 iteration 25/500: return 3.21 lin_vel_err - ang_vel_err - fall_rate - SPS 3302"
        );
    }
}
