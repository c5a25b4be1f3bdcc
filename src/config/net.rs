//! Settings of the masked networks (METHOD.md section 2): network sizes and
//! activation per network, and the mask settings of the method (in [`super::mask`],
//! re-exported here).

pub use super::mask::{
    row_quota, BiasStart, EntropyTarget, MaskConfig, ReinitRange, ScoreReinit, SelectionRule, SigmaScale,
};
use serde::{Deserialize, Serialize};

/// The activation between hidden layers of a [`crate::nn::MaskedMlp`]
/// (the output layer is always linear).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// ELU with alpha = 1 (rsl_rl's and legged_gym's choice, and the shipped policies'; the
    /// paper says ReLU: `activation = "relu"` for its reading).
    #[default]
    Elu,
    /// max(x, 0).
    Relu,
    /// tanh(x).
    Tanh,
    /// No activation.
    Identity,
}

/// Which kind of network a method trains.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NetworkKind {
    /// Masked layers over shared weights (METHOD.md 2).
    #[default]
    Masked,
    /// A dense trunk shared by all tasks, one output head per task (METHOD.md 3).
    Dense,
}

impl NetworkKind {
    /// Whether it is the default (masked): `[net] kind` is then left out of saved configs.
    pub fn is_masked(&self) -> bool {
        *self == Self::Masked
    }
}

/// The widest layer a network may have.
pub const MAX_WIDTH: usize = 65_536;
/// The most weights the hidden layers of one network may have (products of
/// consecutive widths): each weight carries a mask, soft scores, a gradient
/// and Adam's moments, about 40 bytes, so this is about 1.3 GB.
pub const MAX_HIDDEN_WEIGHTS: usize = 1 << 25;

/// Sizes and activation of one network.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MlpConfig {
    /// Hidden layer widths, input to output.
    pub hidden: Vec<usize>,
    /// Activation between hidden layers.
    pub activation: Activation,
}

impl Default for MlpConfig {
    fn default() -> Self {
        Self::elu(&[512, 256, 128])
    }
}

impl MlpConfig {
    /// `hidden` with ELU (see [`Activation::Elu`]).
    fn elu(hidden: &[usize]) -> Self {
        Self { hidden: hidden.to_vec(), activation: Activation::Elu }
    }

    /// Checks the widths; `name` is the table (`actor`, ...) for the message.
    pub fn validate(&self, name: &str) -> anyhow::Result<()> {
        anyhow::ensure!(!self.hidden.is_empty(), "net.{name}.hidden is empty: give at least one hidden layer");
        check_widths(&format!("net.{name}.hidden"), &self.hidden)
    }
}

/// Checks hidden widths (`key` names them): each in 1..=[`MAX_WIDTH`], and at most
/// [`MAX_HIDDEN_WEIGHTS`] weights between them. For `[net]`'s networks and the CENet decoder.
pub fn check_widths(key: &str, hidden: &[usize]) -> anyhow::Result<()> {
    if let Some(w) = hidden.iter().find(|&&w| w == 0 || w > MAX_WIDTH) {
        anyhow::bail!("{key} = {hidden:?}: the width {w} is not in 1..={MAX_WIDTH}");
    }
    let weights: usize = hidden.windows(2).map(|p| p[0] * p[1]).sum();
    anyhow::ensure!(
        weights <= MAX_HIDDEN_WEIGHTS,
        "{key} = {hidden:?} has {weights} hidden weights: at most {MAX_HIDDEN_WEIGHTS} (about 40 bytes each)"
    );
    Ok(())
}

/// Network sizes and the masked-network settings of the method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NetConfig {
    /// The actor (policy mean): 512-256-128 (the paper's sizes), ELU (the paper says ReLU).
    pub actor: MlpConfig,
    /// The critic (privileged value function).
    pub critic: MlpConfig,
    /// The context estimator's encoder (CENet): [256, 128] (DreamWaQ's encoder and the shipped
    /// policies'; the paper says two hidden layers of 256: `hidden = [256, 256]`).
    pub cenet: MlpConfig,
    /// Mask settings shared by every masked network.
    pub mask: MaskConfig,
    /// `masked` (the method) or `dense` (a shared trunk, one head per task: the baselines'
    /// network, and `quadcl train`'s like-for-like PPO). In a run file the method decides.
    #[serde(skip_serializing_if = "NetworkKind::is_masked")]
    pub kind: NetworkKind,
}

impl NetConfig {
    /// Checks every network's widths and the mask settings; errors name the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.actor.validate("actor")?;
        self.critic.validate("critic")?;
        self.cenet.validate("cenet")?;
        anyhow::ensure!(
            !self.mask.rule.is_baseline(),
            "net.mask.rule = {:?}: the methods packnet and piggyback set it themselves; choose them with [method] name",
            self.mask.rule
        );
        self.mask.validate()?;
        self.check_selects(&self.mask)
    }

    /// Checks that `mask` selects something in every layer whose size `[net]` gives (each
    /// network's hidden layers and the fan-in of its output layer); the input layers, sized by
    /// the robot, are checked when the networks are built.
    pub fn check_selects(&self, mask: &MaskConfig) -> anyhow::Result<()> {
        for (name, mlp) in [("actor", &self.actor), ("critic", &self.critic), ("cenet", &self.cenet)] {
            let h = &mlp.hidden;
            for (i, w) in h.windows(2).enumerate() {
                mask.check_selects_in(&format!("net.{name} layer l{}", i + 1), w[1], w[0])?;
            }
            // The output layer has at least one row; under `per-layer` its size is the robot's.
            if let (Some(&last), false) = (h.last(), mask.rule == SelectionRule::PerLayer) {
                mask.check_selects_in(&format!("net.{name} layer l{} (output)", h.len()), 1, last)?;
            }
        }
        Ok(())
    }
}

impl Default for NetConfig {
    fn default() -> Self {
        Self {
            actor: MlpConfig::elu(&[512, 256, 128]),
            critic: MlpConfig::elu(&[512, 256, 128]),
            cenet: MlpConfig::elu(&[256, 128]),
            mask: MaskConfig::default(),
            kind: NetworkKind::Masked,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_that_are_zero_or_cannot_fit_in_memory_are_errors_naming_the_network() {
        NetConfig::default().validate().unwrap();
        for (hidden, expect) in [
            (vec![0, 32], "net.critic.hidden = [0, 32]"),
            (vec![], "net.critic.hidden is empty"),
            (vec![1 << 20], "not in 1..=65536"),
            (vec![60_000, 60_000], "hidden weights: at most"),
        ] {
            let cfg = NetConfig { critic: MlpConfig::elu(&hidden), ..NetConfig::default() };
            let err = cfg.validate().unwrap_err().to_string();
            assert!(err.contains(expect), "{hidden:?}: {err}");
        }
    }
}
