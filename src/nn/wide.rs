//! Element-wise loops at the CPU's full vector width. The crate is built for
//! baseline x86-64 (so the binary runs on any such CPU), which compiles plain
//! loops to 4-wide SSE. [`wide`] runs a loop body inside a function built for
//! AVX-512 (or AVX2), chosen at run time when the CPU has it, so the body
//! inlined there is compiled 16 (or 8) wide, as gemm's own kernels are.
//!
//! Results do not change: each element's arithmetic is the same IEEE
//! operations in the same order at any width (Rust never contracts a multiply
//! and an add into one fused instruction), and reductions written with fixed
//! lanes keep their order.

/// Runs `f` compiled for the widest vectors the CPU has (see the module header).
#[inline(always)]
pub(crate) fn wide<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, checked just above.
            return unsafe { avx512(f) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { avx2(f) };
        }
    }
    f()
}

/// `wide_fn!(fn name(args) -> R => body)` defines `name`, which calls `body` (an
/// `#[inline(always)]` function of the same arguments) inside functions built for AVX-512 or
/// AVX2, chosen at run time. For loops too large for [`wide`]: LLVM inlines a small closure
/// into `wide`'s target-feature function, but a larger one stays a separate, baseline (SSE)
/// function, while `#[inline(always)]` is always honoured.
macro_rules! wide_fn {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $body:path) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                unsafe fn on_avx512($($arg: $ty),*) $(-> $ret)? {
                    $body($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                unsafe fn on_avx2($($arg: $ty),*) $(-> $ret)? {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU has AVX-512F, checked just above.
                    return unsafe { on_avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has AVX2, checked just above.
                    return unsafe { on_avx2($($arg),*) };
                }
            }
            $body($($arg),*)
        }
    };
}
pub(crate) use wide_fn;

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loop_gives_the_same_bits_at_any_width() {
        let x: Vec<f32> = (0..10_007).map(|i| ((i as f32) * 0.37).sin() * 3.0).collect();
        let body = |x: &[f32]| -> Vec<f32> { x.iter().map(|v| crate::nn::fused::elu(*v) * 1.5 + v * v).collect() };
        let plain = body(&x);
        let widened = wide(|| body(&x));
        assert_eq!(
            plain.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            widened.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}
