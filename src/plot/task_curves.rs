//! Figure `task_curves`: each training step's curves, one row of panels per step and one
//! column per measure (performance, linear and yaw-rate tracking error, fall rate), every run
//! overlaid in its colour. Steps are matched by position in the sequence.

use super::data::{Measure, RunData};
use super::header::{draw_header, header_height};
use super::panel::{draw_line_panel, LinePanel};
use super::style::series_colour;
use super::{run_legend, smoothing_note, PlotOptions};
use plotters::coord::Shift;
use plotters::prelude::*;

/// One panel's size in pixels.
const PANEL: (u32, u32) = (450, 320);

/// The figure's title.
pub const TASK_CURVES_TITLE: &str = "Training curves per task";

fn step_rows(runs: &[RunData]) -> usize {
    runs.iter().map(|r| r.steps.len()).max().unwrap_or(0).max(1)
}

/// The figure's size for `runs`.
pub fn task_curves_size(runs: &[RunData]) -> (u32, u32) {
    let width = PANEL.0 * Measure::ALL.len() as u32;
    (width, header_height(width, &run_legend(runs)) + PANEL.1 * step_rows(runs) as u32)
}

/// The task names of step `step` over the runs, once each, in run order.
pub(super) fn step_names(runs: &[RunData], step: usize) -> String {
    let mut names: Vec<&str> = Vec::new();
    for name in runs.iter().filter_map(|r| r.steps.get(step)).map(|s| s.task.as_str()) {
        if !names.contains(&name) {
            names.push(name);
        }
    }
    names.join(" / ")
}

/// Draws the figure for `runs` into `area`.
pub fn draw_task_curves<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    runs: &[RunData],
    options: &PlotOptions,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let title = format!("{TASK_CURVES_TITLE}{}", smoothing_note(options));
    let body = draw_header(area, &title, &run_legend(runs))?;
    let rows = step_rows(runs);
    let panels = body.split_evenly((rows, Measure::ALL.len()));
    for step in 0..rows {
        let task = step_names(runs, step);
        let iterations = runs.iter().filter_map(|r| r.steps.get(step)).map(|s| s.iterations).max().unwrap_or(1);
        for (column, measure) in Measure::ALL.into_iter().enumerate() {
            let lines = runs
                .iter()
                .enumerate()
                .filter_map(|(i, r)| {
                    Some((r.steps.get(step)?.curve(measure).smoothed(options.smooth), series_colour(i)))
                })
                .collect();
            let panel = LinePanel {
                caption: format!("{}. {task}: {}", step + 1, measure.title()),
                x_desc: "iteration of the task".into(),
                y_desc: measure.axis().into(),
                lines,
                boundaries: Vec::new(),
                y_includes: measure.axis_includes().to_vec(),
                x_includes: vec![1.0, iterations as f64],
            };
            draw_line_panel(&panels[step * Measure::ALL.len() + column], &panel)?;
        }
    }
    Ok(())
}
