//! A scripted workbench session on the toy learner, snapshotted along the
//! way: open a fresh run, queue a switch change for the first step, train
//! it, compose the next step's transfer from it, train that, then run
//! through the rest. What the screens show is checked against the run folder.

mod tui_common;
use quadcl::tui::{Action, Screen};
use tui_common::{act, open_toy, screen};

macro_rules! snap {
    ($name:expr, $text:expr) => {
        insta::with_settings!({snapshot_path => "../snapshots", prepend_module_to_snapshot => true}, {
            insta::assert_snapshot!($name, $text);
        })
    };
}

fn steps(app: &quadcl::tui::App) -> usize {
    app.opened.as_ref().map_or(0, |o| o.results.steps.len())
}

#[test]
fn a_scripted_session_starts_a_task_changes_a_switch_composes_a_related_task_and_finishes() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut app, mut worker) = open_toy(tmp.path(), (120, 40));
    let hide = tmp.path();
    snap!("opened", screen(&app, 120, 40, hide));

    // Capacity of the first step: 0.20 -> 0.21.
    app.update(Action::Show(Screen::NextTask));
    app.update(Action::FocusNext);
    for _ in 0..6 {
        app.update(Action::ControlDown);
    }
    act(&mut app, &mut worker, Action::ControlChange(1), |a| a.next.queued.capacity.is_some());
    snap!("switch_queued", screen(&app, 120, 40, hide));

    // Train step 0; the workbench pauses after it.
    act(&mut app, &mut worker, Action::StartPause, |a| steps(a) == 1 && a.paused);
    app.update(Action::Show(Screen::Overview));
    snap!("step0_learned", screen(&app, 120, 40, hide));
    // Its plasticity diagnostics (`m` past the fall rate): the mean |w| of each layer's selection.
    (0..7).for_each(|_| app.update(Action::CurveMetricNext));
    snap!("step0_selected_abs_w", tui_common::panel(&app, 76, 14, hide, quadcl::tui::panels::curves::draw));
    (0..2).for_each(|_| app.update(Action::CurveMetricNext));

    // Step 1 names step 0's task as related; the preview comes from the engine.
    app.update(Action::Show(Screen::NextTask));
    app.update(Action::FocusNext);
    (0..20).for_each(|_| app.update(Action::ControlUp));
    (0..9).for_each(|_| app.update(Action::ControlDown));
    assert_eq!(app.next.cursor, 9, "the first related task (the switches, then the mode)");
    act(&mut app, &mut worker, Action::ControlChange(0), |a| {
        a.next.preview.as_ref().is_some_and(|p| p.related == ["crash:FL".to_string()] && p.lifted_from == p.related)
    });
    snap!("related_composed", screen(&app, 120, 40, hide));

    act(&mut app, &mut worker, Action::StartPause, |a| steps(a) == 2 && a.paused);
    app.update(Action::ToggleRunThrough);
    act(&mut app, &mut worker, Action::StartPause, |a| steps(a) == 3 && a.paused);
    app.update(Action::Show(Screen::Evaluation));
    snap!("finished_matrix", screen(&app, 120, 40, hide));

    app.update(Action::Quit);
    assert!(app.quit, "nothing trains: quit without asking");
    quadcl::tui::dispatch(&mut app, &mut worker);
    worker.shutdown();

    // The run folder holds what the screens showed.
    let m = quadcl::engine::MetricsFile::load(&tmp.path().join("run/metrics.json")).unwrap();
    assert_eq!(m.completed_steps, 3);
    assert_eq!(m.steps[0].switches.as_ref().map(|s| s.capacity), Some(0.21));
    assert_eq!(m.steps[1].switches.as_ref().map(|s| s.capacity), Some(0.2), "the change was for the first step only");
    assert_eq!(m.steps[1].related, vec![0]);
    assert_eq!(m.summary.forgetting, Some(0.0));
    assert_eq!(m.eval_matrix, app.opened.as_ref().unwrap().results.eval_matrix);
    assert!(tmp.path().join("run/checkpoints/step-02-noise_FR/manifest.json").exists());
}
