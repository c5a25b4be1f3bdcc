//! The learner: PPO with a privileged critic and a context estimator
//! (DreamWaQ's CENet), issue 4.
//!
//! | file | what |
//! | --- | --- |
//! | [`ppo`] | the PPO learner: rollout collection and the update, top to bottom |
//! | [`agent`] | actor, critic, CENet encoder/decoder, policy std, observation statistics |
//! | [`rollout`] | the rollout buffer of one iteration, GAE with time-out bootstrapping |
//! | [`normalizer`] | running observation statistics, frozen when a task ends |
//! | [`losses`] | the PPO loss pieces (Gaussian log-prob/entropy, clipped surrogate, value loss, KL, adaptive lr) |
//! | [`cenet_loss`] | the CENet's output split, reparameterisation and beta-VAE loss |
//! | [`trainer`] | one task's training run: progress bar, `metrics.jsonl`, policy directory |
//! | [`evaluate`] | deterministic evaluation, one episode per env: the `quadcl eval` figures |
//! | [`policy_dir`] | save/load a trained policy directory (weights, normaliser statistics, manifest) |
//! | [`env`] | the `TrainEnv` trait: what the learner needs from a batch of environments |
//! | [`toy_env`] | a point-mass `TrainEnv` for fast tests of the loop |
//! | [`sim_env`] | the simulated quadruped (`sim::VecEnv`) as a `TrainEnv` |

pub mod agent;
pub mod cenet_loss;
pub mod env;
pub mod evaluate;
pub mod gait;
pub mod losses;
pub mod normalizer;
pub mod policy_dir;
pub mod ppo;
pub mod rollout;
pub mod sim_env;
#[cfg(test)]
mod test_tensors;
pub mod toy_env;
pub mod trainer;

pub use agent::Agent;
pub use env::{EnvDims, EnvStep, FinishedEpisode, TrainEnv};
pub use evaluate::{evaluate, EvalReport};
pub use normalizer::RunningNormalizer;
pub use policy_dir::{load_policy, save_policy, LoadedPolicy, PolicyInfo};
pub use ppo::{Metrics, PpoLearner};
pub use rollout::{gae, RolloutBuffer, RolloutDims, StepRecord};
pub use trainer::{train, TrainSummary};
