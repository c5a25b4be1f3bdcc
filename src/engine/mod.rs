//! The continual-learning engine: a [`Session`] trains one learner
//! on a sequence of tasks step by step, evaluates every learned task after
//! every task, and tells any number of observers what happens. Headless runs
//! (`quadcl run`) and the workbench are observers; they never compute a metric.
//!
//! | file | what |
//! | --- | --- |
//! | `session` | the engine: step / task / run, pause, next-task switches, evaluation |
//! | `events` | events to observers, commands back |
//! | `learner` | the `Learner` trait the session drives |
//! | `results` | steps, evaluation matrix, curves, summary measures (`metrics.json`) |
//! | `run_config` | a run file: experiment config + method + evaluation + sequence |
//! | `run_dir` | a run's output folder: metrics.json, checkpoints, log, resume |
//! | `runner` | a session bound to its run folder: set-up, restore, writes after each task (`quadcl run`, the workbench) |
//! | `ppo_learner` | the PPO + CENet agent on the quadruped as a `Learner` |
//! | `env_source` | a robot's `[env]` settings by name, URDF or config file (`quadcl robot --config`, the Python package) |
//! | `shift` | a shifted environment (friction, mass, motor strength, latency) for sim-to-real fine-tuning |
//! | `sim2real` | sim-to-real fine-tuning of one learned task (METHOD.md 2.7; `quadcl finetune`) |
//! | `toy_learner` | a tiny masked regression learner for fast tests |

mod env_source;
mod events;
mod learner;
mod ppo_learner;
mod results;
mod run_config;
mod run_dir;
mod runner;
mod session;
mod shift;
mod sim2real;
mod toy_learner;

pub use env_source::{env_of_file, env_of_robot, is_shipped_description, SHIPPED_ROBOTS};
pub use events::{ChannelObserver, Command, CommandSender, Event, EventLog, Observer};
pub use learner::{Evaluation, Learner, TaskStart};
pub use ppo_learner::{make_ppo_learner, max_episode_return, max_reward_rate, PpoTaskLearner};
pub use results::{CommandTracking, SessionResults, SoftScoreSettings, StepRecord, Summary, TaskCurve};
pub use run_config::{BaseVacant, EvalConfig, LearnerKind, RunConfig, RunSection};
pub use run_dir::{
    lock_folder, task_file_name, MetricsFile, RunDir, CHECKPOINTS, CHOSEN_FILE, EPISODES, LOCK_FILE, LOG_FILE,
    METRICS_FILE, RUN_FILE,
};
pub use runner::{make_learner, OpenMode, Runner, VIDEOS};
pub use session::{ChosenSettings, Session, StepOutcome};
pub use shift::{DelayedActions, Shift};
pub use sim2real::{sim2real, Sim2RealReport};
pub use toy_learner::ToyLearner;
