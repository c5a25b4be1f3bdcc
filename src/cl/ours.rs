//! The method `ours` (METHOD.md 2.1 to 2.7) and every switch of the paper's
//! ablations: re-initialisation of vacant weights on/off and of the soft scores
//! (vacant / all / none), entropy on/off (the paper's None / Reinit / Reinit &
//! Entropy, and its scores-only scheme), the range fresh weights are drawn from,
//! where a new task's bias starts, the lambda mode of the selection (a vacant
//! share such as 0.25, `free`, `vacant`, `per-layer`), capacity c and private
//! share p. The switches only translate into the masked networks'
//! [`MaskConfig`]; the mechanics live in `nn`.

use super::method::ContinualMethod;
use crate::config::net::{BiasStart, MaskConfig, ReinitRange, ScoreReinit, SelectionRule};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How each row's selection splits between vacant and occupied elements (METHOD.md 2.1, Figure 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LambdaMode {
    /// The method: round(lambda * k) vacant, the rest occupied; lambda in [0, 1].
    Share(f64),
    /// One per-row top-k over vacant and occupied together (WSN-like).
    Free,
    /// Vacant elements only.
    Vacant,
    /// One top-k over the whole layer (WSN's original rule).
    PerLayer,
}

impl FromStr for LambdaMode {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Self> {
        match s {
            "free" => Ok(Self::Free),
            "vacant" => Ok(Self::Vacant),
            "per-layer" => Ok(Self::PerLayer),
            other => {
                let v: f64 = other.parse().map_err(|_| {
                    anyhow::anyhow!("lambda mode {other:?}: expected a vacant share in [0, 1] (e.g. \"0.25\"), \"free\", \"vacant\" or \"per-layer\"")
                })?;
                anyhow::ensure!((0.0..=1.0).contains(&v), "lambda mode {other:?}: the vacant share must be in [0, 1]");
                Ok(Self::Share(v))
            }
        }
    }
}

impl fmt::Display for LambdaMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Share(v) => write!(f, "{v}"),
            Self::Free => f.write_str("free"),
            Self::Vacant => f.write_str("vacant"),
            Self::PerLayer => f.write_str("per-layer"),
        }
    }
}

impl Serialize for LambdaMode {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for LambdaMode {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(f64),
            Text(String),
        }
        match Raw::deserialize(d)? {
            Raw::Number(v) => LambdaMode::from_str(&v.to_string()),
            Raw::Text(t) => LambdaMode::from_str(&t),
        }
        .map_err(serde::de::Error::custom)
    }
}

/// The ablation switches of `ours`, in force for one task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Switches {
    /// Re-initialise the weights still vacant when the task ends (METHOD.md 2.4 step 4); `reinit`
    /// in files written before issue 31.
    #[serde(alias = "reinit")]
    pub reinit_weights: bool,
    /// Which soft-score means are redrawn when the task ends: `vacant` (the default), `all`, `none`.
    pub reinit_scores: ScoreReinit,
    /// The range fresh vacant weights are drawn from: `initial` (the default) or `he_effective`.
    pub reinit_range: ReinitRange,
    /// Where the task's bias starts: `previous` (the default), `related` or `zero`.
    pub bias_start: BiasStart,
    /// The soft scores' entropy term during the first E iterations (METHOD.md 2.3).
    pub entropy: bool,
    /// The selection rule: a vacant share ("0.25"), "free", "vacant" or "per-layer".
    pub lambda: LambdaMode,
    /// Capacity c: the fraction of each row a task selects.
    pub capacity: f64,
    /// Private share p: the fraction of a layer made private to the task at its end.
    pub private_share: f64,
}

impl Default for Switches {
    fn default() -> Self {
        Self::from_mask_config(&MaskConfig::default())
    }
}

impl Switches {
    /// The switches that a mask configuration encodes.
    pub fn from_mask_config(m: &MaskConfig) -> Self {
        let lambda = match m.rule {
            SelectionRule::Split => LambdaMode::Share(m.vacant_share),
            SelectionRule::Free => LambdaMode::Free,
            SelectionRule::Vacant => LambdaMode::Vacant,
            SelectionRule::PerLayer => LambdaMode::PerLayer,
            // Set by their methods only, never a run's switches ([net] refuses them).
            SelectionRule::PackNet | SelectionRule::Piggyback => LambdaMode::Free,
        };
        Self {
            reinit_weights: m.reinit_weights,
            reinit_scores: m.reinit_scores,
            reinit_range: m.reinit_range,
            bias_start: m.bias_start,
            entropy: m.entropy,
            lambda,
            capacity: m.capacity,
            private_share: m.private_share,
        }
    }

    /// `base` with these switches applied (every other mask setting kept).
    pub fn apply(&self, base: &MaskConfig) -> anyhow::Result<MaskConfig> {
        let mut m = base.clone();
        m.reinit_weights = self.reinit_weights;
        m.reinit_scores = self.reinit_scores;
        m.reinit_range = self.reinit_range;
        m.bias_start = self.bias_start;
        m.entropy = self.entropy;
        m.capacity = self.capacity;
        m.private_share = self.private_share;
        match self.lambda {
            LambdaMode::Share(v) => {
                m.rule = SelectionRule::Split;
                m.vacant_share = v;
            }
            LambdaMode::Free => m.rule = SelectionRule::Free,
            LambdaMode::Vacant => m.rule = SelectionRule::Vacant,
            LambdaMode::PerLayer => m.rule = SelectionRule::PerLayer,
        }
        m.validate()?;
        Ok(m)
    }

    /// These switches with `over`'s set fields replacing them.
    pub fn with(&self, over: &SwitchOverrides) -> Self {
        Self {
            reinit_weights: over.reinit_weights.unwrap_or(self.reinit_weights),
            reinit_scores: over.reinit_scores.unwrap_or(self.reinit_scores),
            reinit_range: over.reinit_range.unwrap_or(self.reinit_range),
            bias_start: over.bias_start.unwrap_or(self.bias_start),
            entropy: over.entropy.unwrap_or(self.entropy),
            lambda: over.lambda.unwrap_or(self.lambda),
            capacity: over.capacity.unwrap_or(self.capacity),
            private_share: over.private_share.unwrap_or(self.private_share),
        }
    }
}

/// A partial set of switches: a per-task change in a sequence file, or what a
/// UI asks for the next task. Unset fields keep the run's switches.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SwitchOverrides {
    /// See [`Switches::reinit_weights`].
    #[serde(alias = "reinit")]
    pub reinit_weights: Option<bool>,
    /// See [`Switches::reinit_scores`].
    pub reinit_scores: Option<ScoreReinit>,
    /// See [`Switches::reinit_range`].
    pub reinit_range: Option<ReinitRange>,
    /// See [`Switches::bias_start`].
    pub bias_start: Option<BiasStart>,
    /// See [`Switches::entropy`].
    pub entropy: Option<bool>,
    /// See [`Switches::lambda`].
    pub lambda: Option<LambdaMode>,
    /// See [`Switches::capacity`].
    pub capacity: Option<f64>,
    /// See [`Switches::private_share`].
    pub private_share: Option<f64>,
}

impl SwitchOverrides {
    /// `self` with `later`'s set fields taking precedence.
    pub fn merged(&self, later: &SwitchOverrides) -> Self {
        Self {
            reinit_weights: later.reinit_weights.or(self.reinit_weights),
            reinit_scores: later.reinit_scores.or(self.reinit_scores),
            reinit_range: later.reinit_range.or(self.reinit_range),
            bias_start: later.bias_start.or(self.bias_start),
            entropy: later.entropy.or(self.entropy),
            lambda: later.lambda.or(self.lambda),
            capacity: later.capacity.or(self.capacity),
            private_share: later.private_share.or(self.private_share),
        }
    }
}

/// The method of the paper: all the work is in the masked networks; its one
/// hook turns the task's switches into their mask settings.
#[derive(Debug, Clone, Default)]
pub struct Ours;

impl ContinualMethod for Ours {
    fn name(&self) -> &str {
        "ours"
    }

    fn task_mask_config(
        &self,
        base: &MaskConfig,
        switches: &Switches,
        _iterations: usize,
    ) -> anyhow::Result<MaskConfig> {
        switches.apply(base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambda_modes_parse_from_numbers_and_names_and_round_trip() {
        for text in ["0.25", "free", "vacant", "per-layer", "1"] {
            let m: LambdaMode = text.parse().unwrap();
            assert_eq!(m.to_string().parse::<LambdaMode>().unwrap(), m);
        }
        let s: Switches = toml::from_str("lambda = 0.5\n").unwrap();
        assert_eq!(s.lambda, LambdaMode::Share(0.5));
        let err = "1.5".parse::<LambdaMode>().unwrap_err().to_string();
        assert!(err.contains("[0, 1]"), "{err}");
        assert!("sometimes".parse::<LambdaMode>().unwrap_err().to_string().contains("free"));
    }

    #[test]
    fn switches_round_trip_through_the_mask_config() {
        let s = Switches {
            reinit_weights: false,
            reinit_scores: ScoreReinit::All,
            reinit_range: ReinitRange::HeEffective,
            bias_start: BiasStart::Zero,
            entropy: false,
            lambda: LambdaMode::Free,
            capacity: 0.3,
            private_share: 0.05,
        };
        let m = s.apply(&MaskConfig::default()).unwrap();
        assert_eq!(
            (m.reinit_weights, m.reinit_scores, m.reinit_range, m.bias_start),
            (false, ScoreReinit::All, ReinitRange::HeEffective, BiasStart::Zero)
        );
        assert_eq!((m.entropy, m.rule, m.capacity, m.private_share), (false, SelectionRule::Free, 0.3, 0.05));
        assert_eq!(Switches::from_mask_config(&m), s);
        assert_eq!(m.sigma_decay, MaskConfig::default().sigma_decay, "other settings are kept");
    }

    #[test]
    fn overrides_replace_only_the_fields_they_set() {
        let base = Switches::default();
        let over = SwitchOverrides { reinit_weights: Some(false), ..Default::default() };
        let s = base.with(&over);
        assert!(!s.reinit_weights);
        assert_eq!((s.entropy, s.reinit_scores), (base.entropy, base.reinit_scores));
        let later = SwitchOverrides {
            reinit_weights: Some(true),
            reinit_scores: Some(ScoreReinit::None),
            capacity: Some(0.1),
            ..Default::default()
        };
        let m = over.merged(&later);
        assert_eq!((m.reinit_weights, m.reinit_scores, m.capacity), (Some(true), Some(ScoreReinit::None), Some(0.1)));
    }

    #[test]
    fn the_pre_issue_31_reinit_key_still_reads_as_the_weights_switch() {
        let s: Switches = toml::from_str("reinit = false\n").unwrap();
        assert!(!s.reinit_weights);
        assert_eq!(s.reinit_scores, ScoreReinit::Vacant, "unset switches keep their defaults");
        let o: SwitchOverrides = toml::from_str("reinit = true\nbias_start = \"zero\"\n").unwrap();
        assert_eq!((o.reinit_weights, o.bias_start), (Some(true), Some(BiasStart::Zero)));
        let err = toml::from_str::<SwitchOverrides>("reinit_scores = \"some\"\n").unwrap_err().to_string();
        assert!(err.contains("vacant"), "{err}");
    }

    #[test]
    fn an_out_of_range_capacity_is_an_error_naming_the_key() {
        let s = Switches { capacity: 2.0, ..Default::default() };
        let err = s.apply(&MaskConfig::default()).unwrap_err().to_string();
        assert!(err.contains("capacity"), "{err}");
    }
}
