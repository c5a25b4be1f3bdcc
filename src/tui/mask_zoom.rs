//! The mask heatmap zoomed into one layer (`z`): which layer of the shown
//! network, and the page of it in view. Rows are the layer's output neurons
//! ordered by how much of each the task took (most first); a page shows as
//! many rows as the panel has lines and two inputs per cell (one element per
//! half-cell). `[` `]` change the layer, PgUp / PgDn page through the rows,
//! ← → through the inputs; `z` or Esc go back to every layer.

use super::app::{App, Panel, Screen};
use super::panels::{mask_zoom, masks};
use crate::nn::LayerView;

/// Where the zoom is.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MaskZoom {
    /// The layer's index among the shown network's layers.
    pub layer: usize,
    /// The first row shown, in the rows' order by share.
    pub first_row: usize,
    /// The first input shown.
    pub first_col: usize,
}

/// A move of the zoom.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZoomMove {
    /// Zoom into the shown network's first layer, or back out.
    Toggle,
    /// The next (+1) or previous (-1) layer.
    Layer(i8),
    /// A page of rows down (+1) or up (-1).
    Rows(i8),
    /// A page of inputs right (+1) or left (-1).
    Columns(i8),
}

/// The zoomed layer's view, if the selected task's views are in.
pub fn zoomed_view<'a>(app: &'a App, zoom: &MaskZoom) -> Option<&'a LayerView> {
    let (_, _, layers) = masks::network_layers(app);
    let n = layers.len();
    (n > 0).then(|| layers[zoom.layer % n])
}

/// `by` pages from `first` over `len` items shown `page` at a time, kept on the last page.
fn paged(first: usize, by: i8, page: usize, len: usize) -> usize {
    let last = len.saturating_sub(page.max(1));
    (first as isize + by as isize * page.max(1) as isize).clamp(0, last as isize) as usize
}

/// Applies one move to the app's zoom.
pub fn update(app: &mut App, m: ZoomMove) {
    if m == ZoomMove::Toggle {
        app.zoom = match app.zoom {
            Some(_) => None,
            None => {
                app.screen = Screen::Overview;
                app.focus = Panel::Masks;
                Some(MaskZoom::default())
            }
        };
        return;
    }
    let Some(mut zoom) = app.zoom else { return };
    let rect = app.panel_rect(Panel::Masks, Screen::Overview);
    let (rows_page, cols_page) = rect.map_or((1, 2), |r| mask_zoom::page(super::ui::block("", false).inner(r)));
    let n_layers = masks::network_layers(app).2.len().max(1);
    let shape = zoomed_view(app, &zoom).map_or([0, 0], |v| v.shape);
    match m {
        ZoomMove::Toggle => unreachable!("handled above"),
        ZoomMove::Layer(d) => {
            zoom = MaskZoom {
                layer: (zoom.layer as isize + d as isize).rem_euclid(n_layers as isize) as usize,
                ..MaskZoom::default()
            };
        }
        ZoomMove::Rows(d) => zoom.first_row = paged(zoom.first_row, d, rows_page, shape[0]),
        ZoomMove::Columns(d) => zoom.first_col = paged(zoom.first_col, d, cols_page, shape[1]),
    }
    app.zoom = Some(zoom);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_stop_at_the_first_and_the_last() {
        assert_eq!(paged(0, 1, 20, 512), 20);
        assert_eq!(paged(500, 1, 20, 512), 492, "the last page is full");
        assert_eq!(paged(10, -1, 20, 512), 0);
        assert_eq!(paged(0, 1, 80, 64), 0, "one page holds it all");
    }
}
