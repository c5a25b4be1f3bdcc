//! `finetune`: the dense network trained on each task in turn with nothing
//! protecting the old ones (METHOD.md 3; Continual World's `fine-tuning`
//! lower bound). Each task still gets its own output head, so forgetting
//! comes from the shared trunk moving.

use super::method::ContinualMethod;
use crate::nn::NetworkKind;

/// The method `finetune`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Finetune;

impl ContinualMethod for Finetune {
    fn name(&self) -> &str {
        "finetune"
    }

    fn network_kind(&self) -> NetworkKind {
        NetworkKind::Dense
    }
}
