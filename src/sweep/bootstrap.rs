//! The mean of a measure over seeds with a 90 % bootstrap interval, Continual
//! World's convention (Wołczyk et al., 2021): the seeds' values are resampled
//! with replacement [`RESAMPLES`] times, and the interval runs from the 5th to
//! the 95th percentile of the resampled means (linear interpolation between
//! order statistics, as numpy's default percentile). The resampling stream is
//! fixed (`util::Stream::Bootstrap`) and restarts for every estimate, so a
//! collected table is the same every time and does not depend on which other
//! groups or measures it holds.

use crate::util::{derive_seed, Stream};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Resampled means per interval.
pub const RESAMPLES: usize = 10_000;
/// The interval's coverage.
pub const CONFIDENCE: f64 = 0.9;

/// A measure over seeds: its mean and bootstrap interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Mean over the seeds.
    pub mean: f64,
    /// Lower end of the 90 % interval (the mean itself with one seed).
    pub low: f64,
    /// Upper end of the 90 % interval.
    pub high: f64,
    /// Seeds it is over.
    pub n: usize,
}

/// The estimate of `values` (one per seed, in a fixed order); None without any.
pub fn estimate(values: &[f64]) -> Option<Estimate> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Some(Estimate { mean, low: mean, high: mean, n });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(0, Stream::Bootstrap));
    let mut means: Vec<f64> =
        (0..RESAMPLES).map(|_| (0..n).map(|_| values[rng.gen_range(0..n)]).sum::<f64>() / n as f64).collect();
    means.sort_by(f64::total_cmp);
    let tail = (1.0 - CONFIDENCE) / 2.0;
    Some(Estimate { mean, low: percentile(&means, tail), high: percentile(&means, 1.0 - tail), n })
}

/// The `q` quantile (0..=1) of sorted `xs`, interpolating linearly between neighbours.
fn percentile(xs: &[f64], q: f64) -> f64 {
    let pos = q * (xs.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    xs[lo] + (xs[hi] - xs[lo]) * (pos - lo as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_seeds_give_their_own_values_as_the_interval() {
        // Resampled means of {a, b}: a (1/4), (a+b)/2 (1/2), b (1/4); the 5th and 95th
        // percentiles fall well inside the first and last quarter.
        let e = estimate(&[0.2, 0.6]).unwrap();
        assert_eq!((e.n, e.low, e.high), (2, 0.2, 0.6));
        assert!((e.mean - 0.4).abs() < 1e-12);
    }

    #[test]
    fn three_seeds_give_the_interval_of_the_exact_resampling_distribution() {
        // Means of three draws from {0, 0, 1}: k/3 with k ~ Binomial(3, 1/3): P(0) = 8/27,
        // P(1/3) = 12/27, P(2/3) = 6/27, P(1) = 1/27, so the 5th percentile is 0 and the
        // 95th is 2/3 (the cumulative share passes 0.95 there, at 26/27).
        let e = estimate(&[0.0, 1.0, 0.0]).unwrap();
        assert_eq!(e.low, 0.0);
        assert!((e.high - 2.0 / 3.0).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn an_estimate_repeats_and_one_seed_has_no_width() {
        let values = [0.31, 0.47, 0.52, 0.29, 0.66];
        let (a, b) = (estimate(&values).unwrap(), estimate(&values).unwrap());
        assert_eq!(a, b);
        assert!(a.low < a.mean && a.mean < a.high && a.low >= 0.29 && a.high <= 0.66, "{a:?}");
        assert_eq!(estimate(&[0.5]).unwrap(), Estimate { mean: 0.5, low: 0.5, high: 0.5, n: 1 });
        assert!(estimate(&[]).is_none());
    }
}
