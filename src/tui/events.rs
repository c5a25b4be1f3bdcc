//! How the worker's messages and the engine's events change the app: the
//! opened run, each step as it starts, iterates and ends (the curve grows,
//! the results, matrix and summary are the engine's), mask statistics and
//! element views, evaluations, previews, queued switches, failures.

use super::app::{App, Live};
use super::next_task::Preview;
use super::worker::WorkerMsg;
use crate::cl::TaskSpec;
use crate::engine::{Event, StepRecord, TaskCurve};

impl App {
    pub(super) fn on_worker(&mut self, msg: WorkerMsg) {
        match msg {
            WorkerMsg::Opened(o) => {
                self.report = Some(o.report.clone());
                self.summary = Some(o.summary.clone());
                let first_pending = o.base_tasks.len() + o.results.steps.len();
                self.next.reset(&o, o.results.steps.len());
                self.next.queued = o.queued.clone();
                self.next.transfer = o.queued_transfer.clone();
                self.opened = Some(*o);
                // The last learned step: its curves and masks are the first thing to look at.
                self.cursor = first_pending.saturating_sub(1);
                self.follow_selection();
                self.refresh_preview();
            }
            WorkerMsg::Event(e) => self.on_event(*e),
            WorkerMsg::Failed(e) => {
                self.say(format!("failed: {e}"));
                self.failure = Some(e);
                self.stopped = true;
            }
            WorkerMsg::Exited => self.stopped = true,
            WorkerMsg::Robot { task, frame } if self.robot.task.as_ref() == Some(&task) => {
                self.robot.frame = Some(*frame);
            }
            WorkerMsg::Robot { .. } => {}
            WorkerMsg::RobotPicture { task, picture } if self.robot.task.as_ref() == Some(&task) => {
                self.robot.picture = Some(*picture);
            }
            WorkerMsg::RobotPicture { .. } => {}
            WorkerMsg::Recorded { message, .. } => self.say(message),
            WorkerMsg::RobotFailed { task, error } => {
                self.robot.error = Some(error.clone());
                self.say(format!("robot view of {task}: {error}"));
            }
        }
    }

    fn on_event(&mut self, e: Event) {
        match e {
            Event::TaskStarted { step, task, name, iterations, switches, related, repeat } => {
                let record = StepRecord {
                    step,
                    task,
                    name: name.clone(),
                    iterations,
                    switches,
                    soft_scores: None,
                    related,
                    repeat,
                    capacity: None,
                };
                let curve = TaskCurve { step, task, name, ..Default::default() };
                self.live =
                    Some(Live { record, iteration: 0, curve, arrivals: Vec::new(), sps: None, physics_resets: 0 });
                self.next.task_started();
                if let Some(o) = &self.opened {
                    self.next.reset(o, step + 1);
                    // Follow the step that trains: its live curve and masks.
                    self.cursor = o.base_tasks.len() + step;
                }
                self.follow_selection();
            }
            Event::Iteration { iteration, metrics, .. } => {
                let now = self.now();
                if let Some(l) = &mut self.live {
                    l.iteration = iteration;
                    l.curve.push(&metrics);
                    l.sps = metrics.get(crate::rl::metric_names::SPS).copied().or(l.sps);
                    l.physics_resets += metrics.get(crate::rl::metric_names::PHYSICS_RESETS).map_or(0, |&r| r as usize);
                    l.arrivals.push(now);
                    if l.arrivals.len() > 10 {
                        l.arrivals.remove(0);
                    }
                }
            }
            Event::MaskStats { report, .. } => self.report = Some(report),
            Event::Measures { after_step, eval_matrix, summary } => {
                let live = self.live.take();
                if let Some(o) = &mut self.opened {
                    if let Some(l) = live.filter(|l| l.record.step == after_step) {
                        o.results.steps.push(l.record);
                        o.results.curves.push(l.curve);
                    }
                    o.results.eval_matrix = eval_matrix;
                    if let Some(s) = o.results.steps.last() {
                        o.last_checkpoint = Some(crate::engine::RunDir::new(&o.run_dir).checkpoint(s.step, &s.name));
                    }
                    let next = o.results.steps.len();
                    self.next.reset(o, next);
                }
                self.summary = Some(summary);
                self.refresh_preview();
            }
            Event::Evaluated { evaluation, .. } => {
                if let Some(o) = &mut self.opened {
                    if o.results.evaluations.len() < o.results.steps.len() + 1 {
                        o.results.evaluations.push(Vec::new());
                    }
                    if let Some(row) = o.results.evaluations.last_mut() {
                        row.push(evaluation);
                    }
                }
            }
            Event::MaskViews { task, iteration, layers } => self.views = Some((task, iteration, layers)),
            Event::EvaluatedNow { evaluation } => {
                self.say(format!(
                    "{}: performance {:.3}, return {:.2}, lin_vel_err {:.3}, fall rate {:.2}",
                    evaluation.report.task,
                    evaluation.performance,
                    evaluation.report.mean_return,
                    evaluation.report.lin_vel_err,
                    evaluation.report.fall_rate
                ));
                self.last_eval = Some(evaluation);
            }
            Event::TransferPreview { step, related, init, lifted_from, repeat, layers } => {
                self.next.preview = Some(Preview { step, related, init, lifted_from, repeat, layers });
            }
            Event::TaskAppended { spec, .. } => self.append(spec),
            Event::SwitchesQueued { overrides } => self.next.queued = self.next.queued.merged(&overrides),
            Event::TransferQueued { related, init } => {
                self.next.transfer = Some((related, init));
                self.refresh_preview();
            }
            Event::CommandRejected { error, .. } => {
                self.next.input_error = self.next.input.is_some().then(|| error.clone());
                self.say(format!("rejected: {error}"));
            }
            Event::Failed { error } => {
                self.say(format!("training failed: {error}"));
                self.failure = Some(error);
            }
            Event::Paused { .. } => self.paused = true,
            Event::Resumed { .. } => self.paused = false,
            Event::Stopped { .. } => self.stopped = true,
            Event::SequenceFinished { steps } => self.say(format!("the sequence is done ({steps} steps)")),
            Event::TaskEnded { .. } => {}
        }
    }

    fn append(&mut self, spec: TaskSpec) {
        self.next.input = None;
        self.next.input_error = None;
        self.say(format!("added {} at the end of the sequence", spec.name));
        if let Some(o) = &mut self.opened {
            if !o.results.tasks.contains(&spec.name) {
                o.results.tasks.push(spec.name.clone());
                o.results.eval_matrix.tasks.push(spec.name.clone());
                o.results.eval_matrix.rows.iter_mut().for_each(|r| r.push(None));
            }
            o.sequence.tasks.push(spec);
        }
        // With every earlier step learned, the added one is the next: its controls now act on it.
        if let Some(o) = &self.opened {
            let next = o.results.steps.len() + usize::from(self.live.is_some());
            self.next.reset(o, next);
        }
        self.refresh_preview();
    }
}
