//! Figure `sequence`: the training measures over the whole sequence, one panel per measure,
//! each step's curve placed after the iterations of the steps before it, task boundaries
//! dashed and named (in grey when the runs share them, else in each run's colour), every run
//! overlaid in its colour.

use super::data::{Measure, RunData};
use super::header::{draw_header, header_height};
use super::panel::{draw_line_panel, Boundary, LinePanel, BOUNDARY_GREY};
use super::style::series_colour;
use super::{run_legend, smoothing_note, PlotOptions};
use plotters::coord::Shift;
use plotters::prelude::*;

const PANEL: (u32, u32) = (1600, 340);

/// The figure's title.
pub const SEQUENCE_TITLE: &str = "The whole sequence";

/// The figure's size for `runs`.
pub fn sequence_size(runs: &[RunData]) -> (u32, u32) {
    (PANEL.0, header_height(PANEL.0, &run_legend(runs)) + PANEL.1 * Measure::ALL.len() as u32)
}

/// Where each run's steps start in the sequence, named by their tasks (a boundary sits half an
/// iteration before a step's first one). Runs with the same steps share one grey set; when
/// runs ran other budgets or tasks, each distinct set is drawn in the colour of its first run,
/// its names a line lower than the set before (a boundary an earlier set has is drawn once).
pub(super) fn task_boundaries(runs: &[RunData]) -> Vec<Boundary> {
    let sets: Vec<Vec<(f64, String)>> = runs
        .iter()
        .map(|r| r.step_offsets().iter().zip(&r.steps).map(|(&at, s)| (at as f64 + 0.5, s.task.clone())).collect())
        .collect();
    let shared = sets.iter().all(|s| s == &sets[0]);
    let mut out: Vec<Boundary> = Vec::new();
    let mut row = 0;
    for (i, set) in sets.iter().enumerate() {
        if sets[..i].contains(set) {
            continue;
        }
        let colour = if shared { BOUNDARY_GREY } else { series_colour(i) };
        let new: Vec<Boundary> = set
            .iter()
            .filter(|(at, label)| !out.iter().any(|b| b.at == *at && &b.label == label))
            .map(|(at, label)| Boundary { at: *at, label: label.clone(), colour, label_row: row })
            .collect();
        out.extend(new);
        row += 1;
    }
    out
}

/// The first and last iteration of the longest run's sequence.
pub(super) fn sequence_span(runs: &[RunData]) -> Vec<f64> {
    let last = runs.iter().map(|r| r.steps.iter().map(|s| s.iterations).sum::<usize>()).max().unwrap_or(1);
    vec![1.0, last as f64]
}

/// Draws the figure for `runs` into `area`.
pub fn draw_sequence<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    runs: &[RunData],
    options: &PlotOptions,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let title = format!("{SEQUENCE_TITLE}{}", smoothing_note(options));
    let body = draw_header(area, &title, &run_legend(runs))?;
    let panels = body.split_evenly((Measure::ALL.len(), 1));
    for (measure, panel_area) in Measure::ALL.into_iter().zip(&panels) {
        let mut lines = Vec::new();
        for (i, run) in runs.iter().enumerate() {
            for (offset, step) in run.step_offsets().into_iter().zip(&run.steps) {
                lines.push((step.curve(measure).smoothed(options.smooth).shifted(offset as f64), series_colour(i)));
            }
        }
        let panel = LinePanel {
            caption: measure.title().into(),
            x_desc: "iteration of the sequence".into(),
            y_desc: measure.axis().into(),
            lines,
            boundaries: task_boundaries(runs),
            y_includes: measure.axis_includes().to_vec(),
            x_includes: sequence_span(runs),
        };
        draw_line_panel(panel_area, &panel)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::StepCurves;

    fn run(steps: &[(&str, usize)]) -> RunData {
        let steps =
            steps.iter().map(|(task, n)| StepCurves { task: task.to_string(), iterations: *n, ..Default::default() });
        RunData { label: "r".into(), source: "x".into(), steps: steps.collect(), eval_matrix: None, over_seeds: None }
    }

    #[test]
    fn runs_with_the_same_steps_share_grey_boundaries_and_other_budgets_get_their_own() {
        let short = run(&[("a", 4), ("b", 2)]);
        let shared = task_boundaries(&[short.clone(), short.clone()]);
        let at: Vec<(f64, &str)> = shared.iter().map(|b| (b.at, b.label.as_str())).collect();
        assert_eq!(at, [(0.5, "a"), (4.5, "b")]);
        assert!(shared.iter().all(|b| b.colour == BOUNDARY_GREY));
        let long = run(&[("a", 10), ("b", 2)]);
        let both = task_boundaries(&[short, long]);
        let at: Vec<(f64, RGBColor, u32)> = both.iter().map(|b| (b.at, b.colour, b.label_row)).collect();
        assert_eq!(at, [(0.5, series_colour(0), 0), (4.5, series_colour(0), 0), (10.5, series_colour(1), 1)]);
    }
}
