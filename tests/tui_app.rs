//! `App::update`, one action at a time, without a terminal: each key's
//! effect on the state and on what is sent to the engine, on a toy-learner
//! run opened by the real worker.

mod tui_common;
use quadcl::cl::SwitchOverrides;
use quadcl::engine::Command;
use quadcl::nn::ScoreReinit;
use quadcl::tui::{Action, Outgoing, Panel, Screen};
use tui_common::{act, open_toy, pump, screen};

fn sent(app: &mut quadcl::tui::App) -> Vec<Outgoing> {
    std::mem::take(&mut app.outbox)
}

#[test]
fn navigation_keys_move_the_cursor_focus_and_screen() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, _worker) = open_toy(tmp.path(), (120, 40));
    assert_eq!(app.rows().len(), 3);
    assert_eq!(app.cursor, 0, "nothing learned yet: the first step is selected");
    app.update(Action::CursorDown);
    assert_eq!(app.cursor, 1);
    assert_eq!(sent(&mut app), vec![Outgoing::Engine(Command::WatchMasks("invert:RR".into()))]);
    app.update(Action::CursorDown);
    app.update(Action::CursorDown);
    assert_eq!(app.cursor, 2, "the cursor stops at the last row");
    app.update(Action::CursorUp);
    assert_eq!(app.cursor, 1);

    assert_eq!(app.focus, Panel::Timeline);
    app.update(Action::FocusNext);
    assert_eq!(app.focus, Panel::Curves);
    app.update(Action::FocusNext);
    app.update(Action::FocusNext);
    assert_eq!(app.focus, Panel::Training);
    app.update(Action::FocusNext);
    assert_eq!(app.focus, Panel::Timeline, "Tab cycles");
    app.update(Action::FocusPrev);
    assert_eq!(app.focus, Panel::Training);

    app.update(Action::Show(Screen::NextTask));
    assert_eq!(app.screen, Screen::NextTask);
    app.update(Action::FocusNext);
    app.update(Action::FocusNext);
    assert_eq!(app.focus, Panel::Controls);
    app.update(Action::Show(Screen::Evaluation));
    assert_eq!(app.focus, Panel::Timeline, "a panel not on the new screen loses the focus");

    // A click on the timeline's third row (screen row 5: header line, border, column
    // names, two rows) selects it and focuses the timeline; one on the right focuses the matrix.
    app.update(Action::Click(80, 10));
    assert_eq!(app.focus, Panel::Matrix);
    app.update(Action::Click(5, 5));
    assert_eq!((app.focus, app.cursor), (Panel::Timeline, 2));

    app.update(Action::ToggleHelp);
    assert!(app.help);
    app.update(Action::ToggleHelp);
    assert!(!app.help);
    app.update(Action::Resize(90, 30));
    assert_eq!(app.size, (90, 30));
}

#[test]
fn curve_and_mask_keys_change_what_is_drawn() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, _worker) = open_toy(tmp.path(), (120, 40));
    let w = app.smoothing;
    app.update(Action::SmoothingUp);
    assert!(app.smoothing > w);
    app.update(Action::SmoothingDown);
    app.update(Action::SmoothingDown);
    assert!(app.smoothing < w);
    for _ in 0..40 {
        app.update(Action::SmoothingDown);
    }
    assert_eq!(app.smoothing, 0.0, "the weight stays in [0, 0.99]");
    app.update(Action::SmoothingToggle);
    assert!(!app.smoothing_on);
    let m = app.metric;
    app.update(Action::CurveMetricNext);
    assert_ne!(app.metric, m);
    app.update(Action::WholeSequence);
    assert!(app.whole_sequence);
    app.update(Action::NetworkNext);
    assert_eq!(app.network, 0, "the toy learner has one network");
    app.update(Action::OpenViewer);
    assert!(app.messages.last().unwrap().contains("not learned yet"), "a pending task has nothing to show");
}

#[test]
fn m_cycles_through_the_plasticity_diagnostics_and_the_mask_churn_of_a_trained_step() {
    use quadcl::tui::app::CurveMetric;
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_toy(tmp.path(), (120, 40));
    act(&mut app, &mut worker, Action::StartPause, |a| a.paused && a.opened.as_ref().unwrap().results.steps.len() == 1);
    let curve = &app.opened.as_ref().unwrap().results.curves[0];
    let dormant = &curve.plasticity["plasticity/dormant/toy"];
    assert_eq!(dormant.len(), curve.performance.len(), "one value per iteration");
    assert!(dormant.iter().all(|d| (0.0..=1.0).contains(d)), "{dormant:?}");
    let panel = |app: &quadcl::tui::App| tui_common::panel(app, 76, 14, tmp.path(), quadcl::tui::panels::curves::draw);
    (0..5).for_each(|_| app.update(Action::CurveMetricNext));
    assert_eq!(app.metric, CurveMetric::Dormant);
    let text = panel(&app);
    assert!(text.contains("Curves: dormant units · step 0 crash:FL"), "{text}");
    assert!(text.contains("toy"), "the network's line is named: {text}");
    app.update(Action::CurveMetricNext);
    assert!(panel(&app).contains("Curves: effective rank"));
    app.update(Action::CurveMetricNext);
    let text = panel(&app);
    assert!(text.contains("Curves: selected |w| · step 0 crash:FL · toy (1/1)"), "{text}");
    assert!(text.contains("toy.l0") && text.contains("toy.l1"), "one line per layer: {text}");
    app.update(Action::CurveMetricNext);
    assert!(panel(&app).contains("Curves: trainable share"));
    app.update(Action::CurveMetricNext);
    let text = panel(&app);
    assert!(text.contains("Curves: mask churn · step 0 crash:FL · toy (1/1)"), "{text}");
    assert!(text.contains("toy.l0") && text.contains("toy.l1"), "one churn line per layer: {text}");
    app.update(Action::CurveMetricNext);
    assert_eq!(app.metric, CurveMetric::Performance, "the cycle closes");
}

#[test]
fn start_pause_and_quit_while_training_ask_the_engine_and_the_user() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_toy(tmp.path(), (120, 40));
    app.update(Action::StartPause);
    assert_eq!(sent(&mut app), vec![Outgoing::Engine(Command::Resume)]);
    worker.send(Command::Resume);
    pump(&mut app, &mut worker, |a| a.live.is_some() || a.opened.as_ref().unwrap().results.steps.len() == 1);
    // The toy task may already be over; pause after it is the default, so wait for that.
    pump(&mut app, &mut worker, |a| a.paused && a.opened.as_ref().unwrap().results.steps.len() == 1);
    assert!(app.messages.is_empty() || !app.messages.iter().any(|m| m.contains("rejected")), "{:?}", app.messages);
    assert_eq!(app.rows()[0].status, quadcl::tui::timeline::RowStatus::Learned);
    assert!(app.rows()[0].performance.is_some());
    app.update(Action::EvaluateSelected);
    assert_eq!(sent(&mut app), vec![Outgoing::Engine(Command::Evaluate("crash:FL".into()))]);
    app.update(Action::CursorDown);
    sent(&mut app);
    app.update(Action::EvaluateSelected);
    assert!(sent(&mut app).is_empty(), "a pending task is not evaluated");

    // Pretend a task is training: quit asks first; "no" keeps it.
    app.paused = false;
    app.live = Some(quadcl::tui::app::Live {
        record: app.opened.as_ref().unwrap().results.steps[0].clone(),
        iteration: 2,
        curve: Default::default(),
        arrivals: vec![],
        sps: None,
        physics_resets: 0,
    });
    let training = |app: &quadcl::tui::app::App| screen(app, 120, 40, tmp.path());
    assert!(!training(&app).contains("physics resets"));
    app.live.as_mut().unwrap().physics_resets = 3;
    assert!(training(&app).contains("physics resets 3"), "{}", training(&app));
    app.update(Action::Quit);
    assert!(app.confirm_quit && !app.quit);
    app.update(Action::ConfirmQuit(false));
    assert!(!app.confirm_quit && !app.quit);
    app.update(Action::Quit);
    app.update(Action::ConfirmQuit(true));
    assert!(app.quit);
    assert_eq!(sent(&mut app), vec![Outgoing::Engine(Command::Stop)]);
}

#[test]
fn next_task_controls_queue_switches_and_transfer_and_typed_tasks() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_toy(tmp.path(), (120, 40));
    app.update(Action::Show(Screen::NextTask));
    // Row 6 is the capacity: one step up.
    for _ in 0..6 {
        app.update(Action::ControlDown);
    }
    let before = app.next.pending(app.switches().unwrap()).capacity;
    act(&mut app, &mut worker, Action::ControlChange(1), |a| a.next.queued.capacity.is_some());
    assert!((app.next.pending(app.switches().unwrap()).capacity - (before + 0.01)).abs() < 1e-9);
    // Re-initialisation of weights off, then the scores' reading one step on (vacant -> all).
    for _ in 0..6 {
        app.update(Action::ControlUp);
    }
    act(&mut app, &mut worker, Action::ControlChange(0), |a| a.next.queued.reinit_weights == Some(false));
    app.update(Action::ControlDown);
    act(&mut app, &mut worker, Action::ControlChange(1), |a| a.next.queued.reinit_scores.is_some());
    app.update(Action::ControlUp);
    let capacity = Some(((before + 0.01) * 100.0).round() / 100.0);
    assert_eq!(
        app.next.queued,
        SwitchOverrides {
            reinit_weights: Some(false),
            reinit_scores: Some(ScoreReinit::All),
            capacity,
            ..Default::default()
        }
    );

    // Nothing learned yet: no related task to pick; the mode cycles.
    assert!(app.next.learned.is_empty());
    for _ in 0..8 {
        app.update(Action::ControlDown);
    }
    app.update(Action::ControlChange(1));
    assert!(matches!(sent(&mut app)[..], [Outgoing::Engine(Command::SetNextTransfer { .. })]));

    // A typed task: a bad name is an inline error and sends nothing; a good one is appended.
    app.update(Action::BeginAddTask);
    "wobble:FL".chars().for_each(|c| app.update(Action::Input(c)));
    app.update(Action::InputSubmit);
    assert!(app.next.input_error.as_ref().unwrap().contains("wobble"));
    assert!(sent(&mut app).is_empty());
    app.update(Action::InputClear);
    "invert:RR+noise:FR".chars().for_each(|c| app.update(Action::Input(c)));
    act(&mut app, &mut worker, Action::InputSubmit, |a| a.opened.as_ref().unwrap().sequence.tasks.len() == 4);
    assert!(app.next.input.is_none() && app.next.input_error.is_none());
    assert_eq!(app.rows()[3].task, "invert:RR+noise:FR");
}

/// Key presses one by one, then nothing (the loop waits for the app to quit).
struct Script(std::collections::VecDeque<ratatui::crossterm::event::Event>);

impl quadcl::tui::EventSource for Script {
    fn next(&mut self, _timeout: std::time::Duration) -> anyhow::Result<Option<ratatui::crossterm::event::Event>> {
        Ok(self.0.pop_front())
    }
}

fn key(c: char) -> ratatui::crossterm::event::Event {
    use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
    Event::Key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE))
}

#[test]
fn the_event_loop_runs_on_a_test_backend_with_scripted_keys_until_q() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_toy(tmp.path(), (100, 30));
    let mut terminal = ratatui::Terminal::new(ratatui::backend::TestBackend::new(100, 30)).unwrap();
    let resize = ratatui::crossterm::event::Event::Resize(100, 30);
    let mut script = Script([key('2'), key('?'), key('x'), resize, key('3'), key('q')].into_iter().collect());
    quadcl::tui::run_app(&mut terminal, &mut app, &mut worker, &mut script).unwrap();
    assert!(app.quit);
    assert_eq!(app.screen, Screen::NextTask);
    assert!(!app.help, "any key closed the help");
    let shown = format!("{:?}", terminal.backend().buffer());
    assert!(shown.contains("Next task"), "the last frame is the Next task screen: {shown}");
    assert_eq!(app.messages.last().unwrap(), "stopping: writing the results ...");
    assert!(tmp.path().join("run/metrics.json").exists());
}

#[test]
fn z_zooms_the_masks_into_a_layer_and_arrows_scroll_the_matrix_on_the_evaluation_screen() {
    use quadcl::tui::input::key_action;
    use quadcl::tui::mask_zoom::ZoomMove;
    use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
    let key = |app: &quadcl::tui::App, code| key_action(app, &KeyEvent::new(code, KeyModifiers::NONE));
    let mut app = quadcl::tui::App::new("run".into(), (120, 40), quadcl::tui::Clock::Ticks(0));
    app.update(Action::Show(Screen::Evaluation));
    assert!(matches!(key(&app, KeyCode::Right), Some(Action::MatrixScroll(1))));
    assert!(matches!(key(&app, KeyCode::Char('h')), Some(Action::MatrixScroll(-1))));
    assert!(key(&app, KeyCode::PageDown).is_none(), "no zoom: page keys do nothing");
    assert!(matches!(key(&app, KeyCode::Char('z')), Some(Action::Zoom(ZoomMove::Toggle))));
    app.update(Action::Zoom(ZoomMove::Toggle));
    assert_eq!((app.screen, app.focus), (Screen::Overview, Panel::Masks), "z shows the masks");
    assert!(app.zoom.is_some());
    assert!(matches!(key(&app, KeyCode::PageDown), Some(Action::Zoom(ZoomMove::Rows(1)))));
    assert!(matches!(key(&app, KeyCode::PageUp), Some(Action::Zoom(ZoomMove::Rows(-1)))));
    assert!(matches!(key(&app, KeyCode::Char(']')), Some(Action::Zoom(ZoomMove::Layer(1)))));
    assert!(matches!(key(&app, KeyCode::Left), Some(Action::Zoom(ZoomMove::Columns(-1)))));
    assert!(matches!(key(&app, KeyCode::Esc), Some(Action::Zoom(ZoomMove::Toggle))));
    app.update(Action::Zoom(ZoomMove::Toggle));
    assert!(app.zoom.is_none());
    let help: Vec<&str> = quadcl::tui::panels::help::KEYS.iter().map(|(k, _)| *k).collect();
    assert!(help.contains(&"z") && help.iter().any(|k| k.contains("PgUp")) && help.iter().any(|k| k.contains("← →")));
}
