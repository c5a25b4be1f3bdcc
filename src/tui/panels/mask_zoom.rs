//! One masked layer up close (`z` on the Masks panel): one element per
//! half-cell (`▌`, its left half one input, its right half the next, each in
//! its element's colour), rows ordered by how much of them the task took,
//! each with a bar of its share beside it: `█` selected from vacant elements
//! (fresh capacity, private ones included), `▓` selected from occupied ones
//! (reuse), `░` not selected. The page in view is [`MaskZoom`]'s.

use crate::nn::{ElementView, LayerView, RowShare};
use crate::tui::mask_zoom::MaskZoom;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};
use ratatui::Frame;

/// Lines above the rows: the layer, the page in view, the legend.
const HEAD: u16 = 3;
/// The row label ("  37 "), the share bar and its percentage (" 41% ").
const LABEL: u16 = 5;
const BAR: u16 = 8;
const PERCENT: u16 = 5;

/// Rows per page and inputs per page in a zoom drawn in `inner` (the panel inside its border).
pub fn page(inner: Rect) -> (usize, usize) {
    let rows = inner.height.saturating_sub(HEAD).max(1) as usize;
    let cells = inner.width.saturating_sub(LABEL + BAR + PERCENT).max(1) as usize;
    (rows, 2 * cells)
}

fn color(code: u8) -> Color {
    let (r, g, b) = ElementView::from_code(code).unwrap_or(ElementView::Vacant).rgb();
    Color::Rgb(r, g, b)
}

/// A row's share as a bar of `width` cells: from vacant, from occupied, the rest.
pub fn share_bar(share: &RowShare, cols: usize, width: usize) -> [String; 3] {
    let cells = |n: usize| ((n as f64 / cols.max(1) as f64) * width as f64).round() as usize;
    let filled = cells(share.selected()).min(width);
    let vacant = cells(share.from_vacant).min(filled);
    ["█".repeat(vacant), "▓".repeat(filled - vacant), "░".repeat(width - filled)]
}

/// The elements of `rows` (layer rows, top to bottom) from input `first_col` on, two per cell.
struct HalfCells<'a> {
    view: &'a LayerView,
    rows: &'a [RowShare],
    first_col: usize,
}

impl Widget for HalfCells<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let cols = self.view.shape[1];
        for (y, share) in self.rows.iter().enumerate().take(area.height as usize) {
            let row = &self.view.codes[share.row * cols..(share.row + 1) * cols];
            for x in 0..area.width as usize {
                let (left, right) = (self.first_col + 2 * x, self.first_col + 2 * x + 1);
                let Some(l) = row.get(left) else { break };
                let bg = row.get(right).map_or(Color::Reset, |r| color(*r));
                if let Some(cell) = buf.cell_mut((area.x + x as u16, area.y + y as u16)) {
                    cell.set_char('▌').set_fg(color(*l)).set_bg(bg);
                }
            }
        }
    }
}

/// The legend: the elements' colours (short labels), then the bar's characters.
fn legend() -> Line<'static> {
    let labels = ["vacant", "occupied", "private", "new", "reused", "own private"];
    let mut spans = Vec::new();
    for (v, label) in ElementView::ALL.iter().zip(labels) {
        let (r, g, b) = v.rgb();
        spans.push(Span::styled("■", Style::new().fg(Color::Rgb(r, g, b))));
        spans.push(Span::raw(format!("{label} ")));
    }
    spans.push(Span::styled("· bar █ new ▓ reused", Style::new().fg(Color::Gray)));
    Line::from(spans)
}

pub fn draw(f: &mut Frame, inner: Rect, view: &LayerView, zoom: &MaskZoom) {
    let [out, inp] = view.shape;
    let (rows_page, cols_page) = page(inner);
    let first_row = zoom.first_row.min(out.saturating_sub(rows_page));
    let first_col = zoom.first_col.min(inp.saturating_sub(cols_page));
    let order = view.rows_by_share();
    let shown = &order[first_row.min(order.len())..(first_row + rows_page).min(order.len())];
    let last_col = (first_col + cols_page).min(inp);
    let heading = format!("{} {out}x{inp}: one row per output, by the task's share of it", view.layer);
    let rows = format!("rows {}-{} of {out} (PgUp/PgDn)", first_row + 1, first_row + shown.len());
    let inputs = if last_col - first_col < inp {
        format!("inputs {}-{last_col} of {inp} (←→)", first_col + 1)
    } else {
        format!("all {inp} inputs")
    };
    let lines = vec![Line::raw(heading), Line::raw(format!("{rows} · {inputs} · [ ] layer · z back")), legend()];
    f.render_widget(Paragraph::new(lines), Rect { height: HEAD.min(inner.height), ..inner });
    let body = Rect { y: inner.y + HEAD, height: inner.height.saturating_sub(HEAD), ..inner };
    let labels: Vec<Line> = shown
        .iter()
        .map(|s| {
            let [v, o, rest] = share_bar(s, inp, BAR as usize);
            Line::from(vec![
                Span::styled(format!("{:>4} ", s.row), Style::new().fg(Color::Gray)),
                Span::styled(v, Style::new().fg(color(ElementView::SelectedFromVacant as u8))),
                Span::styled(o, Style::new().fg(color(ElementView::SelectedFromOccupied as u8))),
                Span::styled(rest, Style::new().fg(Color::DarkGray)),
                Span::raw(format!("{:>3.0}% ", 100.0 * s.selected() as f64 / inp.max(1) as f64)),
            ])
        })
        .collect();
    let prefix = LABEL + BAR + PERCENT;
    f.render_widget(Paragraph::new(labels), Rect { width: prefix.min(body.width), ..body });
    let map = Rect { x: body.x + prefix, width: body.width.saturating_sub(prefix), ..body };
    f.render_widget(HalfCells { view, rows: shown, first_col }, map);
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;

    #[test]
    fn each_half_cell_is_one_element_in_its_colour_and_rows_come_most_taken_first() {
        // 2 rows of 3: row 0 takes nothing (vacant, occupied, vacant); row 1 takes two.
        let codes = vec![0, 1, 0, 3, 4, 0];
        let view = LayerView { network: "n".into(), layer: "n.l0".into(), shape: [2, 3], codes, counts: [0; 6] };
        let mut terminal = Terminal::new(TestBackend::new(40, 5)).unwrap();
        terminal.draw(|f| draw(f, f.area(), &view, &MaskZoom::default())).unwrap();
        let buf = terminal.backend().buffer();
        let x = LABEL + BAR + PERCENT;
        // Line 3 is row 1 (two of three selected: first), line 4 row 0.
        let text: String = (0..x).map(|i| buf[(i, 3)].symbol().to_string()).collect();
        assert_eq!(text, "   1 ███▓▓░░░ 67% ", "one of three from vacant, one from occupied: 3 and 2 of 8 cells");
        let (first, second) = (&buf[(x, 3)], &buf[(x + 1, 3)]);
        assert_eq!(first.symbol(), "▌");
        assert_eq!((first.fg, first.bg), (color(3), color(4)), "inputs 0 and 1 of row 1");
        assert_eq!((second.fg, second.bg), (color(0), Color::Reset), "input 2, and nothing right of it");
        assert_eq!((buf[(x, 4)].fg, buf[(x, 4)].bg), (color(0), color(1)), "row 0 below");
        assert_eq!(buf[(x + 2, 4)].symbol(), " ", "nothing past the layer's inputs");
    }

    #[test]
    fn share_bars_split_fresh_from_reused() {
        let s = RowShare { row: 0, from_vacant: 16, from_occupied: 16 };
        assert_eq!(share_bar(&s, 64, 8), ["██".to_string(), "▓▓".to_string(), "░░░░".to_string()]);
    }
}
