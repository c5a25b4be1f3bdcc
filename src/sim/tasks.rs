//! Task perturbations: what goes wrong with which legs, applied between the
//! policy and the motors (DESIGN.md, "Task perturbations").
//!
//! - `crash:LEG`: that leg's action is zero (it holds the default pose);
//! - `invert:LEG`: that leg's action is negated (the target offset mirrors);
//! - `noise:LEG`: Gaussian noise (std `EnvConfig::noise_std`) is added.
//!
//! Syntax: `none`, or perturbations joined by `+`, e.g. `invert:RR+noise:FR`.
//! The canonical form (Display) sorts by kind (crash, invert, noise) then leg
//! (FL, FR, RL, RR), so `noise:FR+invert:RR` prints as `invert:RR+noise:FR`;
//! parsing the canonical form gives the same value back.

use super::robot::{Leg, JOINTS_PER_LEG, NUM_LEGS};
use crate::util::text::clip;
use anyhow::{anyhow, bail};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::fmt;
use std::str::FromStr;

/// How one leg is perturbed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PerturbationKind {
    /// The leg's action is zero.
    Crash,
    /// The leg's action is negated.
    Invert,
    /// Gaussian noise is added to the leg's action.
    Noise,
}

impl PerturbationKind {
    /// Every kind, in canonical order.
    pub const ALL: [PerturbationKind; 3] = [PerturbationKind::Crash, PerturbationKind::Invert, PerturbationKind::Noise];

    /// "crash", "invert", "noise".
    pub fn name(self) -> &'static str {
        match self {
            PerturbationKind::Crash => "crash",
            PerturbationKind::Invert => "invert",
            PerturbationKind::Noise => "noise",
        }
    }
}

/// A task's leg perturbations: a sorted set of (kind, leg).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct Perturbation {
    items: Vec<(PerturbationKind, Leg)>,
}

impl Perturbation {
    /// The unperturbed robot.
    pub fn none() -> Self {
        Self::default()
    }

    /// A perturbation from (kind, leg) pairs (duplicates removed).
    pub fn new(items: impl IntoIterator<Item = (PerturbationKind, Leg)>) -> Self {
        let mut items: Vec<_> = items.into_iter().collect();
        items.sort();
        items.dedup();
        Self { items }
    }

    /// The (kind, leg) pairs, in canonical order.
    pub fn items(&self) -> &[(PerturbationKind, Leg)] {
        &self.items
    }

    /// Whether nothing is perturbed.
    pub fn is_none(&self) -> bool {
        self.items.is_empty()
    }

    /// Applies the perturbation in place to a 12-action (FL hip/thigh/calf, FR, RL, RR).
    /// Order per leg: crash, then invert, then noise.
    pub fn apply(&self, action: &mut [f32], noise_std: f32, rng: &mut impl Rng) {
        debug_assert_eq!(action.len(), NUM_LEGS * JOINTS_PER_LEG);
        for &(kind, leg) in &self.items {
            let joints = &mut action[leg.index() * JOINTS_PER_LEG..(leg.index() + 1) * JOINTS_PER_LEG];
            match kind {
                PerturbationKind::Crash => joints.fill(0.0),
                PerturbationKind::Invert => joints.iter_mut().for_each(|a| *a = -*a),
                PerturbationKind::Noise => joints.iter_mut().for_each(|a| {
                    let n: f32 = StandardNormal.sample(rng);
                    *a += noise_std * n
                }),
            }
        }
    }
}

fn valid_syntax() -> String {
    let kinds: Vec<&str> = PerturbationKind::ALL.iter().map(|k| k.name()).collect();
    let legs: Vec<&str> = Leg::ALL.iter().map(|l| l.name()).collect();
    format!(
        "valid: \"none\", or KIND:LEG joined by '+', KIND one of {}, LEG one of {} (e.g. \"invert:RR+noise:FR\")",
        kinds.join(", "),
        legs.join(", ")
    )
}

impl FromStr for Perturbation {
    type Err = anyhow::Error;

    fn from_str(text: &str) -> anyhow::Result<Self> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("none") {
            return Ok(Self::none());
        }
        if text.is_empty() {
            bail!("empty task name; {}", valid_syntax());
        }
        let mut items = Vec::new();
        for part in text.split('+') {
            let (kind, leg) = part
                .trim()
                .split_once(':')
                .ok_or_else(|| anyhow!("unknown task part '{}' in '{}'; {}", clip(part), clip(text), valid_syntax()))?;
            let kind =
                PerturbationKind::ALL.into_iter().find(|k| k.name().eq_ignore_ascii_case(kind.trim())).ok_or_else(
                    || anyhow!("unknown perturbation '{}' in task '{}'; {}", clip(kind), clip(text), valid_syntax()),
                )?;
            let leg = Leg::ALL
                .into_iter()
                .find(|l| l.name().eq_ignore_ascii_case(leg.trim()))
                .ok_or_else(|| anyhow!("unknown leg '{}' in task '{}'; {}", clip(leg), clip(text), valid_syntax()))?;
            items.push((kind, leg));
        }
        Ok(Self::new(items))
    }
}

impl fmt::Display for Perturbation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.items.is_empty() {
            return f.write_str("none");
        }
        for (i, (kind, leg)) in self.items.iter().enumerate() {
            if i > 0 {
                f.write_str("+")?;
            }
            write!(f, "{}:{}", kind.name(), leg.name())?;
        }
        Ok(())
    }
}

impl serde::Serialize for Perturbation {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Perturbation {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(|e: anyhow::Error| serde::de::Error::custom(format!("{e:#}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn canonical_form_round_trips_and_sorts() {
        let p: Perturbation = "noise:FR+invert:RR".parse().unwrap();
        assert_eq!(p.to_string(), "invert:RR+noise:FR");
        assert_eq!(p.to_string().parse::<Perturbation>().unwrap(), p);
        assert_eq!("none".parse::<Perturbation>().unwrap(), Perturbation::none());
        assert_eq!(Perturbation::none().to_string(), "none");
    }

    #[test]
    fn unknown_names_list_the_valid_ones() {
        for bad in ["break:FL", "crash:XX", "crash", ""] {
            let err = format!("{:#}", bad.parse::<Perturbation>().unwrap_err());
            assert!(err.contains("crash, invert, noise") && err.contains("FL, FR, RL, RR"), "{bad}: {err}");
        }
    }

    #[test]
    fn configs_name_tasks_with_the_same_syntax() {
        #[derive(serde::Serialize, serde::Deserialize)]
        struct Sequence {
            tasks: Vec<Perturbation>,
        }
        let seq: Sequence = toml::from_str("tasks = [\"none\", \"noise:FR+invert:RR\"]").unwrap();
        assert_eq!(seq.tasks[1].to_string(), "invert:RR+noise:FR");
        assert_eq!(toml::to_string(&seq).unwrap().trim(), "tasks = [\"none\", \"invert:RR+noise:FR\"]");
        let err = toml::from_str::<Sequence>("tasks = [\"crash:XL\"]").err().unwrap().to_string();
        assert!(err.contains("unknown leg 'XL'") && err.contains("FL, FR, RL, RR"), "{err}");
    }

    #[test]
    fn apply_touches_only_the_named_legs() {
        let p: Perturbation = "crash:FL+invert:RR".parse().unwrap();
        let mut a: Vec<f32> = (1..=12).map(|x| x as f32).collect();
        p.apply(&mut a, 0.5, &mut rand_chacha::ChaCha8Rng::seed_from_u64(0));
        assert_eq!(a, vec![0., 0., 0., 4., 5., 6., 7., 8., 9., -10., -11., -12.]);
    }
}
