//! The screen: a header (run folder, method, where training is, the
//! screens), the timeline and training control on the left of every screen,
//! the screen's panels on the right, and a key bar with the focused panel's
//! keys. Below 80x24 a message says so instead. Overlays: help, quit.

use super::app::{App, Panel, Screen};
use super::panels;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Borders, Clear, Paragraph, Wrap};
use ratatui::Frame;

/// The smallest terminal the workbench draws in.
pub const MIN_SIZE: (u16, u16) = (80, 24);

/// The panels that can take the focus on `screen`, in Tab order.
pub fn focus_order(screen: Screen) -> Vec<Panel> {
    let right: &[Panel] = match screen {
        Screen::Overview => &[Panel::Curves, Panel::Masks],
        Screen::Evaluation => &[Panel::Matrix],
        Screen::NextTask => &[Panel::Controls],
        Screen::Robot => &[Panel::Robot],
    };
    [Panel::Timeline].iter().chain(right).chain(&[Panel::Training]).copied().collect()
}

/// Where each panel of `screen` goes in a terminal of `area`.
pub fn panels(area: Rect, screen: Screen) -> Vec<(Panel, Rect)> {
    let [_, body, _] = Layout::vertical([Constraint::Length(1), Constraint::Min(0), Constraint::Length(1)]).areas(area);
    let left_width = (body.width * 37 / 100).clamp(32, 48);
    let [left, right] = Layout::horizontal([Constraint::Length(left_width), Constraint::Min(0)]).areas(body);
    let [timeline, training] = Layout::vertical([Constraint::Min(5), Constraint::Length(8)]).areas(left);
    let mut out = vec![(Panel::Timeline, timeline), (Panel::Training, training)];
    match screen {
        Screen::Overview => {
            let [curves, masks] =
                Layout::vertical([Constraint::Percentage(38), Constraint::Percentage(62)]).areas(right);
            out.push((Panel::Curves, curves));
            out.push((Panel::Masks, masks));
        }
        Screen::Evaluation => out.push((Panel::Matrix, right)),
        Screen::NextTask => out.push((Panel::Controls, right)),
        Screen::Robot => out.push((Panel::Robot, right)),
    }
    out
}

/// Below [`MIN_SIZE`], says so on the whole frame and returns true (the caller draws nothing else).
pub fn draw_too_small(f: &mut Frame) -> bool {
    let area = f.area();
    let small = area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1;
    if small {
        let text = format!(
            "The terminal is {}x{}; the workbench needs at least {}x{}.\nEnlarge the window, or press q to quit.",
            area.width, area.height, MIN_SIZE.0, MIN_SIZE.1
        );
        f.render_widget(Paragraph::new(text).wrap(Wrap { trim: true }), area);
    }
    small
}

/// Draws the whole screen.
pub fn draw(f: &mut Frame, app: &App) {
    let area = f.area();
    if draw_too_small(f) {
        return;
    }
    let [header, _, keys] =
        Layout::vertical([Constraint::Length(1), Constraint::Min(0), Constraint::Length(1)]).areas(area);
    f.render_widget(Paragraph::new(header_line(app)), header);
    for (panel, rect) in panels(area, app.screen) {
        let focused = app.focus == panel;
        match panel {
            Panel::Timeline => panels::timeline::draw(f, rect, app, focused),
            Panel::Training => panels::training::draw(f, rect, app, focused),
            Panel::Curves => panels::curves::draw(f, rect, app, focused),
            Panel::Masks => panels::masks::draw(f, rect, app, focused),
            Panel::Matrix => panels::matrix::draw(f, rect, app, focused),
            Panel::Controls => panels::controls::draw(f, rect, app, focused),
            Panel::Robot => panels::robot::draw(f, rect, app, focused),
        }
    }
    f.render_widget(Paragraph::new(key_line(app)), keys);
    if app.help {
        panels::help::draw(f, area);
    } else if app.confirm_quit {
        confirm_quit(f, area, app);
    }
}

/// A bordered block titled `title`, highlighted when focused.
pub fn block(title: &str, focused: bool) -> Block<'static> {
    let style = if focused { Style::new().fg(Color::Cyan).add_modifier(Modifier::BOLD) } else { Style::new() };
    Block::new().borders(Borders::ALL).border_style(style).title(Span::styled(format!(" {title} "), style))
}

fn header_line(app: &App) -> Line<'static> {
    let mut spans = vec![Span::styled(" quadcl ", Style::new().fg(Color::Black).bg(Color::Cyan))];
    match &app.opened {
        Some(o) => spans.push(Span::raw(format!(
            " {} · {} · {}/{} steps ",
            o.run_dir.display(),
            o.method,
            o.results.steps.len(),
            o.sequence.tasks.len()
        ))),
        None => spans.push(Span::raw(format!(" opening {} ... ", app.opening.display()))),
    }
    for (i, (screen, name)) in [
        (Screen::Overview, "Overview"),
        (Screen::Evaluation, "Evaluation"),
        (Screen::NextTask, "Next task"),
        (Screen::Robot, "Robot"),
    ]
    .into_iter()
    .enumerate()
    {
        let style = if app.screen == screen {
            Style::new().add_modifier(Modifier::REVERSED)
        } else {
            Style::new().fg(Color::Gray)
        };
        spans.push(Span::styled(format!(" {} {name} ", i + 1), style));
    }
    Line::from(spans)
}

/// The keys of the focused panel, then the global ones.
pub fn panel_keys(panel: Panel) -> &'static str {
    match panel {
        Panel::Timeline => "↑↓ select step",
        Panel::Training => "space start/pause  r run through  e evaluate  S save",
        Panel::Curves => "m metric  s smoothing on/off  +/- smoothing  w whole sequence",
        Panel::Masks => "n network  z zoom a layer ([ ] layer, PgUp/PgDn rows, ←→ inputs)",
        Panel::Matrix => "↑↓ select step  ←→ scroll tasks  e evaluate",
        Panel::Controls => "↑↓ row  ←→ change  enter toggle  a add task",
        Panel::Robot => "v Rerun 3D view",
    }
}

fn key_line(app: &App) -> Line<'static> {
    let global = "space start/pause  Tab focus  1-4 screens  ? help  q quit";
    let message = app.messages.last().cloned().unwrap_or_default();
    Line::from(vec![
        Span::styled(format!(" {} ", panel_keys(app.focus)), Style::new().fg(Color::Black).bg(Color::Gray)),
        Span::raw(format!("  {global}  ")),
        Span::styled(message, Style::new().fg(Color::Yellow)),
    ])
}

fn confirm_quit(f: &mut Frame, area: Rect, app: &App) {
    let what = app.live.as_ref().map_or(String::new(), |l| {
        format!("{} (step {}) is at iteration {}/{}. ", l.record.name, l.record.step, l.iteration, l.record.iterations)
    });
    let text = format!(
        "{what}Quit now? The finished steps are saved; this step restarts from its beginning (with the settings it has now) when the run is reopened.\n\ny quit   n go on"
    );
    let rect = centered(area, 60, 7);
    f.render_widget(Clear, rect);
    f.render_widget(Paragraph::new(text).wrap(Wrap { trim: true }).block(block("Quit?", true)), rect);
}

/// A `width` x `height` rectangle centred in `area` (clipped to it).
pub fn centered(area: Rect, width: u16, height: u16) -> Rect {
    let (w, h) = (width.min(area.width), height.min(area.height));
    Rect::new(area.x + (area.width - w) / 2, area.y + (area.height - h) / 2, w, h)
}
