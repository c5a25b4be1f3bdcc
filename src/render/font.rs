//! The one font of every picture quadcl draws (figures, video frames): DejaVu Sans, compiled in
//! and registered with plotters' ab_glyph text renderer, so no system font library is needed.
//!
//! The font is `DejaVuSans.ttf` beside this file, DejaVu fonts 2.37, unmodified; its licence
//! (Bitstream Vera's, DejaVu's changes in the public domain) is `DejaVuSans.LICENSE` beside it.

use plotters::style::FontStyle;
use std::sync::OnceLock;

/// The family name the font is registered under (SVG files name it too, so a viewer without
/// DejaVu Sans shows its own sans-serif).
pub const FONT: &str = "sans-serif";

static FONT_BYTES: &[u8] = include_bytes!("DejaVuSans.ttf");

/// Registers the font with plotters, once per process; everything that draws text calls it first.
pub fn register_font() -> anyhow::Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok());
    anyhow::ensure!(ok, "the compiled-in font src/render/DejaVuSans.ttf did not load");
    Ok(())
}
