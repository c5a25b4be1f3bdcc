//! Settings of the masked networks (METHOD.md section 2): network sizes and
//! activation per network, and the mask settings of the method.

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

/// How a layer's mask is chosen from the soft scores (METHOD.md 2.1 and its ablation variants).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SelectionRule {
    /// Per row: round(lambda*k) from vacant elements, the rest from occupied ones, filled from the other group when one runs short.
    #[default]
    Split,
    /// Per row: one top-k over vacant and occupied together (WSN-like).
    Free,
    /// Per row: top-k over vacant elements only (fewer if there are not enough).
    Vacant,
    /// One top-k over the whole layer (WSN's original rule).
    PerLayer,
    /// PackNet (set by the method `packnet`): every vacant and occupied element, the vacant
    /// ones pruned by magnitude to `packnet_keep` at `packnet_prune_at` or the task's end.
    #[serde(rename = "packnet")]
    PackNet,
    /// Piggyback (set by the method `piggyback`): the occupied elements whose real-valued
    /// score exceeds `piggyback_threshold`; no weight trains.
    Piggyback,
}

impl SelectionRule {
    /// Whether the rule belongs to a mask baseline, set by its method rather than a run's [net.mask].
    pub fn is_baseline(&self) -> bool {
        matches!(self, Self::PackNet | Self::Piggyback)
    }
}

/// Where a new task's per-task bias starts (METHOD.md 2.6; the paper does not say).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum BiasStart {
    /// The mean of the related tasks' biases (zero without any, e.g. in `scratch` mode).
    #[default]
    Related,
    /// Zero for every task, whatever its related tasks: every transfer mode starts alike.
    Zero,
}

/// What the soft-score sigma is measured in (METHOD.md 2.3; the scale is ours, the paper gives none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SigmaScale {
    /// Score units: S = mu + sigma * eps. With the score means spread 0.3 a sigma of 0.005-0.05
    /// moves almost no element across the top-k cut (the runs before issue 13 used this).
    Absolute,
    /// Units of the score spread at each row's top-k cut: S = mu + sigma * g_row * eps, where
    /// g_row is half the distance between the scores ranked k - w and k + w + 1 among the row's
    /// selectable elements (w = max(1, round(k / 10)); the whole layer for `per-layer`), taken
    /// from mu at every iteration. Where the row's selection is one top-k over its selectable
    /// elements (a first task, `free`, `per-layer`), a score at the cut moves about w ranks per
    /// standard deviation at sigma 1, whatever the scores' spread, so the entropy term changes the
    /// selection. Under `split` the rule cuts the vacant and the occupied groups apart, at their
    /// own quotas, where ranks lie sparser than in the pooled row: at c 0.2, lambda 0.25 with the
    /// base occupying 0.2 of a row and alike spread scores, a score at a group's cut moves about
    /// w/3 (vacant) to w/4 (occupied) ranks per sigma. (A gap per group is the refinement; the
    /// shipped paper-regime runs used this one.)
    #[default]
    ScoreGap,
}

/// Which distribution the plasticity entropy term of the first E iterations acts on (METHOD.md
/// 2.3 says the soft scores; the paper's Figure 8 caption says "of the action").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EntropyTarget {
    /// -beta_H * H(soft scores), H = sum 0.5 ln(2 pi e sigma^2): widens sigma, so the sampled
    /// masks explore which weights to use.
    #[default]
    SoftScores,
    /// -beta_H * H(action distribution), added to PPO's own entropy bonus for the first E
    /// iterations of each new task (the toy learner has no action distribution: no term).
    /// H(action) has one term per action dimension, not one per weight: beta_H needs to be
    /// about 1e-2 here where 1e-4 acts on the soft scores.
    Action,
}

/// The masked-layer settings of the method (METHOD.md 2.1 to 2.6).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MaskConfig {
    /// Capacity ratio c: the fraction of each row (or layer, for `per-layer`) a task selects.
    pub capacity: f64,
    /// Vacant share lambda: the fraction of a row's selection taken from vacant elements.
    pub vacant_share: f64,
    /// Private share p: the fraction of the layer's elements made private to a task at its end.
    pub private_share: f64,
    /// Selection rule: "split" (the method), "free", "vacant" or "per-layer".
    pub rule: SelectionRule,
    /// Standard deviation of the initial soft-score means (Gaussian around 0). Adam moves every
    /// mean by about the learning rate per step, so the spread sets how fast the means' drift
    /// changes the hard mask; in score units (`sigma_scale = "absolute"`) it also sets what the
    /// noise does: there, at 0.01 a PPO run redrew 37 % of its selected weights every iteration
    /// (`charts/mask_churn_actor`), at 0.3 about 2-3 %. Under `score_gap` the noise scales with
    /// the spread and only the drift depends on it.
    pub score_init_std: f64,
    /// What sigma, sigma_init, sigma_floor and sigma_max are measured in: `score_gap` (the
    /// scores' spread at each row's top-k cut) or `absolute` (score units). Set the three sigma
    /// values with it: the defaults (0.5, 1e-3, 4) are in score-gap units, and in score units a
    /// sigma of 0.5 against means spread 0.3 draws nearly random masks.
    pub sigma_scale: SigmaScale,
    /// Initial soft-score sigma (one per layer) at the start of every task, in `sigma_scale`
    /// units (the layer trains ln sigma, so sigma stays > 0 whatever the optimiser does).
    pub sigma_init: f64,
    /// Adam's learning rate for ln sigma, fixed (the paper: Adam 1e-3 for the soft networks);
    /// 0: the PPO optimiser's rate, which the KL adaptation drives (about 2e-4 in the base run).
    /// Adam moves ln sigma by about its rate per step whatever beta_H is, so this rate and E
    /// decide how far the entropy term widens sigma.
    pub sigma_learning_rate: f64,
    /// Whether the entropy term -beta_H * H is used (METHOD.md 2.3).
    pub entropy: bool,
    /// What the entropy term acts on: `soft_scores` (METHOD.md 2.3) or `action` (Figure 8's caption).
    pub entropy_target: EntropyTarget,
    /// beta_H, the weight of the entropy term.
    pub entropy_weight: f64,
    /// E: the number of iterations of each task during which the entropy term is on.
    pub entropy_iterations: usize,
    /// Multiplicative decay of sigma per iteration after E iterations (ln(decay) added to ln sigma).
    pub sigma_decay: f64,
    /// Lower bound of sigma (sigma units; applied to ln sigma as ln of it).
    pub sigma_floor: f64,
    /// Upper bound of sigma (sigma units; applied to ln sigma as ln of it): Adam moves the one
    /// ln sigma per layer by about the learning rate per step whatever beta_H is, so sigma grows
    /// by a factor of about exp(lr) per step and without a bound the entropy term would drown the
    /// scores' ranking.
    pub sigma_max: f64,
    /// Re-initialise vacant weights and redraw soft-score means at the end of each task (METHOD.md 2.4).
    pub reinit: bool,
    /// The range of re-initialised vacant weights as a fraction of the initialiser's (1 = METHOD.md
    /// 2.4 as written). Below 1, a later task that selects all of a related task's elements plus
    /// fresh vacant ones starts close to the related task's function: at 1 the fresh elements
    /// (a quarter of a row's selection at lambda 0.25) add noise of about a third of the layer's
    /// output variance, and the new task's first policy does not walk. Acts at the end of a task.
    pub reinit_scale: f64,
    /// Forward-transfer bonus on related tasks' elements, in units of `score_init_std` (METHOD.md 2.6).
    pub transfer_bonus: f64,
    /// PackNet: the share of a task's fresh (vacant) weights kept, by magnitude, when it is pruned;
    /// the others are zeroed and stay vacant for later tasks.
    pub packnet_keep: f64,
    /// PackNet: the task's iteration from which its fresh weights are pruned (the rest of the task
    /// retrains the kept ones); none prunes at the task's end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub packnet_prune_at: Option<usize>,
    /// Piggyback: a mask element is on where its real-valued score exceeds this.
    pub piggyback_threshold: f64,
    /// Piggyback: every score's value when a task starts.
    pub piggyback_init: f64,
    /// Whether the soft scores of occupied elements train too (one reading of METHOD.md 2.2's
    /// straight-through gradient); off: only vacant elements' scores move, occupied ones keep
    /// the ranking the task started with (its transfer bonus included).
    pub score_grad_occupied: bool,
    /// Where a new task's bias starts: `related` (the related tasks' mean) or `zero`.
    pub bias_start: BiasStart,
}

impl Default for MaskConfig {
    fn default() -> Self {
        Self {
            capacity: 0.2,
            vacant_share: 0.25,
            private_share: 0.02,
            rule: SelectionRule::Split,
            score_init_std: 0.3,
            sigma_scale: SigmaScale::ScoreGap,
            sigma_init: 0.5,
            sigma_learning_rate: 1e-3,
            entropy: true,
            entropy_target: EntropyTarget::SoftScores,
            entropy_weight: 1e-4,
            entropy_iterations: 100,
            sigma_decay: 0.99,
            sigma_floor: 1e-3,
            sigma_max: 4.0,
            reinit: true,
            reinit_scale: 1.0,
            transfer_bonus: 3.0,
            packnet_keep: 0.5,
            packnet_prune_at: None,
            piggyback_threshold: 5e-3,
            piggyback_init: 1e-2,
            score_grad_occupied: true,
            bias_start: BiasStart::Related,
        }
    }
}

impl MaskConfig {
    /// These settings with `other`'s end-of-task ones (`private_share`, `reinit`,
    /// `reinit_scale`): the ones that act only when a task ends (METHOD.md 2.4), so
    /// they may change while a task is in progress.
    pub fn with_end_of_task(&self, other: &MaskConfig) -> MaskConfig {
        MaskConfig {
            private_share: other.private_share,
            reinit: other.reinit,
            reinit_scale: other.reinit_scale,
            ..self.clone()
        }
    }

    /// Fills in what a saved mask configuration from before issue 13 left out: such a file ran
    /// with sigma in score units and ln sigma at the PPO optimiser's rate, so a `mask` object
    /// without `sigma_scale` gets `"absolute"` (and `sigma_learning_rate` 0 when missing) instead
    /// of today's defaults. For checkpoints and manifests, which record a run; a run file a user
    /// writes takes the defaults. Anything but a JSON object is left as it is.
    pub fn fill_in_pre_issue_13(mask: &mut serde_json::Value) {
        if let Some(m) = mask.as_object_mut() {
            if !m.contains_key("sigma_scale") {
                m.insert("sigma_scale".into(), "absolute".into());
                m.entry("sigma_learning_rate").or_insert(0.0.into());
            }
        }
    }

    /// Checks the ranges of every field; the error names the key and the expected range.
    pub fn validate(&self) -> anyhow::Result<()> {
        let in_unit = |name: &str, v: f64| -> anyhow::Result<()> {
            anyhow::ensure!((0.0..=1.0).contains(&v), "net.mask.{name} = {v}: expected a value in [0, 1]");
            Ok(())
        };
        in_unit("capacity", self.capacity)?;
        in_unit("vacant_share", self.vacant_share)?;
        in_unit("private_share", self.private_share)?;
        in_unit("sigma_decay", self.sigma_decay)?;
        in_unit("reinit_scale", self.reinit_scale)?;
        in_unit("packnet_keep", self.packnet_keep)?;
        anyhow::ensure!(
            self.piggyback_threshold.is_finite() && self.piggyback_init.is_finite(),
            "net.mask.piggyback_threshold and piggyback_init must be finite"
        );
        anyhow::ensure!(self.score_init_std > 0.0, "net.mask.score_init_std must be > 0");
        anyhow::ensure!(
            self.sigma_init >= 0.0 && self.sigma_floor >= 0.0,
            "net.mask.sigma_init and sigma_floor must be >= 0"
        );
        anyhow::ensure!(
            self.sigma_max >= self.sigma_floor,
            "net.mask.sigma_max ({}) must be >= sigma_floor ({})",
            self.sigma_max,
            self.sigma_floor
        );
        anyhow::ensure!(
            self.sigma_learning_rate.is_finite() && (0.0..=1.0).contains(&self.sigma_learning_rate),
            "net.mask.sigma_learning_rate = {}: expected a value in [0, 1] (0: the PPO optimiser's rate)",
            self.sigma_learning_rate
        );
        anyhow::ensure!(
            self.entropy_weight.is_finite() && self.entropy_weight >= 0.0,
            "net.mask.entropy_weight = {}: expected a finite value >= 0",
            self.entropy_weight
        );
        anyhow::ensure!(
            self.transfer_bonus.is_finite(),
            "net.mask.transfer_bonus = {}: expected a finite value",
            self.transfer_bonus
        );
        anyhow::ensure!(
            self.score_init_std.is_finite() && self.sigma_max.is_finite(),
            "net.mask.score_init_std and sigma_max must be finite"
        );
        Ok(())
    }
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
        if let Some(w) = self.hidden.iter().find(|&&w| w == 0 || w > MAX_WIDTH) {
            anyhow::bail!("net.{name}.hidden = {:?}: the width {w} is not in 1..={MAX_WIDTH}", self.hidden);
        }
        let weights: usize = self.hidden.windows(2).map(|p| p[0] * p[1]).sum();
        anyhow::ensure!(
            weights <= MAX_HIDDEN_WEIGHTS,
            "net.{name}.hidden = {:?} has {weights} hidden weights: at most {MAX_HIDDEN_WEIGHTS} (about 40 bytes each)",
            self.hidden
        );
        Ok(())
    }
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
        self.mask.validate()
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

    #[test]
    fn a_saved_mask_without_a_sigma_scale_is_read_as_it_ran_in_score_units() {
        let mut old = serde_json::json!({ "capacity": 0.2, "sigma_init": 0.005, "sigma_max": 0.05 });
        MaskConfig::fill_in_pre_issue_13(&mut old);
        let m: MaskConfig = serde_json::from_value(old).unwrap();
        assert_eq!((m.sigma_scale, m.sigma_learning_rate, m.sigma_init), (SigmaScale::Absolute, 0.0, 0.005));
        // A mask that names its scale keeps everything it says.
        let mut new = serde_json::json!({ "sigma_scale": "score_gap", "sigma_learning_rate": 0.002 });
        MaskConfig::fill_in_pre_issue_13(&mut new);
        let m: MaskConfig = serde_json::from_value(new).unwrap();
        assert_eq!((m.sigma_scale, m.sigma_learning_rate), (SigmaScale::ScoreGap, 0.002));
    }

    #[test]
    fn non_finite_mask_settings_are_errors_naming_the_key() {
        assert!(MaskConfig::default().validate().is_ok());
        for (key, cfg) in [
            ("entropy_weight", MaskConfig { entropy_weight: f64::NAN, ..MaskConfig::default() }),
            ("transfer_bonus", MaskConfig { transfer_bonus: f64::INFINITY, ..MaskConfig::default() }),
            ("score_init_std", MaskConfig { score_init_std: f64::INFINITY, ..MaskConfig::default() }),
            ("reinit_scale", MaskConfig { reinit_scale: 1.5, ..MaskConfig::default() }),
            ("sigma_learning_rate", MaskConfig { sigma_learning_rate: -1e-3, ..MaskConfig::default() }),
            ("sigma_learning_rate", MaskConfig { sigma_learning_rate: f64::NAN, ..MaskConfig::default() }),
        ] {
            let err = cfg.validate().unwrap_err().to_string();
            assert!(err.contains(key), "{key}: {err}");
        }
    }
}
