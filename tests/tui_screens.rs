//! The workbench's screens on the shipped run (`policies/sequence-a1-adapter`
//! continued with the 12-task sequence, into a temporary folder), drawn on
//! ratatui's TestBackend and snapshotted (in `snapshots/`): the first screen
//! at 120x40 and 80x24 with the masks of `crash:FL`, the evaluation matrix,
//! the next-task controls, the help overlay, the robot panel with a
//! simulated frame, and what a resize to too small a terminal shows. The
//! Sweep screen on the committed sweep fixture (`tests/sweep_fixture`). The
//! Masks panel zoomed into one layer, and the Evaluation screen after twelve
//! learned tasks (a toy-learner run) at 120x40 and 80x24.

mod tui_common;
use quadcl::tui::mask_zoom::ZoomMove;
use quadcl::tui::{Action, Screen, WorkerMsg};
use tui_common::{act, open_shipped, pump, root, screen};

macro_rules! snap {
    ($name:expr, $text:expr) => {
        insta::with_settings!({snapshot_path => "../snapshots", prepend_module_to_snapshot => true}, {
            insta::assert_snapshot!($name, $text);
        })
    };
}

#[test]
fn the_shipped_run_opens_on_every_screen() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_shipped(tmp.path(), (120, 40));
    let hide = tmp.path();
    let rows = app.rows();
    assert_eq!(rows.len(), 13, "the base task and twelve steps");
    assert_eq!(app.selected().unwrap().task, "crash:FR", "the last learned step is selected first");
    // Up to crash:FL, and wait for its element views.
    for _ in 0..2 {
        app.update(Action::CursorUp);
    }
    let crash_fl = app.opened.as_ref().unwrap().results.tasks.iter().position(|t| t == "crash:FL").unwrap();
    act(&mut app, &mut worker, Action::CursorUp, |a| a.views.as_ref().is_some_and(|v| v.0 == crash_fl));
    assert_eq!(app.selected().unwrap().task, "crash:FL");
    snap!("overview_crash_fl_120x40", screen(&app, 120, 40, hide));
    snap!("overview_crash_fl_80x24", screen(&app, 80, 24, hide));
    // Zoomed into actor.l0 (512 x 64: every input of a row fits), then actor.l1 (256 x 512), a
    // page down and a page right.
    app.update(Action::Zoom(ZoomMove::Toggle));
    let zoomed = screen(&app, 120, 40, hide);
    assert!(
        zoomed.contains("actor.l0 512x64") && zoomed.contains("rows 1-19 of 512 (PgUp/PgDn) · all 64 inputs"),
        "{zoomed}"
    );
    snap!("masks_zoom_actor_l0_120x40", zoomed);
    app.update(Action::Zoom(ZoomMove::Layer(1)));
    app.update(Action::Zoom(ZoomMove::Rows(1)));
    app.update(Action::Zoom(ZoomMove::Columns(1)));
    let paged = screen(&app, 120, 40, hide);
    assert!(
        paged.contains("actor.l1 256x512") && paged.contains("rows 20-38 of 256 (PgUp/PgDn) · inputs 113-224 of 512"),
        "{paged}"
    );
    snap!("masks_zoom_actor_l1_paged_120x40", paged);
    app.update(Action::Zoom(ZoomMove::Toggle));
    assert!(app.zoom.is_none());
    // Each panel alone, at the size it has on a 120x40 screen.
    use quadcl::tui::panels;
    type Draw = fn(&mut ratatui::Frame, ratatui::layout::Rect, &quadcl::tui::App, bool);
    let alone: [(&str, Draw, u16, u16); 7] = [
        ("panel_timeline", panels::timeline::draw, 44, 30),
        ("panel_training", panels::training::draw, 44, 8),
        ("panel_curves", panels::curves::draw, 76, 14),
        ("panel_masks", panels::masks::draw, 76, 24),
        ("panel_matrix", panels::matrix::draw, 76, 30),
        ("panel_controls", panels::controls::draw, 76, 30),
        ("panel_robot_waiting", panels::robot::draw, 76, 12),
    ];
    for (name, draw, w, h) in alone {
        snap!(name, tui_common::panel(&app, w, h, hide, draw));
    }
    app.update(Action::Show(Screen::Evaluation));
    snap!("evaluation_matrix_120x40", screen(&app, 120, 40, hide));
    snap!("evaluation_matrix_80x24", screen(&app, 80, 24, hide));
    app.update(Action::Show(Screen::NextTask));
    snap!("next_task_120x40", screen(&app, 120, 40, hide));
    app.update(Action::ToggleHelp);
    snap!("help_120x40", screen(&app, 120, 40, hide));
    snap!("help_80x24", screen(&app, 80, 24, hide));
    app.update(Action::ToggleHelp);
    assert!(!app.help);

    // The robot panel: stop the live thread and draw a frame simulated here (deterministic).
    app.update(Action::Show(Screen::Robot));
    worker.stop_robot();
    let policy = root().join("policies/sequence-a1-adapter/checkpoints/step-03-crash_FR");
    let mut viewer = quadcl::rl::RobotViewer::new(&policy, "crash:FL", 1, Some([0.5, 0.0, 0.0])).unwrap();
    let mut frame = viewer.frame();
    for _ in 0..50 {
        frame = viewer.step().unwrap();
    }
    app.robot.frame = None;
    app.update(Action::Worker(WorkerMsg::Robot { task: "crash:FL".into(), frame: Box::new(frame) }));
    snap!("robot_crash_fl_120x40", screen(&app, 120, 40, hide));

    // `v`: 20 s of the task in the Rerun viewer, or (no `rerun` on PATH, as in CI) into the .rrd only.
    let shown = |m: &String| m.starts_with("showed") || m.starts_with("no Rerun viewer");
    act(&mut app, &mut worker, Action::OpenViewer, |a| a.messages.last().is_some_and(shown));
    assert!(app.messages.iter().any(|m| m.starts_with("opening crash:FL in the Rerun viewer")), "{:?}", app.messages);
    let episode = tmp.path().join("workbench/episodes/workbench-crash_FL.rrd");
    let message = app.messages.last().unwrap();
    assert!(message.contains(&episode.display().to_string()), "{message}");
    let file = std::io::BufReader::new(std::fs::File::open(&episode).unwrap());
    let messages = re_log_encoding::DecoderApp::decode_lazy(file).collect::<Result<Vec<_>, _>>().unwrap();
    assert!(messages.len() > 10, "a complete recording: {} messages", messages.len());
    worker.shutdown();
}

#[test]
fn twelve_learned_tasks_show_every_task_column_at_120x40_and_scroll_at_80x24() {
    let tmp = tempfile::tempdir().unwrap();
    let config = tmp.path().join("twelve.toml");
    std::fs::write(&config, tui_common::twelve_task_run()).unwrap();
    let spec = quadcl::tui::OpenSpec { run_dir: tmp.path().join("run"), config: Some(config), continues: None };
    let (mut app, mut worker) = tui_common::open(spec, (120, 40));
    let hide = tmp.path();
    let steps = |a: &quadcl::tui::App| a.opened.as_ref().map_or(0, |o| o.results.steps.len());
    app.update(Action::ToggleRunThrough);
    app.update(Action::StartPause);
    for _ in 0..12 {
        pump(&mut app, &mut worker, |a| steps(a) == 12 || a.live.is_some());
        pump(&mut app, &mut worker, |a| steps(a) == 12 || a.live.is_none());
        if steps(&app) == 12 {
            break;
        }
    }
    pump(&mut app, &mut worker, |a| steps(a) == 12 && a.paused && a.summary.is_some());
    app.update(Action::Show(Screen::Evaluation));
    let tasks = app.opened.as_ref().unwrap().results.tasks.clone();
    assert_eq!(tasks.len(), 12);
    let wide = screen(&app, 120, 40, hide);
    let head = wide.lines().nth(2).unwrap();
    for t in &tasks {
        assert!(head.contains(&quadcl::tui::panels::short_task(t)), "{t} missing from {head}");
    }
    snap!("evaluation_twelve_tasks_120x40", wide);
    // At 80x24 a window of the columns, marked, holding the selected (last) step's task.
    app.update(Action::Resize(80, 24));
    let narrow = screen(&app, 80, 24, hide);
    assert!(narrow.contains("◂") && narrow.contains(" of 12 ←→") && narrow.contains("iRR"), "{narrow}");
    snap!("evaluation_twelve_tasks_80x24", narrow);
    // Scrolling left reaches the first column; the window then marks more on the right.
    (0..12).for_each(|_| app.update(Action::MatrixScroll(-1)));
    let left = screen(&app, 80, 24, hide);
    assert!(left.contains("tasks 1-") && left.contains("▸") && left.contains("cFL"), "{left}");
    snap!("evaluation_twelve_tasks_80x24_scrolled_left", left);
    // Selecting a step follows its task again.
    app.update(Action::CursorUp);
    assert_eq!(app.matrix_scroll, None);
    worker.shutdown();
}

#[test]
fn a_resize_below_80x24_says_so_and_a_resize_back_redraws_everything() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, _worker) = open_shipped(tmp.path(), (120, 40));
    let mut terminal = ratatui::Terminal::new(ratatui::backend::TestBackend::new(120, 40)).unwrap();
    terminal.draw(|f| quadcl::tui::ui::draw(f, &app)).unwrap();
    for (w, h) in [(79, 24), (80, 23), (60, 10)] {
        terminal.backend_mut().resize(w, h);
        app.update(Action::Resize(w, h));
        terminal.draw(|f| quadcl::tui::ui::draw(f, &app)).unwrap();
        let text = format!("{:?}", terminal.backend().buffer());
        assert!(text.contains("needs at least 80x24"), "{w}x{h}: {text}");
    }
    terminal.backend_mut().resize(80, 24);
    app.update(Action::Resize(80, 24));
    terminal.draw(|f| quadcl::tui::ui::draw(f, &app)).unwrap();
    let text = format!("{:?}", terminal.backend().buffer());
    assert!(!text.contains("needs at least") && text.contains("Sequence") && text.contains("Masks"), "{text}");
    assert_eq!(app.size, (80, 24));
}

#[test]
fn the_sweep_screen_shows_every_cell_and_the_collected_table() {
    use quadcl::tui::{SweepAction, SweepView};
    let dir = std::path::PathBuf::from("tests/sweep_fixture");
    let mut view = SweepView::new(dir.clone(), (120, 40));
    let read = quadcl::tui::sweep_view::snapshot(&root().join(&dir), false);
    view.update(SweepAction::Refresh(Box::new(read)));
    assert!(view.error.is_none(), "{:?}", view.error);
    let text = tui_common::sweep_screen(&view, 120, 40);
    assert!(text.contains("5 finished, 1 stopped") && text.contains("0.500 [0.400, 0.600]"), "{text}");
    snap!("sweep_fixture_120x40", text);
    snap!("sweep_fixture_80x24", tui_common::sweep_screen(&view, 80, 24));
    // Enter on the stopped cell asks for its run to be opened in the workbench.
    for _ in 0..5 {
        view.update(SweepAction::Down);
    }
    view.update(SweepAction::Open);
    assert_eq!(view.open, Some(dir.join("runs/5")));
}
