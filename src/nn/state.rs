//! The life cycle of one weight element of a masked layer (METHOD.md 2, 2.4):
//! VACANT (no finished task uses it) -> OCCUPIED (at least one finished task
//! uses it, frozen) or PRIVATE(t) (reserved for task t alone). The legal
//! transitions are the only way a state changes.

use serde::{Deserialize, Serialize};

/// Index of a task in the learner's task list; a repeated task reuses its id.
pub type TaskId = usize;

/// The state of one element of a masked layer's base weights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ElementState {
    /// No finished task uses the element: it may be trained and re-initialised.
    Vacant,
    /// At least one finished task uses the element: frozen forever, selectable by every task.
    Occupied,
    /// Reserved for one task: only that task selects it, only its fine-tuning moves it.
    Private(TaskId),
}

/// An illegal state change was asked for.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("illegal element state change {from:?} -> {to:?}")]
pub struct IllegalTransition {
    pub from: ElementState,
    pub to: ElementState,
}

impl ElementState {
    /// Whether a task `task` may select the element (a private element of another task never).
    pub fn selectable_by(self, task: TaskId) -> bool {
        match self {
            ElementState::Vacant | ElementState::Occupied => true,
            ElementState::Private(owner) => owner == task,
        }
    }

    /// The end-of-task transition: VACANT -> OCCUPIED or PRIVATE(t); nothing else leaves its state.
    pub fn transition(self, to: ElementState) -> Result<ElementState, IllegalTransition> {
        match (self, to) {
            (ElementState::Vacant, ElementState::Occupied | ElementState::Private(_)) => Ok(to),
            (a, b) if a == b => Ok(a),
            (from, to) => Err(IllegalTransition { from, to }),
        }
    }

    /// Compact code used in checkpoints: 0 vacant, 1 occupied, 2 + t private to t.
    pub fn to_code(self) -> u32 {
        match self {
            ElementState::Vacant => 0,
            ElementState::Occupied => 1,
            ElementState::Private(t) => 2 + t as u32,
        }
    }

    /// Inverse of [`ElementState::to_code`].
    pub fn from_code(code: u32) -> ElementState {
        match code {
            0 => ElementState::Vacant,
            1 => ElementState::Occupied,
            c => ElementState::Private((c - 2) as TaskId),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_vacant_elements_change_state() {
        use ElementState::*;
        assert_eq!(Vacant.transition(Occupied), Ok(Occupied));
        assert_eq!(Vacant.transition(Private(3)), Ok(Private(3)));
        assert!(Occupied.transition(Vacant).is_err());
        assert!(Occupied.transition(Private(1)).is_err());
        assert!(Private(1).transition(Vacant).is_err());
        assert!(Private(1).transition(Private(2)).is_err());
        assert_eq!(Occupied.transition(Occupied), Ok(Occupied));
    }

    #[test]
    fn private_elements_are_selectable_only_by_their_owner() {
        assert!(ElementState::Private(2).selectable_by(2));
        assert!(!ElementState::Private(2).selectable_by(1));
        assert!(ElementState::Occupied.selectable_by(7));
    }

    #[test]
    fn state_codes_round_trip() {
        for s in [ElementState::Vacant, ElementState::Occupied, ElementState::Private(0), ElementState::Private(41)] {
            assert_eq!(ElementState::from_code(s.to_code()), s);
        }
    }
}
