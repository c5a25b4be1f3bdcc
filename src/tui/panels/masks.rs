//! The selected task's masks, per layer of one network (n cycles actor,
//! critic, CENet, ...): a density heatmap of element states in half-block
//! cells (two pixels per cell; each pixel a block of elements, its colour
//! the states' colours mixed in the block's proportions),
//! per-layer fractions as bars, a legend, and the task's overlap with every
//! other task. The element views and statistics are the engine's. `z`
//! zooms into one layer (`mask_zoom`).

use crate::nn::{ElementView, LayerMasks, LayerView};
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};
use ratatui::Frame;

/// The heatmap's pixels: at most `height` rows of `width` (never more than the layer has
/// elements), each the count of every view in the block of elements it covers (indexed
/// by code). The longer side of the layer runs across.
pub fn heat_pixels(view: &LayerView, width: usize, height: usize) -> Vec<Vec<[u32; 6]>> {
    let [out, inp] = view.shape;
    let across_out = out >= inp;
    let (cols, rows) = if across_out { (out, inp) } else { (inp, out) };
    let (width, height) = (width.clamp(1, cols.max(1)), height.clamp(1, rows.max(1)));
    (0..height)
        .map(|py| {
            let (r0, r1) = (py * rows / height, ((py + 1) * rows / height).max(py * rows / height + 1));
            (0..width)
                .map(|px| {
                    let (c0, c1) = (px * cols / width, ((px + 1) * cols / width).max(px * cols / width + 1));
                    let mut counts = [0u32; 6];
                    for r in r0..r1 {
                        for c in c0..c1 {
                            let (o, i) = if across_out { (c, r) } else { (r, c) };
                            counts[(view.codes[o * inp + i] as usize).min(5)] += 1;
                        }
                    }
                    counts
                })
                .collect()
        })
        .collect()
}

/// The colours of a block's views mixed in proportion to their counts.
pub fn mix(counts: &[u32; 6]) -> Color {
    let total = counts.iter().sum::<u32>().max(1) as f32;
    let mut rgb = [0.0f32; 3];
    for (v, n) in ElementView::ALL.iter().zip(counts) {
        let (r, g, b) = v.rgb();
        for (acc, c) in rgb.iter_mut().zip([r, g, b]) {
            *acc += c as f32 * *n as f32 / total;
        }
    }
    Color::Rgb(rgb[0].round() as u8, rgb[1].round() as u8, rgb[2].round() as u8)
}

/// A layer's heatmap in half-block cells.
struct Heatmap<'a>(&'a LayerView);

impl Widget for Heatmap<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        // At most one pixel per element; a small layer is stretched over the whole area.
        let (w, h) = (area.width as usize, area.height as usize * 2);
        let pixels = heat_pixels(self.0, w, h);
        let (ph, pw) = (pixels.len(), pixels.first().map_or(0, |r| r.len()));
        if ph == 0 || pw == 0 {
            return;
        }
        let at = |x: usize, y: usize| &pixels[y * ph / h][x * pw / w];
        for y in 0..area.height as usize {
            for x in 0..w {
                let (top, bottom) = (at(x, 2 * y), at(x, 2 * y + 1));
                if let Some(cell) = buf.cell_mut((area.x + x as u16, area.y + y as u16)) {
                    cell.set_char('▀').set_fg(mix(top)).set_bg(mix(bottom));
                }
            }
        }
    }
}

fn bar(fraction: f64, width: usize) -> String {
    let filled = (fraction.clamp(0.0, 1.0) * width as f64).round() as usize;
    format!("{}{}", "█".repeat(filled), "░".repeat(width - filled))
}

fn layer_line(stats: Option<&LayerMasks>, view: &LayerView, task: &str, width: u16) -> Line<'static> {
    let total = (view.shape[0] * view.shape[1]).max(1) as f64;
    let head = format!("{} {}x{} ", view.layer, view.shape[0], view.shape[1]);
    // A finished task's figures come from the mask statistics; a task in training has none
    // yet, so its live element views' counts stand in (the same quantities).
    let mine = stats.and_then(|s| s.per_task.iter().find(|p| p.task == task).map(|p| (s, p)));
    let (sel, vac, occ, private, vacant) = match mine {
        Some((s, p)) => {
            (p.selected, p.from_vacant, p.from_occupied, s.private.get(task).copied().unwrap_or(0), s.vacant)
        }
        None => {
            let c = view.counts;
            (c[3] + c[4] + c[5], c[3] + c[5], c[4], c[5], c[0])
        }
    };
    let tail = format!(
        " sel {:.1}% (vac {:.1} occ {:.1}) priv {:.1}% · vacant {:.1}%",
        100.0 * sel as f64 / total,
        100.0 * vac as f64 / total,
        100.0 * occ as f64 / total,
        100.0 * private as f64 / total,
        100.0 * vacant as f64 / total
    );
    let room = (width as usize).saturating_sub(head.chars().count() + tail.chars().count()).clamp(0, 16);
    Line::from(vec![
        Span::raw(head),
        Span::styled(bar(sel as f64 / total, room), Style::new().fg(Color::Green)),
        Span::raw(tail),
    ])
}

/// The legend in two lines: the other tasks' states, then this task's.
fn legend() -> [Line<'static>; 2] {
    let line = |views: &[ElementView]| {
        let mut spans = Vec::new();
        for v in views {
            let (r, g, b) = v.rgb();
            spans.push(Span::styled("■ ", Style::new().fg(Color::Rgb(r, g, b))));
            spans.push(Span::raw(format!("{:<24}", v.label())));
        }
        Line::from(spans)
    };
    [line(&ElementView::ALL[..3]), line(&ElementView::ALL[3..])]
}

/// The share of the task's selected elements (in this network) that each other task selects too.
fn overlap_line(app: &App, network: &str, task: &str) -> Line<'static> {
    let shared = app.report.as_ref().map(|r| r.shared_with(network, task)).unwrap_or_default();
    let parts: Vec<String> =
        shared.iter().map(|(n, share)| format!("{} {:.1}%", super::short_task(n), 100.0 * share)).collect();
    Line::raw(format!("shared with: {}", if parts.is_empty() { "-".to_string() } else { parts.join("  ") }))
}

/// A dense network's layers (the baselines have no masks): the trunk every task shares and
/// one head per task, from the mask report; None when the networks are masked.
fn dense_summary(app: &App) -> Option<Vec<Line<'static>>> {
    let report = app.report.as_ref()?;
    let is_dense = |n: &crate::nn::NetworkMasks| n.layers.last().is_some_and(|l| l.name.ends_with(".head"));
    if report.networks.is_empty() || !report.networks.iter().all(is_dense) {
        return None;
    }
    let mut lines = vec![Line::raw("a dense network: no masks, every task trains the shared trunk"), Line::raw("")];
    for n in &report.networks {
        for l in &n.layers {
            let [out, inp] = l.shape;
            let who = if l.name.ends_with(".head") {
                format!("one per task ({} heads)", l.per_task.len())
            } else {
                format!("shared by {} tasks", l.per_task.len())
            };
            lines.push(Line::raw(format!("  {:<22} {out:>4} x {inp:<4} {who}", l.name)));
        }
    }
    Some(lines)
}

/// The selected task's element views grouped by network: the networks in order, the one shown
/// (`n` cycles), and its layers (empty while the views are not in).
pub fn network_layers(app: &App) -> (Vec<&str>, &str, Vec<&LayerView>) {
    let task = app.selected().map(|r| r.task).unwrap_or_default();
    let views: Vec<&LayerView> = match &app.views {
        Some((t, _, layers)) if app.opened.as_ref().and_then(|o| o.results.tasks.get(*t)) == Some(&task) => {
            layers.iter().collect()
        }
        _ => Vec::new(),
    };
    let mut networks: Vec<&str> = Vec::new();
    for v in &views {
        if !networks.contains(&v.network.as_str()) {
            networks.push(&v.network);
        }
    }
    let network = networks.get(app.network % networks.len().max(1)).copied().unwrap_or("");
    let layers = views.into_iter().filter(|v| v.network == network).collect();
    (networks, network, layers)
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let task = app.selected().map(|r| r.task).unwrap_or_default();
    let (networks, network, layers) = network_layers(app);
    let live = match &app.views {
        Some((_, Some(it), _)) => format!(" · live, iteration {it}"),
        _ => String::new(),
    };
    let title = if networks.is_empty() {
        format!("Masks: {task}")
    } else {
        format!("Masks: {task} · {network} ({}/{}){live}", app.network % networks.len().max(1) + 1, networks.len())
    };
    let inner = block(&title, focused).inner(area);
    f.render_widget(block(&title, focused), area);
    if layers.is_empty() {
        let text = match dense_summary(app) {
            Some(lines) => Paragraph::new(lines),
            None => Paragraph::new("waiting for the element views ..."),
        };
        f.render_widget(text, inner);
        return;
    }
    if let Some(zoom) = &app.zoom {
        super::mask_zoom::draw(f, inner, layers[zoom.layer % layers.len()], zoom);
        return;
    }
    let stats = |name: &str| {
        app.report.as_ref().and_then(|r| r.networks.iter().flat_map(|n| &n.layers).find(|l| l.name == name))
    };
    let [a, b] = legend();
    f.render_widget(
        Paragraph::new(vec![a, b, overlap_line(app, network, &task)]),
        Rect { height: 3.min(inner.height), ..inner },
    );
    let body = Rect { y: inner.y + 3, height: inner.height.saturating_sub(3), ..inner };
    let per_layer = (body.height / layers.len().max(1) as u16).max(2);
    for (i, view) in layers.iter().enumerate() {
        let y = body.y + i as u16 * per_layer;
        if y + 1 >= body.y + body.height {
            break;
        }
        let height = per_layer.min(body.y + body.height - y);
        f.render_widget(
            Paragraph::new(layer_line(stats(&view.layer), view, &task, body.width)),
            Rect::new(body.x, y, body.width, 1),
        );
        let map = Rect::new(body.x, y + 1, body.width, height - 1);
        if map.height > 0 {
            f.render_widget(Heatmap(view), map);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_pixels_count_the_states_of_each_block_and_mix_their_colours() {
        // 4 x 2 layer (out 4, in 2): the first two outputs selected from vacant, the rest vacant
        // but for one occupied element.
        let codes = vec![3, 3, 3, 3, 0, 0, 0, 1];
        let view =
            LayerView { network: "n".into(), layer: "n.l0".into(), shape: [4, 2], codes, counts: [3, 1, 0, 4, 0, 0] };
        let px = heat_pixels(&view, 2, 1);
        assert_eq!(px.len(), 1);
        assert_eq!(px[0][0], [0, 0, 0, 4, 0, 0]);
        assert_eq!(px[0][1], [3, 1, 0, 0, 0, 0]);
        let full = heat_pixels(&view, 10, 10);
        assert_eq!((full.len(), full[0].len()), (2, 4), "never more pixels than elements");
        assert_eq!(full[1][3], [0, 1, 0, 0, 0, 0]);
        let (r, g, b) = ElementView::SelectedFromVacant.rgb();
        assert_eq!(mix(&px[0][0]), Color::Rgb(r, g, b));
        let (vr, _, _) = ElementView::Vacant.rgb();
        let (or, _, _) = ElementView::OccupiedByOthers.rgb();
        let Color::Rgb(red, _, _) = mix(&px[0][1]) else { panic!("an RGB colour") };
        assert_eq!(red, ((3.0 * vr as f32 + or as f32) / 4.0).round() as u8, "3 vacant to 1 occupied");
    }
}
