//! The continual-learning engine (issue 5): a [`Session`] trains one learner
//! on a sequence of tasks step by step, evaluates every learned task after
//! every task, and tells any number of observers what happens. Headless runs
//! (`quadcl run`) and, later, the TUI are observers; they never compute a metric.
//!
//! | file | what |
//! | --- | --- |
//! | [`session`] | the engine: step / task / run, pause, next-task switches, evaluation |
//! | [`events`] | events to observers, commands back |
//! | [`learner`] | the `Learner` trait the session drives |
//! | [`results`] | steps, evaluation matrix, curves, summary measures (`metrics.json`) |
//! | [`run_config`] | a run file: experiment config + method + evaluation + sequence |
//! | [`run_dir`] | a run's output folder: metrics.json, checkpoints, log, resume |
//! | [`ppo_learner`] | the PPO + CENet agent on the quadruped as a `Learner` |
//! | [`shift`] | a shifted environment (friction, mass, motor strength, latency) for fine-tuning |
//! | [`finetune`] | sim-to-real fine-tuning of one learned task (METHOD.md 2.7) |
//! | [`toy_learner`] | a tiny masked regression learner for fast tests |

pub mod events;
pub mod finetune;
pub mod learner;
pub mod ppo_learner;
pub mod results;
pub mod run_config;
pub mod run_dir;
pub mod session;
pub mod shift;
pub mod toy_learner;

pub use events::{Command, CommandSender, Event, EventLog, Observer};
pub use learner::{Evaluation, Learner, Metrics, TaskStart};
pub use results::{SessionResults, StepRecord, Summary, TaskCurve};
pub use session::{derive_seed, Session, StepOutcome};
