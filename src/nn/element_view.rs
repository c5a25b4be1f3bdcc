//! Every element of a masked layer as one task sees it (the TUI's mask
//! heatmap draws these codes; the per-layer counts are in `stats`):
//! vacant, occupied by other tasks, private to other tasks, selected by the
//! task from vacant elements (fresh capacity), selected from occupied ones
//! (reuse), private to the task. While a task trains, its selection is the
//! current iteration's hard mask. Codes are row-major over (out, in).
//!
//! Also the forward-transfer preview: how many elements of each layer the
//! transfer bonus (METHOD.md 2.6) lifts for a given set of related tasks.

use super::masked::MaskedLinear;
use super::mlp::MaskedMlp;
use super::state::{ElementState, TaskId};
use serde::{Deserialize, Serialize};

/// The state of one element from one task's point of view (its code is `as u8`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum ElementView {
    /// No finished task uses it, and the task does not select it.
    Vacant = 0,
    /// Used by other finished tasks, not by this one.
    OccupiedByOthers = 1,
    /// Reserved for another task.
    PrivateToOthers = 2,
    /// Selected by the task; no task finished before it used the element.
    SelectedFromVacant = 3,
    /// Selected by the task and used by a task finished before it.
    SelectedFromOccupied = 4,
    /// Reserved for this task.
    PrivateToTask = 5,
}

impl ElementView {
    /// Every view in code order (the legend's order).
    pub const ALL: [ElementView; 6] = [
        ElementView::Vacant,
        ElementView::OccupiedByOthers,
        ElementView::PrivateToOthers,
        ElementView::SelectedFromVacant,
        ElementView::SelectedFromOccupied,
        ElementView::PrivateToTask,
    ];

    /// The view of code `code` (None for a code no view has).
    pub fn from_code(code: u8) -> Option<ElementView> {
        Self::ALL.get(code as usize).copied()
    }

    /// A short label for legends.
    pub fn label(self) -> &'static str {
        match self {
            ElementView::Vacant => "vacant",
            ElementView::OccupiedByOthers => "occupied (others)",
            ElementView::PrivateToOthers => "private (others)",
            ElementView::SelectedFromVacant => "selected from vacant",
            ElementView::SelectedFromOccupied => "selected from occupied",
            ElementView::PrivateToTask => "private (this task)",
        }
    }

    /// Its colour (r, g, b) wherever masks are drawn: the workbench's heatmap and legend, and
    /// the mask images of a Rerun recording.
    pub fn rgb(self) -> (u8, u8, u8) {
        match self {
            ElementView::Vacant => (48, 48, 48),
            ElementView::OccupiedByOthers => (70, 110, 200),
            ElementView::PrivateToOthers => (150, 80, 200),
            ElementView::SelectedFromVacant => (60, 210, 90),
            ElementView::SelectedFromOccupied => (235, 195, 50),
            ElementView::PrivateToTask => (235, 80, 60),
        }
    }
}

/// One layer's elements seen from one task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerView {
    /// The network (`actor`, `critic`, `cenet`, ...).
    pub network: String,
    /// The layer (`actor.l0`, ...).
    pub layer: String,
    /// [out, in].
    pub shape: [usize; 2],
    /// One [`ElementView`] code per element, row-major (out, in).
    pub codes: Vec<u8>,
    /// How many elements have each view (indexed by code): the live fractions of a task in training.
    pub counts: [usize; 6],
}

/// How much of one row (an output neuron) a task took: the counts of its elements the task
/// selects, split by where they came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RowShare {
    /// The row (output index).
    pub row: usize,
    /// Selected elements that were vacant (private to the task included).
    pub from_vacant: usize,
    /// Selected elements that earlier tasks occupied.
    pub from_occupied: usize,
}

impl RowShare {
    pub fn selected(&self) -> usize {
        self.from_vacant + self.from_occupied
    }
}

impl LayerView {
    /// Every row's share, in row order.
    pub fn row_shares(&self) -> Vec<RowShare> {
        let cols = self.shape[1];
        (0..self.shape[0])
            .map(|row| {
                let codes = &self.codes[row * cols..(row + 1) * cols];
                let count =
                    |views: &[ElementView]| codes.iter().filter(|c| views.iter().any(|v| **c == *v as u8)).count();
                RowShare {
                    row,
                    from_vacant: count(&[ElementView::SelectedFromVacant, ElementView::PrivateToTask]),
                    from_occupied: count(&[ElementView::SelectedFromOccupied]),
                }
            })
            .collect()
    }

    /// The rows ordered by how much of them the task took: most selected first, then most
    /// taken from vacant elements, then by row.
    pub fn rows_by_share(&self) -> Vec<RowShare> {
        let mut rows = self.row_shares();
        rows.sort_by(|a, b| {
            b.selected().cmp(&a.selected()).then(b.from_vacant.cmp(&a.from_vacant)).then(a.row.cmp(&b.row))
        });
        rows
    }
}

/// How many elements of one layer the transfer bonus lifts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerLift {
    pub layer: String,
    /// Elements selected by at least one related task.
    pub lifted: usize,
    /// Elements of the layer.
    pub total: usize,
}

fn layer_view(network: &str, l: &MaskedLinear, task: TaskId) -> LayerView {
    let n = l.out_dim * l.in_dim;
    let training = l.training.as_ref().filter(|t| t.task == task);
    let live = training.and_then(|t| t.previous_selection.as_deref());
    let stored = l.masks.get(&task);
    let position = l.finish_order.iter().position(|t| *t == task);
    let earlier: Vec<_> = match (training, position) {
        // A repeat, or a finished task: the tasks that finished before it first did.
        (_, Some(p)) => l.finish_order[..p].iter().filter_map(|t| l.masks.get(t)).collect(),
        // A new task in training: every finished task came before it.
        (Some(_), None) => l.finish_order.iter().filter_map(|t| l.masks.get(t)).collect(),
        (None, None) => Vec::new(),
    };
    let codes: Vec<u8> = (0..n)
        .map(|i| {
            let selected = match live {
                Some(sel) => sel[i],
                None => stored.is_some_and(|m| m.get(i)),
            };
            let view = match (l.states[i], selected) {
                (ElementState::Private(owner), _) if owner == task => ElementView::PrivateToTask,
                (ElementState::Private(_), _) => ElementView::PrivateToOthers,
                (_, true) if earlier.iter().any(|m| m.get(i)) => ElementView::SelectedFromOccupied,
                (_, true) => ElementView::SelectedFromVacant,
                (ElementState::Vacant, false) => ElementView::Vacant,
                (ElementState::Occupied, false) => ElementView::OccupiedByOthers,
            };
            view as u8
        })
        .collect();
    let mut counts = [0usize; 6];
    codes.iter().for_each(|c| counts[*c as usize] += 1);
    LayerView { network: network.to_string(), layer: l.name.clone(), shape: [l.out_dim, l.in_dim], codes, counts }
}

/// Every layer of every network, seen from `task`.
pub fn mask_views(networks: &[&MaskedMlp], task: TaskId) -> Vec<LayerView> {
    networks.iter().flat_map(|net| net.layers().iter().map(|l| layer_view(net.name(), l, task))).collect()
}

/// Per layer of every network: the elements the transfer bonus lifts when a new task names `related`.
pub fn transfer_lift(networks: &[&MaskedMlp], related: &[TaskId]) -> Vec<LayerLift> {
    networks
        .iter()
        .flat_map(|net| net.layers().iter())
        .map(|l| {
            let masks: Vec<_> = related.iter().filter_map(|t| l.masks.get(t)).collect();
            let n = l.out_dim * l.in_dim;
            LayerLift {
                layer: l.name.clone(),
                lifted: (0..n).filter(|&i| masks.iter().any(|m| m.get(i))).count(),
                total: n,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_ordered_by_the_share_the_task_took_then_by_what_was_vacant() {
        // 3 rows of 4: row 0 one selected (occupied), row 1 three (two vacant, one private),
        // row 2 one selected from vacant.
        let codes = vec![4, 0, 1, 2, 3, 3, 5, 0, 0, 3, 1, 1];
        let view = LayerView { network: "n".into(), layer: "n.l0".into(), shape: [3, 4], codes, counts: [0; 6] };
        let order: Vec<usize> = view.rows_by_share().iter().map(|r| r.row).collect();
        assert_eq!(order, [1, 2, 0]);
        assert_eq!(view.row_shares()[1], RowShare { row: 1, from_vacant: 3, from_occupied: 0 });
        assert_eq!(view.row_shares()[0].selected(), 1);
    }
}
