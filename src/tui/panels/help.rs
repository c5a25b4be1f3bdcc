//! The help overlay: every key of the workbench.

use crate::tui::ui::{block, centered};
use ratatui::layout::Rect;
use ratatui::widgets::{Clear, Paragraph, Wrap};
use ratatui::Frame;

/// Every key, one line each.
pub const KEYS: &[(&str, &str)] = &[
    ("?", "this help (any key closes it)"),
    ("q", "quit (asks first while a task trains)"),
    ("Tab / Shift-Tab", "next / previous panel (a mouse click focuses one too)"),
    ("1 2 3 4", "screens: Overview, Evaluation, Next task, Robot"),
    ("↑ ↓ / k j", "select a step (a row of the Next task panel when it has the focus)"),
    ("space", "start the next step / pause / resume training"),
    ("r", "run through the rest of the sequence, or pause after each step (the default)"),
    ("e", "evaluate the selected learned task now (also while a step trains)"),
    ("S", "save metrics.json and the log now"),
    ("m", "curves: next metric (performance, return, tracking, fall rate, plasticity/*)"),
    ("s  + -", "curves: smoothing on/off, stronger / weaker (debiased EMA)"),
    ("w", "curves: the selected step / the whole sequence"),
    ("n", "masks and per-layer plasticity curves: next network"),
    ("z", "masks: zoom into one layer (one element per half-cell, rows by the task's share) / back"),
    ("[ ] PgUp PgDn", "zoomed masks: previous / next layer, page through the rows; ← → the inputs"),
    ("← → / h l", "evaluation matrix: scroll the task columns (◂ ▸ mark more)"),
    ("← → enter", "next task: change the row (switch, mode, related task)"),
    ("a", "next task: type a task to add at the end (e.g. invert:RR+noise:FR)"),
    ("v", "3D: 20 s of the task in the Rerun viewer (started if needed), saved as .rrd"),
    ("V", "video: 10 s of the task as MP4 (videos/workbench-TASK.mp4; ffmpeg on PATH)"),
];

pub fn draw(f: &mut Frame, area: Rect) {
    let text: Vec<String> = KEYS.iter().map(|(k, what)| format!(" {k:<16} {what}")).collect();
    // As wide as the longest line allows; on a narrow terminal the lines wrap.
    let width = (text.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u16 + 2).min(area.width);
    let inner = width.saturating_sub(2).max(1) as usize;
    let rows: usize = text.iter().map(|l| l.chars().count().div_ceil(inner).max(1)).sum();
    let rect = centered(area, width, rows as u16 + 2);
    f.render_widget(Clear, rect);
    f.render_widget(Paragraph::new(text.join("\n")).wrap(Wrap { trim: false }).block(block("Keys", true)), rect);
}
