//! Element-wise complex products over slices, with an AVX2 + FMA kernel where the CPU has one: LLVM
//! wraps num-complex's product in lane shuffles.

#[cfg(target_arch = "x86_64")]
use murk_core::simd::has_avx2_fma;
use rustfft::num_complex::Complex32;

/// `a[i] *= b[i]`.
pub fn mul_assign(a: &mut [Complex32], b: &[Complex32]) {
    let n = a.len().min(b.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        let p = a.as_mut_ptr();
        // SAFETY: AVX2 and FMA were just detected; `n` bounds every access; in place is allowed.
        let done = unsafe { avx::mul(p, p, b.as_ptr(), n, false) };
        return tail(&mut a[done..n], &b[done..n]);
    }
    tail(&mut a[..n], &b[..n]);
}

/// `dst[i] += a[i] · b[i]`.
pub fn mul_add(dst: &mut [Complex32], a: &[Complex32], b: &[Complex32]) {
    let n = dst.len().min(a.len()).min(b.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: as in `mul_assign`; `dst` does not alias `a` or `b` (borrow rules).
        let done = unsafe { avx::mul(dst.as_mut_ptr(), a.as_ptr(), b.as_ptr(), n, true) };
        return tail2(&mut dst[done..n], &a[done..n], &b[done..n]);
    }
    tail2(&mut dst[..n], &a[..n], &b[..n]);
}

/// `a[i] += b[i]`.
pub fn add_assign(a: &mut [Complex32], b: &[Complex32]) {
    murk_core::simd::wide(
        #[inline(always)]
        || a.iter_mut().zip(b).for_each(|(a, b)| *a += b),
    );
}

fn tail(d: &mut [Complex32], b: &[Complex32]) {
    d.iter_mut().zip(b).for_each(|(d, b)| *d *= b);
}

fn tail2(d: &mut [Complex32], a: &[Complex32], b: &[Complex32]) {
    d.iter_mut()
        .zip(a.iter().zip(b))
        .for_each(|(d, (a, b))| *d += a * b);
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use rustfft::num_complex::Complex32;
    use std::arch::x86_64::*;

    /// `dst[i] = a[i]·b[i]` (or `+=` when `add`) for the largest multiple of 4 below `n`; returns it.
    /// `dst` may equal `a` (each group of four is read before it is written).
    ///
    /// # Safety
    /// AVX2 and FMA must be available, and `dst`, `a`, `b` valid for `n` elements.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn mul(
        dst: *mut Complex32,
        a: *const Complex32,
        b: *const Complex32,
        n: usize,
        add: bool,
    ) -> usize {
        // Complex32 is #[repr(C)] {re, im}: four of them are eight interleaved f32.
        let (d, a, b) = (dst as *mut f32, a as *const f32, b as *const f32);
        let full = n / 4 * 4;
        let mut i = 0;
        while i < full {
            let va = _mm256_loadu_ps(a.add(2 * i));
            let vb = _mm256_loadu_ps(b.add(2 * i));
            // (ar·br − ai·bi, ai·br + ar·bi) per lane pair.
            let br = _mm256_moveldup_ps(vb);
            let bi = _mm256_movehdup_ps(vb);
            let swapped = _mm256_permute_ps(va, 0b10_11_00_01);
            let mut p = _mm256_fmaddsub_ps(va, br, _mm256_mul_ps(swapped, bi));
            if add {
                p = _mm256_add_ps(p, _mm256_loadu_ps(d.add(2 * i)));
            }
            _mm256_storeu_ps(d.add(2 * i), p);
            i += 4;
        }
        full
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(n: usize, seed: f32) -> Vec<Complex32> {
        (0..n)
            .map(|i| Complex32::new((i as f32 * seed).sin(), (i as f32 * 0.7 + seed).cos()))
            .collect()
    }

    #[test]
    fn products_match_scalar_for_every_tail_length() {
        for n in [0, 1, 3, 4, 5, 8, 13, 270] {
            let (a, b, c) = (data(n, 0.3), data(n, 1.1), data(n, 2.3));
            let want: Vec<Complex32> = a.iter().zip(&b).map(|(a, b)| a * b).collect();
            let close = |got: &[Complex32], want: &[Complex32]| {
                got.iter().zip(want).all(|(g, w)| (g - w).norm() <= 1e-6)
            };
            let mut d = a.clone();
            mul_assign(&mut d, &b);
            assert!(close(&d, &want), "mul_assign, n = {n}");
            let mut d = c.clone();
            mul_add(&mut d, &a, &b);
            let want_add: Vec<Complex32> = c.iter().zip(&want).map(|(c, w)| c + w).collect();
            assert!(close(&d, &want_add), "mul_add, n = {n}");
        }
    }
}
