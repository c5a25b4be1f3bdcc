//! Settings of the simulated robot (owned by the `sim` work; skeleton).

use serde::{Deserialize, Serialize};

/// The simulated robot, its control, rewards and randomisation.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EnvConfig {}
