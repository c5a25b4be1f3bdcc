//! The evaluation matrix `R[i][j]` (performance on task j after step i) as a
//! coloured table, forgetting per task, and the summary measures: average
//! performance, forgetting, plasticity, forward transfer, command tracking.
//! All from the engine's `Measures` events (or `metrics.json` when opened).

use super::{performance_color, short_task};
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

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let mut lines = Vec::new();
    let (Some(o), Some(summary)) = (&app.opened, &app.summary) else {
        f.render_widget(Paragraph::new("no results yet").block(block("Evaluation matrix", focused)), area);
        return;
    };
    let m = &o.results.eval_matrix;
    let selected_step = app.selected().and_then(|r| r.step);
    let mut head = vec![Span::raw(format!("{:<13}", "after step"))];
    head.extend(m.tasks.iter().map(|t| Span::raw(format!("{:>6}", short_task(t)))));
    lines.push(Line::from(head).style(Style::new().add_modifier(Modifier::UNDERLINED)));
    for (i, row) in m.rows.iter().enumerate() {
        let trained = m.trained.get(i).and_then(|j| m.tasks.get(*j)).map_or(String::new(), |t| short_task(t));
        let style = if selected_step == Some(i) { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() };
        let mut spans = vec![Span::styled(format!("{i:>2} {trained:<10}"), style)];
        for (j, v) in row.iter().enumerate() {
            let cell = v.map_or(format!("{:>6}", "·"), |x| format!("{x:>6.2}"));
            let mut s = v.map_or(Style::new().fg(Color::DarkGray), |x| Style::new().fg(performance_color(x)));
            if m.trained.get(i) == Some(&j) {
                s = s.add_modifier(Modifier::BOLD | Modifier::UNDERLINED);
            }
            spans.push(Span::styled(cell, s));
        }
        lines.push(Line::from(spans));
    }
    let mut forget = vec![Span::styled(format!("{:<13}", "forgetting"), Style::new().fg(Color::Gray))];
    forget.extend(summary.forgetting_per_task.iter().map(|v| {
        let color = match v {
            Some(x) if *x > 0.01 => Color::Red,
            Some(_) => Color::Green,
            None => Color::DarkGray,
        };
        Span::styled(v.map_or(format!("{:>6}", "-"), |x| format!("{x:>6.2}")), Style::new().fg(color))
    }));
    lines.push(Line::from(forget));
    lines.push(Line::raw(""));
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
    f.render_widget(Paragraph::new(lines).block(block("Evaluation matrix R[step][task]", focused)), area);
}
