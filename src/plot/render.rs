//! A figure drawn to PNG bytes (plotters' bitmap backend, encoded by `png`) or SVG text, and
//! every figure of some runs written into a folder, each file atomically.

use super::data::RunData;
use super::{Figure, PlotOptions};
use crate::util::write_atomic;
use anyhow::{ensure, Context};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The most pixels a figure may have (about 36 MB of RGB while it is drawn).
const MAX_PIXELS: u64 = 12_000_000;

fn checked_size(figure: Figure, runs: &[RunData]) -> anyhow::Result<(u32, u32)> {
    let (w, h) = figure.size(runs);
    ensure!(
        w as u64 * h as u64 <= MAX_PIXELS,
        "figure {} would be {w} x {h} pixels, more than {MAX_PIXELS}: plot fewer runs at once",
        figure.file_stem()
    );
    Ok((w, h))
}

/// `figure` of `runs` as a PNG file's bytes.
pub fn render_png(figure: Figure, runs: &[RunData], options: &PlotOptions) -> anyhow::Result<Vec<u8>> {
    let (w, h) = checked_size(figure, runs)?;
    encode_figure_png(w, h, |root| figure.draw(root, runs, options))
}

/// A `w` x `h` figure on white that `draw` draws, as a PNG file's bytes.
pub(super) fn encode_figure_png(
    w: u32,
    h: u32,
    draw: impl FnOnce(&DrawingArea<BitMapBackend, plotters::coord::Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<Vec<u8>> {
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root)?;
        root.present()?;
    }
    crate::render::encode_png(&rgb, w, h)
}

/// `figure` of `runs` as an SVG document.
pub fn render_svg(figure: Figure, runs: &[RunData], options: &PlotOptions) -> anyhow::Result<String> {
    let size = checked_size(figure, runs)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        figure.draw(&root, runs, options)?;
        root.present()?;
    }
    Ok(svg)
}

/// Writes `NAME.png` and `NAME.svg` of every figure that has something to show for `runs` into
/// `out` (created if missing); returns the files written.
pub fn write_figures(runs: &[RunData], out: &Path, options: &PlotOptions) -> anyhow::Result<Vec<PathBuf>> {
    ensure!(!runs.is_empty(), "no run to plot");
    std::fs::create_dir_all(out).with_context(|| format!("creating folder {}", out.display()))?;
    let mut written = Vec::new();
    for figure in Figure::ALL.into_iter().filter(|f| f.applies_to(runs)) {
        let png = render_png(figure, runs, options).with_context(|| format!("drawing {}.png", figure.file_stem()))?;
        let svg = render_svg(figure, runs, options).with_context(|| format!("drawing {}.svg", figure.file_stem()))?;
        for (extension, bytes) in [("png", png.as_slice()), ("svg", svg.as_bytes())] {
            let path = out.join(format!("{}.{extension}", figure.file_stem()));
            write_atomic(&path, bytes)?;
            written.push(path);
        }
    }
    Ok(written)
}
