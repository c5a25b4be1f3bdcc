//! A legend as a strip of its own (a colour swatch and a label per series, wrapping into
//! rows), drawn beside the panels rather than over the curves.

use super::style::{text, text_width, LABEL_SIZE};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One series of a legend.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendEntry {
    pub label: String,
    pub colour: RGBColor,
}

const SWATCH: i32 = 28;
const ROW: i32 = 24;
const GAP: i32 = 26;
const PAD: i32 = 8;

/// Where each entry goes in a strip `width` pixels wide: (x, row).
fn layout(entries: &[LegendEntry], width: u32) -> Vec<(i32, i32)> {
    let (mut x, mut row) = (PAD, 0);
    let mut at = Vec::with_capacity(entries.len());
    for e in entries {
        let w = SWATCH + 6 + text_width(LABEL_SIZE, &e.label) as i32;
        if x > PAD && x + w > width as i32 - PAD {
            (x, row) = (PAD, row + 1);
        }
        at.push((x, row));
        x += w + GAP;
    }
    at
}

/// The height, in pixels, a legend of `entries` takes in a strip `width` pixels wide.
pub fn legend_height(entries: &[LegendEntry], width: u32) -> u32 {
    let rows = layout(entries, width).last().map_or(0, |(_, row)| row + 1);
    (rows * ROW + 2 * PAD) as u32
}

/// Draws the legend into `area`, from its top left.
pub fn draw_legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[LegendEntry]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let (width, _) = area.dim_in_pixel();
    for (e, (x, row)) in entries.iter().zip(layout(entries, width)) {
        let y = PAD + row * ROW + ROW / 2;
        area.draw(&PathElement::new(vec![(x, y), (x + SWATCH, y)], e.colour.stroke_width(3)))?;
        let style = text(LABEL_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
        area.draw_text(&e.label, &style, (x + SWATCH + 6, y))?;
    }
    Ok(())
}
