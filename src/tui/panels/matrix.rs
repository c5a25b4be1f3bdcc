//! The evaluation matrix `R[i][j]` (performance on task j after step i) as a
//! coloured table, forgetting per task, and the summary measures: average
//! performance, forgetting, plasticity, forward transfer, command tracking.
//! All from the engine's `Measures` events (or `metrics.json` when opened).
//!
//! Every task is reachable at any size from 80x24: the columns are the short
//! task names (`cFL` for `crash:FL`), as narrow as the numbers allow, and when
//! they still do not fit, a window of them scrolls sideways (← →) with `◂` /
//! `▸` marks and "tasks a-b of n" in the title. The window follows the
//! selected step's task until the user scrolls. Rows past the panel's height
//! scroll with the selected step the same way.

use super::{performance_color, short_task};
use crate::cl::EvalMatrix;
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;
use ratatui::Frame;

fn fmt(x: Option<f64>) -> String {
    x.map_or("-".to_string(), |v| format!("{v:.3}"))
}

/// Which columns of the matrix are drawn, and how wide everything is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Columns {
    /// The first task column drawn.
    pub first: usize,
    /// How many task columns are drawn.
    pub count: usize,
    /// Task columns in the matrix.
    pub total: usize,
    /// Width of one task column (its leading space included).
    pub cell: usize,
    /// Width of the row labels ("11 iRR ").
    pub label: usize,
}

impl Columns {
    /// Some task columns are off the panel.
    pub fn scrolls(&self) -> bool {
        self.count < self.total
    }
}

/// The column of step `step`'s task.
fn trained_column(m: &EvalMatrix, step: Option<usize>) -> Option<usize> {
    step.and_then(|i| m.trained.get(i)).copied()
}

/// The columns that fit `width` (the panel's inner width): all of them when they fit, else the
/// window starting at `scroll` (clamped), or, when the user has not scrolled (`None`), the
/// first window that holds the selected step's task.
pub fn columns(m: &EvalMatrix, width: usize, scroll: Option<usize>, selected_step: Option<usize>) -> Columns {
    let total = m.tasks.len();
    let widest = m.rows.iter().flatten().flatten().map(|x| format!("{x:.2}").chars().count()).max().unwrap_or(4);
    let cell = widest.max(4) + 1;
    let trained = m.trained.iter().filter_map(|j| m.tasks.get(*j)).map(|t| short_task(t).chars().count());
    let label = (3 + trained.max().unwrap_or(3).clamp(3, 10) + 1).max(7);
    let all = (width.saturating_sub(label)) / cell;
    if all >= total {
        return Columns { first: 0, count: total, total, cell, label };
    }
    // One character is kept for the `▸` mark.
    let count = (width.saturating_sub(label + 1) / cell).max(1).min(total);
    let last_first = total - count;
    let first = match scroll {
        Some(s) => s.min(last_first),
        None => trained_column(m, selected_step).map_or(0, |j| j.saturating_sub(count - 1)).min(last_first),
    };
    Columns { first, count, total, cell, label }
}

/// The window of the matrix's rows that fits `height` lines and holds the selected step.
fn row_window(n: usize, height: usize, selected_step: Option<usize>) -> std::ops::Range<usize> {
    if n <= height {
        return 0..n;
    }
    let height = height.max(1);
    let want = selected_step.unwrap_or(n - 1).min(n - 1);
    let first = want.saturating_sub(height - 1).min(n - height);
    first..first + height
}

/// A column heading in `cell - 1` characters (a longer short name ends in `…`).
fn heading(task: &str, cell: usize) -> String {
    let short = short_task(task);
    let room = cell - 1;
    if short.chars().count() <= room {
        format!("{short:>cell$}")
    } else {
        let cut: String = short.chars().take(room - 1).collect();
        format!(" {cut}…")
    }
}

/// The panel's title: where the window is when the columns scroll.
fn title(c: &Columns) -> String {
    if c.scrolls() {
        format!("Evaluation matrix · tasks {}-{} of {} ←→", c.first + 1, c.first + c.count, c.total)
    } else {
        "Evaluation matrix R[step][task]".to_string()
    }
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let (Some(o), Some(summary)) = (&app.opened, &app.summary) else {
        f.render_widget(Paragraph::new("no results yet").block(block("Evaluation matrix", focused)), area);
        return;
    };
    let m = &o.results.eval_matrix;
    let selected_step = app.selected().and_then(|r| r.step);
    let inner = block("", focused).inner(area);
    let c = columns(m, inner.width as usize, app.matrix_scroll, selected_step);
    let shown = c.first..c.first + c.count;
    let more_left = c.first > 0;
    let more_right = c.first + c.count < c.total;
    let mark = |on: bool, glyph: &'static str| {
        Span::styled(if on { glyph } else { " " }, Style::new().fg(Color::Cyan).add_modifier(Modifier::BOLD))
    };
    let label = c.label;
    let mut lines = Vec::new();
    let mut head = vec![Span::raw(format!("{:<w$}", "step", w = label - 1)), mark(more_left, "◂")];
    head.extend(m.tasks[shown.clone()].iter().map(|t| Span::raw(heading(t, c.cell))));
    head.push(mark(more_right, "▸"));
    lines.push(Line::from(head).style(Style::new().add_modifier(Modifier::UNDERLINED)));
    // Header, forgetting, a blank line and the two summary lines stay in view.
    let rows = row_window(m.rows.len(), (inner.height as usize).saturating_sub(5).max(3), selected_step);
    let cell = c.cell;
    for i in rows.clone() {
        let row = &m.rows[i];
        let trained = m.trained.get(i).and_then(|j| m.tasks.get(*j)).map_or(String::new(), |t| short_task(t));
        let style = if selected_step == Some(i) { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() };
        let name: String = trained.chars().take(label - 4).collect();
        let mut spans = vec![Span::styled(format!("{i:>2} {name:<w$}", w = label - 4), style), Span::raw(" ")];
        for (j, v) in row.iter().enumerate().filter(|(j, _)| shown.contains(j)) {
            let text = v.map_or(format!("{:>cell$}", "·"), |x| format!("{x:>cell$.2}"));
            let mut s = v.map_or(Style::new().fg(Color::DarkGray), |x| Style::new().fg(performance_color(x)));
            if m.trained.get(i) == Some(&j) {
                s = s.add_modifier(Modifier::BOLD | Modifier::UNDERLINED);
            }
            spans.push(Span::styled(text, s));
        }
        lines.push(Line::from(spans));
    }
    let hidden_rows = m.rows.len() - rows.len();
    let word = if label > 10 { "forgetting" } else { "forget" };
    let mut forget = vec![Span::styled(format!("{word:<label$}"), Style::new().fg(Color::Gray))];
    forget.extend(summary.forgetting_per_task.iter().enumerate().filter(|(j, _)| shown.contains(j)).map(|(_, v)| {
        let color = match v {
            Some(x) if *x > 0.01 => Color::Red,
            Some(_) => Color::Green,
            None => Color::DarkGray,
        };
        Span::styled(v.map_or(format!("{:>cell$}", "-"), |x| format!("{x:>cell$.2}")), Style::new().fg(color))
    }));
    lines.push(Line::from(forget));
    let mut notes = Vec::new();
    if hidden_rows > 0 {
        notes.push(format!("steps {}-{} of {} (↑↓ selects)", rows.start, rows.end - 1, m.rows.len()));
    }
    if c.scrolls() {
        notes.push(format!("{} tasks off the panel: ←→", c.total - c.count));
    }
    notes.push("c crash  i invert  n noise".to_string());
    lines.push(Line::styled(notes.join(" · "), Style::new().fg(Color::Gray)));
    lines.push(Line::raw(format!(
        "average performance {}   forgetting {}   plasticity {}",
        fmt(summary.average_performance),
        fmt(summary.forgetting),
        fmt(summary.plasticity),
    )));
    lines.push(Line::raw(format!(
        "forward transfer {}",
        summary.forward_transfer_mean.map_or("- (the run file names no [run] reference)".into(), |v| format!("{v:.3}"))
    )));
    let t = &summary.command_tracking;
    lines.push(Line::styled("at the end, per task:", Style::new().fg(Color::Gray)));
    for (j, name) in o.results.tasks.iter().enumerate() {
        let get = |v: &Vec<Option<f64>>| v.get(j).copied().flatten();
        if get(&t.lin_vel_err).is_none() {
            continue;
        }
        lines.push(Line::raw(format!(
            "  {name:<18} lin_vel_err {}  ang_vel_err {}  fall rate {}",
            fmt(get(&t.lin_vel_err)),
            fmt(get(&t.ang_vel_err)),
            fmt(get(&t.fall_rate))
        )));
    }
    if let Some(e) = &app.last_eval {
        lines.push(Line::raw(format!(
            "evaluated now: {} R {:.3} return {:.2} lin {:.3} ang {:.3} fall {:.2} ({} episodes)",
            e.report.task,
            e.performance,
            e.report.mean_return,
            e.report.lin_vel_err,
            e.report.ang_vel_err,
            e.report.fall_rate,
            e.report.episodes
        )));
    }
    f.render_widget(Paragraph::new(lines).block(block(&title(&c), focused)), area);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(n: usize) -> EvalMatrix {
        let names = ["crash", "invert", "noise"];
        let legs = ["FL", "FR", "RL", "RR"];
        let mut tasks = vec!["none".to_string()];
        tasks.extend((0..n).map(|i| format!("{}:{}", names[i % 3], legs[i / 3 % 4])));
        let mut m = EvalMatrix::new(tasks);
        for i in 0..n {
            let results: Vec<(usize, f64)> = (0..=i + 1).map(|j| (j, 0.8)).collect();
            m.push_step(i + 1, &results).unwrap();
        }
        m
    }

    #[test]
    fn thirteen_columns_fit_the_120_column_panel_without_scrolling() {
        let c = columns(&matrix(12), 74, None, Some(11));
        assert_eq!((c.first, c.count, c.total), (0, 13, 13), "{c:?}");
        assert!(!c.scrolls());
    }

    #[test]
    fn at_80_columns_the_window_follows_the_selected_task_and_scrolls_to_every_column() {
        let m = matrix(12);
        let c = columns(&m, 46, None, Some(11));
        assert!(c.scrolls() && c.count >= 5, "{c:?}");
        assert_eq!(c.first + c.count, 13, "the last step's task (column 12) is in view");
        let first = columns(&m, 46, None, Some(0));
        assert_eq!(first.first, 0, "step 0's task (column 1) is in the first window");
        // Scrolling reaches every column and stops at the last window.
        let mut seen = [false; 13];
        for s in 0..20 {
            let c = columns(&m, 46, Some(s), None);
            (c.first..c.first + c.count).for_each(|j| seen[j] = true);
            assert!(c.first + c.count <= 13);
        }
        assert!(seen.iter().all(|s| *s));
    }

    #[test]
    fn rows_past_the_height_scroll_with_the_selected_step() {
        assert_eq!(row_window(12, 20, Some(3)), 0..12);
        assert_eq!(row_window(30, 10, Some(3)), 0..10);
        assert_eq!(row_window(30, 10, Some(25)), 16..26);
        assert_eq!(row_window(30, 10, None), 20..30);
    }

    #[test]
    fn a_long_short_name_is_cut_with_an_ellipsis() {
        assert_eq!(heading("crash:FL", 5), "  cFL");
        assert_eq!(heading("invert:RR+noise:FR", 5), " iRR…");
    }
}
