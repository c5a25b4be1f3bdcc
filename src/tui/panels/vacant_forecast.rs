//! The Next task panel's capacity forecast: per masked layer, the vacant
//! share now and after the next step at its pending switches, the step at
//! which a layer runs out if the rest of the sequence keeps them, and what
//! the selection does then. The figures are `cl::forecast`'s, on the mask
//! statistics of the last finished step; a layer that the next step leaves
//! without a vacant element is red, one that runs out later in the sequence
//! yellow.

use crate::cl::{forecast, LambdaMode, LayerForecast, Switches};
use crate::tui::app::App;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};

/// The methods whose selection is the per-row quota rule the forecast follows.
const FORECAST_METHODS: [&str; 2] = ["ours", "wsn"];

/// What the selection does in a layer with no vacant element left (`nn::select`).
pub fn when_out(lambda: LambdaMode) -> &'static str {
    match lambda {
        LambdaMode::Share(_) | LambdaMode::Free | LambdaMode::PerLayer => {
            "a layer with no vacant element left takes each row's quota from occupied weights, which stay \
             frozen: the task only chooses among them and trains its bias"
        }
        LambdaMode::Vacant => {
            "lambda vacant takes only vacant elements: a row with none left selects nothing, and the layer \
             passes only the task's bias"
        }
    }
}

/// The forecast for every masked layer: the next step (index `step` of the sequence) and those
/// after it, each a new task unless its task is learned or comes earlier among them.
pub fn layer_forecasts(app: &App, step: usize, pending: &Switches) -> Vec<LayerForecast> {
    let (Some(o), Some(report)) = (&app.opened, &app.report) else { return Vec::new() };
    // PackNet and Piggyback choose their masks by rules of their own (`nn/masked/baselines.rs`).
    if !FORECAST_METHODS.contains(&o.method.as_str()) {
        return Vec::new();
    }
    let mut known = app.next.learned.clone();
    let coming: Vec<bool> = o.sequence.tasks[step.min(o.sequence.tasks.len())..]
        .iter()
        .map(|t| {
            let new = !known.contains(&t.name);
            known.push(t.name.clone());
            new
        })
        .collect();
    report.networks.iter().flat_map(|n| &n.layers).map(|l| forecast(l, pending, &coming)).collect()
}

/// The forecast's lines for a panel `width` wide, before step `step` starts.
pub fn lines(app: &App, step: usize, pending: &Switches, width: usize) -> Vec<Line<'static>> {
    let layers = layer_forecasts(app, step, pending);
    if layers.is_empty() {
        return Vec::new();
    }
    let gray = Style::new().fg(Color::Gray);
    let mut out = vec![Line::styled(
        format!(
            "  vacant share per layer, now→after step {step} (c {:.2}, lambda {}):",
            pending.capacity, pending.lambda
        ),
        gray,
    )];
    let mut line: Vec<Span> = vec![Span::raw("  ")];
    let mut used = 2;
    for l in &layers {
        let part = format!("{} {:.0}→{:.0}%", l.layer, 100.0 * l.share_now(), 100.0 * l.share_after_next());
        let style = match l.runs_out_at() {
            Some(0) => Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
            Some(_) => Style::new().fg(Color::Yellow),
            None => Style::new(),
        };
        if used + part.chars().count() + 2 > width && used > 2 {
            out.push(Line::from(std::mem::replace(&mut line, vec![Span::raw("  ")])));
            used = 2;
        }
        used += part.chars().count() + 2;
        line.push(Span::styled(part, style));
        line.push(Span::raw("  "));
    }
    out.push(Line::from(line));
    let first_out = layers.iter().filter_map(|l| l.runs_out_at().map(|s| (s, l))).min_by_key(|(s, _)| *s);
    let already: Vec<&str> = layers.iter().filter(|l| l.vacant_now == 0).map(|l| l.layer.as_str()).collect();
    let end = o_len(app).saturating_sub(1);
    let summary = match first_out {
        Some((0, l)) => format!("  step {step} uses up the vacant elements of {} (red)", l.layer),
        Some((s, l)) => {
            format!("  at these settings {} runs out at step {} (last step {end}; yellow)", l.layer, step + s)
        }
        None if !already.is_empty() => format!("  no vacant element left in {}", already.join(", ")),
        None => format!("  every layer keeps vacant elements to the last step ({end})"),
    };
    out.push(Line::styled(summary, Style::new().fg(if first_out.is_some() { Color::Yellow } else { Color::Gray })));
    if first_out.is_some() || !already.is_empty() {
        out.push(Line::styled(format!("  then: {}", when_out(pending.lambda)), gray));
    }
    out
}

fn o_len(app: &App) -> usize {
    app.opened.as_ref().map_or(0, |o| o.sequence.tasks.len())
}
