//! Every hyperparameter of quadcl, with a doc comment and a default, in one
//! tree that loads from a TOML file under `scenes/`.
//!
//! One file per concern: [`env`](mod@env) (the simulated robot and its rewards),
//! [`net`] (network sizes), [`mask`] (the method's mask settings), [`ppo`] (the
//! learner), [`robot`] (per-joint robot settings by name pattern), and
//! [`bounds`], the one check per kind of bound that every key and command-line
//! option goes through. A TOML file only names what it changes; every table and
//! key is optional, and an unknown key is an error that names the file and the
//! key. Every number is checked when a file loads: finite, in its documented
//! range, and consistent with the others (see each `validate`).

pub mod bounds;
pub mod env;
pub mod mask;
pub mod net;
pub mod ppo;
pub mod robot;

pub use env::{CoriolisForces, EnvConfig};
pub use net::NetConfig;
pub use ppo::PpoConfig;
pub use robot::RobotConfig;

use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The whole configuration of one experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// Master seed: every random stream of a run is derived from it.
    pub seed: u64,
    /// The simulated robot, its control, rewards and randomisation.
    pub env: EnvConfig,
    /// Network sizes and the masked-network settings of the method.
    pub net: NetConfig,
    /// PPO and the context estimator.
    pub ppo: PpoConfig,
}

impl Default for Config {
    fn default() -> Self {
        Self { seed: 1, env: EnvConfig::default(), net: NetConfig::default(), ppo: PpoConfig::default() }
    }
}

impl Config {
    /// Reads a TOML file. Errors name the file and, from the TOML parser,
    /// the line, column and key that is wrong.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading config {}", path.display()))?;
        Self::from_toml_str(&text).with_context(|| format!("in config {}", path.display()))
    }

    /// Parses TOML text and checks every value (no file name in the error;
    /// [`Config::load`] adds it).
    pub fn from_toml_str(text: &str) -> anyhow::Result<Self> {
        let cfg: Config = toml::from_str(text).map_err(|e| anyhow::anyhow!("{e}"))?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Checks every table: ranges, finiteness, sizes that fit in memory. Errors name the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.env.validate()?;
        self.net.validate()?;
        self.ppo.validate()
    }

    /// The configuration as TOML, as it is written beside every result.
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).expect("a Config always serialises to TOML")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_config_round_trips_through_toml() {
        let cfg = Config::default();
        let back = Config::from_toml_str(&cfg.to_toml_string()).unwrap();
        assert_eq!(cfg, back);
    }

    #[test]
    fn unknown_key_is_an_error_naming_the_file_and_key() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, "seed = 3\nsede = 4\n").unwrap();
        let err = format!("{:#}", Config::load(&path).unwrap_err());
        assert!(err.contains("bad.toml"), "{err}");
        assert!(err.contains("sede"), "{err}");
    }

    #[test]
    fn a_value_out_of_range_is_an_error_naming_the_file_and_the_key() {
        let dir = tempfile::tempdir().unwrap();
        for (text, key) in [
            ("[ppo]\nnum_envs = 0\n", "ppo.num_envs"),
            ("[net.critic]\nhidden = [0, 32]\n", "net.critic.hidden"),
            ("[env]\nmotor_strength_range = [1.0, 0.5]\n", "env.motor_strength_range"),
            ("[ppo]\nnum_envs = 100000000\n", "at most 16384"),
        ] {
            let path = dir.path().join("bad.toml");
            std::fs::write(&path, text).unwrap();
            let err = format!("{:#}", Config::load(&path).unwrap_err());
            assert!(err.contains("bad.toml") && err.contains(key), "{text}: {err}");
        }
    }

    #[test]
    fn partial_file_keeps_defaults_for_the_rest() {
        let cfg = Config::from_toml_str("seed = 7\n").unwrap();
        assert_eq!(cfg.seed, 7);
        assert_eq!(cfg.env, EnvConfig::default());
    }
}
