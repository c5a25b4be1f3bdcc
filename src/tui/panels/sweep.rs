//! The Sweep screen (`quadcl tui --sweep DIR`): a header with the folder and
//! the count of cells per state, the cells (state, a progress bar over the
//! iterations of the whole sequence, steps done, name, the scheduler's word),
//! the collected table as it fills in (means with 90 % bootstrap intervals
//! over the finished seeds), and the keys. Draws from [`SweepView`] only.

use crate::sweep::collect::rows;
use crate::sweep::{CellState, CellStatus};
use crate::tui::sweep_view::SweepView;
use crate::tui::ui::{block, draw_too_small};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;
use ratatui::Frame;

/// Width of a cell's progress bar.
const BAR: usize = 12;

fn state_style(state: CellState) -> Style {
    Style::new().fg(match state {
        CellState::Finished => Color::Green,
        CellState::Running => Color::Cyan,
        CellState::Queued => Color::Blue,
        CellState::Stopped => Color::Yellow,
        CellState::Failed => Color::Red,
        CellState::Foreign => Color::Magenta,
        CellState::Pending => Color::DarkGray,
    })
}

fn cell_line(c: &CellStatus, selected: bool) -> Line<'static> {
    let filled = ((c.progress() * BAR as f64).round() as usize).min(BAR);
    let bar = format!("{}{}", "█".repeat(filled), "░".repeat(BAR - filled));
    let note = if c.note.is_empty() { String::new() } else { format!("  ({})", c.note) };
    let marker = if selected { "› " } else { "  " };
    let mut line = Line::from(vec![
        Span::raw(format!("{marker}{:>3} ", c.index)),
        Span::styled(format!("{:<9}", c.state.label()), state_style(c.state)),
        Span::styled(bar, state_style(c.state)),
        Span::raw(format!(
            " {:>5.1} %  step {}/{}  {}{note}",
            100.0 * c.progress(),
            c.completed_steps,
            c.total_steps,
            c.name
        )),
    ]);
    if selected {
        line = line.style(Style::new().add_modifier(Modifier::REVERSED));
    }
    line
}

fn header(view: &SweepView) -> Line<'static> {
    let count = |s: CellState| view.cells.iter().filter(|c| c.state == s).count();
    let mut spans = vec![
        Span::styled(" quadcl ", Style::new().fg(Color::Black).bg(Color::Cyan)),
        Span::raw(format!(" sweep {} · {} cells: ", view.dir.display(), view.cells.len())),
    ];
    let states = [
        CellState::Finished,
        CellState::Running,
        CellState::Queued,
        CellState::Stopped,
        CellState::Failed,
        CellState::Pending,
    ];
    let parts: Vec<(CellState, usize)> = states.iter().map(|s| (*s, count(*s))).filter(|(_, n)| *n > 0).collect();
    for (i, (s, n)) in parts.iter().enumerate() {
        let sep = if i + 1 < parts.len() { ", " } else { "" };
        spans.push(Span::styled(format!("{n} {}", s.label()), state_style(*s)));
        spans.push(Span::raw(sep.to_string()));
    }
    Line::from(spans)
}

/// The collected table in lines of at most `width` characters: the group and seeds columns,
/// then as many measure columns as fit; the measures that do not fit follow in further blocks.
fn table_lines(view: &SweepView, width: usize) -> Vec<Line<'static>> {
    let Some(table) = &view.table else {
        return vec![Line::raw("reading the sweep ...")];
    };
    let (head, body) = rows(table);
    let widths: Vec<usize> = (0..head.len())
        .map(|c| body.iter().map(|r| r[c].chars().count()).chain([head[c].chars().count()]).max().unwrap_or(0))
        .collect();
    const GAP: usize = 2;
    let fixed = widths[0] + GAP + widths[1];
    let mut blocks: Vec<Vec<usize>> = vec![Vec::new()];
    let mut used = fixed;
    for (c, w) in widths.iter().enumerate().skip(2) {
        let current = blocks.last_mut().expect("one block at least");
        if !current.is_empty() && used + GAP + w > width {
            blocks.push(vec![c]);
            used = fixed + GAP + w;
        } else {
            current.push(c);
            used += GAP + w;
        }
    }
    let text = |cells: &[String], columns: &[usize]| {
        [0, 1].iter().chain(columns).map(|&c| format!("{:<w$}", cells[c], w = widths[c])).collect::<Vec<_>>().join("  ")
    };
    let mut lines = Vec::new();
    for columns in &blocks {
        lines.push(Line::from(text(&head, columns)).style(Style::new().add_modifier(Modifier::UNDERLINED)));
        lines.extend(body.iter().map(|r| Line::raw(text(r, columns))));
    }
    lines.push(Line::styled(
        format!(
            "mean over the finished seeds [{:.0} % bootstrap interval]; seeds: finished/planned",
            table.confidence * 100.0
        ),
        Style::new().fg(Color::DarkGray),
    ));
    lines
}

/// Draws the whole Sweep screen.
pub fn draw(f: &mut Frame, view: &SweepView) {
    let area = f.area();
    if draw_too_small(f) {
        return;
    }
    let table = table_lines(view, area.width.saturating_sub(2) as usize);
    // The cells keep at least 6 rows; the table takes what it needs of the rest.
    let table_height = (table.len() as u16 + 2).min(area.height.saturating_sub(2 + 6));
    let wanted = view.cells.len() as u16 + 2 + u16::from(view.error.is_some());
    let cells_height = wanted.max(3).min(area.height - 2 - table_height);
    let [top, cells, table_area, _, keys] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(cells_height),
        Constraint::Length(table_height),
        Constraint::Min(0),
        Constraint::Length(1),
    ])
    .areas(area);
    f.render_widget(Paragraph::new(header(view)), top);
    let visible = cells.height.saturating_sub(2) as usize;
    let scroll = (view.cursor + 1).saturating_sub(visible);
    let mut lines: Vec<Line> = match &view.error {
        Some(e) => vec![Line::styled(e.clone(), Style::new().fg(Color::Red))],
        None => Vec::new(),
    };
    lines.extend(view.cells.iter().enumerate().skip(scroll).map(|(i, c)| cell_line(c, i == view.cursor)));
    f.render_widget(Paragraph::new(lines).block(block("Cells", true)), cells);
    f.render_widget(Paragraph::new(table).block(block("Collected", false)), table_area);
    let chip = Style::new().fg(Color::Black).bg(Color::Gray);
    // A message takes the line's room from the keys' explanations, which the chip still names.
    let line = match &view.message {
        Some(message) => Line::from(vec![
            Span::styled(" ↑↓ enter q ", chip),
            Span::raw("  "),
            Span::styled(message.clone(), Style::new().fg(Color::Yellow)),
        ]),
        None => Line::from(vec![
            Span::styled(" ↑↓ select cell  enter open its run ", chip),
            Span::raw("  q quit (in an opened run, q comes back)"),
        ]),
    };
    f.render_widget(Paragraph::new(line), keys);
}
