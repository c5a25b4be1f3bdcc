//! One widget file per panel; each draws from the app's state only.

pub mod controls;
pub mod curves;
pub mod help;
pub mod mask_zoom;
pub mod masks;
pub mod matrix;
pub mod plasticity_series;
pub mod robot;
pub mod sweep;
pub mod timeline;
pub mod training;
pub mod vacant_forecast;

use ratatui::style::Color;

/// A colour from red (0) through yellow to green (1) for a normalised performance.
pub fn performance_color(x: f64) -> Color {
    let x = x.clamp(0.0, 1.0);
    let (r, g) = if x < 0.5 { (230.0, 60.0 + 340.0 * x) } else { (230.0 - 300.0 * (x - 0.5), 230.0) };
    Color::Rgb(r as u8, g as u8, 70)
}

/// A short name for a task in narrow columns: `crash:FL` -> `cFL`, `invert:RR+noise:FR` -> `iRR+nFR`.
pub fn short_task(name: &str) -> String {
    name.split('+')
        .map(|part| match part.split_once(':') {
            Some((kind, leg)) => format!("{}{leg}", &kind[..1]),
            None => part.to_string(),
        })
        .collect::<Vec<_>>()
        .join("+")
}
