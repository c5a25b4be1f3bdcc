//! The Sweep screen's event loop: a reader thread takes a [`SweepSnapshot`] of
//! the folder every second; keys move the cursor; Enter on a cell opens its run
//! in the workbench (today's screens, through `open`), and quitting that comes
//! back here. [`run_sweep_app`] takes its backend, events and opener, so tests
//! drive it on ratatui's `TestBackend`.

use super::sweep_view::{snapshot, SweepAction, SweepSnapshot, SweepView};
use super::{EventSource, FRAME};
use ratatui::backend::Backend;
use ratatui::crossterm::event::{Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::Terminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// How often the folder is read.
pub const REFRESH: Duration = Duration::from_secs(1);

/// The thread that reads the sweep folder every [`REFRESH`] (and once right away).
pub struct SweepReader {
    pub snapshots: Receiver<SweepSnapshot>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl SweepReader {
    /// Starts reading `dir` (`scheduler`: ask Slurm too).
    pub fn spawn(dir: &Path, scheduler: bool) -> Self {
        let (sender, snapshots) = channel();
        let stop = Arc::new(AtomicBool::new(false));
        let (dir, flag) = (dir.to_path_buf(), stop.clone());
        let handle = std::thread::spawn(move || {
            while !flag.load(Ordering::Relaxed) {
                if sender.send(snapshot(&dir, scheduler)).is_err() {
                    return;
                }
                let mut waited = Duration::ZERO;
                while waited < REFRESH && !flag.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(50));
                    waited += Duration::from_millis(50);
                }
            }
        });
        Self { snapshots, stop, handle: Some(handle) }
    }
}

impl Drop for SweepReader {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// The action of a terminal event on the Sweep screen.
pub fn sweep_event_action(event: &Event) -> Option<SweepAction> {
    match event {
        Event::Key(k) if k.kind != KeyEventKind::Release => match k.code {
            KeyCode::Char('c') if k.modifiers.contains(KeyModifiers::CONTROL) => Some(SweepAction::Quit),
            KeyCode::Char('q') | KeyCode::Esc => Some(SweepAction::Quit),
            KeyCode::Up | KeyCode::Char('k') => Some(SweepAction::Up),
            KeyCode::Down | KeyCode::Char('j') => Some(SweepAction::Down),
            KeyCode::Enter => Some(SweepAction::Open),
            _ => None,
        },
        Event::Resize(w, h) => Some(SweepAction::Resize(*w, *h)),
        _ => None,
    }
}

/// Opens a run folder in the workbench on the terminal and returns when the user quits it.
pub type OpenRun<'a, B> = dyn FnMut(&mut Terminal<B>, &mut dyn EventSource, PathBuf) -> anyhow::Result<()> + 'a;

/// The Sweep screen until the user quits.
pub fn run_sweep_app<B: Backend>(
    terminal: &mut Terminal<B>,
    view: &mut SweepView,
    reader: &SweepReader,
    events: &mut dyn EventSource,
    open: &mut OpenRun<'_, B>,
) -> anyhow::Result<()>
where
    B::Error: Send + Sync + 'static,
{
    loop {
        while let Ok(s) = reader.snapshots.try_recv() {
            view.update(SweepAction::Refresh(Box::new(s)));
        }
        if let Some(run) = view.open.take() {
            open(terminal, events, run)?;
            terminal.clear()?;
            view.message = None;
            view.dirty = true;
        }
        if std::mem::take(&mut view.dirty) {
            terminal.draw(|f| super::panels::sweep::draw(f, view))?;
        }
        if view.quit {
            return Ok(());
        }
        let mut wait = FRAME;
        while let Some(e) = events.next(wait)? {
            if let Some(a) = sweep_event_action(&e) {
                view.update(a);
            }
            if view.quit || view.open.is_some() {
                break;
            }
            wait = Duration::ZERO;
        }
    }
}
