//! The session on its own thread: the worker opens the run folder (an
//! existing run, the continuation of a shorter run, or a fresh run file),
//! sends the UI one [`Opened`] snapshot, then serves commands (the session's
//! own channel) and forwards every engine event. It starts paused: nothing
//! trains until the user starts a step. A second thread steps the robot
//! viewer of one task for the robot panel, at real time.

use crate::cl::{Sequence, SwitchOverrides, Switches, TransferInit};
use crate::engine::{ChannelObserver, CommandSender, Event, OpenMode, Runner, SessionResults, Summary};
use crate::nn::MaskReport;
use crate::rl::{RobotFrame, RobotViewer};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Which run the workbench opens.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenSpec {
    /// The run folder everything trained lands in.
    pub run_dir: PathBuf,
    /// The run file for a new folder (ignored when the folder holds a run).
    pub config: Option<PathBuf>,
    /// A shorter finished run that a new folder continues (its steps begin `config`'s sequence).
    pub continues: Option<PathBuf>,
}

/// What the UI knows of a run when it opens.
#[derive(Debug, Clone)]
pub struct Opened {
    pub run_dir: PathBuf,
    /// How the folder was opened, in words.
    pub origin: String,
    pub method: String,
    pub sequence: Sequence,
    /// Tasks learned before the sequence (the base policy's).
    pub base_tasks: Vec<String>,
    pub switches: Switches,
    pub results: SessionResults,
    pub report: MaskReport,
    pub summary: Summary,
    /// The policy that recalls every learned task (the robot view runs it).
    pub last_checkpoint: Option<PathBuf>,
    /// Switch changes and transfer queued for the next step (kept in the folder across reopens).
    pub queued: SwitchOverrides,
    pub queued_transfer: Option<(Vec<String>, TransferInit)>,
}

/// The robot view's pictures: one every this many control steps (10 a second for the A1) ...
pub const PICTURE_EVERY: u32 = 5;
/// ... of this many pixels (about 3 ms each on one core); the panel scales it to its cells.
pub const PICTURE_SIZE: (usize, usize) = (160, 120);

/// A message from the worker thread.
#[derive(Debug, Clone)]
pub enum WorkerMsg {
    Opened(Box<Opened>),
    Event(Box<Event>),
    /// The run could not be opened, or the session failed.
    Failed(String),
    /// The session thread ended (after a stop, results written).
    Exited,
    /// A robot frame of task `task`.
    Robot {
        task: String,
        frame: Box<RobotFrame>,
    },
    /// A picture of task `task`'s robot (`render`), every [`PICTURE_EVERY`] control steps.
    RobotPicture {
        task: String,
        picture: Box<crate::render::Frame>,
    },
    /// A recording asked for from the workbench ended (the message says where, or why not).
    Recorded {
        task: String,
        message: String,
    },
    /// The robot view could not start.
    RobotFailed {
        task: String,
        error: String,
    },
}

/// The session thread: commands go in through `commands` (once opened), messages come out.
pub struct Worker {
    pub messages: Receiver<WorkerMsg>,
    sender: Sender<WorkerMsg>,
    commands: Arc<std::sync::Mutex<Option<CommandSender>>>,
    /// Set by [`Worker::shutdown`]: a run still opening stops as soon as it is open.
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    /// The robot view's stop flag.
    robot: Option<Arc<AtomicBool>>,
    /// Robot threads told to stop (joined at shutdown, not on the UI thread's way).
    stopping: Vec<JoinHandle<()>>,
    robot_handle: Option<JoinHandle<()>>,
}

fn open(spec: &OpenSpec) -> anyhow::Result<(Runner, String)> {
    let dir = &spec.run_dir;
    let shown = dir.display();
    if crate::engine::RunDir::new(dir).results_only() {
        anyhow::bail!(
            "{shown} holds a run's results only (metrics.json, no {} or checkpoint): nothing to reopen; \
             `quadcl plot {shown}` draws its figures",
            crate::engine::RUN_FILE
        );
    }
    if has_run(dir) {
        // The folder's own run file: it has the tasks added in the workbench, which `config` lacks.
        let config = dir.join(crate::engine::RUN_FILE);
        return Ok((Runner::open(&config, dir, OpenMode::Resume, false)?, format!("reopened {shown}")));
    }
    let config = spec
        .config
        .as_deref()
        .ok_or_else(|| anyhow::anyhow!("{shown} holds no run, and no --config names one to start"))?;
    if let Some(prior) = spec.continues.as_deref().filter(|p| has_run(p)) {
        let runner = Runner::continue_run(prior, config, dir, false)?;
        return Ok((runner, format!("continues {} with {}", prior.display(), config.display())));
    }
    Ok((Runner::open(config, dir, OpenMode::New, false)?, format!("new run of {}", config.display())))
}

fn has_run(dir: &Path) -> bool {
    crate::engine::RunDir::new(dir).has_run()
}

fn opened(runner: &Runner, origin: String) -> Opened {
    let session = runner.session();
    let results = session.results().clone();
    let metrics = runner.metrics();
    let sequence = session.sequence().clone();
    let in_sequence = sequence.distinct_tasks();
    Opened {
        run_dir: runner.root().to_path_buf(),
        origin,
        method: results.method.clone(),
        base_tasks: results.tasks.iter().filter(|t| !in_sequence.contains(t)).cloned().collect(),
        switches: session.switches().clone(),
        report: session.learner().mask_report(&results.tasks),
        summary: metrics.summary,
        last_checkpoint: runner.last_checkpoint().or_else(|| runner.base_policy()),
        queued: session.queued_switches().clone(),
        queued_transfer: session.queued_transfer().cloned(),
        sequence,
        results,
    }
}

impl Worker {
    /// Starts the session thread on `spec`.
    pub fn spawn(spec: OpenSpec) -> Self {
        let (sender, messages) = channel();
        let commands = Arc::new(std::sync::Mutex::new(None));
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, slot, stopped) = (sender.clone(), commands.clone(), stop.clone());
        let handle = std::thread::spawn(move || {
            let (mut runner, origin) = match open(&spec) {
                Ok(r) => r,
                Err(e) => {
                    let _ = tx.send(WorkerMsg::Failed(crate::util::text::error_text(&e)));
                    return;
                }
            };
            let (etx, events) = channel::<Event>();
            runner.session_mut().add_observer(Box::new(ChannelObserver(etx)));
            runner.session_mut().pause();
            runner.session_mut().set_pause_after_each_task(true);
            if let Ok(mut s) = slot.lock() {
                *s = Some(runner.session().command_sender());
            }
            let _ = tx.send(WorkerMsg::Opened(Box::new(opened(&runner, origin))));
            let forward = {
                let tx = tx.clone();
                std::thread::spawn(move || events.iter().for_each(|e| drop(tx.send(WorkerMsg::Event(Box::new(e))))))
            };
            if stopped.load(Ordering::SeqCst) {
                runner.session_mut().stop();
            }
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| runner.serve()));
            // Dropping the runner closes the event channel: every event is forwarded before the end.
            drop(runner);
            let _ = forward.join();
            match outcome {
                Ok(Ok(())) => {}
                Ok(Err(e)) => drop(tx.send(WorkerMsg::Failed(crate::util::text::error_text(&e)))),
                Err(_) => drop(tx.send(WorkerMsg::Failed("the session thread panicked (see stderr)".into()))),
            }
            let _ = tx.send(WorkerMsg::Exited);
        });
        Self {
            messages,
            sender,
            commands,
            stop,
            handle: Some(handle),
            robot: None,
            stopping: Vec::new(),
            robot_handle: None,
        }
    }

    /// Sends a command to the session (dropped before the run is open).
    pub fn send(&self, command: crate::engine::Command) {
        if let Some(s) = self.commands.lock().ok().and_then(|s| s.clone()) {
            let _ = s.send(command);
        }
    }

    /// Stops the session and waits for its thread (its results are written by then).
    pub fn shutdown(&mut self) {
        self.stop_robot();
        self.stop.store(true, Ordering::SeqCst);
        self.send(crate::engine::Command::Stop);
        if let Some(h) = self.handle.take() {
            // A run still opening sees the flag once open; one serving gets the command.
            while !h.is_finished() {
                self.send(crate::engine::Command::Stop);
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = h.join();
        }
        self.stopping.drain(..).for_each(|h| drop(h.join()));
    }

    /// Runs task `task` of the policy `policy` in the robot view (replacing any running one).
    pub fn start_robot(&mut self, policy: PathBuf, task: String) {
        self.stop_robot();
        let stop = Arc::new(AtomicBool::new(false));
        let (flag, tx) = (stop.clone(), self.sender.clone());
        let handle = std::thread::spawn(move || {
            // A checkpoint announced by the engine may still be being written: wait a little for it.
            let deadline = Instant::now() + Duration::from_secs(10);
            while !policy.exists() && Instant::now() < deadline && !flag.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
            }
            let mut viewer = match RobotViewer::new(&policy, &task, 1, None) {
                Ok(v) => v,
                Err(e) => {
                    let _ = tx.send(WorkerMsg::RobotFailed { task, error: crate::util::text::error_text(&e) });
                    return;
                }
            };
            let dt = Duration::from_secs_f32(viewer.policy_dt());
            let start = Instant::now();
            let mut steps = 0u32;
            while !flag.load(Ordering::Relaxed) {
                match viewer.step() {
                    Ok(frame) => {
                        if tx.send(WorkerMsg::Robot { task: task.clone(), frame: Box::new(frame) }).is_err() {
                            return;
                        }
                    }
                    Err(e) => {
                        let _ = tx.send(WorkerMsg::RobotFailed { task, error: crate::util::text::error_text(&e) });
                        return;
                    }
                }
                if steps % PICTURE_EVERY == 0 {
                    let (w, h) = PICTURE_SIZE;
                    // Closer than a video's camera: the panel has a few dozen cells.
                    let camera = crate::render::Camera { distance: 1.0, ..Default::default() };
                    if let Ok(picture) = crate::render::frame_of(viewer.env(), &camera, w, h) {
                        if tx.send(WorkerMsg::RobotPicture { task: task.clone(), picture: Box::new(picture) }).is_err()
                        {
                            return;
                        }
                    }
                }
                steps += 1;
                // Real time: sleep until this step's simulated time has passed.
                if let Some(wait) = (dt * steps).checked_sub(start.elapsed()) {
                    std::thread::sleep(wait);
                }
            }
        });
        self.robot = Some(stop);
        self.robot_handle = Some(handle);
    }

    /// Shows 20 s of `task` under `policy` in the Rerun viewer (started, or the one already
    /// running) and saves the same stream to `out` (`.rrd`), on a thread of its own. Without a
    /// viewer the recording goes to `out` only, and the message says how to open it.
    pub fn view(&mut self, policy: PathBuf, task: String, out: PathBuf) {
        use crate::record::{record_episodes, view_policy, RecordOptions, RerunSink};
        let tx = self.sender.clone();
        let handle = std::thread::spawn(move || {
            let options = RecordOptions { seconds: 20.0, episodes: None, command: None, seed: 1, force: true };
            let made = out.parent().map_or(Ok(()), std::fs::create_dir_all).map_err(anyhow::Error::from);
            let sinks = [RerunSink::Spawn, RerunSink::Save(out.clone())];
            let message = match made.and_then(|()| view_policy(&policy, &task, &sinks, &options)) {
                Ok(s) => {
                    format!("showed {:.0} s of {task} in the Rerun viewer; saved to {}", s.sim_seconds, out.display())
                }
                Err(live) => match record_episodes(&policy, &task, &out, &options) {
                    Ok(s) => format!(
                        "no Rerun viewer ({live:#}); saved {:.0} s of {task} to {}: open it with `rerun {}`",
                        s.sim_seconds,
                        out.display(),
                        out.display()
                    ),
                    Err(e) => format!("recording {task} failed: {}", crate::util::text::error_text(&e)),
                },
            };
            let _ = tx.send(WorkerMsg::Recorded { task, message });
        });
        self.stopping.push(handle);
    }

    /// Writes 10 s of `task` (480 x 360, the env's random commands) into `out` on a thread of its
    /// own; the screen hears how it went.
    pub fn film(&mut self, policy: PathBuf, task: String, out: PathBuf) {
        use crate::record::{record_video, RecordOptions, VideoSize};
        let tx = self.sender.clone();
        let handle = std::thread::spawn(move || {
            let options = RecordOptions { seconds: 10.0, episodes: None, command: None, seed: 1, force: true };
            let message = match record_video(&policy, std::slice::from_ref(&task), &out, VideoSize::default(), &options)
            {
                Ok(s) => format!(
                    "wrote {:.0} s of {task} to {} ({:.1} MB)",
                    s.sim_seconds,
                    out.display(),
                    s.bytes as f64 / 1e6
                ),
                Err(e) => format!("filming {task} failed: {}", crate::util::text::error_text(&e)),
            };
            let _ = tx.send(WorkerMsg::Recorded { task, message });
        });
        self.stopping.push(handle);
    }

    /// Tells the robot view's thread to stop (without waiting for it: the UI stays responsive).
    pub fn stop_robot(&mut self) {
        if let Some(stop) = self.robot.take() {
            stop.store(true, Ordering::Relaxed);
        }
        self.stopping.extend(self.robot_handle.take());
        self.stopping.retain(|h| !h.is_finished());
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.shutdown();
    }
}
