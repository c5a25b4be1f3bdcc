//! Keys, clicks and resizes to [`Action`]s. What a key does depends on what
//! is open (help, the quit question, a task being typed) and on the focus.

use super::app::{Action, App, Panel, Screen};
use super::mask_zoom::ZoomMove;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEventKind};

/// The action of a terminal event, if it has one.
pub fn event_action(app: &App, event: &Event) -> Option<Action> {
    match event {
        Event::Key(k) if k.kind != KeyEventKind::Release => key_action(app, k),
        Event::Mouse(m) if m.kind == MouseEventKind::Down(MouseButton::Left) => Some(Action::Click(m.column, m.row)),
        Event::Resize(w, h) => Some(Action::Resize(*w, *h)),
        _ => None,
    }
}

/// The action of one key press.
pub fn key_action(app: &App, key: &KeyEvent) -> Option<Action> {
    if key.modifiers.contains(KeyModifiers::CONTROL) && key.code == KeyCode::Char('c') {
        // A second Ctrl-C answers the quit question: a forced quit.
        return Some(if app.confirm_quit { Action::ConfirmQuit(true) } else { Action::Quit });
    }
    if app.help {
        return Some(Action::ToggleHelp);
    }
    if app.confirm_quit {
        return match key.code {
            KeyCode::Char('y' | 'Y') => Some(Action::ConfirmQuit(true)),
            KeyCode::Char('n' | 'N') | KeyCode::Esc => Some(Action::ConfirmQuit(false)),
            _ => None,
        };
    }
    if app.next.input.is_some() {
        let control = key.modifiers.contains(KeyModifiers::CONTROL);
        return match key.code {
            KeyCode::Char('u') if control => Some(Action::InputClear),
            KeyCode::Char(_) if control => None,
            KeyCode::Enter => Some(Action::InputSubmit),
            KeyCode::Esc => Some(Action::InputCancel),
            KeyCode::Backspace => Some(Action::InputBackspace),
            KeyCode::Char(c) => Some(Action::Input(c)),
            _ => None,
        };
    }
    let controls = app.focus == Panel::Controls;
    let zoomed = app.zoom.is_some() && app.screen == Screen::Overview;
    let matrix = app.screen == Screen::Evaluation;
    Some(match key.code {
        KeyCode::Char('q') => Action::Quit,
        KeyCode::Char('?') => Action::ToggleHelp,
        KeyCode::Tab => Action::FocusNext,
        KeyCode::BackTab => Action::FocusPrev,
        KeyCode::Char('1') => Action::Show(Screen::Overview),
        KeyCode::Char('2') => Action::Show(Screen::Evaluation),
        KeyCode::Char('3') => Action::Show(Screen::NextTask),
        KeyCode::Char('4') => Action::Show(Screen::Robot),
        KeyCode::Char(' ') => Action::StartPause,
        KeyCode::Char('e') => Action::EvaluateSelected,
        KeyCode::Char('r') => Action::ToggleRunThrough,
        KeyCode::Char('S') => Action::Save,
        KeyCode::Char('v') => Action::OpenViewer,
        KeyCode::Char('V') => Action::WriteVideo,
        KeyCode::Char('m') => Action::CurveMetricNext,
        KeyCode::Char('s') => Action::SmoothingToggle,
        KeyCode::Char('+' | '=') => Action::SmoothingUp,
        KeyCode::Char('-') => Action::SmoothingDown,
        KeyCode::Char('w') => Action::WholeSequence,
        KeyCode::Char('n') => Action::NetworkNext,
        KeyCode::Char('a') => Action::BeginAddTask,
        KeyCode::Char('z') => Action::Zoom(ZoomMove::Toggle),
        KeyCode::Esc if zoomed => Action::Zoom(ZoomMove::Toggle),
        KeyCode::Char('[') if zoomed => Action::Zoom(ZoomMove::Layer(-1)),
        KeyCode::Char(']') if zoomed => Action::Zoom(ZoomMove::Layer(1)),
        KeyCode::PageUp if zoomed => Action::Zoom(ZoomMove::Rows(-1)),
        KeyCode::PageDown if zoomed => Action::Zoom(ZoomMove::Rows(1)),
        KeyCode::Left if zoomed => Action::Zoom(ZoomMove::Columns(-1)),
        KeyCode::Right if zoomed => Action::Zoom(ZoomMove::Columns(1)),
        KeyCode::Left | KeyCode::Char('h') if matrix => Action::MatrixScroll(-1),
        KeyCode::Right | KeyCode::Char('l') if matrix => Action::MatrixScroll(1),
        KeyCode::Up | KeyCode::Char('k') if controls => Action::ControlUp,
        KeyCode::Down | KeyCode::Char('j') if controls => Action::ControlDown,
        KeyCode::Up | KeyCode::Char('k') => Action::CursorUp,
        KeyCode::Down | KeyCode::Char('j') => Action::CursorDown,
        KeyCode::Left if controls => Action::ControlChange(-1),
        KeyCode::Right if controls => Action::ControlChange(1),
        KeyCode::Enter if controls => Action::ControlChange(0),
        _ => return None,
    })
}
