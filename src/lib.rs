//! quadcl: a terminal workbench for continual reinforcement learning on a
//! simulated quadruped (Gai et al., "Continual Reinforcement Learning for
//! Quadruped Robot Locomotion", Entropy 2024).
//!
//! The map of the crate, lowest layer first. A module may import only the
//! layers its row names (`tests/layering.rs` checks the code against this table):
//!
//! | module | what it is for | may import |
//! | --- | --- | --- |
//! | [`util`] | atomic writes, content hashes, every random stream's seed | nothing of the crate |
//! | [`config`] | every hyperparameter, with doc comments and defaults, loadable from TOML | nothing of the crate |
//! | [`log`] | training curves for other tools: TensorBoard event files and a CSV of scalars | `util` |
//! | [`sim`] | the Rapier quadruped: URDF loading, PD motors, `LocomotionEnv`, task perturbations, a parallel batch of envs | `config`, `util` |
//! | [`nn`] | masked networks in candle: `MaskedLinear`, `MaskedMlp`, the masked Adam, checkpoints, mask statistics | `config`, `util` |
//! | [`rl`] | PPO with a privileged critic and a context estimator (CENet), rollouts, GAE, normalisation, evaluation, policy directories, metric names and progress | `config`, `util`, `sim`, `nn`, `log` |
//! | [`export`] | a learned task as plain dense networks for deployment: ONNX and PyTorch-named safetensors with the robot's contract as metadata | `config`, `util`, `sim`, `nn`, `rl` |
//! | [`cl`] | continual learning around the learner: the method's hooks and switches, sequences, the continual measures | `config`, `util`, `sim`, `nn`, `rl` |
//! | [`engine`] | a `Session` trains a learner on a sequence step by step and emits events; the PPO and toy learners, run files and folders, sim-to-real fine-tuning | `config`, `util`, `sim`, `nn`, `rl`, `cl`, `record`, `log` |
//! | [`plot`] | figures of runs as PNG and SVG (`quadcl plot`): training curves, the whole sequence, the evaluation matrix, plasticity; a sweep folder as its groups across seeds | `util`, `cl`, `sweep`, `render` |
//! | [`headless`] | `quadcl run`: a run file to the end with a progress bar, results and checkpoints, resumable | `util`, `rl`, `cl`, `engine`, `record`, `log` |
//! | [`render`] | pictures without a GPU: a ray-cast frame of a `LocomotionEnv` from a tracking camera, text on frames, PNG, MP4 through ffmpeg; the one font | `util`, `sim` |
//! | [`record`] | recorders of simulation steps: episodes as MCAP for Foxglove and as Rerun `.rrd` or a live Rerun viewer (`quadcl record`, `quadcl view`) | `util`, `config`, `sim`, `nn`, `rl`, `render` |
//! | [`sweep`] | grids of runs: a sweep file planned into cells, run here (child processes) or as a Slurm array job, status, collected with bootstrap intervals over seeds | `util`, `engine` |
//! | [`tui`] | the workbench: ratatui app state, panels, input, the session's worker thread, the Sweep screen | `util`, `config`, `sim`, `nn`, `rl`, `cl`, `engine`, `record`, `render`, `sweep` |
//!
//! Two Cargo features, both on by default, build the parts a library user may not
//! want: `workbench` (the [`tui`] module, ratatui) and `rerun` (the Rerun recorders
//! of [`record`]). The binary needs both; the Python package (`python/`) builds
//! with neither.
//!
//! `engine` imports `sim` for what only a simulator-backed learner needs (the
//! task perturbations it trains on, the shifted environments of sim-to-real
//! fine-tuning). `sim` never imports `nn`; `nn` never imports `sim`.
//!
//! The binary `quadcl` (`src/main.rs`) adds, outside this library:
//!
//! | module | what it is for | may import |
//! | --- | --- | --- |
//! | `cli` | the clap command line and its dispatch | `cmd` (and the library) |
//! | `cmd` | one file per subcommand, thin glue over the library | `bench` (and the library) |
//! | `bench` | the throughput figures printed by `quadcl bench` | the library |

pub mod cl;
pub mod config;
pub mod engine;
pub mod export;
pub mod headless;
pub mod log;
pub mod nn;
pub mod plot;
pub mod record;
pub mod render;
pub mod rl;
pub mod sim;
pub mod sweep;
#[cfg(feature = "workbench")]
pub mod tui;
pub mod util;
