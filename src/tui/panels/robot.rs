//! The robot under the selected task's policy, live: a side view (x, z) and
//! a top view (x, y) of the trunk box and the legs (hip, thigh, knee, foot)
//! from the simulator's poses, feet in contact highlighted, the command and
//! the actual body velocity. The frames come from the worker's robot thread.

use crate::rl::RobotFrame;
use crate::tui::app::App;
use crate::tui::ui::block;
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
    f.render_widget(view("side (x, z)", frame, 0, 2, ([x - 0.6, x + 0.6], [-0.05, 0.55])), side);
    f.render_widget(view("top (x, y)", frame, 0, 1, ([x - 0.5, x + 0.5], [y - 0.4, y + 0.4])), top);
}
