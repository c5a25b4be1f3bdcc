//! Training control: where training is (task, progress, iterations per
//! second, time left, env steps per second, the actor's mask sigma and churn),
//! what starts next, the last evaluation asked for, and the run folder
//! everything lands in.

use crate::engine::TaskCurve;
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Wrap};
use ratatui::Frame;
use std::collections::BTreeMap;

fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s}s"),
        60..=3599 => format!("{}m {:02}s", s / 60, s % 60),
        _ => format!("{}h {:02}m", s / 3600, s % 3600 / 60),
    }
}

/// The actor's soft scores at the last iteration (a masked method in a new task): the mean
/// sigma of its layers (in the run's `sigma_scale` units) and the mean share of its hard mask
/// redrawn, so the entropy phase's effect on the selection shows while it runs.
fn soft_scores_line(curve: &TaskCurve) -> Option<String> {
    let last_of_actor = |series: &BTreeMap<String, Vec<f64>>| -> Option<f64> {
        let last: Vec<f64> =
            series.iter().filter(|(k, _)| k.starts_with("actor.")).filter_map(|(_, v)| v.last().copied()).collect();
        (!last.is_empty()).then(|| last.iter().sum::<f64>() / last.len() as f64)
    };
    let sigma = last_of_actor(&curve.sigma)?;
    let churn = last_of_actor(&curve.mask_churn).map_or("-".into(), |c| format!("{:.1} %", 100.0 * c));
    Some(format!("actor masks: sigma {sigma:.3}  redrawn {churn}"))
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let mut lines = Vec::new();
    let bar_width = area.width.saturating_sub(22).max(5) as usize;
    if let Some(e) = &app.failure {
        lines.push(Line::styled(format!("failed: {e}"), Style::new().fg(Color::Red)));
    } else if let Some(l) = &app.live {
        let state = if app.paused { "paused" } else { "training" };
        lines.push(Line::raw(format!("{state} step {} {}", l.record.step, l.record.name)));
        let done = l.iteration as f64 / l.record.iterations.max(1) as f64;
        let filled = (done * bar_width as f64).round() as usize;
        lines.push(Line::from(vec![
            Span::styled("█".repeat(filled), Style::new().fg(Color::Cyan)),
            Span::styled("░".repeat(bar_width - filled.min(bar_width)), Style::new().fg(Color::DarkGray)),
            Span::raw(format!(" {}/{}", l.iteration, l.record.iterations)),
        ]));
        let rate = l.rate();
        let left = rate.map(|r| (l.record.iterations - l.iteration) as f64 / r);
        lines.push(Line::raw(format!(
            "{} it/s  {} SPS  left {}",
            rate.map_or("-".into(), |r| format!("{r:.2}")),
            l.sps.map_or("-".into(), |s| format!("{s:.0}")),
            left.map_or("-".into(), duration)
        )));
        if let Some(line) = soft_scores_line(&l.curve) {
            lines.push(Line::styled(line, Style::new().fg(Color::Gray)));
        }
        if l.physics_resets > 0 {
            lines.push(Line::styled(
                format!("physics resets {} (envs whose physics blew up, reset)", l.physics_resets),
                Style::new().fg(Color::Yellow),
            ));
        }
    } else if app.stopped {
        lines.push(Line::raw("stopped: the results are written"));
    } else {
        match app.next.step.as_ref() {
            Some((step, spec)) => {
                lines.push(Line::raw(format!("idle · next: step {step} {} · space starts it", spec.name)))
            }
            None => lines.push(Line::raw("idle · every step is learned (3, a: add a task)")),
        }
    }
    lines.push(Line::styled(
        if app.run_through {
            "mode: run through the sequence (r: step)"
        } else {
            "mode: one step at a time (r: run through)"
        },
        Style::new().fg(Color::Gray),
    ));
    if let Some(e) = &app.last_eval {
        lines.push(Line::raw(format!(
            "eval {}: R {:.3} lin {:.3} fall {:.2}",
            e.report.task, e.performance, e.report.lin_vel_err, e.report.fall_rate
        )));
    }
    let dir = app.opened.as_ref().map_or(app.opening.clone(), |o| o.run_dir.clone());
    lines.push(Line::styled(format!("→ {}", dir.display()), Style::new().fg(Color::Gray)));
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: true }).block(block("Training", focused)), area);
}
