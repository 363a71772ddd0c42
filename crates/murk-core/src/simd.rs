//! Runtime CPU dispatch for hot loops: the closure is compiled a second time for AVX2 + FMA and that
//! copy runs where the CPU has them. Portable builds otherwise stop at SSE2, which halves the width of
//! every vectorised loop on the machines murk targets.

/// Runs `f`, vectorised for AVX2 + FMA when this CPU supports them. Keep `f` small and self-contained
/// (plain loops over slices) and mark it `#[inline(always)]` (`wide(#[inline(always)] || …)`): only
/// code inlined into the AVX2 copy gets the wider instructions, and LLVM does not always inline a
/// closure on its own.
#[inline]
pub fn wide<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        if has_avx2_fma() {
            // SAFETY: the features `avx2_fma` is compiled for were just detected on this CPU.
            return unsafe { avx2_fma(f) };
        }
    }
    f()
}

/// Whether this CPU has AVX2 and FMA (for hand-written kernels that `wide` cannot express).
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn avx2_fma<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(test)]
mod tests {
    #[test]
    fn wide_runs_the_closure_once_and_returns_its_value() {
        let mut calls = 0;
        let v: Vec<f32> = (0..37).map(|i| i as f32).collect();
        let s = super::wide(|| {
            calls += 1;
            v.iter().map(|x| x * 2.0).sum::<f32>()
        });
        assert_eq!((calls, s), (1, 37.0 * 36.0));
    }
}
