//! Masked networks in candle (METHOD.md section 2): knows nothing of the simulator.
//!
//! - `state`: the life cycle of one weight element (vacant / occupied / private);
//! - `bitmask`: bit-packed per-task masks;
//! - `select`: the selection rules as pure functions;
//! - `masked`: [`MaskedLinear`], where the algorithm lives;
//! - `mlp`: [`MaskedMlp`] (actor, critic, CENet);
//! - `dense`: [`DenseMlp`], a shared dense trunk with one head per task (the non-mask baselines);
//! - `network`: [`Network`], either of the two, as the agent and checkpoints hold them;
//! - `fused`: the whole MLP as one candle custom op (the speed path: gemm on slices, one backward pass);
//! - `product`: the matrix product on slices it runs (gemm);
//! - `activation`: a fused ELU as candle custom ops (layer-by-layer reference path);
//! - `wide`: element-wise loops at the CPU's vector width (AVX-512 or AVX2, chosen at run time);
//! - `optim`: [`MaskedAdam`], which never moves a frozen element;
//! - [`checkpoint`]: policy directories (safetensors + bit-packed masks + manifest);
//! - `stats`: the mask statistics printed by `quadcl masks`;
//! - `element_view`: every element as one task sees it (the TUI's heatmap), the transfer preview;
//! - `plasticity_probe`: what the plasticity diagnostics read (hidden outputs, selected weights).

mod activation;
mod bitmask;
pub mod checkpoint;
mod dense;
mod element_view;
mod fused;
mod manifest_digest;
mod masked;
mod masked_weight;
mod mlp;
mod network;
mod optim;
mod plasticity_probe;
mod product;
mod select;
mod state;
mod stats;
mod wide;

pub use crate::config::net::{
    Activation, BiasStart, EntropyTarget, MaskConfig, NetworkKind, ReinitRange, ScoreReinit, SelectionRule, SigmaScale,
};
pub use bitmask::BitMask;
pub use checkpoint::{load_policy, save_policy, Policy};
pub use dense::{DenseLayer, DenseMlp};
pub use element_view::{mask_views, transfer_lift, ElementView, LayerLift, LayerView, RowShare};
pub use fused::fused_mlp;
pub use masked::{LayerIteration, MaskedLinear};
pub use mlp::{FrozenWeights, MaskedMlp};
pub use network::{AsNetworkRef, IterationNoise, Network, NetworkRef};
pub use optim::{AdamConfig, MaskedAdam, Moments};
pub use plasticity_probe::SelectedWeights;
pub use product::MatrixProduct;
pub use select::{row_quota, split_counts, vacant_quota};
pub use state::{ElementState, IllegalTransition, TaskId};
pub use stats::{mask_report, LayerMasks, MaskReport, NetworkMasks, TaskMask};

/// A trainable variable with the elements the optimiser may move this step.
#[derive(Debug, Clone)]
pub struct Param {
    /// Checkpoint key, e.g. "actor.l0.weight".
    pub name: String,
    /// The variable.
    pub var: candle_core::Var,
    /// Same shape as `var`, 1.0 where the element may move; None = every element.
    pub update_mask: Option<candle_core::Tensor>,
    /// Adam's learning rate for this variable, fixed: the optimiser's own rate (its schedule,
    /// the KL adaptation) does not apply. None: the optimiser's rate.
    pub fixed_learning_rate: Option<f64>,
}

impl Param {
    /// A variable every element of which moves at the optimiser's rate.
    pub fn free(name: impl Into<String>, var: &candle_core::Var) -> Self {
        Self { name: name.into(), var: var.clone(), update_mask: None, fixed_learning_rate: None }
    }
}
