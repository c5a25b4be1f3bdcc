//! Settings of one task's masks (METHOD.md section 2): how a layer's mask is chosen from the
//! soft scores (capacity c, vacant share lambda, the rule), the soft scores' noise and entropy
//! term (sigma), re-initialisation, forward transfer and the mask baselines' settings. Shared by
//! every masked network (`[net.mask]`); the method's switches change some of them per task.

use super::bounds::{self, Interval, NON_NEGATIVE, POSITIVE, POSITIVE_UNIT, UNIT};
use super::ppo::MAX_ITERATIONS;
use serde::{Deserialize, Serialize};

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

/// Where a new task's per-task bias starts (METHOD.md 2.4 step 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum BiasStart {
    /// The bias of the task that ended last (the last new task to end: the network the new task
    /// continues; zero for the first task): METHOD.md's default, the paper's "further training on the originally learned
    /// network". Every forward-transfer mode starts from it, so only the score bonus differs.
    #[default]
    Previous,
    /// Interpretation: the mean of the related tasks' biases (zero without any, e.g. in `scratch`
    /// mode). The default before issue 31, so a task named related to none started at zero.
    Related,
    /// Interpretation: zero for every task, whatever came before.
    Zero,
}

/// Which soft-score means are redrawn at the end of a task (METHOD.md 2.4 step 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ScoreReinit {
    /// The means of elements still VACANT are redrawn; OCCUPIED ones keep the ranking the tasks
    /// learned, so the next task's occupied quota starts from the top of the previous task's
    /// ranking (the paper's "vacant parameters" reading of its 2.4, and METHOD.md's default).
    #[default]
    Vacant,
    /// Interpretation: every mean is redrawn (the paper's "entire soft network"; before issue 31
    /// the only behaviour): the next task's occupied quota is ranked by fresh noise.
    All,
    /// No mean is redrawn: the next task starts from the previous task's whole ranking.
    None,
}

/// The range re-initialised vacant weights are drawn from (METHOD.md 2.4 step 4), before
/// `reinit_scale`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ReinitRange {
    /// U(-b, b) with b = sqrt(g / F): the layer's own uniform initialiser (g = 6 before an ELU or
    /// ReLU, 3 otherwise, times the layer's init scale) over its full fan-in F, the paper's
    /// "random initialization states". A fresh weight then adds about (lambda / (1 - lambda)) * c
    /// of the selected occupied weights' output variance instead of lambda / (1 - lambda)
    /// (PyTorch's default linear layer draws at 1 / sqrt(F), a further sqrt(g) smaller).
    #[default]
    Initial,
    /// Interpretation: b = sqrt(g / (c F)), He for the effective fan-in of a masked row, the
    /// range of the layer's first weights (before issue 31 the only behaviour): about
    /// 1 / sqrt(c) wider than `initial`, 5.5x PyTorch's default at c 0.2.
    HeEffective,
}

/// The three readings' names as run files spell them (`previous`, `vacant`, `he_effective`, ...).
macro_rules! display_as_in_files {
    ($($ty:ty { $($variant:ident => $text:literal),+ })+) => {$(
        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(match self { $(Self::$variant => $text),+ })
            }
        }
    )+};
}

display_as_in_files! {
    BiasStart { Previous => "previous", Related => "related", Zero => "zero" }
    ScoreReinit { Vacant => "vacant", All => "all", None => "none" }
    ReinitRange { Initial => "initial", HeEffective => "he_effective" }
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
    /// Capacity ratio c: the fraction of each row (or layer, for `per-layer`) a task selects, in
    /// (0, 1]; round(c * fan-in) must be at least 1 in every layer.
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
    /// Adam's learning rate for the soft-score means mu, fixed, apart from the PPO optimiser's
    /// KL-adapted rate (the paper, section 3.2: "Adam with a learning rate of 0.001 to update both
    /// the basic network and the soft network"); 0: the PPO optimiser's rate, as every run before
    /// issue 60 trained them. Piggyback's scores take `piggyback_learning_rate`, WSN's the
    /// optimiser's (one optimiser, as Kang et al.), PackNet's never move.
    pub score_learning_rate: f64,
    /// Whether the entropy term -beta_H * H is used (METHOD.md 2.3).
    pub entropy: bool,
    /// What the entropy term acts on: `soft_scores` (METHOD.md 2.3) or `action` (Figure 8's caption).
    pub entropy_target: EntropyTarget,
    /// beta_H, the weight of the entropy term.
    pub entropy_weight: f64,
    /// E as a share of each task's budget: the entropy term is on for round(entropy_fraction *
    /// iterations) iterations of a task of `iterations` (the paper: "100" of its 500, 0.2; a
    /// share at other budgets is our reading, docs/method.md). With neither this nor
    /// `entropy_iterations` set: 0.2. Set one of the two, not both.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entropy_fraction: Option<f64>,
    /// E as a count of iterations, whatever the task's budget (before issue 60 the only form,
    /// default 100). A task's own settings carry the count its budget gives
    /// ([`MaskConfig::for_budget`]), which its checkpoint records.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entropy_iterations: Option<usize>,
    /// Multiplicative decay of sigma per iteration after E iterations (ln(decay) added to ln sigma).
    pub sigma_decay: f64,
    /// Lower bound of sigma (sigma units; applied to ln sigma as ln of it).
    pub sigma_floor: f64,
    /// Upper bound of sigma (sigma units; applied to ln sigma as ln of it): Adam moves the one
    /// ln sigma per layer by about the learning rate per step whatever beta_H is, so sigma grows
    /// by a factor of about exp(lr) per step and without a bound the entropy term would drown the
    /// scores' ranking.
    pub sigma_max: f64,
    /// Re-initialise the weights still VACANT at the end of each task (METHOD.md 2.4 step 4);
    /// `reinit` in files written before issue 31, when it also redrew every soft-score mean.
    #[serde(alias = "reinit")]
    pub reinit_weights: bool,
    /// Which soft-score means are redrawn at the end of each task: `vacant` (METHOD.md 2.4, the
    /// default: the learned ranking of occupied elements survives), `all` or `none`.
    pub reinit_scores: ScoreReinit,
    /// The range of re-initialised vacant weights: `initial` (the layer's initialiser over its
    /// full fan-in, the default) or `he_effective` (over c times the fan-in).
    pub reinit_range: ReinitRange,
    /// The range of re-initialised vacant weights as a fraction of `reinit_range`'s (1 = METHOD.md
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
    /// Piggyback: the scores' own Adam learning rate (Mallya et al. train the mask at 1e-4
    /// with the weights fixed); 0 steps them at the PPO optimiser's (KL-adapted) rate.
    pub piggyback_learning_rate: f64,
    /// Whether the soft scores of occupied elements train too (one reading of METHOD.md 2.2's
    /// straight-through gradient); off: only vacant elements' scores move, occupied ones keep
    /// the ranking the task started with (its transfer bonus included).
    pub score_grad_occupied: bool,
    /// Where a new task's bias starts: `previous` (the task that ended last, the default),
    /// `related` (the related tasks' mean) or `zero`.
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
            score_learning_rate: PAPER_SOFT_RATE,
            entropy: true,
            entropy_target: EntropyTarget::SoftScores,
            entropy_weight: 1e-4,
            entropy_fraction: None,
            entropy_iterations: None,
            sigma_decay: 0.99,
            sigma_floor: 1e-3,
            sigma_max: 4.0,
            reinit_weights: true,
            reinit_scores: ScoreReinit::Vacant,
            reinit_range: ReinitRange::Initial,
            reinit_scale: 1.0,
            transfer_bonus: 3.0,
            packnet_keep: 0.5,
            packnet_prune_at: None,
            piggyback_threshold: 5e-3,
            piggyback_init: 1e-2,
            piggyback_learning_rate: 1e-4,
            score_grad_occupied: true,
            bias_start: BiasStart::Previous,
        }
    }
}

/// The paper's entropy phase as a share of a task: 100 of its 500 iterations (section 2.4).
pub const PAPER_ENTROPY_FRACTION: f64 = 0.2;
/// The paper's budget of a task, in iterations ("We update each task by 500 epochs").
pub const PAPER_TASK_ITERATIONS: usize = 500;
/// The paper's Adam rate for the soft networks (section 3.2).
pub const PAPER_SOFT_RATE: f64 = 1e-3;
/// E before issue 60, when it was a count only.
pub const PRE_ISSUE_60_ENTROPY_ITERATIONS: usize = 100;

impl MaskConfig {
    /// E for a task of `budget` iterations: the count where one is set, else round(fraction *
    /// budget) (the paper's 0.2 when neither is set). The one place E is computed.
    pub fn entropy_iterations_for(&self, budget: usize) -> usize {
        match self.entropy_iterations {
            Some(n) => n,
            None => (self.entropy_fraction.unwrap_or(PAPER_ENTROPY_FRACTION) * budget as f64).round() as usize,
        }
    }

    /// These settings for a task of `budget` iterations: E as the count it gives, the share cleared.
    pub fn for_budget(&self, budget: usize) -> MaskConfig {
        MaskConfig {
            entropy_iterations: Some(self.entropy_iterations_for(budget)),
            entropy_fraction: None,
            ..self.clone()
        }
    }

    /// E as a layer reads it: the count its task's budget resolved ([`MaskConfig::for_budget`]);
    /// settings never resolved (a layer driven directly, outside a run) take the paper's own
    /// budget, 0.2 x 500 = 100.
    pub fn resolved_entropy_iterations(&self) -> usize {
        self.entropy_iterations_for(PAPER_TASK_ITERATIONS)
    }

    /// The fixed Adam rate of the soft-score means under these settings; None: the optimiser's
    /// (KL-adapted) rate. The one place it is decided.
    pub fn score_rate(&self) -> Option<f64> {
        let rate = match self.rule {
            SelectionRule::Piggyback => self.piggyback_learning_rate,
            // Its scores never move (an all-zero update mask); WSN sets its own rate to 0.
            SelectionRule::PackNet => 0.0,
            _ => self.score_learning_rate,
        };
        (rate > 0.0).then_some(rate)
    }

    /// These settings with what issue 60 changed read as before it, where the settings leave it
    /// open: E a count of 100 unless a share or a count is set, the soft-score means at the
    /// optimiser's rate. For a run that began before issue 60 and is resumed or continued
    /// (see `engine::RunConfig::as_ran_before_issue_60`).
    pub fn as_before_issue_60(&self, score_rate_set: bool) -> MaskConfig {
        let mut m = self.clone();
        if m.entropy_fraction.is_none() && m.entropy_iterations.is_none() {
            m.entropy_iterations = Some(PRE_ISSUE_60_ENTROPY_ITERATIONS);
        }
        if !score_rate_set {
            m.score_learning_rate = 0.0;
        }
        m
    }

    /// Fills in what a saved mask configuration from before issue 60 left out, as it ran: the
    /// soft-score means stepped at the optimiser's rate (`score_learning_rate` 0; Piggyback and
    /// PackNet never used it: the default stands, so a resume compares equal), and E was a count
    /// (100 when the object names none). For checkpoints and manifests, which record a run.
    /// Anything but a JSON object is left as it is.
    pub fn fill_in_pre_issue_60(mask: &mut serde_json::Value) {
        if let Some(m) = mask.as_object_mut() {
            if !m.contains_key("score_learning_rate") {
                let rule = m.get("rule").and_then(|r| r.as_str()).unwrap_or("split");
                let rate = if matches!(rule, "piggyback" | "packnet") { PAPER_SOFT_RATE } else { 0.0 };
                m.insert("score_learning_rate".into(), rate.into());
                if !m.contains_key("entropy_fraction") {
                    m.entry("entropy_iterations").or_insert(PRE_ISSUE_60_ENTROPY_ITERATIONS.into());
                }
            }
        }
    }

    /// These settings with `other`'s that do not act while a task is in progress: the end-of-task
    /// ones (`private_share`, `reinit_weights`, `reinit_scores`, `reinit_range`, `reinit_scale`,
    /// METHOD.md 2.4) and `bias_start`, which acts only when a new task begins. They may change
    /// while a task is in progress (a resumed checkpoint, the workbench's next-task switches).
    pub fn with_end_of_task(&self, other: &MaskConfig) -> MaskConfig {
        MaskConfig {
            private_share: other.private_share,
            reinit_weights: other.reinit_weights,
            reinit_scores: other.reinit_scores,
            reinit_range: other.reinit_range,
            reinit_scale: other.reinit_scale,
            bias_start: other.bias_start,
            ..self.clone()
        }
    }

    /// Fills in what a saved mask configuration from before issue 31 left out, as it ran: `reinit`
    /// redrew the vacant weights at the He range of the effective fan-in and every soft-score mean
    /// (`reinit_scores = "all"`, or `"none"` when off), and a new task's bias started from its
    /// related tasks' mean. For checkpoints and manifests, which record a run; a run file a user
    /// writes takes the defaults. Anything but a JSON object is left as it is.
    pub fn fill_in_pre_issue_31(mask: &mut serde_json::Value) {
        if let Some(m) = mask.as_object_mut() {
            if let Some(reinit) = m.remove("reinit") {
                m.entry("reinit_weights").or_insert(reinit);
            }
            if !m.contains_key("reinit_scores") {
                let on = m.get("reinit_weights").and_then(|v| v.as_bool()).unwrap_or(true);
                m.insert("reinit_scores".into(), if on { "all" } else { "none" }.into());
                m.entry("reinit_range").or_insert("he_effective".into());
                m.entry("bias_start").or_insert("related".into());
            }
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

    /// Fills in what a saved mask configuration from before issue 39 left out: Piggyback's
    /// scores then stepped at the PPO optimiser's rate, so a Piggyback `mask` object without
    /// `piggyback_learning_rate` gets 0 (that rate) instead of today's default; under any other
    /// rule the rate never acts and the default stands (a resumed run compares equal). For
    /// checkpoints and manifests, which record a run. Anything but a JSON object is left as it is.
    pub fn fill_in_pre_issue_39(mask: &mut serde_json::Value) {
        if let Some(m) = mask.as_object_mut() {
            if m.get("rule").and_then(|r| r.as_str()) == Some("piggyback") {
                m.entry("piggyback_learning_rate").or_insert(0.0.into());
            }
        }
    }

    /// Checks the ranges of every field and the relations between them; the error names the
    /// key and the expected range.
    pub fn validate(&self) -> anyhow::Result<()> {
        let key = |name: &str| format!("net.mask.{name}");
        for (name, v, interval) in [
            // A capacity of 0 selects nothing: every task would train biases only.
            ("capacity", self.capacity, POSITIVE_UNIT),
            ("vacant_share", self.vacant_share, UNIT),
            ("private_share", self.private_share, UNIT),
            ("score_init_std", self.score_init_std, POSITIVE),
            // ln sigma is what trains: sigma 0 would start it at minus infinity.
            ("sigma_init", self.sigma_init, POSITIVE),
            ("sigma_floor", self.sigma_floor, POSITIVE),
            ("sigma_max", self.sigma_max, POSITIVE),
            ("sigma_learning_rate", self.sigma_learning_rate, UNIT),
            ("score_learning_rate", self.score_learning_rate, UNIT),
            ("entropy_weight", self.entropy_weight, NON_NEGATIVE),
            // ln(decay) is added to ln sigma: 0 would send sigma to the floor in one step.
            ("sigma_decay", self.sigma_decay, POSITIVE_UNIT),
            ("reinit_scale", self.reinit_scale, UNIT),
            ("transfer_bonus", self.transfer_bonus, Interval::Finite),
            // Keeping none of a task's fresh weights would leave it nothing of its own.
            ("packnet_keep", self.packnet_keep, POSITIVE_UNIT),
            ("piggyback_threshold", self.piggyback_threshold, Interval::Finite),
            ("piggyback_init", self.piggyback_init, Interval::Finite),
            ("piggyback_learning_rate", self.piggyback_learning_rate, UNIT),
        ] {
            bounds::check(&key(name), v, interval)?;
        }
        anyhow::ensure!(
            self.sigma_floor <= self.sigma_max,
            "net.mask.sigma_max ({}) must be >= sigma_floor ({})",
            self.sigma_max,
            self.sigma_floor
        );
        anyhow::ensure!(
            self.piggyback_init > self.piggyback_threshold,
            "net.mask.piggyback_init = {} must exceed piggyback_threshold = {}: every mask element would start \
             off, a mask that selects nothing",
            self.piggyback_init,
            self.piggyback_threshold
        );
        if let Some(e) = self.entropy_iterations {
            bounds::check_count("net.mask.entropy_iterations", e, 0, MAX_ITERATIONS)?;
        }
        if let Some(f) = self.entropy_fraction {
            bounds::check("net.mask.entropy_fraction", f, UNIT)?;
            anyhow::ensure!(
                self.entropy_iterations.is_none(),
                "net.mask.entropy_fraction = {f} and entropy_iterations = {} both set the entropy phase: keep one \
                 (entropy_fraction, a share of each task's budget, the paper's 0.2; entropy_iterations, a count)",
                self.entropy_iterations.unwrap_or_default()
            );
        }
        if let Some(at) = self.packnet_prune_at {
            bounds::check_count("net.mask.packnet_prune_at", at, 0, MAX_ITERATIONS)?;
        }
        Ok(())
    }

    /// Checks that a task selects at least one element of `layer` (`rows x cols`, out x in)
    /// under these settings: k = round(c * F) with F the row's fan-in (the layer's size under
    /// `per-layer`). The mask baselines choose by their own rules and always pass.
    pub fn check_selects_in(&self, layer: &str, rows: usize, cols: usize) -> anyhow::Result<()> {
        let (n, of) = match self.rule {
            SelectionRule::PackNet | SelectionRule::Piggyback => return Ok(()),
            SelectionRule::PerLayer => (rows * cols, "elements"),
            _ => (cols, "inputs per row"),
        };
        anyhow::ensure!(
            row_quota(self.capacity, n) > 0,
            "net.mask.capacity = {}: selects nothing in {layer} ({n} {of}: round({} * {n}) = 0); it needs a capacity of at least {}",
            self.capacity,
            self.capacity,
            0.5 / n.max(1) as f64
        );
        Ok(())
    }
}

/// k = round(c * F): how many elements a row of fan-in `fan_in` selects at capacity c (and a
/// layer of `fan_in` elements under `per-layer`).
pub fn row_quota(capacity: f64, fan_in: usize) -> usize {
    ((capacity * fan_in as f64).round() as usize).min(fan_in)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saved_piggyback_mask_without_a_score_rate_is_read_as_it_ran_at_the_optimisers() {
        let mut old = serde_json::json!({ "rule": "piggyback" });
        MaskConfig::fill_in_pre_issue_39(&mut old);
        let m: MaskConfig = serde_json::from_value(old).unwrap();
        assert_eq!(m.piggyback_learning_rate, 0.0);
        // Under another rule the rate never acted: the default stands, so a resume compares equal.
        let mut other = serde_json::json!({ "rule": "split" });
        MaskConfig::fill_in_pre_issue_39(&mut other);
        let m: MaskConfig = serde_json::from_value(other).unwrap();
        assert_eq!(m.piggyback_learning_rate, MaskConfig::default().piggyback_learning_rate);
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
    fn the_entropy_phase_is_a_share_of_the_budget_unless_a_count_is_set() {
        let paper = MaskConfig::default();
        assert_eq!(
            [500, 200, 3].map(|b| paper.entropy_iterations_for(b)),
            [100, 40, 1],
            "the paper's 100 of 500, as a share"
        );
        let half = MaskConfig { entropy_fraction: Some(0.5), ..MaskConfig::default() };
        assert_eq!(half.entropy_iterations_for(7), 4);
        let count: MaskConfig = toml::from_str("entropy_iterations = 100").unwrap();
        assert_eq!((count.entropy_iterations_for(200), count.entropy_iterations_for(5000)), (100, 100));
        let resolved = half.for_budget(40);
        assert_eq!((resolved.entropy_iterations, resolved.entropy_fraction), (Some(20), None));
        assert_eq!(resolved.resolved_entropy_iterations(), 20, "a resolved count stays whatever the budget");
        let both = MaskConfig { entropy_fraction: Some(0.3), entropy_iterations: Some(100), ..MaskConfig::default() };
        let err = both.validate().unwrap_err().to_string();
        assert!(err.contains("entropy_fraction") && err.contains("entropy_iterations"), "{err}");
        let err = MaskConfig { entropy_fraction: Some(1.5), ..MaskConfig::default() }.validate().unwrap_err();
        assert!(err.to_string().contains("net.mask.entropy_fraction"), "{err}");
    }

    #[test]
    fn the_soft_score_means_have_their_own_rate_by_rule() {
        assert_eq!(MaskConfig::default().score_rate(), Some(1e-3), "the paper's Adam 1e-3");
        let at_ppo = MaskConfig { score_learning_rate: 0.0, ..MaskConfig::default() };
        assert_eq!(at_ppo.score_rate(), None);
        let piggyback = MaskConfig { rule: SelectionRule::Piggyback, ..MaskConfig::default() };
        assert_eq!(piggyback.score_rate(), Some(piggyback.piggyback_learning_rate));
        assert_eq!(MaskConfig { rule: SelectionRule::PackNet, ..MaskConfig::default() }.score_rate(), None);
    }

    #[test]
    fn a_saved_mask_from_before_issue_60_is_read_as_it_ran() {
        let mut old = serde_json::json!({ "rule": "split", "entropy_iterations": 7 });
        MaskConfig::fill_in_pre_issue_60(&mut old);
        let m: MaskConfig = serde_json::from_value(old).unwrap();
        assert_eq!((m.score_rate(), m.entropy_iterations), (None, Some(7)));
        let mut bare = serde_json::json!({ "rule": "split" });
        MaskConfig::fill_in_pre_issue_60(&mut bare);
        let m: MaskConfig = serde_json::from_value(bare).unwrap();
        assert_eq!((m.score_learning_rate, m.entropy_iterations), (0.0, Some(100)));
        // Under Piggyback and PackNet the rate never acted: the default stands.
        let mut piggyback = serde_json::json!({ "rule": "piggyback" });
        MaskConfig::fill_in_pre_issue_60(&mut piggyback);
        assert_eq!(serde_json::from_value::<MaskConfig>(piggyback).unwrap().score_learning_rate, PAPER_SOFT_RATE);
        // A mask written since names its rate and keeps it.
        let mut new = serde_json::json!({ "score_learning_rate": 0.002, "entropy_fraction": 0.2 });
        MaskConfig::fill_in_pre_issue_60(&mut new);
        let m: MaskConfig = serde_json::from_value(new).unwrap();
        assert_eq!((m.score_learning_rate, m.entropy_iterations, m.entropy_fraction), (0.002, None, Some(0.2)));
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
