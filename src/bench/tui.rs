//! The workbench's cost for `quadcl bench`: the time to draw one full frame
//! at 200x60 on each screen of the shipped run (ratatui's TestBackend, so
//! the figure is the app's drawing, not a terminal's), and PPO training
//! throughput with the workbench open (its worker trains while the UI thread
//! draws at 30 fps) against the same run file headless.
//!
//! Keys: `tui_frame_ms_200x60` (the slowest screen's median; no screen holds every panel, so
//! `tui_frame_ms_200x60_all_screens` adds the four: every panel drawn at least once),
//! `tui_frame_ms_200x60_{overview,evaluation,next_task,robot}`,
//! `tui_train_iterations_per_s`, `headless_train_iterations_per_s`,
//! `tui_training_cost` (1 - with UI / headless: the same seed and run file,
//! so the same work, but one short run each, so it wanders by 10-20 % with
//! the machine), and `tui_ui_cpu_share`: the CPU time of the UI thread over
//! the wall time times the cores, i.e. the share of the machine the open UI
//! takes from training (Linux: `/proc/thread-self/stat`). Run from the repository
//! root (the frame figures need `policies/sequence-a1-adapter`; without it they are skipped).

use quadcl::engine::{Event, Observer, OpenMode, Runner};
use quadcl::tui::{tick, ui, wait_until, Action, App, Clock, OpenSpec, Screen, Worker, WorkerMsg};
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use serde_json::json;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

type Report = serde_json::Map<String, serde_json::Value>;

/// A run file sized like the paper's networks with fewer envs, so an iteration takes a fraction of a second.
const TRAIN_RUN: &str = "seed = 1\niterations = 100000\n[ppo]\nnum_envs = 32\nsteps_per_env = 24\n\
[eval]\nepisodes = 4\n[[task]]\nname = \"crash:FL\"\n";

/// A scratch folder under the system's temporary folder, removed when dropped.
struct Scratch(std::path::PathBuf);

impl Scratch {
    fn new(name: &str) -> anyhow::Result<Self> {
        let dir = std::env::temp_dir().join(format!("quadcl-bench-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)?;
        Ok(Self(dir))
    }

    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn frames(seconds: f64, report: &mut Report) -> anyhow::Result<()> {
    if !Path::new("policies/sequence-a1-adapter/metrics.json").exists() {
        report.insert("tui_frame_ms_200x60".into(), json!(null));
        return Ok(());
    }
    let tmp = Scratch::new("frames")?;
    let spec = OpenSpec {
        run_dir: tmp.path().join("workbench"),
        config: Some("scenes/sequence-a1.toml".into()),
        continues: Some("policies/sequence-a1-adapter".into()),
    };
    let mut app = App::new(spec.run_dir.clone(), (200, 60), Clock::Ticks(0));
    let mut worker = Worker::spawn(spec);
    wait_until(&mut app, &mut worker, Duration::from_secs(60), |a| a.opened.is_some() && a.views.is_some())?;
    let mut viewer = quadcl::rl::RobotViewer::new(
        Path::new("policies/sequence-a1-adapter/checkpoints/step-03-crash_FR"),
        "crash:FR",
        1,
        Some([0.5, 0.0, 0.0]),
    )?;
    let frame = viewer.step()?;
    let mut terminal = Terminal::new(TestBackend::new(200, 60))?;
    let (mut slowest, mut all): (f64, f64) = (0.0, 0.0);
    for (screen, key) in [
        (Screen::Overview, "overview"),
        (Screen::Evaluation, "evaluation"),
        (Screen::NextTask, "next_task"),
        (Screen::Robot, "robot"),
    ] {
        app.update(Action::Show(screen));
        app.outbox.clear();
        worker.stop_robot();
        app.robot.task = Some("crash:FR".into());
        app.update(Action::Worker(WorkerMsg::Robot { task: "crash:FR".into(), frame: Box::new(frame) }));
        let mut times = Vec::new();
        let start = Instant::now();
        while times.len() < 20 || start.elapsed().as_secs_f64() < seconds / 4.0 {
            let t = Instant::now();
            terminal.draw(|f| ui::draw(f, &app))?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let ms = median(times);
        slowest = slowest.max(ms);
        all += ms;
        report.insert(format!("tui_frame_ms_200x60_{key}"), json!((ms * 1000.0).round() / 1000.0));
    }
    report.insert("tui_frame_ms_200x60".into(), json!((slowest * 1000.0).round() / 1000.0));
    report.insert("tui_frame_ms_200x60_all_screens".into(), json!((all * 1000.0).round() / 1000.0));
    worker.shutdown();
    Ok(())
}

/// Records when each iteration ended.
struct Stamps(Arc<Mutex<Vec<Instant>>>);

impl Observer for Stamps {
    fn on_event(&mut self, event: &Event) {
        if let (Event::Iteration { .. }, Ok(mut s)) = (event, self.0.lock()) {
            s.push(Instant::now());
        }
    }
}

/// CPU seconds this thread has used (Linux; None elsewhere).
fn thread_cpu_seconds() -> Option<f64> {
    super::cpu_seconds("/proc/thread-self/stat")
}

/// Iterations per second after the first `warm` iterations.
fn rate(stamps: &[Instant], warm: usize) -> f64 {
    match stamps.get(warm..) {
        Some(s) if s.len() > 1 => (s.len() - 1) as f64 / (s[s.len() - 1] - s[0]).as_secs_f64(),
        _ => f64::NAN,
    }
}

fn training(seconds: f64, report: &mut Report) -> anyhow::Result<()> {
    let tmp = Scratch::new("train")?;
    let config = tmp.path().join("train.toml");
    std::fs::write(&config, TRAIN_RUN)?;
    let budget = Duration::from_secs_f64((seconds * 6.0).max(12.0));
    let warm = 2;

    let mut runner = Runner::open(&config, &tmp.path().join("headless"), OpenMode::New, false)?;
    let stamps = Arc::new(Mutex::new(Vec::new()));
    runner.session_mut().add_observer(Box::new(Stamps(stamps.clone())));
    let start = Instant::now();
    while start.elapsed() < budget || stamps.lock().map_or(0, |s| s.len()) < warm + 3 {
        runner.session_mut().step_iteration()?;
    }
    let headless = rate(&stamps.lock().map(|s| s.clone()).unwrap_or_default(), warm);
    drop(runner);

    let spec = OpenSpec { run_dir: tmp.path().join("tui"), config: Some(config), continues: None };
    let mut app = App::new(spec.run_dir.clone(), (200, 60), Clock::Real(Instant::now()));
    let mut worker = Worker::spawn(spec);
    wait_until(&mut app, &mut worker, Duration::from_secs(60), |a| a.opened.is_some())?;
    let mut terminal = Terminal::new(TestBackend::new(200, 60))?;
    app.update(Action::StartPause);
    let mut arrivals: Vec<Instant> = Vec::new();
    let mut seen = 0;
    let cpu_start = thread_cpu_seconds();
    let start = Instant::now();
    while start.elapsed() < budget || arrivals.len() < warm + 3 {
        let frame_start = Instant::now();
        tick(&mut terminal, &mut app, &mut worker)?;
        let done = app.live.as_ref().map_or(seen, |l| l.iteration);
        if done > seen {
            seen = done;
            arrivals.push(Instant::now());
        }
        if let Some(wait) = quadcl::tui::FRAME.checked_sub(frame_start.elapsed()) {
            std::thread::sleep(wait);
        }
    }
    let (wall, cpu_end) = (start.elapsed().as_secs_f64(), thread_cpu_seconds());
    worker.shutdown();
    let with_ui = rate(&arrivals, warm);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let share = cpu_start.zip(cpu_end).map(|(a, b)| ((b - a) / (wall * cores) * 10000.0).round() / 10000.0);
    report.insert("tui_ui_cpu_share".into(), json!(share));
    report.insert("headless_train_iterations_per_s".into(), json!((headless * 1000.0).round() / 1000.0));
    report.insert("tui_train_iterations_per_s".into(), json!((with_ui * 1000.0).round() / 1000.0));
    report.insert("tui_training_cost".into(), json!(((1.0 - with_ui / headless) * 1000.0).round() / 1000.0));
    Ok(())
}

/// Adds the workbench's figures to `report`.
pub fn measure(seconds: f64, report: &mut Report) -> anyhow::Result<()> {
    frames(seconds, report)?;
    training(seconds, report)
}
