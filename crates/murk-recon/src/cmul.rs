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
        let done = unsafe { avx::mul(p, p, b.as_ptr(), n) };
        return tail(&mut a[done..n], &b[done..n]);
    }
    tail(&mut a[..n], &b[..n]);
}

/// `dst[i] = a[i]·b[i]`.
pub fn mul(dst: &mut [Complex32], a: &[Complex32], b: &[Complex32]) {
    let n = dst.len().min(a.len()).min(b.len());
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: AVX2 and FMA were just detected; `n` bounds every access; `dst` is exclusive.
        done = unsafe { avx::mul(dst.as_mut_ptr(), a.as_ptr(), b.as_ptr(), n) };
    }
    for i in done..n {
        dst[i] = a[i] * b[i];
    }
}

/// Σ a[i]·b[i].
pub fn dot(a: &[Complex32], b: &[Complex32]) -> Complex32 {
    let n = a.len().min(b.len());
    let mut done = 0;
    let mut sum = Complex32::default();
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: AVX2 and FMA were just detected; `n` bounds every access.
        (sum, done) = unsafe { avx::dot(a.as_ptr(), b.as_ptr(), n) };
    }
    a[done..n]
        .iter()
        .zip(&b[done..n])
        .fold(sum, |s, (a, b)| s + a * b)
}

/// `acc += a·phase`, then `phase *= step`: a point-side phase applied and advanced to the next
/// frequency in one pass, so the phases are read and written once per frequency, not twice.
pub fn mul_add_advance(
    acc: &mut [Complex32],
    a: &[Complex32],
    phase: &mut [Complex32],
    step: &[Complex32],
) {
    let n = acc.len().min(a.len()).min(phase.len()).min(step.len());
    let scalar = |from: usize, acc: &mut [Complex32], phase: &mut [Complex32]| {
        for i in from..n {
            acc[i] += a[i] * phase[i];
            phase[i] *= step[i];
        }
    };
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: AVX2 and FMA were just detected; all four slices hold at least n values.
        let done = unsafe {
            avx::mul_add_advance(
                acc.as_mut_ptr(),
                a.as_ptr(),
                phase.as_mut_ptr(),
                step.as_ptr(),
                n,
            )
        };
        return scalar(done, acc, phase);
    }
    scalar(0, acc, phase)
}

/// `a[i] += b[i]`.
pub fn add_assign(a: &mut [Complex32], b: &[Complex32]) {
    murk_core::simd::wide(
        #[inline(always)]
        || a.iter_mut().zip(b).for_each(|(a, b)| *a += b),
    );
}

/// The interleaved (re, im) floats of complex values.
pub fn floats(v: &[Complex32]) -> &[f32] {
    // SAFETY: num-complex's Complex<f32> is #[repr(C)] {re, im}: n of them are 2n f32, same alignment.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast(), 2 * v.len()) }
}

/// [`floats`], to write.
pub fn floats_mut(v: &mut [Complex32]) -> &mut [f32] {
    // SAFETY: as in `floats`; the borrow is exclusive for the returned slice's lifetime.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr().cast(), 2 * v.len()) }
}

fn tail(d: &mut [Complex32], b: &[Complex32]) {
    d.iter_mut().zip(b).for_each(|(d, b)| *d *= b);
}

#[cfg(target_arch = "x86_64")]
mod avx {
    //! Each function handles the largest multiple of 4 values below `n`.
    //!
    //! # Safety (every function)
    //! AVX2 and FMA must be available, and every pointer valid for `n` values; an output may equal
    //! an input (each group of four is read before it is written).

    use rustfft::num_complex::Complex32;
    use std::arch::x86_64::*;

    /// The product of four complex values in each of `a` and `b`.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn product(a: __m256, b: __m256) -> __m256 {
        let br = _mm256_moveldup_ps(b);
        let bi = _mm256_movehdup_ps(b);
        let swapped = _mm256_permute_ps(a, 0b10_11_00_01);
        _mm256_fmaddsub_ps(a, br, _mm256_mul_ps(swapped, bi))
    }

    /// [`super::mul_add_advance`] over the first n/4·4 values; returns how many it did.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn mul_add_advance(
        acc: *mut Complex32,
        a: *const Complex32,
        phase: *mut Complex32,
        step: *const Complex32,
        n: usize,
    ) -> usize {
        let (acc, a, phase, step) = (
            acc as *mut f32,
            a as *const f32,
            phase as *mut f32,
            step as *const f32,
        );
        let full = n / 4 * 4;
        let mut i = 0;
        while i < full {
            let p = _mm256_loadu_ps(phase.add(2 * i));
            let sum = _mm256_add_ps(
                _mm256_loadu_ps(acc.add(2 * i)),
                product(_mm256_loadu_ps(a.add(2 * i)), p),
            );
            _mm256_storeu_ps(acc.add(2 * i), sum);
            _mm256_storeu_ps(
                phase.add(2 * i),
                product(p, _mm256_loadu_ps(step.add(2 * i))),
            );
            i += 4;
        }
        full
    }

    /// [`super::dot`] over the first n/4·4 values, and how many that is.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn dot(a: *const Complex32, b: *const Complex32, n: usize) -> (Complex32, usize) {
        let (a, b) = (a as *const f32, b as *const f32);
        let full = n / 4 * 4;
        let mut acc = _mm256_setzero_ps();
        let mut i = 0;
        while i < full {
            let p = product(_mm256_loadu_ps(a.add(2 * i)), _mm256_loadu_ps(b.add(2 * i)));
            acc = _mm256_add_ps(acc, p);
            i += 4;
        }
        // The four lanes' complex sums: high half onto low, then the second complex onto the first.
        let half = _mm_add_ps(_mm256_castps256_ps128(acc), _mm256_extractf128_ps(acc, 1));
        let pair = _mm_add_ps(half, _mm_movehl_ps(half, half));
        let mut out = [0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), pair);
        (Complex32::new(out[0], out[1]), full)
    }

    /// `dst = a·b` over the first n/4·4 values; returns how many it did.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn mul(
        dst: *mut Complex32,
        a: *const Complex32,
        b: *const Complex32,
        n: usize,
    ) -> usize {
        let (d, a, b) = (dst as *mut f32, a as *const f32, b as *const f32);
        let full = n / 4 * 4;
        let mut i = 0;
        while i < full {
            let p = product(_mm256_loadu_ps(a.add(2 * i)), _mm256_loadu_ps(b.add(2 * i)));
            _mm256_storeu_ps(d.add(2 * i), p);
            i += 4;
        }
        full
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustfft::num_complex::Complex64;

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
            mul(&mut d, &a, &b);
            assert!(close(&d, &want), "mul, n = {n}");
            // Against an f64 sum, within f32 rounding of the terms' magnitudes.
            let got = dot(&a, &b);
            let wide = |v: Complex32| Complex64::new(v.re as f64, v.im as f64);
            let want_dot: Complex64 = want.iter().map(|&w| wide(w)).sum();
            let scale: f64 = want.iter().map(|w| w.norm() as f64).sum();
            let err = (wide(got) - want_dot).norm();
            assert!(err <= 1e-6 * scale.max(1.0), "dot, n = {n}: {err}");
            let (mut d, mut p) = (c.clone(), a.clone());
            mul_add_advance(&mut d, &b, &mut p, &c);
            let want_add: Vec<Complex32> = c.iter().zip(&want).map(|(c, w)| c + w).collect();
            let want_p: Vec<Complex32> = a.iter().zip(&c).map(|(a, c)| a * c).collect();
            assert!(close(&d, &want_add), "mul_add_advance's sum, n = {n}");
            assert!(close(&p, &want_p), "mul_add_advance's phase, n = {n}");
        }
    }
}
