//! A session bound to its run folder: what `quadcl run` and the workbench
//! both use, so the folder is written the same way whoever drives it.
//!
//! [`Runner::open`] builds the learner from a run file, restores a stopped run
//! (`--resume`), and writes `run.toml` and `metrics.json` before anything
//! trains; [`Runner::continue_run`] starts a folder from a shorter run whose
//! steps begin the run file's sequence (the workbench continues the shipped
//! 4-task run with the rest of the 12-task sequence). After every task the
//! checkpoint, then `metrics.json`, then `log.txt` are written atomically (see
//! `run_dir`). Tasks added to the sequence on the way are appended to
//! `run.toml`, so a reopened folder has them. [`Runner::train`] runs headless
//! to the end; [`Runner::serve`] waits for commands (a UI's worker thread).
//! With [`Runner::record_episodes`], each step also records one evaluation
//! episode of every learned task into `episodes/` (MCAP, for Foxglove).

use super::events::{Event, Observer};
use super::learner::Learner;
use super::run_config::{LearnerKind, RunConfig};
use super::run_dir::{task_file_name, MetricsFile, RunDir, CHOSEN_FILE, EPISODES, RUN_FILE};
use super::session::{ChosenSettings, Session, StepOutcome};
use super::toy_learner::ToyLearner;
use crate::cl::TaskSpec;
use crate::record::{record_episodes, record_video, RecordFormat, RecordOptions, VideoSize};

use crate::util::{replace_dir, write_atomic, FolderLock, Provenance};
use anyhow::Context;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// `[run] videos`: the folder of the videos, each one's length and picture size.
pub const VIDEOS: &str = "videos";
const VIDEO_SECONDS: f64 = 6.0;
const VIDEO_SIZE: VideoSize = VideoSize { width: 320, height: 240 };

/// How [`Runner::open`] treats the output folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpenMode {
    /// A new run: the folder must not hold one.
    New,
    /// Continue the run in the folder from its last completed task.
    Resume,
    /// Continue the run in the folder if it holds one, else start it.
    ResumeOrNew,
}

/// The learner a run file asks for, with the base policy's tasks it already knows.
pub fn make_learner(cfg: &RunConfig) -> anyhow::Result<(Box<dyn Learner>, Vec<String>)> {
    let mask = cfg.switches.apply(&cfg.config.net.mask)?;
    match cfg.run.learner {
        LearnerKind::Toy => {
            anyhow::ensure!(
                cfg.run.base_vacant == super::run_config::BaseVacant::AsSaved,
                "[run] base_vacant = \"redrawn\": the PPO learner only (this run's learner is the toy)"
            );
            let method = crate::cl::method_by_name(&cfg.method, &cfg.method_settings)?;
            let mut learner = ToyLearner::new_of_kind(&mask, cfg.config.seed, method.network_kind())?
                .with_hooks(method.update_hooks());
            let learned = match &cfg.run.base_policy {
                Some(dir) => learner.load(dir).with_context(|| format!("loading the base policy {}", dir.display()))?,
                None => Vec::new(),
            };
            Ok((Box::new(learner), learned))
        }
        LearnerKind::Ppo => super::make_ppo_learner(cfg),
    }
}

/// A session, its run folder and its log.
pub struct Runner {
    session: Session,
    dir: RunDir,
    run_text: String,
    /// Sequence entries `run.toml` holds.
    written_tasks: usize,
    keep_last_checkpoint_only: bool,
    base_policy: Option<PathBuf>,
    /// Record one evaluation episode of every learned task after each step (`--record mcap|rrd`).
    record: Option<RecordFormat>,
    /// `[run] videos`.
    videos: bool,
    learner: LearnerKind,
    seed: u64,
    episode_s: f64,
    lines: Arc<Mutex<String>>,
    /// The run folder's lock, held as long as the runner lives (see [`RunDir::lock`]).
    lock: FolderLock,
}

/// The run file `text` (read from `path`) as the run `prev` records read it: a run begun before
/// issue 60 goes on as it ran (`RunConfig::load_text_as_ran_before_issue_60`, docs/method.md).
fn load_as_run(prev: &MetricsFile, path: &Path, text: &str) -> anyhow::Result<RunConfig> {
    match prev.ran_before_issue_60() {
        true => RunConfig::load_text_as_ran_before_issue_60(path, text),
        false => RunConfig::load_text(path, text),
    }
}

impl Runner {
    /// Opens the run file `config` into `out` (see [`OpenMode`]). Every check (config,
    /// existing results, checkpoint) happens before anything is written. `echo`: log lines go to stderr too.
    pub fn open(config: &Path, out: &Path, mode: OpenMode, echo: bool) -> anyhow::Result<Self> {
        Self::open_with_method(config, out, mode, echo, None)
    }

    /// [`Self::open`] with the run file's method replaced by `method` (`quadcl run --method`).
    pub fn open_with_method(
        config: &Path,
        out: &Path,
        mode: OpenMode,
        echo: bool,
        method: Option<&str>,
    ) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(config).with_context(|| format!("reading {}", config.display()))?;
        let text = match method {
            Some(name) => RunConfig::text_with_method(&text, name, config)?,
            None => text,
        };
        let cfg = RunConfig::load_text(config, &text)?;
        let dir = RunDir::new(out);
        // Before the folder is looked at: a second process must not even read a folder that
        // another is writing. (A bad run file is refused before, and writes nothing.)
        let lock = dir.lock()?;
        let resume = match mode {
            OpenMode::New => {
                anyhow::ensure!(
                    !dir.has_run(),
                    "{} already holds a run: use --resume to continue it, or another --out",
                    out.display()
                );
                false
            }
            OpenMode::Resume => true,
            OpenMode::ResumeOrNew => dir.has_run(),
        };
        let (cfg, previous) = if resume {
            let prev = MetricsFile::load(&dir.metrics_path())?;
            let read = |path: &Path, text: &str| load_as_run(&prev, path, text);
            let cfg = read(config, &text)?;
            let stored_path = out.join(RUN_FILE);
            let stored = std::fs::read_to_string(&stored_path)
                .map_err(anyhow::Error::from)
                .and_then(|t| read(&stored_path, &t))
                .with_context(|| format!("--resume: {} holds no readable run", out.display()))?;
            anyhow::ensure!(
                stored == cfg,
                "--resume: {} differs from the run in {} (its {RUN_FILE}: method {:?}, this one {:?}); \
                 start a new --out instead",
                config.display(),
                out.display(),
                stored.method,
                cfg.method
            );
            (cfg, Some(prev))
        } else {
            (cfg, None)
        };
        let mut runner = Self::build(&cfg, text, dir, echo, lock)?;
        if let Some(h) = runner.lock.took_over() {
            let line =
                format!("took over the folder's lock from {}, which had ended without releasing it\n", h.describe());
            if let Ok(mut l) = runner.lines.lock() {
                l.push_str(&line);
            }
        }
        match previous {
            Some(prev) => {
                let checkpoint = match prev.completed_steps {
                    0 => out.to_path_buf(),
                    n => runner.dir.checkpoint(n - 1, &prev.steps[n - 1].name),
                };
                runner.session.restore(prev.results(), &checkpoint).context("--resume")?;
                let chosen = out.join(CHOSEN_FILE);
                if chosen.exists() {
                    let text =
                        std::fs::read_to_string(&chosen).with_context(|| format!("reading {}", chosen.display()))?;
                    let settings: ChosenSettings = serde_json::from_str(&text)
                        .with_context(|| format!("{}: not the workbench's next-step settings", chosen.display()))?;
                    runner.session.apply_chosen(settings).with_context(|| format!("{}", chosen.display()))?;
                }
            }
            None => runner.write_start()?,
        }
        Ok(runner)
    }

    /// Starts `out` as the continuation of the finished or stopped run in `prior`
    /// by the run file `config`: `prior`'s steps must be the first steps of
    /// `config`'s sequence and its run file must train the same way (config, method, base).
    /// Its results and last checkpoint are copied; `prior` is only read.
    pub fn continue_run(prior: &Path, config: &Path, out: &Path, echo: bool) -> anyhow::Result<Self> {
        let dir = RunDir::new(out);
        let lock = dir.lock()?;
        anyhow::ensure!(!dir.has_run(), "{} already holds a run: open it instead", out.display());
        let text = std::fs::read_to_string(config).with_context(|| format!("reading {}", config.display()))?;
        let prev = MetricsFile::load(&prior.join(super::run_dir::METRICS_FILE))?;
        let read = |path: &Path, text: &str| load_as_run(&prev, path, text);
        let cfg = read(config, &text)?;
        let prior_path = prior.join(RUN_FILE);
        let prior_text =
            std::fs::read_to_string(&prior_path).with_context(|| format!("reading {}", prior_path.display()))?;
        let prior_cfg = read(&prior_path, &prior_text)?;
        for (what, same) in [
            ("seed, [env], [net] or [ppo]", cfg.config == prior_cfg.config),
            (
                "[method]",
                cfg.method == prior_cfg.method
                    && cfg.switches == prior_cfg.switches
                    && cfg.method_settings == prior_cfg.method_settings,
            ),
            (
                "[run] base_policy or learner",
                cfg.run.base_policy == prior_cfg.run.base_policy && cfg.run.learner == prior_cfg.run.learner,
            ),
        ] {
            anyhow::ensure!(same, "{} cannot continue {}: their {what} differ", config.display(), prior.display());
        }
        let done = prev.completed_steps;
        anyhow::ensure!(done > 0, "{} has no completed step to continue", prior.display());
        let source = RunDir::new(prior).checkpoint(done - 1, &prev.steps[done - 1].name);
        let mut runner = Self::build(&cfg, text, dir, echo, lock)?;
        runner.session.restore(prev.results(), &source).with_context(|| format!("continuing {}", prior.display()))?;
        // The whole folder is written beside `out` and renamed into place: an interruption
        // leaves either no run or the complete continuation.
        let log = std::fs::read_to_string(prior.join(super::run_dir::LOG_FILE)).unwrap_or_default();
        if let Ok(mut l) = runner.lines.lock() {
            *l = format!("{log}continued from {} after {done} steps\n", prior.display());
        }
        let (metrics, log) = (runner.metrics(), runner.log_text());
        let name = prev.steps[done - 1].name.clone();
        replace_dir(out, |fresh| {
            let staged = RunDir::new(fresh);
            replace_dir(&staged.checkpoint(done - 1, &name), |dir| copy_files(&source, dir))?;
            write_atomic(&fresh.join(RUN_FILE), runner.run_text.as_bytes())?;
            staged.write_metrics(&metrics)?;
            staged.write_log(&log)?;
            // The new folder carries the lock this runner holds.
            runner.lock.move_into(fresh)
        })?;
        Ok(runner)
    }

    fn build(cfg: &RunConfig, run_text: String, dir: RunDir, echo: bool, lock: FolderLock) -> anyhow::Result<Self> {
        let reference = match &cfg.run.reference {
            Some(p) => Some(MetricsFile::load(p).context("the [run] reference")?),
            None => None,
        };
        let (learner, learned) = make_learner(cfg)?;
        let method = crate::cl::method_by_name(&cfg.method, &cfg.method_settings)?;
        let mut session = Session::new(
            learner,
            method,
            cfg.sequence.clone(),
            cfg.config.net.mask.clone(),
            cfg.switches.clone(),
            cfg.config.seed,
        )?
        .with_learned_tasks(&learned)?;
        if let Some(r) = &reference {
            // Every task the reference file has (tasks added later find theirs too).
            let curves: BTreeMap<String, Vec<f64>> =
                r.tasks.iter().filter_map(|t| Some((t.clone(), r.reference_curve(t)?))).collect();
            session.set_reference(curves);
        }
        let lines = Arc::new(Mutex::new(dir.read_log()));
        session.add_observer(Box::new(LogObserver { lines: lines.clone(), echo }));
        Ok(Self {
            written_tasks: cfg.sequence.tasks.len(),
            session,
            dir,
            run_text,
            keep_last_checkpoint_only: cfg.run.keep_last_checkpoint_only,
            base_policy: cfg.run.base_policy.clone(),
            record: None,
            videos: cfg.run.videos,
            learner: cfg.run.learner,
            seed: cfg.config.seed,
            episode_s: f64::from(cfg.config.env.episode_s),
            lines,
            lock,
        })
    }

    fn write_start(&self) -> anyhow::Result<()> {
        write_atomic(&self.dir.root.join(RUN_FILE), self.run_text.as_bytes())?;
        self.dir.write_metrics(&self.metrics())
    }

    /// The session (to add observers, take a command sender, read results).
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// The session, mutably.
    pub fn session_mut(&mut self) -> &mut Session {
        &mut self.session
    }

    /// The run folder.
    pub fn root(&self) -> &Path {
        &self.dir.root
    }

    /// The path of the newest checkpoint (the policy that recalls every learned task), if any.
    pub fn last_checkpoint(&self) -> Option<PathBuf> {
        let steps = &self.session.results().steps;
        steps.last().map(|s| self.dir.checkpoint(s.step, &s.name))
    }

    /// After each step, record one evaluation episode of every learned task as `format` into
    /// `episodes/step-NN-TASK/TASK.mcap` (or `.rrd`, `.mp4`; the PPO learner only: its checkpoints are policies).
    pub fn record_episodes(&mut self, format: Option<RecordFormat>) -> anyhow::Result<()> {
        anyhow::ensure!(
            format.is_none() || self.learner == LearnerKind::Ppo,
            "--record needs the PPO learner: a [run] learner = \"toy\" run has no robot to record"
        );
        self.record = format;
        Ok(())
    }

    fn record_step(&self, step: usize, format: RecordFormat) -> anyhow::Result<()> {
        let results = self.session.results();
        let checkpoint = self.dir.checkpoint(step, &results.steps[step].name);
        let folder = self.dir.root.join(EPISODES).join(checkpoint.file_name().unwrap_or_default());
        std::fs::create_dir_all(&folder).with_context(|| format!("creating {}", folder.display()))?;
        let row = &results.eval_matrix.rows[step];
        for (t, name) in results.tasks.iter().enumerate().filter(|(t, _)| row.get(*t).copied().flatten().is_some()) {
            let options = RecordOptions {
                seconds: self.episode_s,
                episodes: Some(1),
                command: None,
                seed: crate::util::derive_seed(self.seed, crate::util::Stream::SequenceEval(t)),
                force: true,
            };
            record_episodes(
                &checkpoint,
                name,
                &folder.join(format!("{}.{}", task_file_name(name), format.extension())),
                &options,
            )
            .with_context(|| format!("recording {name} after step {step}"))?;
        }
        Ok(())
    }

    /// `[run] videos`: `videos/TASK.mp4` of the task step `step` learned, from its checkpoint.
    fn video_step(&self, step: usize) -> anyhow::Result<()> {
        let results = self.session.results();
        let name = &results.steps[step].name;
        let checkpoint = self.dir.checkpoint(step, name);
        let t = results.tasks.iter().position(|n| n == name).context("the step's task is in the sequence")?;
        let options = RecordOptions {
            seconds: VIDEO_SECONDS,
            episodes: None,
            command: None,
            seed: crate::util::derive_seed(self.seed, crate::util::Stream::SequenceEval(t)),
            force: true,
        };
        let out = self.dir.root.join(VIDEOS).join(format!("{}.mp4", task_file_name(name)));
        record_video(&checkpoint, std::slice::from_ref(name), &out, VIDEO_SIZE, &options)?;
        Ok(())
    }

    /// The run file's base policy (`[run] base_policy`), if any.
    pub fn base_policy(&self) -> Option<PathBuf> {
        self.base_policy.clone()
    }

    /// `metrics.json` as it stands.
    pub fn metrics(&self) -> MetricsFile {
        let reference = |name: &str| self.session.reference_curve(name);
        let mut metrics = MetricsFile::new(self.session.results(), self.session.sequence().tasks.len(), &reference);
        metrics.provenance = Some(self.provenance());
        metrics
    }

    /// This build and machine, with the hash of the run file as the folder's `run.toml` holds it.
    pub fn provenance(&self) -> Provenance {
        Provenance::of_this_build(Some(self.run_text.as_bytes()))
    }

    fn log_text(&self) -> String {
        self.lines.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// Writes what is not yet on disk: tasks added to the sequence (into `run.toml`),
    /// `metrics.json`, the settings chosen for the next step (`next-step.json`) and the log.
    /// A task in progress is not saved (a resume retrains it from its start, as it started).
    pub fn save(&mut self) -> anyhow::Result<()> {
        let tasks = &self.session.sequence().tasks;
        if tasks.len() > self.written_tasks {
            self.run_text.push_str(&appended_tasks(&tasks[self.written_tasks..])?);
            write_atomic(&self.dir.root.join(RUN_FILE), self.run_text.as_bytes())?;
            self.written_tasks = tasks.len();
        }
        self.dir.write_metrics(&self.metrics())?;
        let chosen = self.dir.root.join(CHOSEN_FILE);
        match self.session.chosen_settings() {
            Some(c) => write_atomic(&chosen, serde_json::to_string_pretty(&c)?.as_bytes())?,
            None if chosen.exists() => {
                std::fs::remove_file(&chosen).with_context(|| format!("removing {}", chosen.display()))?
            }
            None => {}
        }
        self.dir.write_log(&self.log_text())
    }

    /// After step `step` finished: its checkpoint, then `metrics.json` (then the older checkpoint
    /// goes, if only the last is kept), then the log.
    fn after_task(&mut self, step: usize) -> anyhow::Result<()> {
        let results = self.session.results();
        let name = &results.steps[step].name;
        self.dir.write_checkpoint(step, name, self.session.learner(), &results.tasks, &self.provenance())?;
        self.save()?;
        if let Some(format) = self.record {
            self.record_step(step, format)?;
        }
        if self.videos {
            if let Err(e) = self.video_step(step) {
                let line = format!("warning: no video of step {step}: {}\n", crate::util::text::error_text(&e));
                eprint!("{line}");
                if let Ok(mut l) = self.lines.lock() {
                    l.push_str(&line);
                }
                self.dir.write_log(&self.log_text())?;
            }
        }
        let results = self.session.results();
        if self.keep_last_checkpoint_only && step > 0 {
            let previous = self.dir.checkpoint(step - 1, &results.steps[step - 1].name);
            if previous.exists() {
                std::fs::remove_dir_all(&previous).with_context(|| format!("removing {}", previous.display()))?;
            }
        }
        Ok(())
    }

    /// Trains until the sequence ends, the session pauses or stops, or `stop_after`
    /// more tasks have finished; writes after every task.
    pub fn train(&mut self, stop_after: Option<usize>) -> anyhow::Result<StepOutcome> {
        let mut trained = 0;
        loop {
            if stop_after == Some(trained) {
                return Ok(StepOutcome::Paused);
            }
            match self.session.train_next_task()? {
                StepOutcome::TaskFinished { step } => {
                    self.after_task(step)?;
                    trained += 1;
                }
                other => return Ok(other),
            }
        }
    }

    /// Serves a UI until [`crate::engine::Command::Stop`]: trains while resumed, blocks on the
    /// command channel while paused, pauses at the end of the sequence (a task may
    /// still be added), writes after every task and on [`crate::engine::Command::Save`].
    /// On stop the results are written once more.
    pub fn serve(&mut self) -> anyhow::Result<()> {
        loop {
            if self.session.take_save_request() {
                self.save()?;
            }
            if self.session.is_stopped() {
                return self.save();
            }
            if self.session.is_paused() {
                self.session.wait_for_command();
                continue;
            }
            match self.session.step_iteration()? {
                StepOutcome::TaskFinished { step } => self.after_task(step)?,
                StepOutcome::SequenceDone => self.session.pause(),
                StepOutcome::Iterated { .. } | StepOutcome::Paused | StepOutcome::Stopped => {}
            }
        }
    }
}

/// The `[[task]]` tables of `tasks`, to append to a run file.
fn appended_tasks(tasks: &[TaskSpec]) -> anyhow::Result<String> {
    #[derive(serde::Serialize)]
    struct Tasks<'a> {
        task: &'a [TaskSpec],
    }
    Ok(format!("\n# Added in the workbench:\n{}", toml::to_string(&Tasks { task: tasks })?))
}

fn copy_files(from: &Path, to: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let path = entry?.path();
        if path.is_file() {
            let target = to.join(path.file_name().unwrap_or_default());
            std::fs::copy(&path, &target).with_context(|| format!("copying {}", path.display()))?;
        }
    }
    Ok(())
}

/// One line per task-level event, kept for `log.txt` (and echoed to stderr
/// when asked, e.g. under nohup where there is no progress bar).
struct LogObserver {
    lines: Arc<Mutex<String>>,
    echo: bool,
}

/// When echoing, every this many iterations a line on stderr says
/// where training is, so a long run can be followed with `tail -f`.
const ECHO_EVERY: usize = 25;

impl Observer for LogObserver {
    fn on_event(&mut self, event: &Event) {
        let line = match event {
            Event::Iteration { step, iteration, iterations, metrics, .. } => {
                if self.echo && (iteration % ECHO_EVERY == 0 || iteration == iterations) {
                    eprintln!("{}", crate::rl::iteration_line(*step, *iteration, *iterations, metrics));
                }
                return;
            }
            Event::MaskStats { .. }
            | Event::MaskViews { .. }
            | Event::Measures { .. }
            | Event::TransferPreview { .. }
            | Event::EvaluatedNow { .. } => return,
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
