//! Continual learning around the learner: the method's hooks and its
//! ablation switches, task sequences, the continual measures (Continual
//! World conventions, METHOD.md section 4).
//!
//! - `method`: [`ContinualMethod`], hooks around one training loop, and the method by name;
//! - `ours`: the paper's method and its [`Switches`];
//! - `sequence`: a [`Sequence`] of tasks as written in a run file;
//! - `metrics`: the evaluation matrix [`EvalMatrix`] and the measures on it.

mod method;
mod metrics;
mod ours;
mod sequence;

pub use method::{method_by_name, ContinualMethod};
pub use metrics::{curve_auc, forward_transfer, EvalMatrix};
pub use ours::{LambdaMode, Ours, SwitchOverrides, Switches};
pub use sequence::{KnownBefore, Sequence, TaskSpec, TransferInit};
