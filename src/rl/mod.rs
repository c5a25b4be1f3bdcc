//! The learner: PPO with a privileged critic and a context estimator
//! (DreamWaQ's CENet).
//!
//! | file | what |
//! | --- | --- |
//! | `ppo` | the PPO learner: rollout collection and the update, top to bottom |
//! | `acting_settings` | the settings a policy acts under, which a base policy must share with its sequence |
//! | `agent` | actor, critic, CENet encoder/decoder, policy std, observation statistics |
//! | `rollout` | the rollout buffer of one iteration, GAE with time-out bootstrapping |
//! | `update_hooks` | [`UpdateHooks`]: how a continual-learning method reaches into the update |
//! | `rollout_sample` | the last rollout as the sample a method probes the ending task's policy with |
//! | `normalizer` | running observation statistics, frozen when a task ends |
//! | `losses` | the PPO loss pieces (Gaussian log-prob/entropy, clipped surrogate, value loss, KL, adaptive lr) |
//! | `cenet_loss` | the CENet's output split, reparameterisation and beta-VAE loss |
//! | `trainer` | one task's training run: `metrics.jsonl`, checkpoints, policy directory |
//! | `training_state` | what a checkpoint keeps beyond the policy so that a resume is exact (Adam, streams, envs) |
//! | `metrics` | the [`Metrics`] of an iteration and the metric names every loop shares |
//! | `plasticity` | plasticity diagnostics per iteration: dormant units, effective rank, selected weights |
//! | `metrics_log` | `metrics.jsonl`, a row appended per iteration, cut to the checkpoint on resume |
//! | `progress` | what every training loop shares in reporting: the bar, the iteration line, the step and time counters |
//! | `evaluate` | deterministic evaluation, one episode per env: the `quadcl eval` figures |
//! | `gait` | the contact pattern of a policy under one held command |
//! | `robot_view` | watching a policy: one env stepped by its deterministic policy, the robot's pose per step |
//! | `policy_dir` | save/load a trained policy directory (weights, normaliser statistics, manifest) |
//! | `env` | the [`TrainEnv`] trait: what the learner needs from a batch of environments |
//! | `toy_env` | a point-mass [`TrainEnv`] for fast tests of the loop |
//! | `sim_env` | the simulated quadruped (`sim::VecEnv`) as a [`TrainEnv`] |

mod acting;
mod acting_settings;
mod agent;
mod cenet_loss;
mod env;
mod evaluate;
mod external_policy;
mod gait;
mod losses;
mod metrics;
mod metrics_log;
mod normalizer;
mod plasticity;
mod policy_dir;
mod ppo;
mod progress;
mod robot_view;
mod rollout;
mod rollout_sample;
mod sim_env;
#[cfg(test)]
mod test_tensors;
mod toy_env;
mod trainer;
mod training_state;
mod update_hooks;

pub use acting::{ActOutput, ActingWeights};
pub use acting_settings::{acting_settings_differences, ACTING_SETTINGS};
pub use agent::Agent;
pub use env::{EnvDims, EpisodeReplay, EpisodeSummary, TrainEnv, VecStep};
pub use evaluate::{evaluate, evaluate_with, EvalReport};
pub use external_policy::ExternalPolicy;
pub use gait::{record_gait, GaitReport, GaitSummary, HeldCommand};
pub use metrics::{layer_metrics, names as metric_names, Metrics};
pub use normalizer::RunningNormalizer;
pub use plasticity::{dormant_fraction, dormant_units, effective_rank, network_plasticity, subsample_rows};
pub use policy_dir::{
    learned_task_names, load_for_task, load_policy, load_policy_or_checkpoint, load_training_checkpoint, save_policy,
    LoadedPolicy, PolicyInfo, PolicyOrCheckpoint,
};
pub use ppo::{check_physics_resets, PpoLearner};
pub use progress::{iteration_line, iteration_summary, progress_bar, TrainingClock};
pub use robot_view::{RobotFrame, RobotViewer};
pub use sim_env::SimTrainEnv;
pub use toy_env::ToyEnv;
pub use trainer::{load_resume_point, train, train_from, ResumePoint, TrainSummary, TrainerState};
pub use training_state::{TrainingState, TRAINING_STATE_FILE};
pub use update_hooks::{apply_hooks, NoHooks, NoProbe, OutputSample, PolicyProbe, UpdateHooks};
