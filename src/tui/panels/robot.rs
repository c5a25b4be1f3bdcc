//! The robot under the selected task's policy, live: a side view (x, z) and
//! a top view (x, y) of the trunk box and the legs (hip, thigh, knee, foot)
//! from the simulator's poses, feet in contact highlighted, the command and
//! the actual body velocity. The frames come from the worker's robot thread. Where the panel
//! is large enough, the side view gives way to the robot as the renderer draws it (`render`, a
//! picture ten times a second), in half-block characters of the terminal's true colours.

use crate::rl::RobotFrame;
use crate::tui::app::App;
use crate::tui::ui::block;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::canvas::{Canvas, Context, Line as Segment, Points};
use ratatui::widgets::Paragraph;
use ratatui::Frame;

const LEGS: [&str; 4] = ["FL", "FR", "RL", "RR"];
/// Trunk box edges as pairs of corner indices (bit 0 +x, bit 1 +y, bit 2 +z).
const EDGES: [(usize, usize); 12] =
    [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)];

/// Draws the robot projected on the plane of axes (`a`, `b`) (0 x, 1 y, 2 z).
fn paint(ctx: &mut Context, frame: &RobotFrame, a: usize, b: usize) {
    let p = &frame.pose;
    let corners = p.trunk_corners();
    for (i, j) in EDGES {
        let (u, v) = (corners[i], corners[j]);
        ctx.draw(&Segment { x1: u[a] as f64, y1: u[b] as f64, x2: v[a] as f64, y2: v[b] as f64, color: Color::White });
    }
    for (k, leg) in p.legs.iter().enumerate() {
        let color = if k % 2 == 0 { Color::Cyan } else { Color::LightMagenta };
        let chain = [leg.hip, leg.thigh, leg.knee, leg.foot];
        for w in chain.windows(2) {
            ctx.draw(&Segment {
                x1: w[0][a] as f64,
                y1: w[0][b] as f64,
                x2: w[1][a] as f64,
                y2: w[1][b] as f64,
                color,
            });
        }
        let foot = [(leg.foot[a] as f64, leg.foot[b] as f64)];
        let color = if leg.contact { Color::Green } else { Color::DarkGray };
        ctx.draw(&Points { coords: &foot, color });
    }
}

fn view<'a>(
    title: &'a str,
    frame: &'a RobotFrame,
    a: usize,
    b: usize,
    bounds: ([f64; 2], [f64; 2]),
) -> Canvas<'a, impl Fn(&mut Context) + 'a> {
    Canvas::default().block(block(title, false)).marker(Marker::Braille).x_bounds(bounds.0).y_bounds(bounds.1).paint(
        move |ctx| {
            if b == 2 {
                ctx.draw(&Segment { x1: bounds.0[0], y1: 0.0, x2: bounds.0[1], y2: 0.0, color: Color::DarkGray });
            }
            paint(ctx, frame, a, b);
        },
    )
}

pub fn draw(f: &mut Frame, area: Rect, app: &App, focused: bool) {
    let task = app.robot.task.clone().unwrap_or_default();
    let outer = block(&format!("Robot: {task} (v: in Rerun 3D)"), focused);
    let inner = outer.inner(area);
    f.render_widget(outer, area);
    let Some(frame) = &app.robot.frame else {
        let why = match (&app.robot.error, app.robot.task.is_some()) {
            (Some(e), _) => e.clone(),
            (None, true) => "starting the simulator ...".into(),
            (None, false) => "select a learned task to watch it walk".into(),
        };
        f.render_widget(Paragraph::new(why), inner);
        return;
    };
    let [text, views] = Layout::vertical([Constraint::Length(3), Constraint::Min(0)]).areas(inner);
    let (c, v) = (frame.command, frame.base_velocity);
    let contacts: String =
        frame.pose.legs.iter().zip(LEGS).map(|(l, n)| format!("{n}{} ", if l.contact { "●" } else { "○" })).collect();
    let lines = vec![
        Line::raw(format!(
            "t {:.2} s · episode {} · {}",
            frame.sim_time,
            frame.episode,
            if frame.fell { "fell" } else { "standing" }
        )),
        Line::raw(format!(
            "command vx {:+.2} vy {:+.2} wz {:+.2}   actual vx {:+.2} vy {:+.2} wz {:+.2}",
            c[0], c[1], c[2], v[0], v[1], v[2]
        )),
        Line::styled(format!("feet {contacts}(● in contact)"), Style::new().fg(Color::Gray)),
    ];
    f.render_widget(Paragraph::new(lines), text);
    let [side, top] = Layout::horizontal([Constraint::Percentage(55), Constraint::Percentage(45)]).areas(views);
    let (x, y) = (frame.pose.trunk_center[0] as f64, frame.pose.trunk_center[1] as f64);
    match &app.robot.picture {
        // Large enough: the rendered picture in place of the side view.
        Some(picture) if side.width >= PICTURE_MIN.0 && side.height >= PICTURE_MIN.1 => {
            let framed = block("3D (rendered)", false);
            let inside = framed.inner(side);
            f.render_widget(framed, side);
            draw_picture(f.buffer_mut(), inside, picture);
        }
        _ => f.render_widget(view("side (x, z)", frame, 0, 2, ([x - 0.6, x + 0.6], [-0.05, 0.55])), side),
    }
    f.render_widget(view("top (x, y)", frame, 0, 1, ([x - 0.5, x + 0.5], [y - 0.4, y + 0.4])), top);
}

/// The least side area, in cells, that shows the rendered picture instead of the side view.
pub const PICTURE_MIN: (u16, u16) = (40, 16);

/// `picture` in `area` as half-block characters (two pixels a cell, the upper one the
/// foreground of `▀`), scaled to fit with its aspect kept (a cell is about twice as tall as
/// wide), centred.
pub fn draw_picture(buf: &mut Buffer, area: Rect, picture: &crate::render::Frame) {
    let (pw, ph) = (picture.width as f64, picture.height as f64);
    // Pixels available: one per column, two per row.
    let (aw, ah) = (f64::from(area.width), 2.0 * f64::from(area.height));
    let scale = (aw / pw).min(ah / ph);
    let (w, h) = ((pw * scale).floor() as u16, ((ph * scale / 2.0).floor()) as u16);
    let (x0, y0) = (area.x + (area.width - w) / 2, area.y + (area.height - h) / 2);
    // The mean of the source pixels under a target pixel (nearest-neighbour sampling turns the
    // ground's grid into scattered dots at a few cells).
    let sample = |col: u16, row: u32| {
        let x0 = (f64::from(col) / scale) as usize;
        let x1 = ((f64::from(col + 1) / scale) as usize).clamp(x0 + 1, picture.width);
        let y0 = (f64::from(row) / scale) as usize;
        let y1 = ((f64::from(row + 1) / scale) as usize).clamp(y0 + 1, picture.height);
        let mut sum = [0u32; 3];
        for y in y0..y1 {
            for x in x0..x1 {
                let p = picture.pixel(x.min(picture.width - 1), y.min(picture.height - 1));
                (0..3).for_each(|i| sum[i] += u32::from(p[i]));
            }
        }
        let n = ((x1 - x0) * (y1 - y0)) as u32;
        Color::Rgb((sum[0] / n) as u8, (sum[1] / n) as u8, (sum[2] / n) as u8)
    };
    for cy in 0..h {
        for cx in 0..w {
            let cell = &mut buf[(x0 + cx, y0 + cy)];
            cell.set_symbol("▀").set_fg(sample(cx, 2 * u32::from(cy))).set_bg(sample(cx, 2 * u32::from(cy) + 1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_picture_is_drawn_in_half_blocks_with_its_upper_and_lower_pixels_centred_and_in_proportion() {
        // 4 x 4 pixels: the upper half red, the lower half blue.
        let mut picture = crate::render::Frame::filled(4, 4, [0, 0, 255]).unwrap();
        picture.rgb[..24].copy_from_slice(&[255, 0, 0].repeat(8));
        let area = Rect::new(0, 0, 10, 4);
        let mut buf = Buffer::empty(area);
        draw_picture(&mut buf, area, &picture);
        // 4 rows of cells hold 8 pixel rows: the 4 x 4 picture scales by 2 to 8 x 8, that is
        // 8 columns and 4 rows of cells, centred in 10 columns.
        let drawn: Vec<(u16, u16)> =
            (0..4).flat_map(|y| (0..10).map(move |x| (x, y))).filter(|&(x, y)| buf[(x, y)].symbol() == "▀").collect();
        assert_eq!(drawn.len(), 32);
        assert!(drawn.iter().all(|&(x, _)| (1..9).contains(&x)), "{drawn:?}");
        assert_eq!((buf[(1, 0)].fg, buf[(1, 0)].bg), (Color::Rgb(255, 0, 0), Color::Rgb(255, 0, 0)));
        assert_eq!((buf[(1, 3)].fg, buf[(1, 3)].bg), (Color::Rgb(0, 0, 255), Color::Rgb(0, 0, 255)));
        assert_eq!(buf[(0, 0)].symbol(), " ", "outside the picture nothing is drawn");
    }
}
