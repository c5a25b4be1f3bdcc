//! quadcl: a terminal workbench for continual reinforcement learning on a
//! simulated quadruped (Gai et al., "Continual Reinforcement Learning for
//! Quadruped Robot Locomotion", Entropy 2024).
//!
//! The map of the crate:
//!
//! | module | what it is for | may import |
//! | --- | --- | --- |
//! | [`config`] | every hyperparameter, with doc comments and defaults, loadable from TOML | serde only |
//! | [`sim`] | the Rapier quadruped: URDF loading, PD motors, `LocomotionEnv`, task perturbations, a parallel batch of envs | `config` |
//! | [`nn`] | masked networks in candle: `MaskedLinear`, `MaskedMlp`, the masked Adam, checkpoints | `config` |
//! | [`rl`] | PPO with a privileged critic and a context estimator (CENet), rollouts, GAE, observation normalisation | `config`, `sim`, `nn` |
//! | [`cl`] | continual learning around the learner: sequences, the continual measures | `config`, `sim`, `nn`, `rl` |
//! | [`engine`] | the continual-learning engine: a `Session` trains a learner on a sequence step by step and emits events | `config`, `nn`, `rl`, `cl` |
//! | [`headless`] | `quadcl run`: a run file to the end with a progress bar, results and checkpoints, resumable | `engine` |
//! | [`bench`] | the throughput figures printed by `quadcl bench` | everything |
//! | [`cmd`] | one file per CLI subcommand, thin glue over the modules above | everything |
//!
//! `sim` never imports `nn`; `nn` never imports `sim`.

pub mod bench;
pub mod cl;
pub mod cli;
pub mod cmd;
pub mod config;
pub mod engine;
pub mod headless;
pub mod nn;
pub mod rl;
pub mod sim;
pub mod util;
