//! Running observation statistics (METHOD 2.4 step 5: part of a task's saved
//! state).
//!
//! Per feature: a running mean and (population) variance over every row seen,
//! merged batch by batch with Chan et al.'s parallel update, accumulated in
//! f64. `normalize` maps x to `clip((x - mean) / sqrt(var + eps), +-clip)`.
//! While training a task the statistics follow the data; when the task ends
//! they are frozen and stored with its masks, so recalling that task later
//! normalises exactly as it did when the task ended.

/// Added to the variance before the square root.
pub const NORMALIZER_EPS: f64 = 1e-8;

/// Running mean/variance of a `dim`-wide feature vector.
#[derive(Debug, Clone, PartialEq)]
pub struct RunningNormalizer {
    mean: Vec<f64>,
    var: Vec<f64>,
    count: f64,
    clip: f32,
    frozen: bool,
}

impl RunningNormalizer {
    /// Fresh statistics (mean 0, variance 1, no rows seen) for `dim` features.
    pub fn new(dim: usize, clip: f32) -> Self {
        Self { mean: vec![0.0; dim], var: vec![1.0; dim], count: 0.0, clip, frozen: false }
    }

    /// Rebuilds statistics saved with [`RunningNormalizer::mean`],
    /// [`RunningNormalizer::var`] and [`RunningNormalizer::count`]; they come back frozen.
    pub fn from_saved(mean: &[f32], var: &[f32], count: f64, clip: f32) -> anyhow::Result<Self> {
        anyhow::ensure!(mean.len() == var.len(), "normaliser: mean has {} entries, var {}", mean.len(), var.len());
        anyhow::ensure!(var.iter().all(|v| *v >= 0.0 && v.is_finite()), "normaliser: variance must be finite and >= 0");
        Ok(Self {
            mean: mean.iter().map(|&m| f64::from(m)).collect(),
            var: var.iter().map(|&v| f64::from(v)).collect(),
            count,
            clip,
            frozen: true,
        })
    }

    pub fn dim(&self) -> usize {
        self.mean.len()
    }
    /// Per-feature mean, as saved in checkpoints.
    pub fn mean(&self) -> Vec<f32> {
        self.mean.iter().map(|&m| m as f32).collect()
    }
    /// Per-feature population variance, as saved in checkpoints.
    pub fn var(&self) -> Vec<f32> {
        self.var.iter().map(|&v| v as f32).collect()
    }
    /// Per-feature factor of the normalisation, 1 / sqrt(var + eps), rounded to f32 (what a
    /// deployed copy multiplies by; `normalize` keeps it in f64).
    pub fn scale(&self) -> Vec<f32> {
        self.var.iter().map(|v| (1.0 / (v + NORMALIZER_EPS).sqrt()) as f32).collect()
    }
    /// Normalised values are clipped to [-clip, clip].
    pub fn clip(&self) -> f32 {
        self.clip
    }
    /// Rows seen so far.
    pub fn count(&self) -> f64 {
        self.count
    }
    /// Mean, variance and row count at full precision (a training checkpoint's copy: the
    /// policy keeps f32, and a run resumed from f32 statistics would drift from the original).
    pub fn exact(&self) -> (&[f64], &[f64], f64) {
        (&self.mean, &self.var, self.count)
    }
    /// Takes statistics saved with [`Self::exact`]; the width must match and every value be finite.
    pub fn restore_exact(&mut self, mean: Vec<f64>, var: Vec<f64>, count: f64) -> anyhow::Result<()> {
        let dim = self.dim();
        anyhow::ensure!(
            mean.len() == dim && var.len() == dim,
            "normaliser: {} means and {} variances for {dim} features",
            mean.len(),
            var.len()
        );
        anyhow::ensure!(
            mean.iter().all(|m| m.is_finite()) && var.iter().all(|v| v.is_finite() && *v >= 0.0),
            "normaliser: a mean or variance is not finite (or a variance < 0)"
        );
        anyhow::ensure!(count.is_finite() && count >= 0.0, "normaliser: row count {count}");
        (self.mean, self.var, self.count) = (mean, var, count);
        Ok(())
    }
    pub fn is_frozen(&self) -> bool {
        self.frozen
    }
    /// Stops updates (a task ended). The statistics are rounded to f32, the
    /// precision they are saved in, so the live normaliser and one restored
    /// from a checkpoint give bit-identical outputs.
    pub fn freeze(&mut self) {
        self.frozen = true;
        self.mean.iter_mut().for_each(|m| *m = f64::from(*m as f32));
        self.var.iter_mut().for_each(|v| *v = f64::from(*v as f32));
    }
    /// Lets a task that comes back (fine-tuning) update its statistics again.
    pub fn unfreeze(&mut self) {
        self.frozen = false;
    }

    /// Merges a row-major `(rows, dim)` batch into the statistics; does nothing
    /// when frozen. Errors if the batch is not a whole number of rows.
    pub fn update(&mut self, batch: &[f32]) -> anyhow::Result<()> {
        let dim = self.dim();
        anyhow::ensure!(
            dim > 0 && batch.len() % dim == 0,
            "normaliser: batch of {} values is not rows of {dim}",
            batch.len()
        );
        if self.frozen || batch.is_empty() {
            return Ok(());
        }
        let rows = (batch.len() / dim) as f64;
        let mut batch_mean = vec![0.0f64; dim];
        for row in batch.chunks_exact(dim) {
            for (m, &x) in batch_mean.iter_mut().zip(row) {
                *m += f64::from(x);
            }
        }
        batch_mean.iter_mut().for_each(|m| *m /= rows);
        let mut batch_var = vec![0.0f64; dim];
        for row in batch.chunks_exact(dim) {
            for ((v, &x), m) in batch_var.iter_mut().zip(row).zip(&batch_mean) {
                let d = f64::from(x) - m;
                *v += d * d;
            }
        }
        batch_var.iter_mut().for_each(|v| *v /= rows);
        self.merge(&batch_mean, &batch_var, rows);
        Ok(())
    }

    /// Chan et al.'s merge of (mean, var, count) statistics.
    fn merge(&mut self, batch_mean: &[f64], batch_var: &[f64], batch_count: f64) {
        if self.count == 0.0 {
            self.mean.copy_from_slice(batch_mean);
            self.var.copy_from_slice(batch_var);
            self.count = batch_count;
            return;
        }
        let total = self.count + batch_count;
        for i in 0..self.dim() {
            let delta = batch_mean[i] - self.mean[i];
            let m2 = self.var[i] * self.count
                + batch_var[i] * batch_count
                + delta * delta * self.count * batch_count / total;
            self.mean[i] += delta * batch_count / total;
            self.var[i] = m2 / total;
        }
        self.count = total;
    }

    /// Normalises a row-major `(rows, dim)` batch in place.
    pub fn normalize_in_place(&self, batch: &mut [f32]) {
        let dim = self.dim();
        let scale: Vec<f64> = self.var.iter().map(|v| 1.0 / (v + NORMALIZER_EPS).sqrt()).collect();
        for row in batch.chunks_exact_mut(dim) {
            for i in 0..dim {
                let z = ((f64::from(row[i]) - self.mean[i]) * scale[i]) as f32;
                row[i] = z.clamp(-self.clip, self.clip);
            }
        }
    }

    /// A normalised copy of a row-major `(rows, dim)` batch.
    pub fn normalize(&self, batch: &[f32]) -> Vec<f32> {
        let mut out = batch.to_vec();
        self.normalize_in_place(&mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_match_the_whole_data_whatever_the_batching() {
        // Two features; column 0 = 1..=6, column 1 = constant 2.
        let data: Vec<f32> = (1..=6).flat_map(|i| [i as f32, 2.0]).collect();
        let mut whole = RunningNormalizer::new(2, 5.0);
        whole.update(&data).unwrap();
        let mut parts = RunningNormalizer::new(2, 5.0);
        parts.update(&data[..2]).unwrap();
        parts.update(&data[2..8]).unwrap();
        parts.update(&data[8..]).unwrap();
        // mean of 1..6 = 3.5, population variance = 35/12.
        for n in [&whole, &parts] {
            assert!((n.mean()[0] - 3.5).abs() < 1e-6);
            assert!((n.var()[0] - 35.0 / 12.0).abs() < 1e-6, "{:?}", n.var());
            assert_eq!(n.mean()[1], 2.0);
            assert_eq!(n.var()[1], 0.0);
            assert_eq!(n.count(), 6.0);
        }
    }

    #[test]
    fn normalize_centres_scales_and_clips() {
        let mut n = RunningNormalizer::new(1, 1.5);
        n.update(&[1.0, 3.0]).unwrap(); // mean 2, var 1
        let out = n.normalize(&[2.0, 3.0, 10.0, -10.0]);
        assert!(out[0].abs() < 1e-6);
        assert!((out[1] - 1.0).abs() < 1e-6);
        assert_eq!(out[2], 1.5);
        assert_eq!(out[3], -1.5);
    }

    #[test]
    fn frozen_statistics_ignore_new_data_and_survive_saving() {
        let mut n = RunningNormalizer::new(2, 5.0);
        n.update(&[1.0, 2.0, 3.0, 6.0]).unwrap();
        n.freeze();
        let before = n.clone();
        n.update(&[100.0, 100.0]).unwrap();
        assert_eq!(n, before);
        let restored = RunningNormalizer::from_saved(&n.mean(), &n.var(), n.count(), 5.0).unwrap();
        assert!(restored.is_frozen());
        let x = [0.5f32, 7.0];
        assert_eq!(restored.normalize(&x), n.normalize(&x));
    }

    #[test]
    fn a_batch_that_is_not_whole_rows_is_an_error() {
        let mut n = RunningNormalizer::new(3, 5.0);
        assert!(n.update(&[1.0, 2.0]).is_err());
    }
}
