//! Continual learning around the learner: the method's hooks and its
//! ablation switches, task sequences, the continual measures (Continual
//! World conventions, METHOD.md section 4).
//!
//! - `method`: [`ContinualMethod`], hooks around one training loop, and the method by name;
//! - `ours`: the paper's method and its [`Switches`];
//! - `capacity`: how long each layer's vacant elements last at given switches (the Next task panel's forecast);
//! - `wsn`: WSN, `ours` with the per-layer rule and its plasticity mechanisms off;
//! - `packnet`, `piggyback`: the other mask baselines (their rules live in `nn/masked/baselines.rs`);
//! - `finetune`, `ewc`, `si`, `rwalk`, `er`, `agem`: the baselines on the dense network (METHOD.md 3);
//! - `replay`: the rehearsal buffers and behaviour-cloning loss ER and A-GEM share;
//! - `quadratic_penalty`: the anchored penalty EWC and SI share;
//! - `sequence`: a [`Sequence`] of tasks as written in a run file;
//! - `metrics`: the evaluation matrix [`EvalMatrix`] and the measures on it.

mod agem;
mod capacity;
mod er;
mod ewc;
mod finetune;
mod method;
mod metrics;
mod ours;
mod packnet;
mod piggyback;
mod quadratic_penalty;
mod replay;
mod rwalk;
mod sequence;
mod si;
mod wsn;

pub use agem::{project, Agem, AgemHooks};
pub use capacity::{forecast, vacant_taken, LayerForecast};
pub use er::{Er, ErConfig, ErHooks};
pub use ewc::{diagonal_fisher, Ewc, EwcConfig, EwcHooks};
pub use finetune::Finetune;
pub use method::{method_by_name, ContinualMethod, MethodSettings, METHODS};
pub use metrics::{curve_auc, forward_transfer, EvalMatrix};
pub use ours::{LambdaMode, Ours, SwitchOverrides, Switches};
pub use packnet::{PackNet, PackNetConfig};
pub use piggyback::{Piggyback, PiggybackConfig};
pub use quadratic_penalty::{is_regularised, QuadraticPenalty};
pub use replay::{ReplayBuffers, TaskReplay};
pub use rwalk::{Rwalk, RwalkConfig, RwalkHooks};
pub use sequence::{KnownBefore, Sequence, TaskSpec, TransferInit};
pub use si::{Si, SiConfig, SiHooks};
pub use wsn::{Wsn, WSN_SIGMA};
