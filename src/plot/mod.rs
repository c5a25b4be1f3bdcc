//! Figures of runs (`quadcl plot`, and `RUN_DIR/plots/` at the end of `quadcl run`), drawn
//! with plotters as PNG and SVG from the same code:
//!
//! - `task_curves`: each task's training curves (performance, linear and yaw-rate tracking
//!   error, fall rate) with several runs overlaid, one colour per run;
//! - `sequence`: the same measures over the whole sequence, task boundaries marked and named;
//! - `eval_matrix`: `R[i][j]` as a heatmap (performance on task j after step i, annotated) with
//!   each task's forgetting `R[j][j] - R[N][j]` (METHOD.md 4) in a row under it;
//! - `plasticity`: the `plasticity/FAMILY/MEMBER` measures of the curves, one panel per family
//!   (a line per network or layer for one run, each run's mean over them for several), when a
//!   run recorded any;
//! - `summary`: for sweep folders, the collected table drawn: per measure a row per group, its
//!   mean over the seeds, the 90 % interval and each seed.
//!
//! One function per figure takes the data ([`RunData`], read by [`load_run`] from a run's
//! `metrics.json` or a training's `metrics.jsonl`) and a plotters drawing area; [`Figure`]
//! names them. A [`Curve`] may carry a band (low, high per point), drawn shaded, for a spread
//! over seeds: a sweep folder is drawn one run per group, the seeds' mean with their range
//! (`seeds`). Text is DejaVu Sans, compiled in (`render::font`; licence in `src/render/DejaVuSans.LICENSE`).
//!
//! `metrics.json` keeps only the finite values of a measure, not the iterations they came
//! from; a measure with fewer values than its step ran iterations (the tracking errors and
//! fall rate have none before the first episode ends) is drawn ending at the step's last
//! iteration. Where an iteration in the middle had no value, the values before it are drawn
//! one iteration late per missing value. `metrics.jsonl` rows carry their iteration.

mod data;
mod eval_matrix;
mod finetunes;
mod header;
mod legend;
mod load;
mod panel;
mod plasticity;
mod render;
mod seeds;
mod sequence;
mod style;
mod summary;
mod task_curves;

pub use data::{plasticity_parts, Curve, Measure, OverSeeds, RunData, SeedMeasure, StepCurves};
pub use eval_matrix::{draw_eval_matrix, eval_matrix_size};
pub use finetunes::finetunes_png;
pub use legend::LegendEntry;
pub use load::{load_run, RUN_METRICS, TRAIN_METRICS};
pub use panel::{draw_line_panel, Boundary, LinePanel};
pub use plasticity::{draw_plasticity, plasticity_size};
pub use render::{render_png, render_svg, write_figures};
pub use seeds::{curve_across_seeds, is_sweep, load_sweep, runs_across_seeds};
pub use sequence::{draw_sequence, sequence_size};
pub use summary::{draw_summary, summary_size};
pub use task_curves::{draw_task_curves, task_curves_size};

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};
use std::path::{Path, PathBuf};

/// The folder of a run that holds its figures.
pub const PLOTS_DIR: &str = "plots";

/// How the curve figures draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlotOptions {
    /// Draw each curve as its trailing moving mean over this many iterations (1: as recorded).
    pub smooth: usize,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self { smooth: 1 }
    }
}

/// The figures, each written as `NAME.png` and `NAME.svg`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Figure {
    TaskCurves,
    Sequence,
    EvalMatrix,
    Plasticity,
    Summary,
}

impl Figure {
    pub const ALL: [Figure; 5] =
        [Figure::TaskCurves, Figure::Sequence, Figure::EvalMatrix, Figure::Plasticity, Figure::Summary];

    /// The file name without its extension.
    pub fn file_stem(self) -> &'static str {
        match self {
            Figure::TaskCurves => "task_curves",
            Figure::Sequence => "sequence",
            Figure::EvalMatrix => "eval_matrix",
            Figure::Plasticity => "plasticity",
            Figure::Summary => "summary",
        }
    }

    /// Whether `runs` have anything this figure shows (an evaluation matrix, plasticity measures).
    pub fn applies_to(self, runs: &[RunData]) -> bool {
        match self {
            Figure::TaskCurves | Figure::Sequence => !runs.is_empty(),
            Figure::EvalMatrix => runs.iter().any(|r| r.eval_matrix.as_ref().is_some_and(|m| !m.rows.is_empty())),
            Figure::Plasticity => runs.iter().any(RunData::has_plasticity),
            Figure::Summary => runs.iter().any(|r| r.over_seeds.is_some()),
        }
    }

    /// Its size in pixels (the SVG's too).
    pub fn size(self, runs: &[RunData]) -> (u32, u32) {
        match self {
            Figure::TaskCurves => task_curves_size(runs),
            Figure::Sequence => sequence_size(runs),
            Figure::EvalMatrix => eval_matrix_size(runs),
            Figure::Plasticity => plasticity_size(runs),
            Figure::Summary => summary_size(runs),
        }
    }

    /// Draws it into `area`.
    pub fn draw<DB: DrawingBackend>(
        self,
        area: &DrawingArea<DB, Shift>,
        runs: &[RunData],
        options: &PlotOptions,
    ) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        style::register_font()?;
        match self {
            Figure::TaskCurves => draw_task_curves(area, runs, options),
            Figure::Sequence => draw_sequence(area, runs, options),
            Figure::EvalMatrix => draw_eval_matrix(area, runs),
            Figure::Plasticity => draw_plasticity(area, runs, options),
            Figure::Summary => draw_summary(area, runs),
        }
    }
}

/// Writes every figure of the run in `run_dir` into `run_dir/plots/` (what `quadcl run` does
/// when it ends); returns the files written.
pub fn write_run_plots(run_dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let run = load_run(run_dir, None)?;
    write_figures(&[run], &run_dir.join(PLOTS_DIR), &PlotOptions::default())
}

/// The legend of `runs`: each one's label in its colour.
fn run_legend(runs: &[RunData]) -> Vec<LegendEntry> {
    runs.iter()
        .enumerate()
        .map(|(i, r)| LegendEntry { label: r.label.clone(), colour: style::series_colour(i) })
        .collect()
}

/// "(moving mean over N iterations)" after a title, when the curves are smoothed.
fn smoothing_note(options: &PlotOptions) -> String {
    if options.smooth > 1 {
        format!(" (moving mean over {} iterations)", options.smooth)
    } else {
        String::new()
    }
}
