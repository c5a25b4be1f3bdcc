//! The unit of sigma under `sigma_scale = "score_gap"` (METHOD.md 2.3; the scale is
//! ours): how far apart the soft-score means are at the top-k cut, per row.
//!
//! For a row of a layer `rows x cols` (row-major `scores`, `states`): among its
//! selectable elements (vacant, occupied and the task's own private ones), sorted by
//! score from the highest, with k = round(c * F) and w = max(1, round(k / 10)):
//! g_row = (s[k - w - 1] - s[k + w]) / 2 (0-based, clamped to the row): half the
//! distance over the w + 1 scores either side of the cut. A score at the cut that
//! moves by g_row moves by about w ranks. For the `per-layer` rule the
//! whole layer is one "row" with k = round(c * rows * cols). A row with fewer than
//! two selectable elements has nothing to reorder: g = 0.

use crate::config::net::SelectionRule;
use crate::nn::select::{row_quota, SelectionParams};
use crate::nn::state::{ElementState, TaskId};

/// The spread of `scores` around rank k (see the module header): half the distance
/// between the scores ranked k - w and k + w + 1 (1-based; the last selected is rank k),
/// w = max(1, round(k / 10)).
fn spread_at_cut(mut scores: Vec<f32>, k: usize) -> f32 {
    let n = scores.len();
    if n < 2 {
        return 0.0;
    }
    let w = ((k as f64 / 10.0).round() as usize).max(1);
    let above = k.saturating_sub(w + 1).min(n - 1);
    let below = (k + w).min(n - 1);
    let descending = |a: &f32, b: &f32| b.total_cmp(a);
    let (_, high, rest) = scores.select_nth_unstable_by(above, descending);
    let high = *high;
    let low = if below == above {
        high
    } else {
        // The element of rank `below` among those after `above`.
        *rest.select_nth_unstable_by(below - above - 1, descending).1
    };
    0.5 * (high - low).max(0.0)
}

/// g per row (`rows` values; for `per-layer` every row gets the layer's one value).
pub fn score_gaps(
    scores: &[f32],
    states: &[ElementState],
    rows: usize,
    cols: usize,
    task: TaskId,
    p: &SelectionParams,
) -> Vec<f32> {
    let selectable = |range: std::ops::Range<usize>| -> Vec<f32> {
        range.filter(|&i| states[i].selectable_by(task)).map(|i| scores[i]).collect()
    };
    if p.rule == SelectionRule::PerLayer {
        let g = spread_at_cut(selectable(0..rows * cols), row_quota(p.capacity, rows * cols));
        return vec![g; rows];
    }
    let k = row_quota(p.capacity, cols);
    (0..rows).map(|r| spread_at_cut(selectable(r * cols..(r + 1) * cols), k)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(rule: SelectionRule) -> SelectionParams {
        SelectionParams { capacity: 0.2, vacant_share: 0.25, rule }
    }

    #[test]
    fn the_gap_is_half_the_score_distance_w_ranks_either_side_of_the_cut() {
        // One row of 100 scores 0, 1, ..., 99 (shuffled by a stride): k = 20, w = 2, so the
        // scores ranked 18 and 23 are 82 and 77: g = 2.5.
        let scores: Vec<f32> = (0..100).map(|i| ((i * 37) % 100) as f32).collect();
        let states = vec![ElementState::Vacant; 100];
        assert_eq!(score_gaps(&scores, &states, 1, 100, 0, &params(SelectionRule::Split)), vec![2.5]);
        // Scaling the scores scales the gap: it is a unit, not a number of ranks.
        let scaled: Vec<f32> = scores.iter().map(|s| s * 0.01).collect();
        let g = score_gaps(&scaled, &states, 1, 100, 0, &params(SelectionRule::Split))[0];
        assert!((g - 0.025).abs() < 1e-6, "{g}");
    }

    #[test]
    fn other_tasks_private_elements_do_not_count_and_tiny_rows_have_no_gap() {
        let scores: Vec<f32> = (0..10).map(|i| i as f32).collect();
        let mut states = vec![ElementState::Private(7); 10];
        states[3] = ElementState::Vacant;
        assert_eq!(score_gaps(&scores, &states, 1, 10, 0, &params(SelectionRule::Split)), vec![0.0]);
        states[9] = ElementState::Occupied;
        // Two selectable scores, 9 and 3: k = 2, w = 1, ranks clamp to the first and the last.
        assert_eq!(score_gaps(&scores, &states, 1, 10, 0, &params(SelectionRule::Split)), vec![3.0]);
        // The task's own private elements are selectable.
        let own = vec![ElementState::Private(0); 10];
        assert!(score_gaps(&scores, &own, 1, 10, 0, &params(SelectionRule::Split))[0] > 0.0);
    }

    #[test]
    fn per_layer_gives_every_row_the_layers_one_gap() {
        let scores: Vec<f32> = (0..200).map(|i| ((i * 73) % 200) as f32).collect();
        let states = vec![ElementState::Vacant; 200];
        // k = 40, w = 4: ranks 36 and 45 are 164 and 155.
        assert_eq!(score_gaps(&scores, &states, 4, 50, 0, &params(SelectionRule::PerLayer)), vec![4.5; 4]);
    }
}
