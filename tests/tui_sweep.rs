//! The Sweep screen's event loop on ratatui's TestBackend with scripted keys, over the
//! committed fixture (`tests/sweep_fixture`): the cursor moves, Enter on a
//! finished cell hands its run folder to the opener (the workbench, in the real
//! terminal), the screen is drawn again when the opener returns, and q ends the loop.

use quadcl::tui::sweep_view::snapshot;
use quadcl::tui::{run_sweep_app, EventSource, SweepAction, SweepReader, SweepView};
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
use ratatui::Terminal;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Keys, one per call, then nothing.
struct Keys(VecDeque<KeyCode>);

impl EventSource for Keys {
    fn next(&mut self, _timeout: Duration) -> anyhow::Result<Option<Event>> {
        Ok(self.0.pop_front().map(|k| Event::Key(KeyEvent::new(k, KeyModifiers::NONE))))
    }
}

fn screen(terminal: &Terminal<TestBackend>) -> String {
    let buffer = terminal.backend().buffer();
    let area = buffer.area;
    (0..area.height).map(|y| (0..area.width).map(|x| buffer[(x, y)].symbol()).collect::<String>() + "\n").collect()
}

#[test]
fn enter_hands_the_selected_cells_run_to_the_workbench_and_q_quits() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep_fixture");
    let mut view = SweepView::new(dir.clone(), (120, 40));
    view.update(SweepAction::Refresh(Box::new(snapshot(&dir, false))));
    let reader = SweepReader::spawn(&dir, false);
    let mut terminal = Terminal::new(TestBackend::new(120, 40)).unwrap();
    let mut keys = Keys([KeyCode::Down, KeyCode::Down, KeyCode::Enter, KeyCode::Char('q')].into());
    let mut opened: Vec<PathBuf> = Vec::new();
    let mut open = |t: &mut Terminal<TestBackend>, _events: &mut dyn EventSource, run: PathBuf| {
        // What the workbench would leave behind: the loop must draw the Sweep screen again.
        t.draw(|f| f.render_widget(ratatui::widgets::Paragraph::new("a workbench"), f.area())).unwrap();
        opened.push(run);
        Ok(())
    };
    run_sweep_app(&mut terminal, &mut view, &reader, &mut keys, &mut open).unwrap();
    assert_eq!(opened, vec![dir.join("runs/2")]);
    assert!(view.quit && view.cursor == 2);
    let text = screen(&terminal);
    assert!(text.contains("›   2 finished") && text.contains("Collected") && !text.contains("a workbench"), "{text}");
}
