//! Settings of PPO and the context estimator (owned by the `rl` work; skeleton).

use serde::{Deserialize, Serialize};

/// PPO and the context estimator.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {}
