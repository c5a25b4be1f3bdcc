//! The selected step's training curve (or the whole sequence's, with task
//! boundaries): the raw line faint, a debiased-EMA smoothing over it whose
//! weight the user sets (or switches off), downsampled to the chart's width.
//! Live while the step trains (its curve grows with each iteration event).

use crate::engine::TaskCurve;
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph};
use ratatui::Frame;

/// The training curve shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurveMetric {
    Performance,
    Return,
    LinVelErr,
    AngVelErr,
    FallRate,
}

impl CurveMetric {
    pub fn label(self) -> &'static str {
        match self {
            CurveMetric::Performance => "performance",
            CurveMetric::Return => "return",
            CurveMetric::LinVelErr => "lin_vel_err m/s",
            CurveMetric::AngVelErr => "ang_vel_err rad/s",
            CurveMetric::FallRate => "fall rate",
        }
    }

    /// The values of this metric in `curve`.
    pub fn of(self, curve: &TaskCurve) -> &[f64] {
        match self {
            CurveMetric::Performance => &curve.performance,
            CurveMetric::Return => &curve.episodic_return,
            CurveMetric::LinVelErr => &curve.lin_vel_err,
            CurveMetric::AngVelErr => &curve.ang_vel_err,
            CurveMetric::FallRate => &curve.fall_rate,
        }
    }

    /// The next metric in the cycle.
    pub fn next(self) -> Self {
        use CurveMetric::*;
        match self {
            Performance => Return,
            Return => LinVelErr,
            LinVelErr => AngVelErr,
            AngVelErr => FallRate,
            FallRate => Performance,
        }
    }
}

/// Debiased exponential moving average (as TensorBoard's smoothing): s_t = w s_(t-1) + (1 - w) x_t, divided by 1 - w^t.
pub fn debiased_ema(values: &[f64], weight: f64) -> Vec<f64> {
    let mut s = 0.0;
    let mut debias = 1.0;
    values
        .iter()
        .map(|x| {
            s = weight * s + (1.0 - weight) * x;
            debias *= weight;
            if debias < 1.0 {
                s / (1.0 - debias)
            } else {
                *x
            }
        })
        .collect()
}

/// At most `width` points: the mean of each of `width` equal buckets (x = the bucket's middle index).
pub fn downsample(values: &[f64], width: usize) -> Vec<(f64, f64)> {
    if values.len() <= width || width == 0 {
        return values.iter().enumerate().map(|(i, v)| (i as f64, *v)).collect();
    }
    (0..width)
        .map(|b| {
            let (lo, hi) =
                (b * values.len() / width, ((b + 1) * values.len() / width).max(b * values.len() / width + 1));
            let mean = values[lo..hi].iter().sum::<f64>() / (hi - lo) as f64;
            ((lo + hi - 1) as f64 / 2.0, mean)
        })
        .collect()
}

/// The curves to draw: the selected step's, or every step's in order (with the boundaries' x).
fn series(app: &App) -> (Vec<f64>, Vec<f64>, String) {
    let Some(o) = &app.opened else { return (Vec::new(), Vec::new(), String::new()) };
    let mut curves: Vec<&TaskCurve> = o.results.curves.iter().collect();
    if let Some(l) = &app.live {
        curves.push(&l.curve);
    }
    if app.whole_sequence {
        let mut values = Vec::new();
        let mut bounds = Vec::new();
        for c in curves {
            if !values.is_empty() {
                bounds.push(values.len() as f64 - 0.5);
            }
            values.extend_from_slice(app.metric.of(c));
        }
        return (values, bounds, "the whole sequence".into());
    }
    let Some(row) = app.selected() else { return (Vec::new(), Vec::new(), String::new()) };
    match row.step.and_then(|s| curves.iter().find(|c| c.step == s)) {
        Some(c) => (app.metric.of(c).to_vec(), Vec::new(), format!("step {} {}", c.step, c.name)),
        None => (Vec::new(), Vec::new(), row.task),
    }
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let (values, bounds, what) = series(app);
    let smoothing = if app.smoothing_on { format!("EMA {:.2}", app.smoothing) } else { "raw".to_string() };
    let title = format!("Curves: {} · {what} · {smoothing}", app.metric.label());
    if values.is_empty() {
        let why = match app.selected() {
            Some(r) if r.step.is_none() => "learned before the sequence (the base policy): no curve in this run",
            Some(_) => "no iterations yet (space starts the next step)",
            None => "",
        };
        f.render_widget(Paragraph::new(Line::raw(why)).block(block(&title, focused)), area);
        return;
    }
    let width = (area.width.saturating_sub(10) as usize * 2).max(2);
    let raw = downsample(&values, width);
    let smooth = if app.smoothing_on { downsample(&debiased_ema(&values, app.smoothing), width) } else { Vec::new() };
    let (mut lo, mut hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    if hi - lo < 1e-9 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let boundary_lines: Vec<Vec<(f64, f64)>> = bounds.iter().map(|x| vec![(*x, lo), (*x, hi)]).collect();
    let mut datasets: Vec<Dataset> = boundary_lines
        .iter()
        .map(|l| {
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::new().fg(Color::Yellow))
                .data(l)
        })
        .collect();
    let raw_style = if app.smoothing_on { Style::new().fg(Color::DarkGray) } else { Style::new().fg(Color::Cyan) };
    datasets.push(Dataset::default().marker(Marker::Braille).graph_type(GraphType::Line).style(raw_style).data(&raw));
    if app.smoothing_on {
        datasets.push(
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::new().fg(Color::Cyan))
                .data(&smooth),
        );
    }
    let n = values.len() as f64;
    let chart = Chart::new(datasets)
        .block(block(&title, focused))
        .x_axis(
            Axis::default().bounds([0.0, (n - 1.0).max(1.0)]).labels(["0".to_string(), format!("{} it", values.len())]),
        )
        .y_axis(Axis::default().bounds([lo, hi]).labels([format!("{lo:.2}"), format!("{hi:.2}")]));
    f.render_widget(chart, area);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_debiased_ema_starts_at_the_first_value_and_follows_a_step() {
        let s = debiased_ema(&[2.0, 2.0, 4.0, 4.0, 4.0], 0.5);
        assert_eq!(s[0], 2.0);
        assert_eq!(s[1], 2.0);
        assert!(s[2] > 2.0 && s[2] < 4.0);
        assert!(s[4] > s[3] && s[4] < 4.0);
        assert_eq!(debiased_ema(&[1.0, 3.0], 0.0), vec![1.0, 3.0], "weight 0 is the raw line");
    }

    #[test]
    fn downsampling_keeps_bucket_means_and_short_curves_whole() {
        assert_eq!(downsample(&[1.0, 2.0], 10), vec![(0.0, 1.0), (1.0, 2.0)]);
        let d = downsample(&(0..100).map(f64::from).collect::<Vec<_>>(), 10);
        assert_eq!(d.len(), 10);
        assert_eq!(d[0], (4.5, 4.5));
        assert_eq!(d[9], (94.5, 94.5));
    }
}
