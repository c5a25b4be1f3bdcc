//! The selected step's training curve (or the whole sequence's, with task
//! boundaries): the raw line faint, a debiased-EMA smoothing over it whose
//! weight the user sets (or switches off), downsampled to the chart's width.
//! Live while the step trains (its curve grows with each iteration event).

use super::plasticity_series::{churn_series, plasticity_series, Series};
use crate::engine::TaskCurve;
use crate::rl::metric_names;
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::layout::{Constraint, Rect};
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
    /// `plasticity/dormant/NET`, one line per network.
    Dormant,
    /// `plasticity/effective_rank/NET`, one line per network.
    EffectiveRank,
    /// `plasticity/selected_abs_w/LAYER`, one line per layer of one network (`n` cycles them).
    SelectedAbsW,
    /// `plasticity/trainable_share/LAYER`, one line per layer of one network.
    TrainableShare,
    /// `charts/mask_churn/LAYER`: the share of the selected weights redrawn since the last
    /// iteration, one line per layer of one network.
    MaskChurn,
}

impl CurveMetric {
    pub fn label(self) -> &'static str {
        match self {
            CurveMetric::Performance => "performance",
            CurveMetric::Return => "return",
            CurveMetric::LinVelErr => "lin_vel_err m/s",
            CurveMetric::AngVelErr => "ang_vel_err rad/s",
            CurveMetric::FallRate => "fall rate",
            CurveMetric::Dormant => "dormant units",
            CurveMetric::EffectiveRank => "effective rank",
            CurveMetric::SelectedAbsW => "selected |w|",
            CurveMetric::TrainableShare => "trainable share",
            CurveMetric::MaskChurn => "mask churn",
        }
    }

    /// The values of this metric in `curve` (empty for a plasticity metric: see [`Self::plasticity_prefix`]).
    pub fn of(self, curve: &TaskCurve) -> &[f64] {
        match self {
            CurveMetric::Performance => &curve.performance,
            CurveMetric::Return => &curve.episodic_return,
            CurveMetric::LinVelErr => &curve.lin_vel_err,
            CurveMetric::AngVelErr => &curve.ang_vel_err,
            CurveMetric::FallRate => &curve.fall_rate,
            _ => &[],
        }
    }

    /// The metric-name prefix of a plasticity metric's series (`plasticity/dormant`, ...).
    pub fn plasticity_prefix(self) -> Option<&'static str> {
        match self {
            CurveMetric::Dormant => Some(metric_names::DORMANT),
            CurveMetric::EffectiveRank => Some(metric_names::EFFECTIVE_RANK),
            CurveMetric::SelectedAbsW => Some(metric_names::SELECTED_ABS_W),
            CurveMetric::TrainableShare => Some(metric_names::TRAINABLE_SHARE),
            _ => None,
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
            FallRate => Dormant,
            Dormant => EffectiveRank,
            EffectiveRank => SelectedAbsW,
            SelectedAbsW => TrainableShare,
            TrainableShare => MaskChurn,
            MaskChurn => Performance,
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
    let points: Vec<(f64, f64)> = values.iter().enumerate().map(|(i, v)| (i as f64, *v)).collect();
    downsample_points(&points, width)
}

/// At most `width` points: the mean (x and y) of each of `width` equal buckets of `points`.
pub fn downsample_points(points: &[(f64, f64)], width: usize) -> Vec<(f64, f64)> {
    if points.len() <= width || width == 0 {
        return points.to_vec();
    }
    (0..width)
        .map(|b| {
            let (lo, hi) =
                (b * points.len() / width, ((b + 1) * points.len() / width).max(b * points.len() / width + 1));
            let n = (hi - lo) as f64;
            let bucket = &points[lo..hi];
            (bucket.iter().map(|p| p.0).sum::<f64>() / n, bucket.iter().map(|p| p.1).sum::<f64>() / n)
        })
        .collect()
}

/// What the panel draws: one unnamed line for a training curve, or one named line per network
/// or layer for a plasticity diagnostic; the boundaries' x; what the title says it shows.
#[derive(Debug, Default)]
struct Shown {
    lines: Vec<Series>,
    bounds: Vec<f64>,
    what: String,
}

/// The curves to draw: the selected step's, or every step's in order (with the boundaries' x).
fn shown(app: &App) -> Shown {
    let Some(o) = &app.opened else { return Shown::default() };
    let mut curves: Vec<&TaskCurve> = o.results.curves.iter().collect();
    if let Some(l) = &app.live {
        curves.push(&l.curve);
    }
    let (curves, what) = if app.whole_sequence {
        (curves, "the whole sequence".to_string())
    } else {
        let Some(row) = app.selected() else { return Shown::default() };
        match row.step.and_then(|s| curves.iter().find(|c| c.step == s)) {
            Some(c) => (vec![*c], format!("step {} {}", c.step, c.name)),
            None => return Shown { what: row.task, ..Shown::default() },
        }
    };
    let layered = match (app.metric, app.metric.plasticity_prefix()) {
        (CurveMetric::MaskChurn, _) => Some(churn_series(&curves, app.network)),
        (_, Some(prefix)) => {
            let per_layer = matches!(app.metric, CurveMetric::SelectedAbsW | CurveMetric::TrainableShare);
            Some(plasticity_series(&curves, prefix, per_layer, app.network))
        }
        _ => None,
    };
    if let Some(s) = layered {
        let what = match s.network {
            Some((net, i, n)) => format!("{what} · {net} ({i}/{n})"),
            None => what,
        };
        return Shown { lines: s.lines, bounds: s.bounds, what };
    }
    let (mut values, mut bounds) = (Vec::new(), Vec::new());
    for c in curves {
        if !values.is_empty() {
            bounds.push(values.len() as f64 - 0.5);
        }
        values.extend_from_slice(app.metric.of(c));
    }
    let points = values.iter().enumerate().map(|(i, v)| (i as f64, *v)).collect();
    Shown { lines: vec![Series { name: String::new(), points }], bounds, what }
}

/// A line of `data` in `color`.
fn line(data: &[(f64, f64)], color: Color) -> Dataset<'_> {
    Dataset::default().marker(Marker::Braille).graph_type(GraphType::Line).style(Style::new().fg(color)).data(data)
}

/// The colours of the named lines (yellow marks the boundaries).
const LINE_COLORS: [Color; 6] =
    [Color::Cyan, Color::Magenta, Color::Green, Color::LightRed, Color::LightBlue, Color::White];

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let Shown { lines, bounds, what } = shown(app);
    let smoothing = if app.smoothing_on { format!("EMA {:.2}", app.smoothing) } else { "raw".to_string() };
    let title = format!("Curves: {} · {what} · {smoothing}", app.metric.label());
    if lines.iter().all(|l| l.points.is_empty()) {
        let why = match app.selected() {
            Some(r) if r.step.is_none() => "learned before the sequence (the base policy): no curve in this run",
            Some(_) if app.metric == CurveMetric::MaskChurn => {
                "no mask churn here (a dense method, a repeat, or not yet: it starts at a task's second iteration)"
            }
            Some(_) if app.metric.plasticity_prefix().is_some() => {
                "no plasticity diagnostics here (yet, or in a run written before they were recorded)"
            }
            Some(_) => "no iterations yet (space starts the next step)",
            None => "",
        };
        f.render_widget(Paragraph::new(Line::raw(why)).block(block(&title, focused)), area);
        return;
    }
    let width = (area.width.saturating_sub(10) as usize * 2).max(2);
    let ys = || lines.iter().flat_map(|l| l.points.iter().map(|p| p.1));
    let (mut lo, mut hi) = ys().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if hi - lo < 1e-9 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let iterations = lines.iter().flat_map(|l| l.points.last()).map(|p| p.0 as usize + 1).max().unwrap_or(0);
    let smoothed = |l: &Series| -> Vec<(f64, f64)> {
        let ys: Vec<f64> = l.points.iter().map(|p| p.1).collect();
        let ema = debiased_ema(&ys, app.smoothing);
        downsample_points(&l.points.iter().zip(ema).map(|(p, y)| (p.0, y)).collect::<Vec<_>>(), width)
    };
    let raw: Vec<Vec<(f64, f64)>> = lines.iter().map(|l| downsample_points(&l.points, width)).collect();
    let smooth: Vec<Vec<(f64, f64)>> = if app.smoothing_on { lines.iter().map(smoothed).collect() } else { Vec::new() };
    let boundary_lines: Vec<Vec<(f64, f64)>> = bounds.iter().map(|x| vec![(*x, lo), (*x, hi)]).collect();
    let mut datasets: Vec<Dataset> = boundary_lines.iter().map(|l| line(l, Color::Yellow)).collect();
    let named = lines.len() > 1 || lines.iter().any(|l| !l.name.is_empty());
    if named {
        // One colour per line: its smoothed values when smoothing is on, else the raw ones.
        let drawn = if app.smoothing_on { &smooth } else { &raw };
        for (i, (l, data)) in lines.iter().zip(drawn).enumerate() {
            datasets.push(line(data, LINE_COLORS[i % LINE_COLORS.len()]).name(l.name.clone()));
        }
    } else {
        datasets.push(line(&raw[0], if app.smoothing_on { Color::DarkGray } else { Color::Cyan }));
        if app.smoothing_on {
            datasets.push(line(&smooth[0], Color::Cyan));
        }
    }
    let chart = Chart::new(datasets)
        .block(block(&title, focused))
        .hidden_legend_constraints((Constraint::Ratio(1, 2), Constraint::Ratio(1, 1)))
        .x_axis(
            Axis::default()
                .bounds([0.0, (iterations as f64 - 1.0).max(1.0)])
                .labels(["0".to_string(), format!("{iterations} it")]),
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
