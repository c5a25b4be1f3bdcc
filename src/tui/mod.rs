//! The workbench: a terminal app over the engine. `app` holds the state and
//! `update(Action)`, `events` what the engine's events do to it, `timeline`
//! and `next_task` the state of those two panels; `input` turns keys into
//! actions; `ui` lays out and `panels/` draw; `worker` runs the session (and
//! the robot view, and recordings) on threads of their own. `sweep_view` and
//! `sweep_loop` are the Sweep screen (`quadcl tui --sweep DIR`): a sweep's
//! cells and collected table, whose cells open in the workbench.
//! [`run_app`] takes its backend and its event source, so tests drive the real
//! loop on ratatui's `TestBackend` with scripted events; [`run`] opens the
//! terminal (raw mode, alternate screen, mouse capture) and restores it on
//! every exit path, a panic included.

pub mod app;
mod events;
pub mod input;
pub mod mask_zoom;
pub mod next_task;
pub mod panels;
pub mod sweep_loop;
pub mod sweep_view;
pub mod timeline;
pub mod ui;
pub mod worker;

pub use app::{Action, App, Clock, Outgoing, Panel, Screen};
pub use sweep_loop::{run_sweep_app, SweepReader};
pub use sweep_view::{SweepAction, SweepSnapshot, SweepView};
pub use worker::{OpenSpec, Opened, Worker, WorkerMsg};

use ratatui::backend::Backend;
use ratatui::backend::CrosstermBackend;
use ratatui::crossterm::event::{self, DisableMouseCapture, EnableMouseCapture, Event};
use ratatui::crossterm::execute;
use ratatui::crossterm::terminal::{disable_raw_mode, enable_raw_mode, EnterAlternateScreen, LeaveAlternateScreen};
use ratatui::Terminal;
use std::io::Stdout;
use std::time::Duration;

/// About 30 frames per second: the longest wait for input between frames.
pub const FRAME: Duration = Duration::from_millis(33);

/// Where terminal events come from (the terminal, or a script in tests).
pub trait EventSource {
    /// The next event, waiting at most `timeout`; None when none came.
    fn next(&mut self, timeout: Duration) -> anyhow::Result<Option<Event>>;
}

/// The real terminal's events.
pub struct TerminalEvents;

impl EventSource for TerminalEvents {
    fn next(&mut self, timeout: Duration) -> anyhow::Result<Option<Event>> {
        Ok(if event::poll(timeout)? { Some(event::read()?) } else { None })
    }
}

/// Sends what the app queued to the worker.
pub fn dispatch(app: &mut App, worker: &mut Worker) {
    for out in std::mem::take(&mut app.outbox) {
        match out {
            Outgoing::Engine(c) => worker.send(c),
            Outgoing::Robot(Some((policy, task))) => worker.start_robot(policy, task),
            Outgoing::Robot(None) => worker.stop_robot(),
            Outgoing::View { policy, task, out } => worker.view(policy, task, out),
            Outgoing::Video { policy, task, out } => worker.film(policy, task, out),
        }
    }
}

/// Sends what the app queued and applies the worker's messages until `until` holds; an error
/// after `timeout` says where the workbench stood (scripts, benchmarks and tests drive it so).
pub fn wait_until(
    app: &mut App,
    worker: &mut Worker,
    timeout: Duration,
    until: impl Fn(&App) -> bool,
) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    loop {
        dispatch(app, worker);
        if until(app) {
            return Ok(());
        }
        anyhow::ensure!(
            start.elapsed() < timeout,
            "the workbench did not get there in {timeout:?}; messages: {:?}; paused {} live {:?} steps {:?}",
            app.messages,
            app.paused,
            app.live.as_ref().map(|l| l.iteration),
            app.opened.as_ref().map(|o| o.results.steps.len())
        );
        if let Ok(m) = worker.messages.recv_timeout(Duration::from_millis(20)) {
            app.update(Action::Worker(m));
        }
    }
}

/// One pass of the loop: the worker's messages in, the queued commands out, and a frame
/// drawn if anything changed (a training iteration or a robot frame, a key, a resize).
pub fn tick<B: Backend>(terminal: &mut Terminal<B>, app: &mut App, worker: &mut Worker) -> anyhow::Result<()>
where
    B::Error: Send + Sync + 'static,
{
    while let Ok(m) = worker.messages.try_recv() {
        app.update(Action::Worker(m));
    }
    dispatch(app, worker);
    if std::mem::take(&mut app.dirty) {
        terminal.draw(|f| ui::draw(f, app))?;
    }
    Ok(())
}

/// The event loop until the user quits: draws at most every [`FRAME`], applies
/// every pending event, and on quit stops the session and waits for it (its
/// results are written by then).
pub fn run_app<B: Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
    worker: &mut Worker,
    events: &mut dyn EventSource,
) -> anyhow::Result<()>
where
    B::Error: Send + Sync + 'static,
{
    loop {
        tick(terminal, app, worker)?;
        if app.quit {
            break;
        }
        let mut wait = FRAME;
        while let Some(e) = events.next(wait)? {
            if let Some(a) = input::event_action(app, &e) {
                app.update(a);
            }
            dispatch(app, worker);
            if app.quit {
                break;
            }
            wait = Duration::ZERO;
        }
    }
    app.messages.push("stopping: writing the results ...".into());
    terminal.draw(|f| ui::draw(f, app))?;
    worker.shutdown();
    Ok(())
}

/// Restores the terminal when dropped (every exit path of [`run`]).
struct TerminalGuard;

fn restore_terminal() {
    let _ = disable_raw_mode();
    let _ = execute!(std::io::stdout(), LeaveAlternateScreen, DisableMouseCapture);
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        restore_terminal();
    }
}

/// The terminal in raw mode on the alternate screen with the mouse captured, restored on every
/// exit path of `body` (a panic included).
fn with_terminal(
    body: impl FnOnce(&mut Terminal<CrosstermBackend<Stdout>>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        restore_terminal();
        previous(info);
    }));
    enable_raw_mode()?;
    let _guard = TerminalGuard;
    execute!(std::io::stdout(), EnterAlternateScreen, EnableMouseCapture)?;
    let mut terminal = Terminal::new(CrosstermBackend::new(std::io::stdout()))?;
    body(&mut terminal)
}

/// The workbench on `terminal` for the run `spec` names, until the user quits.
fn workbench<B: Backend>(terminal: &mut Terminal<B>, events: &mut dyn EventSource, spec: OpenSpec) -> anyhow::Result<()>
where
    B::Error: Send + Sync + 'static,
{
    let size = terminal.size()?;
    let mut app = App::new(spec.run_dir.clone(), (size.width, size.height), Clock::Real(std::time::Instant::now()));
    let mut worker = Worker::spawn(spec);
    run_app(terminal, &mut app, &mut worker, events)
}

/// Opens the workbench on the terminal for the run `spec` names.
pub fn run(spec: OpenSpec) -> anyhow::Result<()> {
    with_terminal(|terminal| workbench(terminal, &mut TerminalEvents, spec))
}

/// Opens the Sweep screen on the terminal for the sweep folder `dir`; Enter on a cell opens
/// its run in the workbench, and quitting that comes back.
pub fn run_sweep(dir: std::path::PathBuf) -> anyhow::Result<()> {
    // Checked before the terminal changes: a folder without a plan is an error on stderr.
    crate::sweep::Plan::load(&dir)?;
    with_terminal(|terminal| {
        let size = terminal.size()?;
        let mut view = SweepView::new(dir.clone(), (size.width, size.height));
        let reader = SweepReader::spawn(&dir, true);
        let mut open = |t: &mut Terminal<CrosstermBackend<Stdout>>, events: &mut dyn EventSource, run| {
            workbench(t, events, OpenSpec { run_dir: run, config: None, continues: None })
        };
        run_sweep_app(terminal, &mut view, &reader, &mut TerminalEvents, &mut open)
    })
}
