//! Figure `sequence`: the training measures over the whole sequence, one panel per measure,
//! each step's curve placed after the iterations of the steps before it, task boundaries
//! dashed and named (the first run's; a run whose steps ran other budgets keeps its own
//! positions), every run overlaid in its colour.

use super::data::{Measure, RunData};
use super::header::{draw_header, header_height};
use super::panel::{draw_line_panel, Boundary, LinePanel};
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

/// Where each step of `run` starts in the sequence, named by its task (a boundary sits half an
/// iteration before the step's first one).
pub(super) fn task_boundaries(run: &RunData) -> Vec<Boundary> {
    run.step_offsets()
        .iter()
        .zip(&run.steps)
        .map(|(&at, s)| Boundary { at: at as f64 + 0.5, label: s.task.clone() })
        .collect()
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
            boundaries: runs.first().map(task_boundaries).unwrap_or_default(),
            y_includes: measure.axis_includes().to_vec(),
            x_includes: sequence_span(runs),
        };
        draw_line_panel(panel_area, &panel)?;
    }
    Ok(())
}
