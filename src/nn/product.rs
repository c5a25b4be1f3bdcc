//! The matrix product on slices that the fused MLP op runs: gemm (f32, its
//! AVX-512 or AVX2 kernels chosen at run time) into a row-major (m, n)
//! destination, A (m, k) and B (k, n) read through (column stride, row
//! stride) views of slices, so transposes cost nothing. A [`MatrixProduct`]
//! is written into a given matrix, added to it, or returned as a new one that
//! gemm writes without it being zeroed first (a zeroing pass over a fresh
//! (1536, 512) gradient was 1 % of a training iteration).

use gemm::{gemm, Parallelism};
use std::sync::OnceLock;

/// The threads one product runs on: candle's `get_num_threads` (`RAYON_NUM_THREADS` when
/// set, else the physical cores; the binary's `CANDLE_NUM_THREADS=1` sizes only candle's own
/// kernel pool), read once per process. candle 0.11 reads it anew at every call and, with
/// `RAYON_NUM_THREADS` unset, counts the cores by parsing /proc/cpuinfo: about 60,000
/// instructions and a file read per layer product, a fifth of a `quadcl gait` run's
/// instructions (callgrind). gemm's result does not depend on the count.
pub(crate) fn parallelism() -> Parallelism {
    static THREADS: OnceLock<usize> = OnceLock::new();
    match *THREADS.get_or_init(candle_core::utils::get_num_threads) {
        1 => Parallelism::None,
        n => Parallelism::Rayon(n),
    }
}

/// A (m, k) times B (k, n), each read from a slice through its (column stride, row
/// stride) view; gemm's result does not depend on the thread count `par`.
#[derive(Clone, Copy)]
pub struct MatrixProduct<'a> {
    m: usize,
    n: usize,
    k: usize,
    a: &'a [f32],
    a_strides: (usize, usize),
    b: &'a [f32],
    b_strides: (usize, usize),
}

impl<'a> MatrixProduct<'a> {
    /// The product of the (m, k) view of `a` and the (k, n) view of `b`, each given by its
    /// (column stride, row stride). Panics unless both views lie inside their slices.
    pub fn new(
        (m, n, k): (usize, usize, usize),
        a: &'a [f32],
        a_strides: (usize, usize),
        b: &'a [f32],
        b_strides: (usize, usize),
    ) -> Self {
        // The last element each view reaches must lie inside its slice.
        let last = |rows: usize, cols: usize, (cs, rs): (usize, usize)| (rows.max(1) - 1) * rs + (cols.max(1) - 1) * cs;
        assert!(m * k == 0 || last(m, k, a_strides) < a.len(), "MatrixProduct: A ({m} x {k}) out of bounds");
        assert!(k * n == 0 || last(k, n, b_strides) < b.len(), "MatrixProduct: B ({k} x {n}) out of bounds");
        Self { m, n, k, a, a_strides, b, b_strides }
    }

    /// dst (m, n) row-major = A B. Panics if dst holds fewer than m * n elements.
    pub fn write_to(&self, dst: &mut [f32], par: Parallelism) {
        self.gemm_to_slice(dst, false, par)
    }

    /// dst (m, n) row-major += A B. Panics if dst holds fewer than m * n elements.
    pub fn add_to(&self, dst: &mut [f32], par: Parallelism) {
        self.gemm_to_slice(dst, true, par)
    }

    /// A new (m, n) row-major matrix A B, written once by gemm (not zeroed first).
    pub fn to_matrix(&self, par: Parallelism) -> Vec<f32> {
        let (m, n) = (self.m, self.n);
        if m * n == 0 || self.k == 0 {
            // Nothing for gemm to sum: the product is zero.
            return vec![0f32; m * n];
        }
        let mut dst = Vec::<f32>::with_capacity(m * n);
        // SAFETY: the spare capacity holds m * n writable elements that nothing else refers
        // to; gemm without read_dst writes every one of them (A B, k >= 1) and reads none, so
        // all m * n are initialised when the length is set.
        unsafe {
            self.gemm_into(dst.spare_capacity_mut().as_mut_ptr().cast(), false, par);
            dst.set_len(m * n);
        }
        dst
    }

    fn gemm_to_slice(&self, dst: &mut [f32], keep_dst: bool, par: Parallelism) {
        let (m, n) = (self.m, self.n);
        assert!(dst.len() >= m * n, "MatrixProduct: dst holds {} of {m} x {n}", dst.len());
        // SAFETY: dst is an exclusive slice of at least m * n elements; `new` checked the views.
        unsafe { self.gemm_into(dst.as_mut_ptr(), keep_dst, par) }
    }

    /// gemm into the (m, n) row-major matrix at `dst`: dst = (dst if `keep_dst`) + A B.
    ///
    /// # Safety
    /// `dst` must be valid for writes of m * n elements (and for reads when `keep_dst`) and
    /// not aliased by A or B.
    unsafe fn gemm_into(&self, dst: *mut f32, keep_dst: bool, par: Parallelism) {
        let Self { m, n, k, a, a_strides: (a_cs, a_rs), b, b_strides: (b_cs, b_rs) } = *self;
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(len: usize, prime: usize, modulus: usize) -> Vec<f32> {
        (0..len).map(|i| ((i * prime) % modulus) as f32 / modulus as f32 - 0.5).collect()
    }

    fn bits(v: &[f32]) -> Vec<u32> {
        v.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn matrix_products_do_not_depend_on_the_thread_count() {
        let (m, n, k) = (300, 200, 1000);
        let (a, b) = (sample(m * k, 7919, 1000), sample(k * n, 104729, 997));
        let run = |par: Parallelism| {
            let mut dst = vec![0f32; m * n];
            MatrixProduct::new((m, n, k), &a, (1, k), &b, (1, n)).write_to(&mut dst, par);
            bits(&dst)
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
        let product = MatrixProduct::new((m, n, k), &a, (m, 1), &b, (1, n));
        let mut zeroed = vec![0f32; m * n];
        product.write_to(&mut zeroed, Parallelism::None);
        for _ in 0..3 {
            // Leave NaNs in freed memory of that size: the allocator may hand it back.
            drop(vec![f32::NAN; m * n]);
            let fresh = product.to_matrix(Parallelism::None);
            assert_eq!(fresh.len(), m * n);
            assert!(bits(&fresh) == bits(&zeroed), "an element differs");
        }
        let empty = MatrixProduct::new((3, 2, 0), &[], (1, 0), &[], (1, 2));
        assert_eq!(empty.to_matrix(Parallelism::None), vec![0f32; 6], "k = 0 gives zeros");
    }

    #[test]
    fn adding_a_product_adds_it_to_what_the_matrix_held() {
        let (m, n, k) = (5, 3, 4);
        let (a, b) = (sample(m * k, 7919, 1000), sample(k * n, 104729, 997));
        let product = MatrixProduct::new((m, n, k), &a, (1, k), &b, (1, n));
        let mut sum = vec![0.25f32; m * n];
        product.add_to(&mut sum, Parallelism::None);
        for i in 0..m {
            for j in 0..n {
                let expected = 0.25 + (0..k).map(|l| a[i * k + l] * b[l * n + j]).sum::<f32>();
                assert!((sum[i * n + j] - expected).abs() < 1e-5, "({i}, {j}): {} vs {expected}", sum[i * n + j]);
            }
        }
    }

    #[test]
    #[should_panic(expected = "out of bounds")]
    fn a_matrix_view_beyond_its_slice_is_refused() {
        let (a, b) = (vec![1f32; 6], vec![1f32; 6]);
        // A claims (2, 4) with row stride 4: 8 elements, the slice has 6.
        MatrixProduct::new((2, 2, 4), &a, (1, 4), &b, (1, 2));
    }
}
