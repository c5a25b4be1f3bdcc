//! The workbench's state and its one way to change: [`App::update`] with an
//! [`Action`] (a key, a click, a resize, or a message from the worker).
//! Drawing only borrows this state (`ui` and `panels/`). What the engine
//! must do is queued in [`App::outbox`] for the event loop to send; the app
//! computes no measure itself: results, evaluation matrix, summary, mask
//! statistics and element views all come from engine events.

use super::mask_zoom::{MaskZoom, ZoomMove};
use super::next_task::NextTask;
pub use super::panels::curves::CurveMetric;
use super::timeline::{rows, Row};
use super::worker::{Opened, WorkerMsg};
use crate::cl::Switches;
use crate::engine::{Command, Evaluation, StepRecord, Summary, TaskCurve};
use crate::nn::{LayerView, MaskReport};
use crate::rl::RobotFrame;
use std::path::PathBuf;

/// The screens (the timeline and training control are on each).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Screen {
    Overview,
    Evaluation,
    NextTask,
    Robot,
}

/// A panel that can have the focus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Panel {
    Timeline,
    Training,
    Curves,
    Masks,
    Matrix,
    Controls,
    Robot,
}

/// Everything a key, a click or the worker can do.
#[derive(Debug, Clone)]
pub enum Action {
    Quit,
    /// The answer to "quit while training?".
    ConfirmQuit(bool),
    ToggleHelp,
    FocusNext,
    FocusPrev,
    /// A mouse click at (column, row).
    Click(u16, u16),
    Show(Screen),
    CursorUp,
    CursorDown,
    /// Start the next step, or pause / resume the one in progress.
    StartPause,
    /// Step through the sequence (pause after each task) or run through it.
    ToggleRunThrough,
    EvaluateSelected,
    Save,
    /// The selected task in Rerun's 3D viewer (20 s, also saved as .rrd).
    OpenViewer,
    /// Write a short video of the selected task (its last checkpoint) into the run folder.
    WriteVideo,
    CurveMetricNext,
    /// Smoothing weight up / down; toggle off and on.
    SmoothingUp,
    SmoothingDown,
    SmoothingToggle,
    WholeSequence,
    NetworkNext,
    /// The mask heatmap zoomed into one layer: in, out, and moves through it.
    Zoom(ZoomMove),
    /// The evaluation matrix's task columns one to the right (+1) or left (-1).
    MatrixScroll(i8),
    ControlUp,
    ControlDown,
    /// Change the control row under the cursor (-1 / +1; 0 toggles).
    ControlChange(i8),
    BeginAddTask,
    Input(char),
    InputBackspace,
    /// Clear the line being typed.
    InputClear,
    InputSubmit,
    InputCancel,
    Resize(u16, u16),
    Worker(WorkerMsg),
}

/// What the event loop must do for the app.
#[derive(Debug, Clone, PartialEq)]
pub enum Outgoing {
    Engine(Command),
    /// Run the robot view of (policy, task); None stops it.
    Robot(Option<(PathBuf, String)>),
    /// Show (policy, task) in the Rerun viewer and save it into the `.rrd` file.
    View {
        policy: PathBuf,
        task: String,
        out: PathBuf,
    },
    /// Write a video of (policy, task) into the `.mp4` file, in the worker.
    Video {
        policy: PathBuf,
        task: String,
        out: PathBuf,
    },
}

/// The task in training, as its events tell it.
#[derive(Debug, Clone)]
pub struct Live {
    pub record: StepRecord,
    pub iteration: usize,
    pub curve: TaskCurve,
    /// Seconds (of the app's clock) at which recent iterations arrived.
    pub arrivals: Vec<f64>,
    /// Env steps per second the learner reported last.
    pub sps: Option<f64>,
    /// Envs reset so far in this task because their physics blew up (`charts/physics_resets`).
    pub physics_resets: usize,
}

impl Live {
    /// Iterations per second over the recent arrivals.
    pub fn rate(&self) -> Option<f64> {
        let (first, last) = (self.arrivals.first()?, self.arrivals.last()?);
        (self.arrivals.len() > 1 && last > first).then(|| (self.arrivals.len() - 1) as f64 / (last - first))
    }
}

/// The robot panel's state.
#[derive(Debug, Clone, Default)]
pub struct RobotView {
    pub task: Option<String>,
    pub frame: Option<RobotFrame>,
    /// The last picture of the robot (drawn in block characters where the panel is large enough).
    pub picture: Option<crate::render::Frame>,
    pub error: Option<String>,
}

/// Where the app's seconds come from: the wall clock, or a fixed tick per reading (tests).
#[derive(Debug, Clone)]
pub enum Clock {
    Real(std::time::Instant),
    Ticks(u64),
}

/// The workbench.
pub struct App {
    pub opened: Option<Opened>,
    /// What the worker was asked to open (shown until it answers).
    pub opening: PathBuf,
    pub live: Option<Live>,
    pub paused: bool,
    pub stopped: bool,
    pub failure: Option<String>,
    pub summary: Option<Summary>,
    pub report: Option<MaskReport>,
    /// Element views of one task (and the live iteration they show, while it trains).
    pub views: Option<(usize, Option<usize>, Vec<LayerView>)>,
    pub last_eval: Option<Evaluation>,
    pub cursor: usize,
    pub screen: Screen,
    pub focus: Panel,
    pub help: bool,
    pub confirm_quit: bool,
    pub quit: bool,
    /// EMA weight of the smoothed curve; `smoothing_on` false shows the raw line only.
    pub smoothing: f64,
    pub smoothing_on: bool,
    pub metric: CurveMetric,
    pub whole_sequence: bool,
    /// Train the rest of the sequence without pausing after each task.
    pub run_through: bool,
    pub network: usize,
    /// The Masks panel zoomed into one layer (None: every layer of the network).
    pub zoom: Option<MaskZoom>,
    /// The first task column of the evaluation matrix the user scrolled to (None: the window
    /// follows the selected step's task).
    pub matrix_scroll: Option<usize>,
    pub next: NextTask,
    pub robot: RobotView,
    pub messages: Vec<String>,
    pub size: (u16, u16),
    pub outbox: Vec<Outgoing>,
    /// Something changed since the last frame (the event loop draws only then).
    pub dirty: bool,
    clock: Clock,
}

impl App {
    /// A workbench waiting for the run in `opening`, on a terminal of `size`.
    pub fn new(opening: PathBuf, size: (u16, u16), clock: Clock) -> Self {
        Self {
            opened: None,
            opening,
            live: None,
            paused: true,
            stopped: false,
            failure: None,
            summary: None,
            report: None,
            views: None,
            last_eval: None,
            cursor: 0,
            screen: Screen::Overview,
            focus: Panel::Timeline,
            help: false,
            confirm_quit: false,
            quit: false,
            smoothing: 0.9,
            smoothing_on: true,
            metric: CurveMetric::Performance,
            whole_sequence: false,
            run_through: false,
            network: 0,
            zoom: None,
            matrix_scroll: None,
            next: NextTask::default(),
            robot: RobotView::default(),
            messages: Vec::new(),
            size,
            outbox: Vec::new(),
            dirty: true,
            clock,
        }
    }

    pub(super) fn now(&mut self) -> f64 {
        match &mut self.clock {
            Clock::Real(start) => start.elapsed().as_secs_f64(),
            Clock::Ticks(n) => {
                *n += 1;
                *n as f64
            }
        }
    }

    /// The timeline's rows (base tasks, then every step of the sequence).
    pub fn rows(&self) -> Vec<Row> {
        rows(self)
    }

    /// The selected row.
    pub fn selected(&self) -> Option<Row> {
        self.rows().into_iter().nth(self.cursor)
    }

    /// The run's switches, if open.
    pub fn switches(&self) -> Option<&Switches> {
        self.opened.as_ref().map(|o| &o.switches)
    }

    /// Whether a task is in progress (training or paused inside it): quitting loses its iterations.
    pub fn is_training(&self) -> bool {
        self.live.is_some() && !self.stopped
    }

    pub(super) fn say(&mut self, message: impl Into<String>) {
        self.messages.push(message.into());
        let n = self.messages.len();
        if n > 50 {
            self.messages.drain(..n - 50);
        }
    }

    fn send(&mut self, c: Command) {
        self.outbox.push(Outgoing::Engine(c));
    }

    /// Applies one action.
    pub fn update(&mut self, action: Action) {
        self.dirty = true;
        match action {
            Action::Quit if self.is_training() => self.confirm_quit = true,
            Action::Quit | Action::ConfirmQuit(true) => {
                self.confirm_quit = false;
                self.quit = true;
                self.send(Command::Stop);
            }
            Action::ConfirmQuit(false) => self.confirm_quit = false,
            Action::ToggleHelp => self.help = !self.help,
            Action::FocusNext | Action::FocusPrev => {
                let panels = super::ui::focus_order(self.screen);
                let i = panels.iter().position(|p| *p == self.focus).unwrap_or(0);
                let step = if matches!(action, Action::FocusNext) { 1 } else { panels.len() - 1 };
                self.focus = panels[(i + step) % panels.len()];
            }
            Action::Click(col, row) => self.click(col, row),
            Action::Show(screen) => self.show(screen),
            Action::CursorUp => self.move_cursor(-1),
            Action::CursorDown => self.move_cursor(1),
            Action::StartPause => self.start_pause(),
            Action::ToggleRunThrough => {
                self.run_through = !self.run_through;
                self.send(Command::PauseAfterEachTask(!self.run_through));
            }
            Action::EvaluateSelected => match self.selected() {
                Some(r) if r.learned() => self.send(Command::Evaluate(r.task)),
                Some(r) => self.say(format!("{} is not learned yet: nothing to evaluate", r.task)),
                None => {}
            },
            Action::Save => {
                self.send(Command::Save);
                self.say("saving metrics.json and the log (a task in progress is saved when it ends)");
            }
            Action::OpenViewer => self.view_selected(),
            Action::WriteVideo => self.film_selected(),
            Action::CurveMetricNext => self.metric = self.metric.next(),
            Action::SmoothingUp => self.smoothing = (self.smoothing + 0.05).min(0.99),
            Action::SmoothingDown => self.smoothing = (self.smoothing - 0.05).max(0.0),
            Action::SmoothingToggle => self.smoothing_on = !self.smoothing_on,
            Action::WholeSequence => self.whole_sequence = !self.whole_sequence,
            Action::NetworkNext => {
                let n = self.report.as_ref().map_or(1, |r| r.networks.len().max(1));
                self.network = (self.network + 1) % n;
                self.zoom = self.zoom.map(|_| MaskZoom::default());
            }
            Action::Zoom(m) => super::mask_zoom::update(self, m),
            Action::MatrixScroll(by) => self.scroll_matrix(by),
            Action::ControlUp => self.next.move_cursor(-1, self.opened.as_ref()),
            Action::ControlDown => self.next.move_cursor(1, self.opened.as_ref()),
            Action::ControlChange(dir) => {
                let commands = self.next.change(dir, self.opened.as_ref(), self.live.is_some());
                commands.into_iter().for_each(|c| self.send(c));
            }
            Action::BeginAddTask => {
                // The line is typed in the Next task panel: show it.
                self.show(Screen::NextTask);
                self.focus = Panel::Controls;
                self.next.input = Some(String::new());
            }
            Action::Input(c) => self.next.type_char(c),
            Action::InputBackspace => self.next.backspace(),
            Action::InputClear => {
                if let Some(s) = &mut self.next.input {
                    s.clear();
                }
            }
            Action::InputCancel => self.next.cancel_input(),
            Action::InputSubmit => {
                if let Some(spec) = self.next.submit() {
                    self.send(Command::AppendTask(spec));
                }
            }
            Action::Resize(w, h) => self.size = (w, h),
            Action::Worker(msg) => self.on_worker(msg),
        }
    }

    fn show(&mut self, screen: Screen) {
        self.screen = screen;
        if !super::ui::focus_order(screen).contains(&self.focus) {
            self.focus = Panel::Timeline;
        }
        self.follow_selection();
    }

    fn click(&mut self, col: u16, row: u16) {
        let area = ratatui::layout::Rect::new(0, 0, self.size.0, self.size.1);
        let hit = super::ui::panels(area, self.screen)
            .into_iter()
            .find(|(_, r)| col >= r.x && col < r.x + r.width && row >= r.y && row < r.y + r.height);
        if let Some((panel, rect)) = hit {
            self.focus = panel;
            if panel == Panel::Timeline && row > rect.y + 1 {
                let index = (row - rect.y - 2) as usize + super::timeline::scroll(self, rect.height);
                if index < self.rows().len() {
                    self.cursor = index;
                    self.follow_selection();
                }
            }
        }
    }

    fn move_cursor(&mut self, by: isize) {
        let n = self.rows().len();
        if n == 0 {
            return;
        }
        self.matrix_scroll = None;
        self.cursor = (self.cursor as isize + by).clamp(0, n as isize - 1) as usize;
        self.follow_selection();
    }

    /// Asks for what the selected row's panels show: its element views, its robot.
    pub(super) fn follow_selection(&mut self) {
        let Some(row) = self.selected() else { return };
        let known = self.opened.as_ref().is_some_and(|o| o.results.tasks.contains(&row.task));
        if known && self.views.as_ref().map(|v| v.0) != self.task_id(&row.task) {
            self.send(Command::WatchMasks(row.task.clone()));
        }
        let want = (self.screen == Screen::Robot && row.learned())
            .then(|| self.opened.as_ref().and_then(|o| o.last_checkpoint.clone()))
            .flatten()
            .map(|p| (p, row.task.clone()));
        let running = self.robot.task.clone();
        if want.as_ref().map(|w| &w.1) != running.as_ref() {
            self.robot = RobotView { task: want.as_ref().map(|w| w.1.clone()), ..Default::default() };
            self.outbox.push(Outgoing::Robot(want));
        }
    }

    /// The selected task's (policy, task, run-folder file `FOLDER/workbench-TASK.EXT`) when it is
    /// learned; else says that there is nothing to `what` yet.
    fn selected_learned(&mut self, what: &str, folder: &str, ext: &str) -> Option<(PathBuf, String, PathBuf)> {
        let (row, o) = (self.selected()?, self.opened.as_ref()?);
        let policy = o.last_checkpoint.clone().filter(|_| row.learned());
        let out = o.run_dir.join(folder).join(format!("workbench-{}.{ext}", crate::engine::task_file_name(&row.task)));
        match policy {
            Some(policy) => Some((policy, row.task, out)),
            None => {
                self.say(format!("{} is not learned yet: nothing to {what}", row.task));
                None
            }
        }
    }

    /// The selected learned task in Rerun's 3D viewer for 20 s, saved as `.rrd` into the run
    /// folder's `episodes/` too.
    fn view_selected(&mut self) {
        let Some((policy, task, out)) = self.selected_learned("show in 3D", crate::engine::EPISODES, "rrd") else {
            return;
        };
        self.say(format!("opening {task} in the Rerun viewer (and saving it to {}) ...", out.display()));
        self.outbox.push(Outgoing::View { policy, task, out });
    }

    /// 10 s of the selected learned task as a video in the run folder's `videos/`, written by the worker.
    fn film_selected(&mut self) {
        let Some((policy, task, out)) = self.selected_learned("film", crate::engine::VIDEOS, "mp4") else { return };
        self.say(format!("writing 10 s of {task} to {} ...", out.display()));
        self.outbox.push(Outgoing::Video { policy, task, out });
    }

    /// Asks the engine for the transfer preview of the next step's related tasks.
    pub(super) fn refresh_preview(&mut self) {
        let (related, init) = self.next.related();
        if self.next.step.is_some() {
            self.send(Command::PreviewTransfer { related, init });
        }
    }

    /// Moves the matrix's window of task columns from where it is drawn now.
    fn scroll_matrix(&mut self, by: i8) {
        let (Some(o), Some(rect)) = (&self.opened, self.panel_rect(Panel::Matrix, Screen::Evaluation)) else { return };
        let width = super::ui::block("", false).inner(rect).width as usize;
        let step = self.selected().and_then(|r| r.step);
        let now = super::panels::matrix::columns(&o.results.eval_matrix, width, self.matrix_scroll, step);
        self.matrix_scroll =
            Some((now.first as isize + by as isize).clamp(0, (now.total - now.count) as isize) as usize);
    }

    /// Where `panel` is on `screen` at the terminal's size.
    pub fn panel_rect(&self, panel: Panel, screen: Screen) -> Option<ratatui::layout::Rect> {
        let area = ratatui::layout::Rect::new(0, 0, self.size.0, self.size.1);
        super::ui::panels(area, screen).into_iter().find(|(p, _)| *p == panel).map(|(_, r)| r)
    }

    fn task_id(&self, name: &str) -> Option<usize> {
        self.opened.as_ref()?.results.tasks.iter().position(|t| t == name)
    }

    fn start_pause(&mut self) {
        let Some(o) = &self.opened else { return };
        if self.stopped {
            self.say("the session has stopped; reopen the run folder to go on");
        } else if self.paused {
            if self.live.is_none() && o.results.steps.len() >= o.sequence.tasks.len() {
                self.say("every step is learned: add a task on the Next task screen (3, then a)");
            } else {
                self.send(Command::Resume);
            }
        } else {
            self.send(Command::Pause);
        }
    }
}
