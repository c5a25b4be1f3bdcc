//! Masked networks in candle (METHOD.md section 2): knows nothing of the simulator.
//!
//! - [`state`]: the life cycle of one weight element (vacant / occupied / private);
//! - [`bitmask`]: bit-packed per-task masks;
//! - [`select`]: the selection rules as pure functions;
//! - [`masked`]: [`MaskedLinear`], where the algorithm lives;
//! - [`mlp`]: [`MaskedMlp`] (actor, critic, CENet);
//! - [`activation`]: fused ELU as candle custom ops;
//! - [`optim`]: [`MaskedAdam`], which never moves a frozen element;
//! - [`checkpoint`]: policy directories (safetensors + bit-packed masks + manifest);
//! - [`stats`]: the mask statistics printed by `quadcl masks`.

pub mod activation;
pub mod bitmask;
pub mod checkpoint;
pub mod fused;
pub mod masked;
pub mod mlp;
pub mod optim;
pub mod select;
pub mod state;
pub mod stats;

pub use crate::config::net::{Activation, MaskConfig, SelectionRule};
pub use bitmask::BitMask;
pub use masked::MaskedLinear;
pub use mlp::MaskedMlp;
pub use optim::{AdamConfig, MaskedAdam};
pub use state::{ElementState, TaskId};

/// A trainable variable with the elements the optimiser may move this step.
#[derive(Debug, Clone)]
pub struct Param {
    /// Checkpoint key, e.g. "actor.l0.weight".
    pub name: String,
    /// The variable.
    pub var: candle_core::Var,
    /// Same shape as `var`, 1.0 where the element may move; None = every element.
    pub update_mask: Option<candle_core::Tensor>,
}
