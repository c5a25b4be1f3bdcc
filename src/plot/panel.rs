//! One chart of curves over iterations, the building block of the curve figures: lines with
//! optional shaded bands, labelled axes, and dashed vertical task boundaries named at the top.

use super::data::Curve;
use super::style::{text, CAPTION_SIZE, LABEL_SIZE, TICK_SIZE};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// A vertical dashed line at an iteration, named at the top (a task's start).
#[derive(Debug, Clone, PartialEq)]
pub struct Boundary {
    pub at: f64,
    pub label: String,
    pub colour: RGBColor,
    /// Which line of names, from the top, the label goes on (boundaries of several runs).
    pub label_row: u32,
}

/// The colour of boundaries that every run shares, and of a panel's notes.
pub const BOUNDARY_GREY: RGBColor = RGBColor(90, 90, 90);

/// What one panel shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinePanel {
    pub caption: String,
    /// The horizontal axis, with its unit.
    pub x_desc: String,
    /// The vertical axis, with its unit.
    pub y_desc: String,
    /// The curves, each in its colour, drawn in order.
    pub lines: Vec<(Curve, RGBColor)>,
    pub boundaries: Vec<Boundary>,
    /// Values the vertical axis always shows (0 and 1 for a share).
    pub y_includes: Vec<f64>,
    /// Iterations the horizontal axis always shows (a step's first and last, where a measure
    /// begins later).
    pub x_includes: Vec<f64>,
}

/// The horizontal range: every point and boundary.
fn x_range(panel: &LinePanel) -> (f64, f64) {
    let xs = panel.lines.iter().flat_map(|(c, _)| c.points.iter().map(|p| p.0));
    let marks = panel.boundaries.iter().map(|b| b.at).chain(panel.x_includes.iter().copied());
    let xs = xs.chain(marks).filter(|x| x.is_finite());
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
    if lo > hi {
        (0.0, 1.0)
    } else if hi - lo < 1.0 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    }
}

/// The vertical range: every value and band, the panel's fixed values, and a margin above
/// and below unless an end is one of the fixed values.
fn y_range(panel: &LinePanel) -> (f64, f64) {
    let mut range: Option<(f64, f64)> = None;
    let values: Vec<f64> =
        panel.lines.iter().filter_map(|(c, _)| c.value_range()).flat_map(|(lo, hi)| [lo, hi]).collect();
    // Without any value, the axis of a share: 0 to 1.
    let fallback: &[f64] = if values.is_empty() { &[0.0, 1.0] } else { &[] };
    for v in values.into_iter().chain(panel.y_includes.iter().copied()).chain(fallback.iter().copied()) {
        range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
    }
    // Beyond this the span of the axis would overflow (no measure gets near it).
    const LIMIT: f64 = 1e15;
    let (lo, hi) = range.map_or((0.0, 1.0), |(lo, hi)| (lo.clamp(-LIMIT, LIMIT), hi.clamp(-LIMIT, LIMIT)));
    if hi - lo < 1e-12 {
        let half = if lo.abs() > 1e-12 { lo.abs() * 0.1 } else { 0.5 };
        return (lo - half, hi + half);
    }
    let margin = 0.05 * (hi - lo);
    let fixed = |v: f64| panel.y_includes.iter().any(|f| (f - v).abs() < 1e-12);
    (if fixed(lo) { lo } else { lo - margin }, if fixed(hi) { hi } else { hi + margin })
}

/// Tick labels with as many decimals as the span needs.
fn tick_format(span: f64) -> impl Fn(&f64) -> String {
    let decimals = if span >= 20.0 {
        0
    } else if span >= 2.0 {
        1
    } else if span >= 0.2 {
        2
    } else {
        3
    };
    move |v: &f64| {
        let text = format!("{v:.decimals$}");
        // A tick a rounding error below zero reads 0, not -0.00.
        if text.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
            text.trim_start_matches('-').to_string()
        } else {
            text
        }
    }
}

/// Iteration ticks: whole numbers only (a tick between two iterations stays unlabelled).
fn iteration_format(v: &f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{v:.0}")
    } else {
        String::new()
    }
}

/// Draws `panel` into `area`.
pub fn draw_line_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &LinePanel) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let (x0, x1) = x_range(panel);
    let (y0, y1) = y_range(panel);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.caption, text(CAPTION_SIZE))
        .margin(8)
        .margin_right(18)
        .x_label_area_size(46)
        .y_label_area_size(74)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let y_format = tick_format(y1 - y0);
    chart
        .configure_mesh()
        .x_desc(panel.x_desc.as_str())
        .y_desc(panel.y_desc.as_str())
        .x_labels(((x1 - x0).floor() as usize + 1).clamp(2, 6))
        .y_labels(6)
        .x_label_formatter(&iteration_format)
        .y_label_formatter(&y_format)
        .label_style(text(TICK_SIZE))
        .axis_desc_style(text(LABEL_SIZE))
        .bold_line_style(BLACK.mix(0.08))
        .light_line_style(TRANSPARENT)
        .draw()?;
    for (curve, colour) in &panel.lines {
        if let Some(band) = &curve.band {
            let upper = curve.points.iter().zip(band).map(|((x, _), (_, hi))| (*x, *hi));
            let lower = curve.points.iter().zip(band).rev().map(|((x, _), (lo, _))| (*x, *lo));
            chart
                .draw_series(std::iter::once(Polygon::new(upper.chain(lower).collect::<Vec<_>>(), colour.mix(0.2))))?;
        }
    }
    for (curve, colour) in &panel.lines {
        chart.draw_series(LineSeries::new(curve.points.iter().copied(), colour.stroke_width(2)))?;
    }
    for b in &panel.boundaries {
        if b.at > x0 {
            let line = DashedPathElement::new(vec![(b.at, y0), (b.at, y1)], 6, 4, b.colour.stroke_width(1));
            chart.draw_series(std::iter::once(line))?;
        }
        let label = EmptyElement::at((b.at, y1))
            + Text::new(b.label.clone(), (4, 3 + 16 * b.label_row as i32), text(TICK_SIZE).color(&b.colour));
        chart.draw_series(std::iter::once(label))?;
    }
    if panel.lines.iter().all(|(c, _)| c.is_empty()) {
        let centre = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let style = text(LABEL_SIZE).color(&BOUNDARY_GREY).pos(Pos::new(HPos::Center, VPos::Center));
        let note = EmptyElement::at(centre) + Text::new("not recorded", (0, 0), style);
        chart.draw_series(std::iter::once(note))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panel(values: &[f64], includes: &[f64]) -> LinePanel {
        let lines = vec![(Curve::from_values(values, 1), BLACK)];
        LinePanel { lines, y_includes: includes.to_vec(), ..Default::default() }
    }

    #[test]
    fn the_value_axis_keeps_its_fixed_ends_and_pads_the_others() {
        assert_eq!(y_range(&panel(&[0.2, 0.6], &[0.0, 1.0])), (0.0, 1.0));
        let (lo, hi) = y_range(&panel(&[0.5, 2.5], &[0.0]));
        assert_eq!(lo, 0.0);
        assert!((hi - 2.625).abs() < 1e-12, "{hi}");
        assert_eq!(y_range(&panel(&[3.0, 3.0], &[])), (2.7, 3.3));
        assert_eq!(y_range(&panel(&[], &[0.0])), (0.0, 1.05));
        assert_eq!(x_range(&panel(&[1.0, 2.0, 3.0], &[])), (1.0, 3.0));
    }

    #[test]
    fn tick_labels_get_the_decimals_the_span_needs() {
        assert_eq!(tick_format(50.0)(&12.345), "12");
        assert_eq!(tick_format(1.0)(&0.5), "0.50");
        assert_eq!(tick_format(0.05)(&0.0123), "0.012");
        assert_eq!(tick_format(1.0)(&-1e-17), "0.00");
        assert_eq!(tick_format(1.0)(&-0.25), "-0.25");
        assert_eq!((iteration_format(&2.0), iteration_format(&2.5)), ("2".to_string(), String::new()));
    }
}
