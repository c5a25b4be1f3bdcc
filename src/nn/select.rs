//! Choosing a task's mask from scores (METHOD.md 2.1), as pure functions on
//! slices. A layer is `rows x cols` (out x in), row-major; `scores` and
//! `states` have one entry per element. Ties are broken by element index
//! (the lower index wins), so the selection is deterministic.
//!
//! Per row with fan-in F: k = round(c * F); for the `split` rule
//! k_v = round(lambda * k) from the row's VACANT elements and k - k_v from its
//! OCCUPIED ones, each group ranked by score; a group that runs short is
//! filled from the other. PRIVATE elements of other tasks are never selected.

use super::state::{ElementState, TaskId};
use crate::config::net::SelectionRule;

/// What a selection needs to know besides the scores and states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectionParams {
    /// Capacity ratio c.
    pub capacity: f64,
    /// Vacant share lambda (only for [`SelectionRule::Split`]).
    pub vacant_share: f64,
    /// The rule.
    pub rule: SelectionRule,
}

/// k = round(c * F): how many elements a row of fan-in `fan_in` selects (defined beside the
/// capacity it checks, in `config`).
pub use crate::config::net::row_quota;

/// k_v = round(lambda * k): how many of a row's k come from vacant elements (split rule).
pub fn vacant_quota(vacant_share: f64, k: usize) -> usize {
    ((vacant_share * k as f64).round() as usize).min(k)
}

/// The `k` elements of `idx` with the highest scores, ties by lower index, in no particular
/// order (the mask is a set). The order (score descending, then index) is total, so the
/// partition around the k-th (O(n)) picks the same set as a full sort would.
fn top_k(scores: &[f32], mut idx: Vec<usize>, k: usize) -> Vec<usize> {
    if k == 0 {
        return Vec::new();
    }
    if k < idx.len() {
        idx.select_nth_unstable_by(k - 1, |&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
        idx.truncate(k);
    }
    idx
}

/// How many to take from the vacant and occupied groups given quotas and group sizes, filling from the other group.
pub fn split_counts(k: usize, k_v: usize, n_vacant: usize, n_occupied: usize) -> (usize, usize) {
    let take_v = k_v.min(n_vacant);
    let take_o = (k - take_v).min(n_occupied);
    let take_v = (k - take_o).min(n_vacant);
    (take_v, take_o)
}

/// Chooses task `task`'s mask: `true` where selected. Panics only on mismatched slice lengths (a programming error).
pub fn select_mask(
    scores: &[f32],
    states: &[ElementState],
    rows: usize,
    cols: usize,
    task: TaskId,
    p: &SelectionParams,
) -> Vec<bool> {
    assert_eq!(scores.len(), rows * cols);
    assert_eq!(states.len(), rows * cols);
    let mut mask = vec![false; rows * cols];
    let is_vacant = |s: ElementState| s == ElementState::Vacant;
    if p.rule == SelectionRule::PerLayer {
        let k = row_quota(p.capacity, rows * cols);
        let idx: Vec<usize> = (0..rows * cols).filter(|&i| states[i].selectable_by(task)).collect();
        for i in top_k(scores, idx, k) {
            mask[i] = true;
        }
        return mask;
    }
    let k = row_quota(p.capacity, cols);
    for r in 0..rows {
        let row = r * cols..(r + 1) * cols;
        let vacant: Vec<usize> = row.clone().filter(|&i| is_vacant(states[i])).collect();
        let others: Vec<usize> =
            row.clone().filter(|&i| !is_vacant(states[i]) && states[i].selectable_by(task)).collect();
        let chosen = match p.rule {
            SelectionRule::Split => {
                let (take_v, take_o) = split_counts(k, vacant_quota(p.vacant_share, k), vacant.len(), others.len());
                let mut c = top_k(scores, vacant, take_v);
                c.extend(top_k(scores, others, take_o));
                c
            }
            SelectionRule::Free => {
                let mut all = vacant;
                all.extend(others);
                top_k(scores, all, k)
            }
            SelectionRule::Vacant => top_k(scores, vacant, k),
            SelectionRule::PerLayer => unreachable!("handled above"),
            // PackNet and Piggyback choose their masks in `nn/masked/baselines.rs`; as a rule
            // here they take every selectable element.
            SelectionRule::PackNet | SelectionRule::Piggyback => {
                let mut all = vacant;
                all.extend(others);
                all
            }
        };
        for i in chosen {
            mask[i] = true;
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use ElementState::*;

    fn random_layer(rows: usize, cols: usize, seed: u64) -> (Vec<f32>, Vec<ElementState>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let scores = (0..rows * cols).map(|_| rng.gen::<f32>()).collect();
        let states = (0..rows * cols)
            .map(|_| match rng.gen_range(0..10) {
                0..=3 => Vacant,
                4..=7 => Occupied,
                8 => Private(0),
                _ => Private(1),
            })
            .collect();
        (scores, states)
    }

    fn params(rule: SelectionRule) -> SelectionParams {
        SelectionParams { capacity: 0.2, vacant_share: 0.25, rule }
    }

    #[test]
    fn every_row_selects_exactly_round_c_times_fan_in() {
        let (rows, cols) = (17, 53);
        let (scores, states) = random_layer(rows, cols, 1);
        for rule in [SelectionRule::Split, SelectionRule::Free] {
            let m = select_mask(&scores, &states, rows, cols, 2, &params(rule));
            for r in 0..rows {
                let n = m[r * cols..(r + 1) * cols].iter().filter(|b| **b).count();
                assert_eq!(n, (0.2f64 * 53.0).round() as usize, "rule {rule:?} row {r}");
            }
        }
    }

    #[test]
    fn split_rule_takes_lambda_share_from_vacant_and_the_best_of_each_group() {
        let (rows, cols) = (9, 80);
        let (scores, states) = random_layer(rows, cols, 2);
        let m = select_mask(&scores, &states, rows, cols, 5, &params(SelectionRule::Split));
        let k = 16;
        let k_v = 4;
        for r in 0..rows {
            let row = r * cols..(r + 1) * cols;
            let from_vacant = row.clone().filter(|&i| m[i] && states[i] == Vacant).count();
            let from_occupied = row.clone().filter(|&i| m[i] && states[i] == Occupied).count();
            assert_eq!((from_vacant, from_occupied), (k_v, k - k_v), "row {r}");
            // Every selected element of a group beats every unselected one of that group.
            for group in [Vacant, Occupied] {
                let sel_min = row
                    .clone()
                    .filter(|&i| m[i] && states[i] == group)
                    .map(|i| scores[i])
                    .fold(f32::INFINITY, f32::min);
                let unsel_max = row
                    .clone()
                    .filter(|&i| !m[i] && states[i] == group)
                    .map(|i| scores[i])
                    .fold(f32::NEG_INFINITY, f32::max);
                assert!(sel_min > unsel_max, "row {r} group {group:?}");
            }
        }
    }

    #[test]
    fn short_group_is_filled_from_the_other() {
        assert_eq!(split_counts(10, 3, 1, 20), (1, 9));
        assert_eq!(split_counts(10, 3, 20, 2), (8, 2));
        assert_eq!(split_counts(10, 3, 4, 4), (4, 4));
        // First task: everything vacant, a plain top-k.
        let scores: Vec<f32> = (0..10).map(|i| i as f32).collect();
        let m = select_mask(
            &scores,
            &[Vacant; 10],
            1,
            10,
            0,
            &SelectionParams { capacity: 0.5, vacant_share: 0.25, rule: SelectionRule::Split },
        );
        assert_eq!(m, [false, false, false, false, false, true, true, true, true, true]);
    }

    #[test]
    fn no_rule_ever_selects_a_private_element_of_another_task() {
        for seed in 0..5 {
            let (scores, states) = random_layer(12, 40, seed);
            for rule in [SelectionRule::Split, SelectionRule::Free, SelectionRule::Vacant, SelectionRule::PerLayer] {
                let p = SelectionParams { capacity: 0.9, vacant_share: 0.5, rule };
                let m = select_mask(&scores, &states, 12, 40, 7, &p);
                assert!(m.iter().zip(&states).all(|(&sel, s)| !sel || !matches!(s, Private(_))), "{rule:?}");
            }
        }
    }

    #[test]
    fn vacant_rule_selects_only_vacant_and_per_layer_rule_counts_the_whole_layer() {
        let (scores, states) = random_layer(10, 30, 3);
        let m = select_mask(&scores, &states, 10, 30, 9, &params(SelectionRule::Vacant));
        assert!(m.iter().zip(&states).all(|(&sel, s)| !sel || *s == Vacant));
        let m = select_mask(&scores, &states, 10, 30, 9, &params(SelectionRule::PerLayer));
        assert_eq!(m.iter().filter(|b| **b).count(), 60);
    }

    #[test]
    fn ties_are_broken_by_index_and_selection_is_deterministic() {
        let scores = vec![1.0f32; 10];
        let p = SelectionParams { capacity: 0.3, vacant_share: 0.0, rule: SelectionRule::Free };
        let m = select_mask(&scores, &[Vacant; 10], 1, 10, 0, &p);
        assert_eq!(m.iter().positions(), vec![0, 1, 2]);
        let (scores, states) = random_layer(20, 20, 4);
        let a = select_mask(&scores, &states, 20, 20, 3, &params(SelectionRule::Split));
        let b = select_mask(&scores, &states, 20, 20, 3, &params(SelectionRule::Split));
        assert_eq!(a, b);
    }

    trait Positions {
        fn positions(self) -> Vec<usize>;
    }
    impl<'a, I: Iterator<Item = &'a bool>> Positions for I {
        fn positions(self) -> Vec<usize> {
            self.enumerate().filter(|(_, b)| **b).map(|(i, _)| i).collect()
        }
    }
}
