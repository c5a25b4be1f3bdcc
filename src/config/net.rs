//! Settings of the masked networks (owned by the `nn` work; skeleton).

use serde::{Deserialize, Serialize};

/// Network sizes and the masked-network settings of the method.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NetConfig {}
