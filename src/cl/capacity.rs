//! How long each masked layer's vacant elements last (METHOD.md 2.1): the
//! forecast the workbench's Next task panel shows before a step starts.
//!
//! Per row of fan-in F a new task selects k = round(c * F) elements. Under a
//! vacant share lambda (the `split` rule) k_v = round(lambda * k) of them come
//! from the row's VACANT elements and become OCCUPIED (or PRIVATE) at the
//! task's end; a row with fewer vacant elements than k_v gives all it has and
//! fills the rest from occupied ones (`nn::split_counts`). The `vacant`
//! rule takes all k from vacant elements and selects fewer (down to none) when
//! they run short; `free` and `per-layer` take whatever ranks highest, so the
//! forecast gives their most (all k from vacant while there are any). A repeat
//! of a learned task selects nothing new (METHOD.md 2.5).
//!
//! The layer's vacant elements are taken as spread evenly over its rows: exact
//! under the split rule (every row gives the same k_v each task), an upper
//! bound on what a task takes otherwise.

use super::ours::{LambdaMode, Switches};
use crate::nn::LayerMasks;
use crate::nn::{row_quota, split_counts, vacant_quota};

/// One layer's vacant elements now and after each coming step.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerForecast {
    pub layer: String,
    /// Elements of the layer.
    pub total: usize,
    pub vacant_now: usize,
    /// Vacant elements left after each of the coming steps, in order.
    pub vacant_after: Vec<usize>,
}

impl LayerForecast {
    /// Vacant elements over all elements, now.
    pub fn share_now(&self) -> f64 {
        self.vacant_now as f64 / self.total.max(1) as f64
    }

    /// Vacant elements over all elements after the next step (now, when none is coming).
    pub fn share_after_next(&self) -> f64 {
        self.vacant_after.first().map_or(self.vacant_now, |v| *v) as f64 / self.total.max(1) as f64
    }

    /// The first coming step (0 = the next) that leaves the layer no vacant element.
    pub fn runs_out_at(&self) -> Option<usize> {
        self.vacant_after.iter().position(|v| *v == 0).filter(|_| self.vacant_now > 0)
    }
}

/// Vacant elements a new task takes from a layer of `rows` x `cols` with `vacant` of them
/// vacant and `occupied` occupied (spread evenly over the rows).
pub fn vacant_taken(rows: usize, cols: usize, vacant: usize, occupied: usize, s: &Switches) -> usize {
    if rows == 0 || cols == 0 {
        return 0;
    }
    if s.lambda == LambdaMode::PerLayer {
        return row_quota(s.capacity, rows * cols).min(vacant);
    }
    let k = row_quota(s.capacity, cols);
    let per_row = |v: usize| match s.lambda {
        LambdaMode::Share(lambda) => split_counts(k, vacant_quota(lambda, k), v, occupied / rows).0,
        _ => k.min(v),
    };
    // `vacant % rows` rows hold one more than the others.
    let (v, extra) = (vacant / rows, vacant % rows);
    extra * per_row(v + 1) + (rows - extra) * per_row(v)
}

/// The forecast for `layer` over the coming steps (`true` for a new task, `false` for a repeat),
/// each under the switches `s`.
pub fn forecast(layer: &LayerMasks, s: &Switches, coming: &[bool]) -> LayerForecast {
    let [rows, cols] = layer.shape;
    let (mut vacant, mut occupied) = (layer.vacant, layer.occupied);
    let vacant_after = coming
        .iter()
        .map(|new| {
            if *new {
                let taken = vacant_taken(rows, cols, vacant, occupied, s);
                vacant -= taken;
                occupied += taken;
            }
            vacant
        })
        .collect();
    LayerForecast { layer: layer.name.clone(), total: rows * cols, vacant_now: layer.vacant, vacant_after }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn layer(rows: usize, cols: usize, vacant: usize) -> LayerMasks {
        LayerMasks {
            name: "actor.l0".into(),
            shape: [rows, cols],
            vacant,
            occupied: rows * cols - vacant,
            private: BTreeMap::new(),
            per_task: Vec::new(),
            overlap: Vec::new(),
        }
    }

    fn switches(capacity: f64, lambda: LambdaMode) -> Switches {
        Switches { capacity, lambda, ..Switches::default() }
    }

    #[test]
    fn a_split_task_takes_round_lambda_k_per_row_until_the_rows_run_out() {
        // F = 100, c 0.27: k = 27, lambda 0.25: k_v = 7 per row; 25 vacant per row last 3 tasks, then 4 left.
        let f = forecast(&layer(10, 100, 250), &switches(0.27, LambdaMode::Share(0.25)), &[true; 5]);
        assert_eq!(f.vacant_after, [180, 110, 40, 0, 0]);
        assert_eq!(f.runs_out_at(), Some(3));
        assert!((f.share_now() - 0.25).abs() < 1e-12 && (f.share_after_next() - 0.18).abs() < 1e-12);
    }

    #[test]
    fn a_repeat_takes_nothing_and_the_vacant_rule_takes_the_whole_quota() {
        let f = forecast(&layer(10, 100, 250), &switches(0.27, LambdaMode::Share(0.25)), &[false, true]);
        assert_eq!(f.vacant_after, [250, 180]);
        let v = forecast(&layer(10, 100, 250), &switches(0.2, LambdaMode::Vacant), &[true, true]);
        assert_eq!(v.vacant_after, [50, 0]);
        let full = forecast(&layer(10, 100, 0), &switches(0.2, LambdaMode::Vacant), &[true]);
        assert_eq!(full.runs_out_at(), None, "already out: nothing runs out at a coming step");
    }

    #[test]
    fn uneven_vacant_counts_are_spread_over_the_rows() {
        // 3 rows of 10, 7 vacant: rows hold 3, 2, 2; k = 5, k_v = 3 (lambda 0.5): all 7 go.
        assert_eq!(vacant_taken(3, 10, 7, 23, &switches(0.5, LambdaMode::Share(0.5))), 7);
        // The per-layer rule: round(0.2 * 30) = 6 at most.
        assert_eq!(vacant_taken(3, 10, 7, 23, &switches(0.2, LambdaMode::PerLayer)), 6);
    }
}
