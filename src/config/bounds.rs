//! One check per kind of bound, shared by every file and option that reads a
//! number (`[env]`, `[net]`, `[ppo]`, `[method.NAME]`, shift files, the command
//! line), so every error reads alike: `KEY = VALUE: expected ...`, where KEY is
//! the key (`ppo.gamma`) or the option (`--seconds`). Files add their name as
//! context when they load.
//!
//! NaN and the infinities are outside every [`Interval`]: a number that reaches
//! the simulator or the networks is always finite.

use std::fmt;

/// Where a number must lie; always finite as well.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Interval {
    /// Any finite value.
    Finite,
    /// `> lo`.
    Above(f64),
    /// `>= lo`.
    AtLeast(f64),
    /// `[lo, hi]`.
    Closed(f64, f64),
    /// `(lo, hi]`.
    OpenClosed(f64, f64),
}

/// `[0, 1]`: shares, probabilities, discount factors.
pub const UNIT: Interval = Interval::Closed(0.0, 1.0);
/// `(0, 1]`: a share that must keep something (a capacity, a kept fraction).
pub const POSITIVE_UNIT: Interval = Interval::OpenClosed(0.0, 1.0);
/// `> 0`.
pub const POSITIVE: Interval = Interval::Above(0.0);
/// `>= 0`.
pub const NON_NEGATIVE: Interval = Interval::AtLeast(0.0);

impl Interval {
    /// Whether `v` is finite and inside.
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Self::Finite => true,
                Self::Above(lo) => v > lo,
                Self::AtLeast(lo) => v >= lo,
                Self::Closed(lo, hi) => lo <= v && v <= hi,
                Self::OpenClosed(lo, hi) => lo < v && v <= hi,
            }
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Finite => f.write_str("a finite value"),
            Self::Above(lo) => write!(f, "a finite value > {lo}"),
            Self::AtLeast(lo) => write!(f, "a finite value >= {lo}"),
            Self::Closed(lo, hi) => write!(f, "a value in [{lo}, {hi}]"),
            Self::OpenClosed(lo, hi) => write!(f, "a value in ({lo}, {hi}]"),
        }
    }
}

/// Checks that `value` (of key or option `key`) is finite and in `interval`.
pub fn check<T: Into<f64> + fmt::Display + Copy>(key: &str, value: T, interval: Interval) -> anyhow::Result<()> {
    anyhow::ensure!(interval.contains(value.into()), "{key} = {value}: expected {interval}");
    Ok(())
}

/// Checks a `[low, high]` range: both ends in `interval`, low <= high.
pub fn check_range<T: Into<f64> + fmt::Display + Copy + PartialOrd>(
    key: &str,
    [lo, hi]: [T; 2],
    interval: Interval,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        interval.contains(lo.into()) && interval.contains(hi.into()) && lo <= hi,
        "{key} = [{lo}, {hi}]: expected [low, high] with low <= high, each {interval}"
    );
    Ok(())
}

/// Checks a count: `lo <= value <= hi`.
pub fn check_count(key: &str, value: usize, lo: usize, hi: usize) -> anyhow::Result<()> {
    anyhow::ensure!((lo..=hi).contains(&value), "{key} = {value}: expected at least {lo} and at most {hi}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_are_outside_every_interval_and_the_error_names_key_value_and_interval() {
        for interval in [Interval::Finite, POSITIVE, NON_NEGATIVE, UNIT, POSITIVE_UNIT] {
            for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                assert!(!interval.contains(v), "{interval}: {v}");
            }
        }
        assert!(POSITIVE_UNIT.contains(1.0) && !POSITIVE_UNIT.contains(0.0) && UNIT.contains(0.0));
        let err = check("ppo.gamma", 1.5, UNIT).unwrap_err().to_string();
        assert_eq!(err, "ppo.gamma = 1.5: expected a value in [0, 1]");
        let err = check("env.kp", f32::NAN, POSITIVE).unwrap_err().to_string();
        assert_eq!(err, "env.kp = NaN: expected a finite value > 0");
        let err = check_range("env.cmd_vx", [1.0f32, -1.0], Interval::Finite).unwrap_err().to_string();
        assert!(err.starts_with("env.cmd_vx = [1, -1]: expected [low, high] with low <= high"), "{err}");
        let err = check_count("ppo.epochs", 0, 1, 1000).unwrap_err().to_string();
        assert_eq!(err, "ppo.epochs = 0: expected at least 1 and at most 1000");
        check_count("ppo.epochs", 1000, 1, 1000).unwrap();
    }
}
