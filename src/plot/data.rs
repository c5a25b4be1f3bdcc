//! What a figure draws, whatever file it came from (see `load`): per run, a label, each
//! training step's curves over its iterations, and the evaluation matrix `R[i][j]`.
//!
//! A [`Curve`] may carry a band (a low and a high value per point, drawn shaded around the
//! line), so that a figure of several seeds can show their spread with the same functions.

use crate::cl::EvalMatrix;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// One measure over a step's iterations.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Curve {
    /// (iteration, value), iterations counted from 1 within the step, increasing.
    pub points: Vec<(f64, f64)>,
    /// Per point, a (low, high) interval drawn as a band around the line; none draws the line alone.
    pub band: Option<Vec<(f64, f64)>>,
}

impl Curve {
    /// `values` of consecutive iterations, the first one at iteration `first_iteration`.
    pub fn from_values(values: &[f64], first_iteration: usize) -> Self {
        let points = values.iter().enumerate().map(|(i, v)| ((first_iteration + i) as f64, *v)).collect();
        Self { points, band: None }
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The same curve with every iteration moved by `offset` (a step placed in its sequence).
    pub fn shifted(&self, offset: f64) -> Self {
        Self { points: self.points.iter().map(|(x, y)| (x + offset, *y)).collect(), band: self.band.clone() }
    }

    /// The trailing moving mean over `window` points (the band smoothed alike); 0 or 1 keeps it as it is.
    pub fn smoothed(&self, window: usize) -> Self {
        if window <= 1 {
            return self.clone();
        }
        let mean = |ys: &[f64]| -> Vec<f64> {
            (0..ys.len())
                .map(|i| {
                    let from = (i + 1).saturating_sub(window);
                    ys[from..=i].iter().sum::<f64>() / (i + 1 - from) as f64
                })
                .collect()
        };
        let ys: Vec<f64> = self.points.iter().map(|p| p.1).collect();
        let points = self.points.iter().zip(mean(&ys)).map(|((x, _), y)| (*x, y)).collect();
        let band = self.band.as_ref().map(|b| {
            let low = mean(&b.iter().map(|p| p.0).collect::<Vec<_>>());
            let high = mean(&b.iter().map(|p| p.1).collect::<Vec<_>>());
            low.into_iter().zip(high).collect()
        });
        Self { points, band }
    }

    /// The mean of `curves` at each iteration that all of them have (no band).
    pub fn mean_of(curves: &[&Curve]) -> Self {
        let points = Self::aligned(curves).into_iter().map(|(x, ys)| (x, ys.iter().sum::<f64>() / ys.len() as f64));
        Self { points: points.collect(), band: None }
    }

    /// The x values every curve of `curves` has a point at (matched to 1/1024 of an
    /// iteration), in order, each with the curves' values there.
    pub fn aligned(curves: &[&Curve]) -> Vec<(f64, Vec<f64>)> {
        let key = |x: f64| (x * 1024.0).round() as i64;
        let mut at: BTreeMap<i64, (f64, Vec<f64>)> = BTreeMap::new();
        for curve in curves {
            for (x, y) in &curve.points {
                at.entry(key(*x)).or_insert((*x, Vec::new())).1.push(*y);
            }
        }
        at.into_values().filter(|(_, ys)| ys.len() == curves.len()).collect()
    }

    /// The smallest and largest value of the line and its band, if it has any point.
    pub fn value_range(&self) -> Option<(f64, f64)> {
        let band = self.band.iter().flatten().flat_map(|(lo, hi)| [*lo, *hi]);
        let values = self.points.iter().map(|p| p.1).chain(band).filter(|v| v.is_finite());
        values.fold(None, |acc, v| Some(acc.map_or((v, v), |(lo, hi): (f64, f64)| (lo.min(v), hi.max(v)))))
    }
}

/// The training measures every step records, in the order the figures show them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Measure {
    Performance,
    LinVelErr,
    AngVelErr,
    FallRate,
}

impl Measure {
    pub const ALL: [Measure; 4] = [Measure::Performance, Measure::LinVelErr, Measure::AngVelErr, Measure::FallRate];

    /// The measure's name in an iteration's metrics (`metrics.jsonl`).
    pub fn metric_name(self) -> &'static str {
        match self {
            Measure::Performance => "charts/performance",
            Measure::LinVelErr => "charts/lin_vel_err",
            Measure::AngVelErr => "charts/ang_vel_err",
            Measure::FallRate => "charts/fall_rate",
        }
    }

    /// What a panel of it is called.
    pub fn title(self) -> &'static str {
        match self {
            Measure::Performance => "performance",
            Measure::LinVelErr => "linear velocity error",
            Measure::AngVelErr => "yaw rate error",
            Measure::FallRate => "fall rate",
        }
    }

    /// The value axis: the quantity and its unit.
    pub fn axis(self) -> &'static str {
        match self {
            Measure::Performance => "normalised return (0-1)",
            Measure::LinVelErr => "|v_xy - v_cmd| (m/s)",
            Measure::AngVelErr => "|ω_z - ω_cmd| (rad/s)",
            Measure::FallRate => "share of ended episodes that fell (0-1)",
        }
    }

    /// Values the axis always shows (performance and fall rate span 0-1; errors start at 0).
    pub fn axis_includes(self) -> &'static [f64] {
        match self {
            Measure::Performance | Measure::FallRate => &[0.0, 1.0],
            Measure::LinVelErr | Measure::AngVelErr => &[0.0],
        }
    }
}

/// One training step's curves.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepCurves {
    /// The task trained.
    pub task: String,
    /// How many iterations the step ran (where the next step starts in the whole sequence).
    pub iterations: usize,
    pub performance: Curve,
    pub lin_vel_err: Curve,
    pub ang_vel_err: Curve,
    pub fall_rate: Curve,
    /// Plasticity measures by full metric name, `plasticity/FAMILY/MEMBER`
    /// (`plasticity/dormant/actor`, `plasticity/selected_abs_w/actor.l0`).
    pub plasticity: BTreeMap<String, Curve>,
}

impl StepCurves {
    pub fn curve(&self, measure: Measure) -> &Curve {
        match measure {
            Measure::Performance => &self.performance,
            Measure::LinVelErr => &self.lin_vel_err,
            Measure::AngVelErr => &self.ang_vel_err,
            Measure::FallRate => &self.fall_rate,
        }
    }

    pub fn curve_mut(&mut self, measure: Measure) -> &mut Curve {
        match measure {
            Measure::Performance => &mut self.performance,
            Measure::LinVelErr => &mut self.lin_vel_err,
            Measure::AngVelErr => &mut self.ang_vel_err,
            Measure::FallRate => &mut self.fall_rate,
        }
    }
}

/// One run as the figures see it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunData {
    /// The name in legends: the run folder's name unless given.
    pub label: String,
    /// The file it was read from.
    pub source: PathBuf,
    /// The training steps in order.
    pub steps: Vec<StepCurves>,
    /// `R[i][j]` after each step; none for a single training (`quadcl train`).
    pub eval_matrix: Option<EvalMatrix>,
    /// For a sweep's group drawn across seeds: its collected measures (figure `summary`).
    pub over_seeds: Option<OverSeeds>,
}

/// A sweep group's measures over its finished seeds, as `sweep collect` has them.
#[derive(Debug, Clone, PartialEq)]
pub struct OverSeeds {
    /// The group's name in the sweep (`lambda=0.25`), without the seeds' note.
    pub group: String,
    /// Finished seeds it is over.
    pub seeds: usize,
    /// The measures the runs have, in the collected table's order.
    pub measures: Vec<SeedMeasure>,
}

/// One measure of a group over its seeds.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedMeasure {
    /// `sweep::MEASURES`' key and heading.
    pub key: String,
    pub heading: String,
    /// Each finished seed's value, in the plan's order.
    pub values: Vec<f64>,
    /// Their mean and 90 % bootstrap interval (`sweep::estimate`).
    pub estimate: crate::sweep::Estimate,
}

impl RunData {
    /// Where each step starts in the whole sequence (iterations before it).
    pub fn step_offsets(&self) -> Vec<usize> {
        self.steps
            .iter()
            .scan(0usize, |start, s| Some(std::mem::replace(start, start.saturating_add(s.iterations))))
            .collect()
    }

    /// Whether any step recorded a plasticity measure.
    pub fn has_plasticity(&self) -> bool {
        self.steps.iter().any(|s| s.plasticity.values().any(|c| !c.is_empty()))
    }
}

/// A plasticity metric name split into its family and member: `plasticity/dormant/actor` ->
/// (`dormant`, `actor`); None for a name outside `plasticity/`.
pub fn plasticity_parts(name: &str) -> Option<(&str, &str)> {
    let rest = name.strip_prefix("plasticity/")?;
    Some(rest.split_once('/').unwrap_or((rest, "")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_is_a_trailing_mean_that_keeps_the_iterations() {
        let c = Curve::from_values(&[0.0, 2.0, 4.0, 6.0], 3);
        assert_eq!(c.smoothed(2).points, vec![(3.0, 0.0), (4.0, 1.0), (5.0, 3.0), (6.0, 5.0)]);
        assert_eq!(c.smoothed(1), c);
    }

    #[test]
    fn the_mean_of_curves_keeps_only_iterations_all_of_them_have() {
        let a = Curve::from_values(&[1.0, 2.0, 3.0], 1);
        let b = Curve::from_values(&[3.0, 4.0], 2);
        assert_eq!(Curve::mean_of(&[&a, &b]).points, vec![(2.0, 2.5), (3.0, 3.5)]);
    }

    #[test]
    fn step_offsets_add_up_the_iterations_before_each_step() {
        let step = |n| StepCurves { iterations: n, ..Default::default() };
        let run = RunData {
            label: "r".into(),
            source: "x".into(),
            steps: vec![step(5), step(3), step(7)],
            eval_matrix: None,
            over_seeds: None,
        };
        assert_eq!(run.step_offsets(), vec![0, 5, 8]);
    }

    #[test]
    fn a_value_range_covers_the_band() {
        let mut c = Curve::from_values(&[0.5, 0.6], 1);
        c.band = Some(vec![(0.2, 0.7), (0.5, 0.9)]);
        assert_eq!(c.value_range(), Some((0.2, 0.9)));
        assert_eq!(Curve::default().value_range(), None);
        assert_eq!(plasticity_parts("plasticity/selected_abs_w/actor.l0"), Some(("selected_abs_w", "actor.l0")));
        assert_eq!(plasticity_parts("charts/performance"), None);
    }
}
