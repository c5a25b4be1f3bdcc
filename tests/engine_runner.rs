//! What a UI needs of the engine, on the toy learner: a session that moves to
//! another thread and reports through a channel, a runner that waits for
//! commands while paused, trains on resume, writes after every task, keeps
//! tasks added on the way, and continues a shorter run; element views that
//! agree with the mask statistics; commands that fail without stopping anything.

use quadcl::cl::{SwitchOverrides, TaskSpec};
use quadcl::engine::{ChannelObserver, Command, Event, OpenMode, Runner, StepOutcome};
use quadcl::nn::ElementView;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

const HEAD: &str = "seed = 5\niterations = 4\n[run]\nlearner = \"toy\"\n[net.mask]\nentropy_iterations = 2\n";
const TWO: &str = "[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Waits (at most 30 s) for the first event that `pick` accepts.
fn wait_for<T>(events: &Receiver<Event>, mut pick: impl FnMut(&Event) -> Option<T>) -> T {
    loop {
        let e = events.recv_timeout(Duration::from_secs(30)).expect("the event came");
        if let Some(t) = pick(&e) {
            return t;
        }
    }
}

#[test]
fn a_runner_serves_on_its_own_thread_waits_while_paused_and_keeps_added_tasks() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "run.toml", &format!("{HEAD}{TWO}"));
    let out = tmp.path().join("out");
    let mut runner = Runner::open(&cfg, &out, OpenMode::New, false).unwrap();
    let (tx, events) = channel();
    runner.session_mut().add_observer(Box::new(ChannelObserver(tx)));
    runner.session_mut().pause();
    let commands = runner.session().command_sender();
    let worker = std::thread::spawn(move || {
        runner.serve().unwrap();
        runner
    });
    // Paused: a command is answered, and nothing trains.
    commands.send(Command::WatchMasks("crash:FL".into())).unwrap();
    let iteration = wait_for(&events, |e| match e {
        Event::MaskViews { iteration, .. } => Some(*iteration),
        Event::Iteration { .. } => panic!("trained while paused"),
        _ => None,
    });
    assert_eq!(iteration, None);
    commands.send(Command::Resume).unwrap();
    wait_for(&events, |e| matches!(e, Event::TaskEnded { step: 0, .. }).then_some(()));
    let live = wait_for(&events, |e| match e {
        Event::Measures { after_step, eval_matrix, .. } => Some((*after_step, eval_matrix.rows.len())),
        _ => None,
    });
    assert_eq!(live, (0, 1));
    commands.send(Command::Pause).unwrap();
    let spec = TaskSpec {
        name: "invert:RR+noise:FR".into(),
        iterations: Some(2),
        related: vec!["crash:FL".into()],
        init: Default::default(),
        switches: SwitchOverrides::default(),
    };
    commands.send(Command::AppendTask(spec)).unwrap();
    wait_for(&events, |e| matches!(e, Event::TaskAppended { step: 2, .. }).then_some(()));
    commands.send(Command::Stop).unwrap();
    let runner = worker.join().unwrap();
    assert!(runner.session().is_stopped());
    let done = runner.session().completed_steps();
    assert!(done >= 1);

    let text = std::fs::read_to_string(out.join("run.toml")).unwrap();
    assert!(text.contains("invert:RR+noise:FR"), "{text}");
    // The folder is one process's at a time: the runner lets it go before it is reopened.
    drop(runner);
    let reopened = Runner::open(&out.join("run.toml"), &out, OpenMode::ResumeOrNew, false).unwrap();
    assert_eq!(reopened.session().sequence().tasks.len(), 3);
    assert_eq!(reopened.session().completed_steps(), done, "every finished task is kept");
    assert_eq!(reopened.session().results().tasks.len(), 3);
}

#[test]
fn a_rejected_command_is_announced_and_training_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "run.toml", &format!("{HEAD}{TWO}"));
    let mut runner = Runner::open(&cfg, &tmp.path().join("out"), OpenMode::New, false).unwrap();
    let (tx, events) = channel();
    runner.session_mut().add_observer(Box::new(ChannelObserver(tx)));
    let commands = runner.session().command_sender();
    commands.send(Command::SetNextSwitches(SwitchOverrides { capacity: Some(2.0), ..Default::default() })).unwrap();
    commands.send(Command::Evaluate("invert:RR".into())).unwrap();
    commands
        .send(Command::AppendTask(TaskSpec {
            name: "wobble:FL".into(),
            iterations: None,
            related: vec![],
            init: Default::default(),
            switches: SwitchOverrides::default(),
        }))
        .unwrap();
    assert_eq!(runner.train(None).unwrap(), StepOutcome::SequenceDone);
    let rejected: Vec<String> = events
        .try_iter()
        .filter_map(|e| match e {
            Event::CommandRejected { error, .. } => Some(error),
            _ => None,
        })
        .collect();
    assert_eq!(rejected.len(), 3, "{rejected:?}");
    assert!(rejected[0].contains("capacity"), "{}", rejected[0]);
    assert!(rejected[1].contains("has not been learned"), "{}", rejected[1]);
    assert!(rejected[2].contains("wobble"), "{}", rejected[2]);
    assert_eq!(runner.session().completed_steps(), 2);
}

#[test]
fn element_views_agree_with_the_mask_statistics() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "run.toml", &format!("{HEAD}{TWO}"));
    let mut runner = Runner::open(&cfg, &tmp.path().join("out"), OpenMode::New, false).unwrap();
    runner.train(None).unwrap();
    let tasks = runner.session().results().tasks.clone();
    let report = runner.session().learner().mask_report(&tasks);
    for (t, name) in tasks.iter().enumerate() {
        let views = runner.session().learner().mask_views(t);
        let layers = report.networks.iter().flat_map(|n| &n.layers);
        for (view, stats) in views.iter().zip(layers) {
            assert_eq!(view.layer, stats.name);
            let count = |v: ElementView| view.codes.iter().filter(|c| **c == v as u8).count();
            let own = stats.per_task.iter().find(|p| &p.task == name).unwrap();
            let private = stats.private.get(name).copied().unwrap_or(0);
            assert_eq!(count(ElementView::SelectedFromVacant) + count(ElementView::PrivateToTask), own.from_vacant);
            assert_eq!(count(ElementView::SelectedFromOccupied), own.from_occupied);
            assert_eq!(count(ElementView::PrivateToTask), private);
            assert_eq!(count(ElementView::Vacant), stats.vacant);
            for v in ElementView::ALL {
                assert_eq!(view.counts[v as usize], count(v), "{v:?} counted in the view");
            }
        }
    }
    let lift = runner.session().learner().transfer_lift(&[0]);
    let first = &report.networks[0].layers[0];
    assert_eq!(lift[0].lifted, first.per_task[0].selected);
}

#[test]
fn a_longer_sequence_continues_a_shorter_run_without_touching_it() {
    let tmp = tempfile::tempdir().unwrap();
    let short = write(tmp.path(), "short.toml", &format!("{HEAD}{TWO}"));
    let prior = tmp.path().join("prior");
    Runner::open(&short, &prior, OpenMode::New, false).unwrap().train(None).unwrap();
    let before = std::fs::read(prior.join("metrics.json")).unwrap();
    let long = write(tmp.path(), "long.toml", &format!("{HEAD}{TWO}[[task]]\nname = \"noise:FR\"\n"));
    let out = tmp.path().join("out");
    let mut runner = Runner::continue_run(&prior, &long, &out, false).unwrap();
    assert_eq!(runner.session().completed_steps(), 2);
    assert_eq!(runner.session().results().eval_matrix.rows[1].len(), 3, "rows gain the new task's column");
    assert_eq!(runner.train(None).unwrap(), StepOutcome::SequenceDone);
    assert_eq!(runner.metrics().summary.forgetting, Some(0.0));
    assert_eq!(std::fs::read(prior.join("metrics.json")).unwrap(), before, "the prior run is only read");
    drop(runner);
    let reopened = Runner::open(&out.join("run.toml"), &out, OpenMode::ResumeOrNew, false).unwrap();
    assert!(reopened.session().is_done());

    let other = write(tmp.path(), "other.toml", &(format!("seed = 6\n{}", &HEAD[9..]) + TWO));
    let err = Runner::continue_run(&prior, &other, &tmp.path().join("o2"), false).err().unwrap();
    assert!(format!("{err:#}").contains("seed"), "{err:#}");
}

#[test]
fn settings_chosen_for_the_next_step_survive_a_reopen_and_an_interrupted_step_retrains_as_chosen() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "run.toml", &format!("{HEAD}{TWO}[[task]]\nname = \"noise:FR\"\n"));
    let change = SwitchOverrides { capacity: Some(0.3), ..Default::default() };
    let related = (vec!["crash:FL".to_string()], quadcl::cl::TransferInit::Related);

    // A: step 0, then the change for step 1 queued, stop before it starts, reopen, finish.
    let a = tmp.path().join("a");
    let mut runner = Runner::open(&cfg, &a, OpenMode::New, false).unwrap();
    runner.train(Some(1)).unwrap();
    runner.session_mut().set_next_switches(change.clone()).unwrap();
    runner.session_mut().set_next_transfer(related.0.clone(), related.1).unwrap();
    runner.session_mut().stop();
    runner.serve().unwrap();
    assert!(a.join("next-step.json").exists());
    drop(runner);
    let mut runner = Runner::open(&cfg, &a, OpenMode::Resume, false).unwrap();
    assert_eq!(runner.session().queued_switches(), &change);
    assert_eq!(runner.session().queued_transfer(), Some(&related));
    assert_eq!(runner.train(None).unwrap(), StepOutcome::SequenceDone);
    assert!(!a.join("next-step.json").exists(), "nothing is pending once the step ran");
    let done_a = runner.metrics();
    assert_eq!(done_a.steps[1].switches.as_ref().map(|s| s.capacity), Some(0.3));
    assert_eq!(done_a.steps[1].related, vec![0]);

    // B: the same, but step 1 is stopped after two of its iterations; reopened, it retrains from its start.
    let b = tmp.path().join("b");
    let mut runner = Runner::open(&cfg, &b, OpenMode::New, false).unwrap();
    runner.train(Some(1)).unwrap();
    runner.session_mut().set_next_switches(change.clone()).unwrap();
    runner.session_mut().set_next_transfer(related.0.clone(), related.1).unwrap();
    runner.session_mut().step_iteration().unwrap();
    runner.session_mut().step_iteration().unwrap();
    runner.session_mut().stop();
    runner.serve().unwrap();
    drop(runner);
    let mut runner = Runner::open(&cfg, &b, OpenMode::Resume, false).unwrap();
    assert_eq!(runner.session().completed_steps(), 1);
    assert_eq!(runner.train(None).unwrap(), StepOutcome::SequenceDone);
    let done_b = runner.metrics();
    assert_eq!(done_b.curves, done_a.curves, "the interrupted step retrained exactly as chosen");
    assert_eq!(done_b.eval_matrix, done_a.eval_matrix);
    assert_eq!(done_b.steps, done_a.steps);
}

#[test]
fn a_start_interrupted_before_metrics_json_is_started_again_but_a_run_is_never_overwritten() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "run.toml", &format!("{HEAD}{TWO}"));
    let out = tmp.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("run.toml"), "half").unwrap();
    let mut runner = Runner::open(&cfg, &out, OpenMode::ResumeOrNew, false).unwrap();
    assert_eq!(runner.session().completed_steps(), 0, "nothing was there: a new run");
    runner.train(Some(1)).unwrap();
    drop(runner);
    let before = std::fs::read(out.join("metrics.json")).unwrap();
    let err = Runner::open(&cfg, &out, OpenMode::New, false).err().unwrap();
    assert!(format!("{err:#}").contains("already holds a run"), "{err:#}");
    assert_eq!(std::fs::read(out.join("metrics.json")).unwrap(), before);
    // Checkpoints without a metrics.json are a run too: never written over.
    std::fs::remove_file(out.join("metrics.json")).unwrap();
    let err = Runner::open(&cfg, &out, OpenMode::New, false).err().unwrap();
    assert!(format!("{err:#}").contains("already holds a run"), "{err:#}");
}

#[test]
fn forward_transfer_against_a_reference_run_is_the_same_in_events_and_in_metrics_json() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(tmp.path(), "a.toml", &format!("{HEAD}{TWO}"));
    let a = tmp.path().join("a");
    Runner::open(&cfg, &a, OpenMode::New, false).unwrap().train(None).unwrap();
    let with_ref = HEAD.replace("[run]\n", &format!("[run]\nreference = {:?}\n", a.join("metrics.json")));
    let cfg_b = write(tmp.path(), "b.toml", &format!("{with_ref}{TWO}"));
    let mut b = Runner::open(&cfg_b, &tmp.path().join("b"), OpenMode::New, false).unwrap();
    let (tx, events) = channel();
    b.session_mut().add_observer(Box::new(ChannelObserver(tx)));
    b.train(None).unwrap();
    let last = events
        .try_iter()
        .filter_map(|e| match e {
            Event::Measures { summary, .. } => Some(summary),
            _ => None,
        })
        .last()
        .unwrap();
    let written = b.metrics().summary;
    assert_eq!(last, written);
    assert!(written.forward_transfer.iter().all(|f| f.is_some()), "{:?}", written.forward_transfer);
}
