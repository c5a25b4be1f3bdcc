//! A picture: (height, width, 3) RGB bytes, row-major from the top-left pixel, as Gymnasium's
//! `render()` returns it; written as PNG, and with text drawn on it (the font of `font`).

use super::font::{register_font, FONT};
use anyhow::Context;
use plotters::prelude::*;

/// The most pixels a frame may have (4K: about 25 MB of RGB).
pub const MAX_PIXELS: usize = 3840 * 2160;

/// An RGB picture.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    pub width: usize,
    pub height: usize,
    /// (height, width, 3) bytes.
    pub rgb: Vec<u8>,
}

impl Frame {
    /// A frame of one colour; a size of zero or over [`MAX_PIXELS`] is an error naming it.
    pub fn filled(width: usize, height: usize, colour: [u8; 3]) -> anyhow::Result<Self> {
        check_size(width, height)?;
        Ok(Self { width, height, rgb: colour.repeat(width * height) })
    }

    /// The pixel at column `x`, row `y` (from the top).
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y * self.width + x);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// The frame as a PNG file's bytes.
    pub fn png(&self) -> anyhow::Result<Vec<u8>> {
        encode_png(&self.rgb, self.width as u32, self.height as u32)
    }

    /// Lines of text from the top-left corner, white with a dark shadow so that they read on
    /// sky and ground alike; `size` in pixels.
    pub fn write_lines(&mut self, lines: &[String], size: f64) -> anyhow::Result<()> {
        register_font()?;
        let (w, h) = (self.width as u32, self.height as u32);
        let root = BitMapBackend::with_buffer(&mut self.rgb, (w, h)).into_drawing_area();
        let step = (size * 1.25).ceil() as i32;
        let margin = (size * 0.5).ceil() as i32;
        for (i, line) in lines.iter().enumerate() {
            let y = margin + i as i32 * step;
            let shadow = (FONT, size).into_font().color(&RGBColor(20, 20, 24));
            let text = (FONT, size).into_font().color(&WHITE);
            root.draw_text(line, &shadow, (margin + 1, y + 1)).map_err(|e| anyhow::anyhow!("drawing text: {e}"))?;
            root.draw_text(line, &text, (margin, y)).map_err(|e| anyhow::anyhow!("drawing text: {e}"))?;
        }
        root.present().map_err(|e| anyhow::anyhow!("drawing text: {e}"))?;
        Ok(())
    }

    /// Frames side by side, left to right, on one row (all of one height).
    pub fn side_by_side(frames: &[Frame]) -> anyhow::Result<Frame> {
        let height = frames.first().context("no frame to put side by side")?.height;
        anyhow::ensure!(frames.iter().all(|f| f.height == height), "frames of different heights side by side");
        let width = frames.iter().map(|f| f.width).sum();
        let mut out = Frame::filled(width, height, [0, 0, 0])?;
        for y in 0..height {
            let mut x0 = 0;
            for f in frames {
                let (src, dst) = (3 * y * f.width, 3 * (y * width + x0));
                out.rgb[dst..dst + 3 * f.width].copy_from_slice(&f.rgb[src..src + 3 * f.width]);
                x0 += f.width;
            }
        }
        Ok(out)
    }
}

impl Frame {
    /// Frames stacked top to bottom (all of one width).
    pub fn stacked(frames: &[Frame]) -> anyhow::Result<Frame> {
        let width = frames.first().context("no frame to stack")?.width;
        anyhow::ensure!(frames.iter().all(|f| f.width == width), "frames of different widths stacked");
        let height = frames.iter().map(|f| f.height).sum();
        check_size(width, height)?;
        Ok(Frame { width, height, rgb: frames.iter().flat_map(|f| f.rgb.iter().copied()).collect() })
    }
}

/// A width and height a frame may have.
pub fn check_size(width: usize, height: usize) -> anyhow::Result<()> {
    anyhow::ensure!(
        width > 0 && height > 0 && width.saturating_mul(height) <= MAX_PIXELS,
        "a frame of {width} x {height} pixels: each side must be at least 1 and the whole at most {MAX_PIXELS} pixels"
    );
    Ok(())
}

/// RGB bytes of a `w` x `h` picture as a PNG file's bytes.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> anyhow::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().context("encoding the PNG")?;
    writer.write_image_data(rgb).context("encoding the PNG")?;
    writer.finish().context("encoding the PNG")?;
    Ok(bytes)
}
