//! The Session's step-by-step API on the toy masked learner: pause and resume
//! inside and between tasks, switch changes that apply to the next task only,
//! commands from an observer, and exact recall (forgetting 0 for `ours`).

use quadcl::cl::{LambdaMode, Ours, Sequence, SwitchOverrides, Switches};
use quadcl::config::net::MaskConfig;
use quadcl::engine::{Command, CommandSender, Event, EventLog, Observer, Session, StepOutcome, ToyLearner};

fn sequence(text: &str) -> Sequence {
    toml::from_str(text).unwrap()
}

fn session(seq: &str) -> Session {
    let mask = MaskConfig { entropy_iterations: Some(2), ..MaskConfig::default() };
    let learner = ToyLearner::new(&mask, 7).unwrap();
    Session::new(Box::new(learner), Box::new(Ours), sequence(seq), mask.clone(), Switches::from_mask_config(&mask), 7)
        .unwrap()
}

const THREE: &str =
    "iterations = 4\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n";

#[test]
fn pause_inside_a_task_stops_iterations_until_resume() {
    let mut s = session(THREE);
    assert_eq!(s.step_iteration().unwrap(), StepOutcome::Iterated { step: 0, iteration: 1 });
    assert_eq!(s.step_iteration().unwrap(), StepOutcome::Iterated { step: 0, iteration: 2 });
    s.pause();
    assert_eq!(s.step_iteration().unwrap(), StepOutcome::Paused);
    assert_eq!(s.train_next_task().unwrap(), StepOutcome::Paused);
    assert_eq!(s.progress(), Some((0, 2, 4)), "nothing ran while paused");
    s.resume();
    assert_eq!(s.train_next_task().unwrap(), StepOutcome::TaskFinished { step: 0 });
    assert_eq!(s.results().curves[0].performance.len(), 4, "the task got exactly its budget");
    assert_eq!(s.completed_steps(), 1);
}

#[test]
fn pause_between_tasks_holds_the_next_task_back() {
    let mut s = session(THREE);
    assert_eq!(s.train_next_task().unwrap(), StepOutcome::TaskFinished { step: 0 });
    s.pause();
    assert_eq!(s.train_next_task().unwrap(), StepOutcome::Paused);
    assert_eq!(s.progress(), None, "the next task did not start");
    s.resume();
    assert_eq!(s.run(&mut |_| Ok(())).unwrap(), StepOutcome::SequenceDone);
    assert!(s.is_done());
    assert_eq!(s.results().eval_matrix.rows.len(), 3);
    assert_eq!(s.step_iteration().unwrap(), StepOutcome::SequenceDone);
}

#[test]
fn switch_changes_apply_to_the_next_task_only() {
    let mut s = session(THREE);
    let log = EventLog::default();
    s.add_observer(Box::new(log.clone()));
    s.step_iteration().unwrap(); // task 0 in progress
    let change = SwitchOverrides {
        reinit_weights: Some(false),
        lambda: Some(LambdaMode::Free),
        capacity: Some(0.3),
        ..Default::default()
    };
    s.set_next_switches(change).unwrap();
    assert_eq!(s.next_switches().unwrap().capacity, 0.3);
    s.run(&mut |_| Ok(())).unwrap();
    let steps = &s.results().steps;
    let default = Switches::from_mask_config(&MaskConfig::default());
    assert_eq!(steps[0].switches.as_ref(), Some(&default), "the task in progress kept its switches");
    assert_eq!(
        steps[1].switches,
        Some(Switches { reinit_weights: false, lambda: LambdaMode::Free, capacity: 0.3, ..default.clone() })
    );
    assert_eq!(steps[2].switches.as_ref(), Some(&default), "the change was for one task");
    let started: Vec<f64> = log
        .snapshot()
        .iter()
        .filter_map(|e| match e {
            Event::TaskStarted { switches, .. } => switches.as_ref().map(|s| s.capacity),
            _ => None,
        })
        .collect();
    assert_eq!(started, vec![0.2, 0.3, 0.2]);
}

#[test]
fn an_invalid_switch_change_is_refused_and_changes_nothing() {
    let mut s = session(THREE);
    let err = s.set_next_switches(SwitchOverrides { capacity: Some(1.5), ..Default::default() }).unwrap_err();
    assert!(format!("{err:#}").contains("capacity"), "{err:#}");
    assert_eq!(s.next_switches().unwrap().capacity, 0.2);
}

/// Sends a command when it sees the n-th iteration event.
struct PauseAt {
    at: usize,
    seen: usize,
    sender: CommandSender,
}

impl Observer for PauseAt {
    fn on_event(&mut self, event: &Event) {
        if let Event::Iteration { .. } = event {
            self.seen += 1;
            if self.seen == self.at {
                self.sender.send(Command::Pause).unwrap();
            }
        }
    }
}

#[test]
fn an_observer_can_pause_the_session_through_the_command_channel() {
    let mut s = session(THREE);
    let sender = s.command_sender();
    s.add_observer(Box::new(PauseAt { at: 3, seen: 0, sender: sender.clone() }));
    assert_eq!(s.run(&mut |_| Ok(())).unwrap(), StepOutcome::Paused);
    assert_eq!(s.progress(), Some((0, 3, 4)));
    sender.send(Command::Resume).unwrap();
    assert_eq!(s.train_next_task().unwrap(), StepOutcome::TaskFinished { step: 0 });
}

#[test]
fn ours_forgets_nothing_and_recall_is_bit_identical_after_later_tasks() {
    let mut s = session(THREE);
    s.run(&mut |_| Ok(())).unwrap();
    let r = s.results().clone();
    assert_eq!(r.eval_matrix.forgetting(), Some(0.0));
    for j in 0..2 {
        let right_after = r.evaluations[j].iter().find(|e| e.report.task == r.tasks[j]).unwrap();
        let at_end = r.evaluations[2].iter().find(|e| e.report.task == r.tasks[j]).unwrap();
        assert_eq!(right_after, at_end, "task {j}");
    }
    // And evaluating on demand gives the same numbers again.
    let again = s.evaluate(0).unwrap();
    assert_eq!(&again, r.evaluations[2].iter().find(|e| e.report.task == r.tasks[0]).unwrap());
    assert!(s.evaluate(5).is_err());
}

#[test]
fn a_repeated_task_fine_tunes_without_touching_the_others() {
    let mut s = session("iterations = 3\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"crash:FL\"\n");
    s.run(&mut |_| Ok(())).unwrap();
    let r = s.results();
    assert_eq!(r.tasks.len(), 2);
    assert!(r.steps[2].repeat && !r.steps[1].repeat);
    let invert_before = r.evaluations[1].iter().find(|e| e.report.task == "invert:RR").unwrap();
    let invert_after = r.evaluations[2].iter().find(|e| e.report.task == "invert:RR").unwrap();
    assert_eq!(invert_before, invert_after);
}

#[test]
fn random_transfer_draws_as_many_learned_tasks_as_named() {
    let seq = "iterations = 2\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[[task]]\nname = \"noise:FR\"\n\
               [[task]]\nname = \"invert:RR+noise:FR\"\nrelated = [\"invert:RR\", \"noise:FR\"]\ninit = \"random\"\n";
    let mut s = session(seq);
    s.run(&mut |_| Ok(())).unwrap();
    let related = &s.results().steps[3].related;
    assert_eq!(related.len(), 2);
    assert!(related.iter().all(|&t| t < 3), "{related:?}");
    let mut again = session(seq);
    again.run(&mut |_| Ok(())).unwrap();
    assert_eq!(&again.results().steps[3].related, related, "the draw depends only on the seed");
}

#[test]
fn the_toy_learner_learns_within_a_task() {
    let mut s = session("iterations = 60\n[[task]]\nname = \"crash:FL\"\n");
    s.run(&mut |_| Ok(())).unwrap();
    let p = &s.results().curves[0].performance;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(mean(&p[50..]) > mean(&p[..10]) + 0.05, "{p:?}");
}

#[test]
fn a_transfer_change_applies_to_the_next_task_only() {
    let mut s = session(THREE);
    let err = s.set_next_transfer(vec!["invert:RR".into()], quadcl::cl::TransferInit::Related).unwrap_err();
    assert!(err.to_string().contains("not been learned"), "{err}");
    s.train_next_task().unwrap();
    s.set_next_transfer(vec!["crash:FL".into()], quadcl::cl::TransferInit::Related).unwrap();
    s.run(&mut |_| Ok(())).unwrap();
    let steps = &s.results().steps;
    assert_eq!(steps[1].related, vec![0]);
    assert!(steps[2].related.is_empty(), "the sequence entry applies again");
}

#[test]
fn mask_settings_cannot_change_while_a_task_is_in_progress() {
    use quadcl::config::net::Activation;
    use quadcl::nn::MaskedMlp;
    let mut net = MaskedMlp::new("n", &[4, 8, 2], Activation::Elu, &MaskConfig::default(), 1).unwrap();
    let wider = MaskConfig { capacity: 0.5, ..MaskConfig::default() };
    net.set_mask_config(&wider).unwrap();
    assert_eq!(net.mask_config().capacity, 0.5);
    assert!(net.layers().iter().all(|l| l.rule() == wider.rule));
    net.begin_task(0, &[]).unwrap();
    let err = net.set_mask_config(&MaskConfig::default()).unwrap_err().to_string();
    assert!(err.contains("in progress"), "{err}");
    assert_eq!(net.mask_config().capacity, 0.5);
    assert!(net.set_mask_config(&MaskConfig { capacity: 3.0, ..MaskConfig::default() }).is_err());
}
