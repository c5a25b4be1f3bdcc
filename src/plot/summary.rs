//! Figure `summary`, for sweep folders: the collected table drawn. One panel per measure
//! (average performance, forgetting, plasticity, forward transfer, fall rate, tracking
//! errors: those the groups have), a row per group: its mean over the seeds as a dot, the
//! 90 % bootstrap interval over seeds as a bar, and each seed's value as a ring, in the
//! group's colour in the other figures. Where zero is in a panel's range (forgetting,
//! forward transfer) it is marked. This is the figure a paper shows for a comparison of
//! methods or ablations (its Figures 4, 5, 8 and 11), with the spread it hides made visible.

use super::data::{OverSeeds, RunData};
use super::header::draw_header;
use super::style::{series_colour, text, text_width, CAPTION_SIZE, LABEL_SIZE, TICK_SIZE};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The figure's title.
pub const SUMMARY_TITLE: &str = "Each group over its seeds";

const TITLE_HEIGHT: u32 = 40;
const CAPTION: i32 = 34;
const ROW: i32 = 30;
const AXIS: i32 = 36;
const NOTE: i32 = 30;
const PANEL_WIDTH: i32 = 250;
const PANEL_PAD: i32 = 18;
const LEFT_PAD: i32 = 16;
const NOTE_TEXT: &str = "dot: mean over the seeds; bar: its 90 % bootstrap interval (10,000 resamples of the seeds); \
                         rings: each seed (quadcl sweep collect DIR prints the same numbers)";

/// The groups (runs drawn across seeds) with their colour index in the other figures.
fn groups(runs: &[RunData]) -> Vec<(usize, &RunData, &OverSeeds)> {
    runs.iter().enumerate().filter_map(|(i, r)| Some((i, r, r.over_seeds.as_ref()?))).collect()
}

/// The measures any group has, in the table's order: (key, heading).
fn measures(groups: &[(usize, &RunData, &OverSeeds)]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for (_, _, g) in groups {
        for m in &g.measures {
            if !out.iter().any(|(k, _)| *k == m.key) {
                out.push((m.key.clone(), m.heading.clone()));
            }
        }
    }
    let order = |k: &str| crate::sweep::MEASURES.iter().position(|(key, _)| *key == k).unwrap_or(usize::MAX);
    out.sort_by_key(|(k, _)| order(k));
    out
}

/// A group's row label: the run's label with the curves' note on the seeds replaced.
fn row_label(run: &RunData, g: &OverSeeds) -> String {
    let seeds = if g.seeds == 1 { "1 seed".to_string() } else { format!("{} seeds", g.seeds) };
    let prefix = run.label.split(&g.group).next().unwrap_or("");
    format!("{prefix}{} ({seeds})", g.group)
}

fn label_width(groups: &[(usize, &RunData, &OverSeeds)]) -> i32 {
    groups.iter().map(|(_, r, g)| text_width(LABEL_SIZE, &row_label(r, g)) as i32).max().unwrap_or(0) + 2 * LEFT_PAD
}

/// The figure's size for `runs`.
pub fn summary_size(runs: &[RunData]) -> (u32, u32) {
    let g = groups(runs);
    let width = label_width(&g) + measures(&g).len().max(1) as i32 * PANEL_WIDTH + PANEL_PAD;
    let height = TITLE_HEIGHT as i32 + CAPTION + g.len().max(1) as i32 * ROW + AXIS + NOTE;
    let note = text_width(TICK_SIZE, NOTE_TEXT) as i32 + 2 * LEFT_PAD;
    (width.max(note) as u32, height as u32)
}

/// Round tick values covering [low, high] (steps of 1, 2 or 5 times a power of ten, at most
/// six ticks) and the decimals that show the step.
fn ticks(low: f64, high: f64) -> (Vec<f64>, usize) {
    let span = (high - low).max(1e-9);
    let raw = span / 4.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * magnitude).find(|s| span / s <= 5.0).unwrap_or(raw);
    let first = (low / step).ceil() as i64;
    let last = (high / step).floor() as i64;
    let decimals = (-step.log10()).ceil().max(0.0) as usize;
    ((first..=last).map(|k| k as f64 * step).collect(), decimals)
}

/// The x range of a measure over every group's interval and seeds, padded.
fn range(groups: &[(usize, &RunData, &OverSeeds)], key: &str) -> (f64, f64) {
    let values = groups
        .iter()
        .filter_map(|(_, _, g)| g.measures.iter().find(|m| m.key == key))
        .flat_map(|m| m.values.iter().copied().chain([m.estimate.low, m.estimate.high, m.estimate.mean]));
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(0.01);
    (lo - pad, hi + pad)
}

/// Draws the figure for `runs` into `area`.
pub fn draw_summary<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, runs: &[RunData]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let body = draw_header(area, SUMMARY_TITLE, &[])?;
    let g = groups(runs);
    let left = label_width(&g);
    let top = CAPTION;
    let rows_height = g.len() as i32 * ROW;
    let row_y = |i: usize| top + i as i32 * ROW + ROW / 2;
    let label = text(LABEL_SIZE).pos(Pos::new(HPos::Right, VPos::Center));
    for (row, (_, run, over)) in g.iter().enumerate() {
        if row % 2 == 1 {
            let (w, _) = body.dim_in_pixel();
            let y = top + row as i32 * ROW;
            body.draw(&Rectangle::new([(0, y), (w as i32, y + ROW)], RGBColor(245, 245, 245).filled()))?;
        }
        body.draw_text(&row_label(run, over), &label, (left - LEFT_PAD, row_y(row)))?;
    }
    for (p, (key, heading)) in measures(&g).iter().enumerate() {
        let x0 = left + p as i32 * PANEL_WIDTH + PANEL_PAD;
        let x1 = x0 + PANEL_WIDTH - 2 * PANEL_PAD;
        let (lo, hi) = range(&g, key);
        let x_of = |v: f64| x0 + ((v - lo) / (hi - lo) * (x1 - x0) as f64).round() as i32;
        let caption = text(CAPTION_SIZE).pos(Pos::new(HPos::Center, VPos::Center));
        body.draw_text(heading, &caption, ((x0 + x1) / 2, CAPTION / 2))?;
        let tick_style = text(TICK_SIZE).pos(Pos::new(HPos::Center, VPos::Top));
        let (tick_values, decimals) = ticks(lo, hi);
        for t in tick_values {
            let x = x_of(t);
            body.draw(&PathElement::new(
                vec![(x, top), (x, top + rows_height)],
                RGBColor(225, 225, 225).stroke_width(1),
            ))?;
            body.draw(&PathElement::new(
                vec![(x, top + rows_height), (x, top + rows_height + 5)],
                BLACK.stroke_width(1),
            ))?;
            let shown = if t.abs() < 1e-12 { 0.0 } else { t };
            body.draw_text(&format!("{shown:.decimals$}"), &tick_style, (x, top + rows_height + 8))?;
        }
        body.draw(&PathElement::new(vec![(x0, top + rows_height), (x1, top + rows_height)], BLACK.stroke_width(1)))?;
        if lo < 0.0 && hi > 0.0 {
            let x = x_of(0.0);
            body.draw(&PathElement::new(vec![(x, top), (x, top + rows_height)], RGBColor(90, 90, 90).stroke_width(1)))?;
        }
        for (row, (colour_index, _, over)) in g.iter().enumerate() {
            let Some(m) = over.measures.iter().find(|m| m.key == *key) else { continue };
            let colour = series_colour(*colour_index);
            let y = row_y(row);
            let e = m.estimate;
            body.draw(&PathElement::new(vec![(x_of(e.low), y), (x_of(e.high), y)], colour.stroke_width(3)))?;
            for v in &m.values {
                body.draw(&Circle::new((x_of(*v), y), 4, colour.stroke_width(1)))?;
            }
            body.draw(&Circle::new((x_of(e.mean), y), 5, colour.filled()))?;
        }
    }
    let note_style = text(TICK_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    body.draw_text(NOTE_TEXT, &note_style, (LEFT_PAD, top + rows_height + AXIS + NOTE / 2 - 6))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_values_inside_the_range() {
        let (t, decimals) = ticks(0.0, 1.0);
        let expected = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
        assert!(t.len() == 6 && t.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12), "{t:?}");
        assert_eq!(decimals, 1);
        let (t, decimals) = ticks(-0.013, 0.087);
        assert_eq!(decimals, 2);
        assert!(t.len() >= 3 && t.len() <= 6, "{t:?}");
        assert!(t.iter().all(|v| (-0.013..=0.087).contains(v)), "{t:?}");
        assert!(t.iter().any(|v| v.abs() < 1e-12), "zero is a tick: {t:?}");
    }
}
