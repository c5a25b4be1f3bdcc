//! Matrix-product rates for `quadcl bench`: GFLOP/s of the `gemm` kernel the
//! fused MLP op calls (`nn::MatrixProduct`), on the products one PPO minibatch of the base config
//! really has (batch 1536 = 3072 transitions / 2 minibatches; the actor's
//! 64 -> 512 -> 256 -> 128 -> 12 layers), with the fused op's operand layouts:
//! forward z = h W^T, backward dW = g^T h and g_prev = g W. Plus the
//! 1536x512x256 product of issue 15 in plain row-major layout.
//!
//! Keys: `gemm_gflops_square` (1536x512 . 512x256), `gemm_gflops_fwd_512x256`,
//! `gemm_gflops_dw_512x256`, `gemm_gflops_dx_512x256`, `gemm_gflops_fwd_64x512`,
//! `gemm_gflops_fwd_128x12`, `gemm_gflops_dw_64x512`; and `gemm_kernel`
//! (`avx512` when the CPU has AVX-512F, which gemm's `x86-v4` kernels use).

use gemm::Parallelism;
use quadcl::nn::MatrixProduct;
use serde_json::json;
use std::time::Instant;

const BATCH: usize = 1536;

/// One product shape: dst (m, n) = A (m, k) B (k, n), with A and B given by (col stride, row stride).
struct Product {
    key: &'static str,
    m: usize,
    n: usize,
    k: usize,
    a: (usize, usize),
    b: (usize, usize),
}

fn products() -> Vec<Product> {
    // Forward: h (B, in) row-major times W^T with W (out, in) row-major: b = (in, 1).
    let fwd = |key, fan_in: usize, width: usize| Product {
        key,
        m: BATCH,
        n: width,
        k: fan_in,
        a: (1, fan_in),
        b: (fan_in, 1),
    };
    // dW (out, in) = g^T (out, B) h (B, in): a is g (B, out) read transposed.
    let dw = |key, fan_in: usize, width: usize| Product {
        key,
        m: width,
        n: fan_in,
        k: BATCH,
        a: (width, 1),
        b: (1, fan_in),
    };
    vec![
        Product { key: "gemm_gflops_square", m: BATCH, n: 256, k: 512, a: (1, 512), b: (1, 256) },
        fwd("gemm_gflops_fwd_512x256", 512, 256),
        dw("gemm_gflops_dw_512x256", 512, 256),
        // g_prev (B, in) = g (B, out) W (out, in).
        Product { key: "gemm_gflops_dx_512x256", m: BATCH, n: 512, k: 256, a: (1, 256), b: (1, 512) },
        fwd("gemm_gflops_fwd_64x512", 64, 512),
        fwd("gemm_gflops_fwd_128x12", 128, 12),
        dw("gemm_gflops_dw_64x512", 64, 512),
    ]
}

fn rate(p: &Product, seconds: f64, par: Parallelism) -> f64 {
    let a: Vec<f32> = (0..p.m * p.k).map(|i| ((i * 7919) % 1000) as f32 / 1000.0 - 0.5).collect();
    let b: Vec<f32> = (0..p.k * p.n).map(|i| ((i * 104_729) % 997) as f32 / 997.0 - 0.5).collect();
    let mut dst = vec![0f32; p.m * p.n];
    let product = MatrixProduct::new((p.m, p.n, p.k), &a, p.a, &b, p.b);
    let mut run = || product.write_to(&mut dst, par);
    run();
    let (start, mut count) = (Instant::now(), 0usize);
    while count < 5 || start.elapsed().as_secs_f64() < seconds {
        run();
        count += 1;
    }
    let flops = 2.0 * (p.m * p.n * p.k) as f64 * count as f64;
    flops / start.elapsed().as_secs_f64() / 1e9
}

/// Adds the `gemm_*` keys, on all threads (as the fused op runs them).
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let threads = candle_core::utils::get_num_threads();
    let par = if threads == 1 { Parallelism::None } else { Parallelism::Rayon(threads) };
    let shapes = products();
    for p in &shapes {
        report.insert(p.key.into(), json!(rate(p, seconds / shapes.len() as f64, par).round()));
    }
    #[cfg(target_arch = "x86_64")]
    let avx512 = std::arch::is_x86_feature_detected!("avx512f");
    #[cfg(not(target_arch = "x86_64"))]
    let avx512 = false;
    let kernel = if avx512 { "avx512" } else { "avx2 or older" };
    report.insert("gemm_kernel".into(), json!(kernel));
    Ok(())
}
