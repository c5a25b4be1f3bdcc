//! The matrix product on slices that the fused MLP op runs: gemm (f32, its
//! AVX-512 or AVX2 kernels chosen at run time) into a row-major (m, n)
//! destination, A (m, k) and B (k, n) read through (column stride, row
//! stride) views of slices, so transposes cost nothing. `matmul` writes into
//! a given matrix (optionally adding to it); `product` returns a new one that
//! gemm writes without it being zeroed first (a zeroing pass over a fresh
//! (1536, 512) gradient was 1 % of a training iteration).

use gemm::{gemm, Parallelism};

/// The threads one product runs on: candle's setting (the binary pins it at 1,
/// as each network's products already run on their own core).
pub(crate) fn parallelism() -> Parallelism {
    match candle_core::utils::get_num_threads() {
        1 => Parallelism::None,
        n => Parallelism::Rayon(n),
    }
}

/// Panics unless the (m, k) view of `a` and the (k, n) view of `b` lie inside their slices.
#[allow(clippy::too_many_arguments)]
fn check_views(m: usize, n: usize, k: usize, a: &[f32], a_cs: usize, a_rs: usize, b: &[f32], b_cs: usize, b_rs: usize) {
    // The last element each view reaches must lie inside its slice.
    let last = |rows: usize, cols: usize, cs: usize, rs: usize| (rows.max(1) - 1) * rs + (cols.max(1) - 1) * cs;
    assert!(m * k == 0 || last(m, k, a_cs, a_rs) < a.len(), "matmul: A ({m} x {k}) out of bounds");
    assert!(k * n == 0 || last(k, n, b_cs, b_rs) < b.len(), "matmul: B ({k} x {n}) out of bounds");
}

/// gemm into the (m, n) row-major matrix at `dst`: dst = (dst if `keep_dst`) + A B.
///
/// # Safety
/// `dst` must be valid for writes of m * n elements (and for reads when `keep_dst`),
/// not aliased by `a` or `b`, and the views must have passed [`check_views`].
#[allow(clippy::too_many_arguments)]
unsafe fn gemm_into(
    m: usize,
    n: usize,
    k: usize,
    dst: *mut f32,
    keep_dst: bool,
    a: &[f32],
    a_cs: usize,
    a_rs: usize,
    b: &[f32],
    b_cs: usize,
    b_rs: usize,
    par: Parallelism,
) {
    // With read_dst false gemm neither reads dst nor scales it: it writes A B.
    gemm(
        m,
        n,
        k,
        dst,
        1,
        n as isize,
        keep_dst,
        a.as_ptr(),
        a_cs as isize,
        a_rs as isize,
        b.as_ptr(),
        b_cs as isize,
        b_rs as isize,
        if keep_dst { 1.0 } else { 0.0 },
        1.0,
        false,
        false,
        false,
        par,
    )
}

/// dst (m, n) row-major = (dst if `keep_dst`) + A B, with A (m, k) and B (k, n) given as
/// slices with their (column stride, row stride), on `par` threads (gemm's result does
/// not depend on it). Panics if a view is out of bounds.
#[allow(clippy::too_many_arguments)]
pub fn matmul(
    m: usize,
    n: usize,
    k: usize,
    dst: &mut [f32],
    keep_dst: bool,
    a: &[f32],
    a_cs: usize,
    a_rs: usize,
    b: &[f32],
    b_cs: usize,
    b_rs: usize,
    par: Parallelism,
) {
    assert!(dst.len() >= m * n, "matmul: dst holds {} of {m} x {n}", dst.len());
    check_views(m, n, k, a, a_cs, a_rs, b, b_cs, b_rs);
    // SAFETY: dst is an exclusive slice of at least m * n elements and the views are checked.
    unsafe { gemm_into(m, n, k, dst.as_mut_ptr(), keep_dst, a, a_cs, a_rs, b, b_cs, b_rs, par) }
}

/// A new (m, n) row-major matrix A B (views as in [`matmul`]), written once by gemm.
#[allow(clippy::too_many_arguments)]
pub(crate) fn product(
    m: usize,
    n: usize,
    k: usize,
    a: &[f32],
    a_cs: usize,
    a_rs: usize,
    b: &[f32],
    b_cs: usize,
    b_rs: usize,
    par: Parallelism,
) -> Vec<f32> {
    check_views(m, n, k, a, a_cs, a_rs, b, b_cs, b_rs);
    if m * n == 0 || k == 0 {
        // Nothing for gemm to sum: the product is zero.
        return vec![0f32; m * n];
    }
    let mut dst = Vec::<f32>::with_capacity(m * n);
    // SAFETY: the spare capacity holds m * n writable elements that nothing else refers to;
    // gemm without read_dst writes every one of them (A B, k >= 1) and reads none, so all
    // m * n are initialised when the length is set.
    unsafe {
        gemm_into(m, n, k, dst.spare_capacity_mut().as_mut_ptr().cast(), false, a, a_cs, a_rs, b, b_cs, b_rs, par);
        dst.set_len(m * n);
    }
    dst
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(len: usize, prime: usize, modulus: usize) -> Vec<f32> {
        (0..len).map(|i| ((i * prime) % modulus) as f32 / modulus as f32 - 0.5).collect()
    }

    #[test]
    fn matrix_products_do_not_depend_on_the_thread_count() {
        let (m, n, k) = (300, 200, 1000);
        let (a, b) = (sample(m * k, 7919, 1000), sample(k * n, 104729, 997));
        let run = |par: Parallelism| {
            let mut dst = vec![0f32; m * n];
            matmul(m, n, k, &mut dst, false, &a, 1, k, &b, 1, n, par);
            dst.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        let single = run(Parallelism::None);
        assert!(single == run(Parallelism::Rayon(2)), "2 threads differ from 1");
        assert!(single == run(Parallelism::Rayon(3)), "3 threads differ from 1");
    }

    #[test]
    fn a_new_product_is_every_element_of_the_product_into_a_zeroed_matrix() {
        // A transposed view of A (column stride m), as the weight gradient reads it.
        let (m, n, k) = (257, 129, 300);
        let (a, b) = (sample(m * k, 7919, 1000), sample(k * n, 104729, 997));
        let mut zeroed = vec![0f32; m * n];
        matmul(m, n, k, &mut zeroed, false, &a, m, 1, &b, 1, n, Parallelism::None);
        for _ in 0..3 {
            // Leave NaNs in freed memory of that size: the allocator may hand it back.
            drop(vec![f32::NAN; m * n]);
            let fresh = product(m, n, k, &a, m, 1, &b, 1, n, Parallelism::None);
            assert_eq!(fresh.len(), m * n);
            assert!(fresh.iter().zip(&zeroed).all(|(x, y)| x.to_bits() == y.to_bits()), "an element differs");
        }
        assert_eq!(product(3, 2, 0, &[], 1, 0, &[], 1, 2, Parallelism::None), vec![0f32; 6], "k = 0 gives zeros");
    }

    #[test]
    #[should_panic(expected = "out of bounds")]
    fn a_matrix_view_beyond_its_slice_is_refused() {
        let (a, b) = (vec![1f32; 6], vec![1f32; 6]);
        let mut dst = vec![0f32; 4];
        // A claims (2, 4) with row stride 4: 8 elements, the slice has 6.
        matmul(2, 2, 4, &mut dst, false, &a, 1, 4, &b, 1, 2, Parallelism::None);
    }
}
