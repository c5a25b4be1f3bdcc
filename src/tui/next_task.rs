//! The next task's controls: the ablation switches (pending, i.e. the next
//! step's sequence entry with what was queued, against those in force), the
//! forward-transfer composer (related tasks among the learned ones, the
//! mode, and the engine's preview of the elements the bonus lifts), and a
//! task string typed to add a step at the end. Every change becomes an
//! engine command; the state shown comes back from the engine's events.

use super::worker::Opened;
use crate::cl::{LambdaMode, SwitchOverrides, Switches, TaskSpec, TransferInit};
use crate::config::net::{BiasStart, ReinitRange, ScoreReinit};
use crate::engine::Command;
use crate::nn::LayerLift;
use std::str::FromStr;

/// The switch rows, then the mode row, then one row per learned task, then "add a task".
pub const SWITCH_ROWS: [&str; 8] = [
    "reinit weights",
    "reinit scores",
    "reinit range",
    "bias start",
    "entropy",
    "lambda",
    "capacity c",
    "private share p",
];
const MODE_ROW: usize = SWITCH_ROWS.len();

/// The engine's transfer preview for one choice of related tasks and mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Preview {
    pub step: usize,
    pub related: Vec<String>,
    pub init: TransferInit,
    /// The tasks whose masks get the bonus (drawn ones for `random`).
    pub lifted_from: Vec<String>,
    /// The step repeats a learned task: no bonus.
    pub repeat: bool,
    pub layers: Vec<LayerLift>,
}

/// The composer's state.
#[derive(Debug, Clone, Default)]
pub struct NextTask {
    pub cursor: usize,
    /// The step these controls act on, and its sequence entry.
    pub step: Option<(usize, TaskSpec)>,
    /// Switch changes queued since the last task started (from `SwitchesQueued`).
    pub queued: SwitchOverrides,
    /// Related tasks and mode queued (from `TransferQueued`), replacing the entry's.
    pub transfer: Option<(Vec<String>, TransferInit)>,
    /// The learned tasks a next task may name as related.
    pub learned: Vec<String>,
    pub preview: Option<Preview>,
    /// A task string being typed.
    pub input: Option<String>,
    pub input_error: Option<String>,
}

const LAMBDAS: [LambdaMode; 8] = [
    LambdaMode::Share(0.0),
    LambdaMode::Share(0.25),
    LambdaMode::Share(0.5),
    LambdaMode::Share(0.75),
    LambdaMode::Share(1.0),
    LambdaMode::Free,
    LambdaMode::Vacant,
    LambdaMode::PerLayer,
];

const SCORE_REINITS: [ScoreReinit; 3] = [ScoreReinit::Vacant, ScoreReinit::All, ScoreReinit::None];
const REINIT_RANGES: [ReinitRange; 2] = [ReinitRange::Initial, ReinitRange::HeEffective];
const BIAS_STARTS: [BiasStart; 3] = [BiasStart::Previous, BiasStart::Related, BiasStart::Zero];

/// The value after (`dir` >= 0) or before `now` in `values`, wrapping around.
fn cycle<T: Copy + PartialEq>(values: &[T], now: T, dir: i8) -> T {
    let i = values.iter().position(|v| *v == now).unwrap_or(0);
    let n = values.len();
    values[if dir < 0 { (i + n - 1) % n } else { (i + 1) % n }]
}

impl NextTask {
    /// Points the controls at step `step` of the open run.
    pub fn reset(&mut self, o: &Opened, step: usize) {
        self.step = o.sequence.tasks.get(step).map(|s| (step, s.clone()));
        let mut learned = o.base_tasks.clone();
        for s in &o.results.steps {
            if !learned.contains(&s.name) {
                learned.push(s.name.clone());
            }
        }
        self.learned = learned;
    }

    /// A task started: what was queued is in force now.
    pub fn task_started(&mut self) {
        self.queued = SwitchOverrides::default();
        self.transfer = None;
        self.preview = None;
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        MODE_ROW + 1 + self.learned.len() + 1
    }

    /// Whether there are no rows (never: the switches are always there).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The switches the next step will use.
    pub fn pending(&self, run: &Switches) -> Switches {
        let entry = self.step.as_ref().map(|(_, s)| s.switches.clone()).unwrap_or_default();
        run.with(&entry.merged(&self.queued))
    }

    /// The next step's related tasks and mode.
    pub fn related(&self) -> (Vec<String>, TransferInit) {
        match (&self.transfer, &self.step) {
            (Some(t), _) => t.clone(),
            (None, Some((_, s))) => (s.related.clone(), s.init),
            (None, None) => (Vec::new(), TransferInit::Related),
        }
    }

    pub fn move_cursor(&mut self, by: isize, _o: Option<&Opened>) {
        self.cursor = (self.cursor as isize + by).clamp(0, self.len() as isize - 1) as usize;
    }

    /// The commands that change the row under the cursor (`dir` -1 / +1, 0 toggles or steps up).
    pub fn change(&mut self, dir: i8, o: Option<&Opened>, _training: bool) -> Vec<Command> {
        let Some(o) = o else { return Vec::new() };
        if self.step.is_none() {
            if self.cursor == self.len() - 1 {
                self.input = Some(String::new());
            }
            return Vec::new();
        }
        let now = self.pending(&o.switches);
        let step = if dir < 0 { -0.01 } else { 0.01 };
        let round = |x: f64| (x * 100.0).round() / 100.0;
        let mut over = SwitchOverrides::default();
        match self.cursor {
            0 => over.reinit_weights = Some(!now.reinit_weights),
            1 => over.reinit_scores = Some(cycle(&SCORE_REINITS, now.reinit_scores, dir)),
            2 => over.reinit_range = Some(cycle(&REINIT_RANGES, now.reinit_range, dir)),
            3 => over.bias_start = Some(cycle(&BIAS_STARTS, now.bias_start, dir)),
            4 => over.entropy = Some(!now.entropy),
            5 => over.lambda = Some(cycle(&LAMBDAS, now.lambda, dir)),
            6 => over.capacity = Some(round((now.capacity + step).clamp(0.01, 1.0))),
            7 => over.private_share = Some(round((now.private_share + step).clamp(0.0, 1.0))),
            MODE_ROW => {
                let (related, init) = self.related();
                let modes = [TransferInit::Related, TransferInit::Random, TransferInit::Scratch];
                let i = modes.iter().position(|m| *m == init).unwrap_or(0);
                let next = modes[if dir < 0 { (i + 2) % 3 } else { (i + 1) % 3 }];
                return vec![Command::SetNextTransfer { related, init: next }];
            }
            r if r == self.len() - 1 => {
                self.input = Some(String::new());
                return Vec::new();
            }
            r => {
                let name = self.learned[r - MODE_ROW - 1].clone();
                let (mut related, init) = self.related();
                match related.iter().position(|t| *t == name) {
                    Some(i) => {
                        related.remove(i);
                    }
                    None => related.push(name),
                }
                return vec![Command::SetNextTransfer { related, init }];
            }
        }
        vec![Command::SetNextSwitches(over)]
    }

    pub fn type_char(&mut self, c: char) {
        if let Some(s) = &mut self.input {
            s.push(c);
            self.input_error = None;
        }
    }

    pub fn backspace(&mut self) {
        if let Some(s) = &mut self.input {
            s.pop();
            self.input_error = None;
        }
    }

    pub fn cancel_input(&mut self) {
        self.input = None;
        self.input_error = None;
    }

    /// The typed task as a sequence entry, or the parse error shown inline (None).
    pub fn submit(&mut self) -> Option<TaskSpec> {
        let text = self.input.as_deref()?.trim().to_string();
        match crate::sim::Perturbation::from_str(&text) {
            Ok(_) => Some(TaskSpec {
                name: text,
                iterations: None,
                related: Vec::new(),
                init: TransferInit::default(),
                switches: SwitchOverrides::default(),
            }),
            Err(e) => {
                self.input_error = Some(format!("{text:?}: {e}"));
                None
            }
        }
    }
}
