//! Continual learning around the learner: the method and its ablation
//! switches, task sequences, the continual measures (Continual World
//! conventions, METHOD.md section 4).

pub mod method;
pub mod metrics;
pub mod ours;
pub mod sequence;

pub use method::{method_by_name, ContinualMethod};
pub use ours::{LambdaMode, Ours, SwitchOverrides, Switches};
pub use sequence::{Sequence, TaskSpec, TransferInit};
