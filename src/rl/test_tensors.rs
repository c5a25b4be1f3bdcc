//! Small helpers for the loss tests of `rl`: hand-written tensors and
//! scalar comparisons.

use candle_core::{Device, Tensor};

/// A (rows, len / rows) tensor from row-major values.
pub fn t2(v: &[f32], rows: usize) -> Tensor {
    Tensor::new(v, &Device::Cpu).unwrap().reshape((rows, v.len() / rows)).unwrap()
}

/// The value of a scalar tensor.
pub fn scalar(x: &Tensor) -> f64 {
    f64::from(x.to_scalar::<f32>().unwrap())
}

/// Asserts |a - b| < 1e-5.
pub fn close(a: f64, b: f64) {
    assert!((a - b).abs() < 1e-5, "{a} vs {b}");
}
