//! The figures' look, in one place: the font (DejaVu Sans, compiled in: `render::font`), text
//! sizes, the series colours and the colour scales of the evaluation matrix.

pub use crate::render::font::{register_font, FONT};
use plotters::style::{IntoFont, RGBColor, TextStyle};

/// Text of `size` pixels, black.
pub fn text(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&plotters::style::BLACK)
}

/// The width in pixels of `text` at `size` (for laying out before drawing).
pub fn text_width(size: f64, text_: &str) -> u32 {
    text(size).font.box_size(text_).map_or(0, |(w, _)| w)
}

/// A figure's title.
pub const TITLE_SIZE: f64 = 24.0;
/// A panel's caption.
pub const CAPTION_SIZE: f64 = 17.0;
/// Axis descriptions and legend entries.
pub const LABEL_SIZE: f64 = 15.0;
/// Tick labels and annotations.
pub const TICK_SIZE: f64 = 13.0;

/// Series colours, distinct on white (Tableau's 10, then two more); the `i`-th series gets
/// `series_colour(i)`, cycling after 12.
pub fn series_colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 12] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(0, 0, 128),
        RGBColor(128, 128, 0),
    ];
    PALETTE[i % PALETTE.len()]
}

fn lerp(a: RGBColor, b: RGBColor, t: f64) -> RGBColor {
    let mix = |x: u8, y: u8| (x as f64 + (y as f64 - x as f64) * t).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Performance on a 0-1 scale as a colour (viridis: dark purple at 0, yellow at 1); values
/// outside are clamped.
pub fn performance_colour(value: f64) -> RGBColor {
    const STOPS: [RGBColor; 5] = [
        RGBColor(68, 1, 84),
        RGBColor(59, 82, 139),
        RGBColor(33, 145, 140),
        RGBColor(94, 201, 98),
        RGBColor(253, 231, 37),
    ];
    let t = value.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    lerp(STOPS[i], STOPS[i + 1], t - i as f64)
}

/// Forgetting as a colour: white at 0, red as a task lost performance (at 0.5 and more, full),
/// blue as it gained.
pub fn forgetting_colour(value: f64) -> RGBColor {
    let t = (value.abs() / 0.5).min(1.0);
    let end = if value >= 0.0 { RGBColor(214, 39, 40) } else { RGBColor(31, 119, 180) };
    lerp(RGBColor(255, 255, 255), end, t)
}

/// Black or white, whichever reads on `background`.
pub fn text_colour_on(background: RGBColor) -> RGBColor {
    let luminance = 0.299 * background.0 as f64 + 0.587 * background.1 as f64 + 0.114 * background.2 as f64;
    if luminance > 140.0 {
        RGBColor(0, 0, 0)
    } else {
        RGBColor(255, 255, 255)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_performance_scale_runs_from_viridis_purple_to_yellow_and_clamps() {
        assert_eq!(performance_colour(0.0), RGBColor(68, 1, 84));
        assert_eq!(performance_colour(1.0), RGBColor(253, 231, 37));
        assert_eq!(performance_colour(-3.0), performance_colour(0.0));
        assert_eq!(text_colour_on(performance_colour(0.0)), RGBColor(255, 255, 255));
        assert_eq!(text_colour_on(performance_colour(1.0)), RGBColor(0, 0, 0));
    }

    #[test]
    fn forgetting_is_white_at_zero_and_red_when_a_task_lost_performance() {
        assert_eq!(forgetting_colour(0.0), RGBColor(255, 255, 255));
        assert_eq!(forgetting_colour(0.7), RGBColor(214, 39, 40));
        assert_eq!(forgetting_colour(-0.7), RGBColor(31, 119, 180));
    }
}
