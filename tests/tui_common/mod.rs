//! Driving the workbench without a terminal: the real app, worker and
//! drawing code on ratatui's `TestBackend`.

#![allow(dead_code)]

use quadcl::tui::{dispatch, ui, Action, App, Clock, OpenSpec, Worker};
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A toy-learner run file: three quick tasks (the soft-score means at the optimiser's rate, as
/// the screens' snapshots were taken before issue 60).
pub const TOY_RUN: &str = "seed = 4\niterations = 6\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 2\n\
score_learning_rate = 0.0\n\
[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n";

/// A toy-learner run of the default sequence's twelve tasks (`scenes/sequence-a1.toml`'s
/// order), two iterations each.
pub fn twelve_task_run() -> String {
    let tasks = [
        "crash:FL",
        "invert:RL",
        "noise:FL",
        "crash:FR",
        "noise:RL",
        "noise:RR",
        "invert:FR",
        "crash:RR",
        "invert:FL",
        "noise:FR",
        "crash:RL",
        "invert:RR",
    ];
    let mut run =
        "seed = 4\niterations = 2\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 1\nscore_learning_rate = 0.0\n"
            .to_string();
    tasks.iter().for_each(|t| run.push_str(&format!("[[task]]\nname = \"{t}\"\n")));
    run
}

/// The repository root (tests run from it; paths in run files are relative to it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Opens `spec` with a ticking clock (every reading one second later) and waits until it is open.
pub fn open(spec: OpenSpec, size: (u16, u16)) -> (App, Worker) {
    let mut app = App::new(spec.run_dir.clone(), size, Clock::Ticks(0));
    let mut worker = Worker::spawn(spec);
    pump(&mut app, &mut worker, |a| a.opened.is_some() && a.views.is_some());
    (app, worker)
}

/// A fresh toy run in `dir`.
pub fn open_toy(dir: &Path, size: (u16, u16)) -> (App, Worker) {
    let config = dir.join("toy.toml");
    std::fs::write(&config, TOY_RUN).unwrap();
    open(OpenSpec { run_dir: dir.join("run"), config: Some(config), continues: None }, size)
}

/// The shipped 4-task run continued with the 12-task sequence, into `dir` (the shipped folder is only read).
pub fn open_shipped(dir: &Path, size: (u16, u16)) -> (App, Worker) {
    let spec = OpenSpec {
        run_dir: dir.join("workbench"),
        config: Some(root().join("scenes/sequence-a1.toml")),
        continues: Some(root().join("policies/sequence-a1-adapter")),
    };
    open(spec, size)
}

/// Applies `action`, sends what it queued, and applies the worker's answers until `until` holds (at most 20 s).
pub fn act(app: &mut App, worker: &mut Worker, action: Action, until: impl Fn(&App) -> bool) {
    app.update(action);
    pump(app, worker, until);
}

/// Sends what the app queued and applies the worker's messages until `until` holds (at most 20 s).
pub fn pump(app: &mut App, worker: &mut Worker, until: impl Fn(&App) -> bool) {
    quadcl::tui::wait_until(app, worker, Duration::from_secs(20), until).unwrap_or_else(|e| panic!("{e:#}"));
}

/// Applies every message already waiting.
pub fn drain(app: &mut App, worker: &mut Worker) {
    while let Ok(m) = worker.messages.recv_timeout(Duration::from_millis(200)) {
        app.update(Action::Worker(m));
        dispatch(app, worker);
    }
}

/// The screen as text at `width` x `height`, with `hide` (a temporary folder) written as `<tmp>`.
pub fn screen(app: &App, width: u16, height: u16, hide: &Path) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).unwrap();
    terminal.draw(|f| ui::draw(f, app)).unwrap();
    text(&terminal, width, height, hide)
}

/// One panel alone, drawn by `draw` over the whole `width` x `height` area (unfocused).
pub fn panel(
    app: &App,
    width: u16,
    height: u16,
    hide: &Path,
    draw: fn(&mut ratatui::Frame, ratatui::layout::Rect, &App, bool),
) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).unwrap();
    terminal.draw(|f| draw(f, f.area(), app, false)).unwrap();
    text(&terminal, width, height, hide)
}

/// The Sweep screen as text at `width` x `height`.
pub fn sweep_screen(view: &quadcl::tui::SweepView, width: u16, height: u16) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).unwrap();
    terminal.draw(|f| quadcl::tui::panels::sweep::draw(f, view)).unwrap();
    text(&terminal, width, height, Path::new("\0"))
}

fn text(terminal: &Terminal<TestBackend>, width: u16, height: u16, hide: &Path) -> String {
    let buffer = terminal.backend().buffer();
    let mut text = String::new();
    for y in 0..height {
        for x in 0..width {
            text.push_str(buffer[(x, y)].symbol());
        }
        text.push('\n');
    }
    text.replace(&hide.display().to_string(), "<tmp>")
}
