//! Figure `eval_matrix`: per run, the evaluation matrix `R[i][j]` (performance on task j after
//! training step i, METHOD.md 4) as an annotated heatmap, the task each step trained outlined,
//! and under it each task's forgetting `R[j][j] - R[N][j]` (performance right after it was
//! last trained minus at the end). Runs side by side, three to a row; runs without a matrix
//! (a single training) are left out.

use super::data::RunData;
use super::header::draw_header;
use super::style::{forgetting_colour, performance_colour, text, text_colour_on, text_width, LABEL_SIZE, TICK_SIZE};
use crate::cl::EvalMatrix;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The figure's title.
pub const EVAL_MATRIX_TITLE: &str = "Evaluation matrix and forgetting";

const TITLE_HEIGHT: u32 = 40;
const SCALE_HEIGHT: u32 = 64;
const PER_ROW: usize = 3;
const CELL_HEIGHT: i32 = 34;
const PAD: i32 = 16;
const BLOCK_TITLE: i32 = 52;
const X_DESC: i32 = 24;
const COLUMN_NAMES: i32 = 28;
const GAP: i32 = 10;
const NOTE: i32 = 28;
const FORGETTING_LABEL: &str = "forgetting";
const ROW_HEADER: &str = "after step: task trained";

/// The runs that have a matrix, with their colour index.
fn matrices(runs: &[RunData]) -> Vec<(&RunData, &EvalMatrix)> {
    runs.iter().filter_map(|r| Some((r, r.eval_matrix.as_ref().filter(|m| !m.rows.is_empty())?))).collect()
}

/// Row `i`'s label: the step and the task it trained.
fn row_label(m: &EvalMatrix, i: usize) -> String {
    format!("after {}: {}", i + 1, m.tasks[m.trained[i]])
}

/// One block's geometry, the same for every run so that the grid lines up.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Block {
    label_width: i32,
    cell_width: i32,
    /// The widest run label (the block's first title line, which must not run into the next block).
    title_width: i32,
    columns: usize,
    rows: usize,
}

impl Block {
    fn of(blocks: &[(&RunData, &EvalMatrix)]) -> Self {
        let width = |s: &str, size: f64| text_width(size, s) as i32;
        let mut b = Block {
            label_width: width(ROW_HEADER, TICK_SIZE) + 16,
            cell_width: 96,
            title_width: 0,
            columns: 1,
            rows: 1,
        };
        for (run, m) in blocks {
            b.title_width = b.title_width.max(width(&run.label, LABEL_SIZE) + 16);
            b.columns = b.columns.max(m.tasks.len());
            b.rows = b.rows.max(m.rows.len());
            for i in 0..m.rows.len() {
                b.label_width = b.label_width.max(width(&row_label(m, i), TICK_SIZE) + 16);
            }
            for t in &m.tasks {
                b.cell_width = b.cell_width.max(width(t, TICK_SIZE) + 16);
            }
        }
        b
    }

    fn width(&self) -> u32 {
        (2 * PAD + (self.label_width + self.columns as i32 * self.cell_width).max(self.title_width)) as u32
    }

    fn height(&self) -> u32 {
        let cells = (self.rows as i32 + 1) * CELL_HEIGHT;
        (BLOCK_TITLE + X_DESC + COLUMN_NAMES + cells + GAP + NOTE + PAD) as u32
    }
}

/// The figure's size for `runs`.
pub fn eval_matrix_size(runs: &[RunData]) -> (u32, u32) {
    let blocks = matrices(runs);
    let block = Block::of(&blocks);
    let per_row = blocks.len().clamp(1, PER_ROW);
    let grid_rows = blocks.len().div_ceil(PER_ROW).max(1);
    let width = (block.width() * per_row as u32).max(760);
    (width, TITLE_HEIGHT + SCALE_HEIGHT + block.height() * grid_rows as u32)
}

fn cell<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y, w): (i32, i32, i32),
    fill: RGBColor,
    label: &str,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    area.draw(&Rectangle::new([(x, y), (x + w, y + CELL_HEIGHT)], fill.filled()))?;
    area.draw(&Rectangle::new([(x, y), (x + w, y + CELL_HEIGHT)], RGBColor(210, 210, 210).stroke_width(1)))?;
    let ink = text_colour_on(fill);
    let style = text(TICK_SIZE).color(&ink).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw_text(label, &style, (x + w / 2, y + CELL_HEIGHT / 2))?;
    Ok(())
}

/// The colour scale of performance, under the title.
fn draw_scale<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let (width, _) = area.dim_in_pixel();
    let (x0, bar_width, y) = (width as i32 / 2 - 40, 300, 10);
    let left = text(LABEL_SIZE).pos(Pos::new(HPos::Right, VPos::Center));
    area.draw_text("performance R[i][j] (normalised return, 0-1)", &left, (x0 - 14, y + 8))?;
    for dx in 0..bar_width {
        let colour = performance_colour(dx as f64 / (bar_width - 1) as f64);
        area.draw(&Rectangle::new([(x0 + dx, y), (x0 + dx + 1, y + 16)], colour.filled()))?;
    }
    let tick = text(TICK_SIZE).pos(Pos::new(HPos::Center, VPos::Top));
    for k in 0..=4 {
        let v = k as f64 / 4.0;
        let x = x0 + (v * (bar_width - 1) as f64).round() as i32;
        area.draw(&PathElement::new(vec![(x, y + 16), (x, y + 21)], BLACK.stroke_width(1)))?;
        area.draw_text(&format!("{v:.2}"), &tick, (x, y + 23))?;
    }
    Ok(())
}

/// One run's matrix and forgetting into `area` (the block's size).
fn draw_block<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    run: &RunData,
    m: &EvalMatrix,
    b: &Block,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    let left = text(TICK_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    let centre = text(TICK_SIZE).pos(Pos::new(HPos::Center, VPos::Center));
    // Two lines: the run's label (a sweep group's can be long), then its summary.
    let summary = format!("average performance {}, forgetting {}", show(m.average_performance()), show(m.forgetting()));
    let title = text(LABEL_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw_text(&run.label, &title, (PAD, 14))?;
    area.draw_text(&summary, &text(TICK_SIZE).pos(Pos::new(HPos::Left, VPos::Center)), (PAD, 36))?;
    let x_cells = PAD + b.label_width;
    let cells_width = m.tasks.len() as i32 * b.cell_width;
    let mut y = BLOCK_TITLE;
    area.draw_text("task evaluated", &centre, (x_cells + cells_width / 2, y + X_DESC / 2))?;
    y += X_DESC;
    area.draw_text(ROW_HEADER, &left, (PAD, y + COLUMN_NAMES / 2))?;
    for (j, task) in m.tasks.iter().enumerate() {
        area.draw_text(task, &centre, (x_cells + j as i32 * b.cell_width + b.cell_width / 2, y + COLUMN_NAMES / 2))?;
    }
    y += COLUMN_NAMES;
    for (i, row) in m.rows.iter().enumerate() {
        area.draw_text(&row_label(m, i), &left, (PAD, y + CELL_HEIGHT / 2))?;
        for (j, value) in row.iter().enumerate() {
            let x = x_cells + j as i32 * b.cell_width;
            let fill = value.map_or(RGBColor(225, 225, 225), performance_colour);
            cell(area, (x, y, b.cell_width), fill, &show(*value))?;
        }
        let x = x_cells + m.trained[i] as i32 * b.cell_width;
        area.draw(&Rectangle::new(
            [(x + 1, y + 1), (x + b.cell_width - 1, y + CELL_HEIGHT - 1)],
            BLACK.stroke_width(2),
        ))?;
        y += CELL_HEIGHT;
    }
    y += GAP;
    area.draw_text(FORGETTING_LABEL, &left, (PAD, y + CELL_HEIGHT / 2))?;
    for (j, value) in m.forgetting_per_task().into_iter().enumerate() {
        let fill = value.map_or(RGBColor(225, 225, 225), forgetting_colour);
        let label = value.map_or("-".to_string(), |v| format!("{v:+.3}"));
        cell(area, (x_cells + j as i32 * b.cell_width, y, b.cell_width), fill, &label)?;
    }
    y += CELL_HEIGHT;
    let note = "forgetting: R[j][j] - R[N][j], right after last trained minus at the end";
    area.draw_text(note, &text(TICK_SIZE - 1.0).pos(Pos::new(HPos::Left, VPos::Center)), (PAD, y + NOTE / 2))?;
    Ok(())
}

/// Draws the figure for `runs` into `area`.
pub fn draw_eval_matrix<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, runs: &[RunData]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let body = draw_header(area, EVAL_MATRIX_TITLE, &[])?;
    let (scale, grid) = body.split_vertically(SCALE_HEIGHT);
    draw_scale(&scale)?;
    let blocks = matrices(runs);
    let block = Block::of(&blocks);
    for (k, (run, m)) in blocks.iter().enumerate() {
        let (row, column) = ((k / PER_ROW) as u32, (k % PER_ROW) as u32);
        let (x, y) = (column * block.width(), row * block.height());
        let block_area = grid.clone().shrink((x, y), (block.width(), block.height()));
        draw_block(&block_area, run, m, &block)?;
    }
    Ok(())
}
