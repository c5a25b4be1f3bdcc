//! The next task's controls: each ablation switch pending (for the next step
//! to start) beside the one in force (the step training now, or the last);
//! the forward-transfer composer (mode, related tasks among the learned ones,
//! the engine's preview of the elements per layer the bonus lifts); a task
//! string typed to add a step, with its parse error inline. Between steps,
//! the vacant share each layer keeps after the next one (`vacant_forecast`).

use crate::cl::Switches;
use crate::tui::app::App;
use crate::tui::next_task::SWITCH_ROWS;
use crate::tui::ui::block;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Wrap};
use ratatui::Frame;

fn switch_values(s: &Switches) -> [String; 8] {
    let on = |b: bool| if b { "on" } else { "off" }.to_string();
    [
        on(s.reinit_weights),
        s.reinit_scores.to_string(),
        s.reinit_range.to_string(),
        s.bias_start.to_string(),
        on(s.entropy),
        s.lambda.to_string(),
        format!("{:.2}", s.capacity),
        format!("{:.2}", s.private_share),
    ]
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let next = &app.next;
    let Some(run) = app.switches() else {
        f.render_widget(Paragraph::new("opening ...").block(block("Next task", focused)), area);
        return;
    };
    let in_force = app
        .live
        .as_ref()
        .and_then(|l| l.record.switches.clone())
        .or_else(|| app.opened.as_ref().and_then(|o| o.results.steps.last().and_then(|s| s.switches.clone())))
        .unwrap_or_else(|| run.clone());
    let pending = next.pending(run);
    let target = next.step.as_ref().map_or("no pending step: add a task (a)".to_string(), |(step, spec)| {
        let default = app.opened.as_ref().map_or(0, |o| o.sequence.iterations);
        format!("step {step} {} ({} iterations)", spec.name, spec.iterations.unwrap_or(default))
    });
    // The switches act on masked networks; a dense method's runs read none of them.
    let dense = app.opened.as_ref().and_then(|o| {
        let method = crate::cl::method_by_name(&o.method, &Default::default()).ok()?;
        (method.network_kind() == crate::nn::NetworkKind::Dense).then(|| o.method.clone())
    });
    let mut lines = vec![Line::raw(format!("for {target}"))];
    let dense_method = dense.clone();
    if let Some(method) = dense {
        lines.push(Line::styled(
            format!("  {method} trains a dense network: the switches below do nothing"),
            Style::new().fg(Color::Yellow),
        ));
    }
    lines.push(Line::styled(
        format!("  {:<18} {:>12} {:>13}", "switch", "pending", "in force"),
        Style::new().fg(Color::Gray).add_modifier(Modifier::UNDERLINED),
    ));
    let cursor_style = |row: usize| {
        if focused && next.cursor == row {
            Style::new().add_modifier(Modifier::REVERSED)
        } else {
            Style::new()
        }
    };
    let (p, now) = (switch_values(&pending), switch_values(&in_force));
    for (i, name) in SWITCH_ROWS.iter().enumerate() {
        let changed = p[i] != now[i];
        let value = Style::new().fg(if changed { Color::Yellow } else { Color::White });
        lines.push(Line::from(vec![
            Span::styled(format!("  {name:<18} "), cursor_style(i)),
            Span::styled(format!("{:>12}", p[i]), value.patch(cursor_style(i))),
            Span::raw(format!(" {:>13}", now[i])),
        ]));
    }
    match (&next.step, &app.live) {
        (Some((step, _)), None) if dense_method.is_none() => {
            lines.extend(super::vacant_forecast::lines(app, *step, &pending, area.width.saturating_sub(2) as usize));
        }
        (Some(_), Some(_)) if dense_method.is_none() => lines.push(Line::styled(
            "  (the vacant-share forecast for the next step shows when this one ends)",
            Style::new().fg(Color::Gray),
        )),
        _ => {}
    }
    let (related, init) = next.related();
    let mode_row = SWITCH_ROWS.len();
    lines.push(Line::raw(""));
    lines.push(Line::styled(
        format!("  {:<18} {:>12}", "transfer mode", format!("{init:?}").to_lowercase()),
        cursor_style(mode_row),
    ));
    lines.push(Line::styled("  related tasks (enter toggles):", Style::new().fg(Color::Gray)));
    for (k, t) in next.learned.iter().enumerate() {
        let mark = if related.contains(t) { "[x]" } else { "[ ]" };
        lines.push(Line::styled(format!("    {mark} {t}"), cursor_style(mode_row + 1 + k)));
    }
    lines.push(Line::styled("  + add a task at the end (a)", cursor_style(next.len() - 1)));
    if let Some(input) = &next.input {
        lines.push(Line::from(vec![
            Span::raw("  task: "),
            Span::styled(format!("{input}▏"), Style::new().fg(Color::Cyan)),
        ]));
        lines.push(Line::styled("  enter adds it, esc cancels; e.g. invert:RR+noise:FR", Style::new().fg(Color::Gray)));
    }
    if let Some(e) = &next.input_error {
        lines.push(Line::styled(format!("  {e}"), Style::new().fg(Color::Red)));
    }
    let current = next.step.as_ref().map(|(step, _)| *step);
    match &next.preview {
        Some(p) if p.related == related && p.init == init && Some(p.step) == current => {
            lines.push(Line::raw(""));
            if p.repeat {
                lines.push(Line::raw(
                    "  a repeat of a learned task: no transfer bonus (its private weights and bias train)",
                ));
            } else if p.lifted_from.is_empty() {
                lines.push(Line::raw("  no bonus: the soft scores start from their initial draw"));
            } else {
                lines.push(Line::styled(
                    format!("  the bonus on the masks of {} lifts, per layer:", p.lifted_from.join(", ")),
                    Style::new().fg(Color::Gray),
                ));
                let width = area.width.saturating_sub(4) as usize;
                let mut line = String::from("  ");
                for l in &p.layers {
                    let part = format!(
                        "{} {} ({:.0}%)   ",
                        l.layer,
                        l.lifted,
                        100.0 * l.lifted as f64 / l.total.max(1) as f64
                    );
                    if line.len() + part.len() > width {
                        lines.push(Line::raw(std::mem::replace(&mut line, String::from("  "))));
                    }
                    line.push_str(&part);
                }
                lines.push(Line::raw(line));
            }
        }
        _ => lines.push(Line::styled("  (the preview comes from the engine)", Style::new().fg(Color::Gray))),
    }
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: false }).block(block("Next task", focused)), area);
}
