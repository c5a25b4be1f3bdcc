//! The top of every figure: its title, and under it the legend of the runs (or whatever the
//! figure's colours mean), above the panels.

use super::legend::{draw_legend, legend_height, LegendEntry};
use super::style::{text, TITLE_SIZE};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const TITLE_HEIGHT: u32 = 40;

/// The height of the header of a figure `width` pixels wide with `legend` under its title.
pub fn header_height(width: u32, legend: &[LegendEntry]) -> u32 {
    TITLE_HEIGHT + if legend.is_empty() { 0 } else { legend_height(legend, width) }
}

/// Fills `area` white, draws the title and the legend, and returns the area below them.
pub fn draw_header<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    legend: &[LegendEntry],
) -> anyhow::Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    area.fill(&WHITE)?;
    let (width, _) = area.dim_in_pixel();
    let style = text(TITLE_SIZE).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw_text(title, &style, (width as i32 / 2, TITLE_HEIGHT as i32 / 2))?;
    let (head, body) = area.split_vertically(header_height(width, legend));
    if !legend.is_empty() {
        let (_, legend_area) = head.split_vertically(TITLE_HEIGHT);
        draw_legend(&legend_area, legend)?;
    }
    Ok(body)
}
