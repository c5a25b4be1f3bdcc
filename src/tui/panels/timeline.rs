//! The sequence timeline: every step with its task, kind, status (learned,
//! training with progress, pending; repeats marked), budget and final
//! performance. The cursor row selects what every other panel shows.

use crate::tui::app::App;
use crate::tui::timeline::{scroll, RowKind, RowStatus};
use crate::tui::ui::block;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;
use ratatui::Frame;

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let wide = area.width >= 44;
    let mut lines = vec![Line::styled(
        if wide { "  # task        kind status   budget     R" } else { "  # task       status       R" },
        Style::new().fg(Color::Gray).add_modifier(Modifier::UNDERLINED),
    )];
    let rows = app.rows();
    if rows.is_empty() {
        lines.push(Line::raw(if app.failure.is_some() { "  (no run open)" } else { "  opening ..." }));
    }
    let first = scroll(app, area.height);
    for (i, row) in rows.iter().enumerate().skip(first) {
        let step = row.step.map_or(" -".to_string(), |s| format!("{s:>2}"));
        let kind = match row.kind {
            RowKind::Base => "base",
            RowKind::New => "new",
            RowKind::Repeat => "rep",
        };
        let (status, color) = match row.status {
            RowStatus::Learned => ("learned".to_string(), Color::Green),
            RowStatus::Training { iteration, iterations, paused } => {
                let pct = 100 * iteration / iterations.max(1);
                (format!("{}{pct:>3}%", if paused { "‖ " } else { "▶ " }), Color::Cyan)
            }
            RowStatus::Pending => ("pending".to_string(), Color::Gray),
        };
        let budget = row.budget.map_or("-".to_string(), |b| b.to_string());
        let perf = row.performance.map_or("   -".to_string(), |p| format!("{p:.2}"));
        let perf_style =
            row.performance.map_or(Style::new().fg(Color::Gray), |p| Style::new().fg(super::performance_color(p)));
        let selected = i == app.cursor;
        let base = if selected { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() };
        let mut spans =
            vec![Span::styled(format!("{}{step} {:<11.11} ", if selected { "›" } else { " " }, row.task), base)];
        if wide {
            spans.push(Span::styled(format!("{kind:<4} "), base));
        }
        spans.push(Span::styled(format!("{status:<8} "), base.fg(color)));
        if wide {
            spans.push(Span::styled(format!("{budget:>6} "), base));
        }
        spans.push(Span::styled(format!("{perf:>5}"), perf_style.patch(base)));
        lines.push(Line::from(spans));
    }
    f.render_widget(Paragraph::new(lines).block(block("Sequence", focused)), area);
}
