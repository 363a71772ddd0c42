//! 2-D complex FFTs built from rustfft row transforms and blocked transposes, with caller-owned buffers.
//! The forward transform leaves its spectrum transposed ([ky][kx]); the inverse expects that layout, so a
//! forward/multiply/inverse round trip costs two transposes instead of four, each of only the lines and
//! columns that are read.

use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::ops::Range;
use std::sync::Arc;

pub struct Fft2 {
    pub fx: usize,
    pub fy: usize,
    fwd_x: Arc<dyn Fft<f32>>,
    fwd_y: Arc<dyn Fft<f32>>,
    inv_x: Arc<dyn Fft<f32>>,
    inv_y: Arc<dyn Fft<f32>>,
    scratch_len: usize,
}

impl Fft2 {
    pub fn new(fx: usize, fy: usize) -> Self {
        let mut p = FftPlanner::new();
        let (fwd_x, fwd_y, inv_x, inv_y) = (
            p.plan_fft_forward(fx),
            p.plan_fft_forward(fy),
            p.plan_fft_inverse(fx),
            p.plan_fft_inverse(fy),
        );
        let scratch_len = [&fwd_x, &fwd_y, &inv_x, &inv_y]
            .iter()
            .map(|f| f.get_inplace_scratch_len())
            .max()
            .unwrap_or(0);
        Fft2 {
            fx,
            fy,
            fwd_x,
            fwd_y,
            inv_x,
            inv_y,
            scratch_len,
        }
    }

    pub fn scratch(&self) -> Vec<Complex32> {
        vec![Complex32::default(); self.scratch_len]
    }

    /// `a` is [x][y] (fx rows of fy); the spectrum is written to `t` as [ky][kx]. `a` is clobbered.
    #[cfg(test)]
    pub fn forward(&self, a: &mut [Complex32], t: &mut [Complex32], scratch: &mut [Complex32]) {
        self.forward_lines(a, self.fx, t, self.fy / 2, scratch);
    }

    /// [`Fft2::forward`] for an `a` whose rows x ≥ `rows` are zero (they are left untouched), on the
    /// lines ky that [`kept_lines`] keeps for `lines` only: the other lines of `t` are left as they
    /// were.
    pub fn forward_lines(
        &self,
        a: &mut [Complex32],
        rows: usize,
        t: &mut [Complex32],
        lines: usize,
        scratch: &mut [Complex32],
    ) {
        let (fx, fy) = (self.fx, self.fy);
        self.fwd_y
            .process_with_scratch(&mut a[..rows * fy], scratch);
        for r in kept_lines(fy, lines) {
            transpose_part(a, fy, 0..fx, r.clone(), t, fx);
            self.fwd_x
                .process_with_scratch(&mut t[r.start * fx..r.end * fx], scratch);
        }
    }

    /// Forward 1-D transforms along y of consecutive rows of length `fy`.
    pub fn rows_y(&self, rows: &mut [Complex32], scratch: &mut [Complex32]) {
        self.fwd_y.process_with_scratch(rows, scratch);
    }

    /// Forward 1-D transforms along x of consecutive lines of length `fx`.
    pub fn rows_x(&self, lines: &mut [Complex32], scratch: &mut [Complex32]) {
        self.fwd_x.process_with_scratch(lines, scratch);
    }

    /// First half of the inverse of [`Fft2::forward`] (unnormalised): along x on the lines of `t`
    /// ([ky][kx]) that [`kept_lines`] keeps for `lines` (the others are neither read nor transformed),
    /// written transposed into `a` ([x][ky], rows of fy) for x ∈ `xs` and the kept ky only; the rest
    /// of `a` is left as it was. `t` is clobbered.
    pub fn inverse_x(
        &self,
        t: &mut [Complex32],
        a: &mut [Complex32],
        xs: Range<usize>,
        lines: usize,
        scratch: &mut [Complex32],
    ) {
        let fx = self.fx;
        for r in kept_lines(self.fy, lines) {
            self.inv_x
                .process_with_scratch(&mut t[r.start * fx..r.end * fx], scratch);
            transpose_part(t, fx, r, xs.clone(), a, self.fy);
        }
    }

    /// Inverse 1-D transforms (unnormalised) along x of consecutive lines of length `fx`.
    pub fn inverse_rows_x(&self, lines: &mut [Complex32], scratch: &mut [Complex32]) {
        self.inv_x.process_with_scratch(lines, scratch);
    }

    /// Second half of the inverse (unnormalised): along y on consecutive rows of length fy.
    pub fn inverse_y(&self, rows: &mut [Complex32], scratch: &mut [Complex32]) {
        self.inv_y.process_with_scratch(rows, scratch);
    }
}

/// The lines ky of a spectrum whose distance min(ky, fy − ky) from ky = 0 is at most `lines`, as two
/// ranges (the second empty when they cover all fy).
pub fn kept_lines(fy: usize, lines: usize) -> [Range<usize>; 2] {
    if 2 * lines + 1 >= fy {
        [0..fy, fy..fy]
    } else {
        [0..lines + 1, fy - lines..fy]
    }
}

/// The element ranges of [`kept_lines`] in a [ky][kx] spectrum with lines of `fx`.
pub fn kept_spans(fy: usize, lines: usize, fx: usize) -> [Range<usize>; 2] {
    kept_lines(fy, lines).map(|r| r.start * fx..r.end * fx)
}

/// `dst[c·dst_stride + r] = src[r·src_stride + c]` for r ∈ `rows`, c ∈ `cols`: part of a transpose, in
/// 8 × 8 tiles so that both sides stay in cache.
pub fn transpose_part(
    src: &[Complex32],
    src_stride: usize,
    rows: Range<usize>,
    cols: Range<usize>,
    dst: &mut [Complex32],
    dst_stride: usize,
) {
    const TILE: usize = 8;
    if rows.is_empty() || cols.is_empty() {
        return;
    }
    // Every index below lies within these two bounds.
    assert!((rows.end - 1) * src_stride + cols.end <= src.len());
    assert!((cols.end - 1) * dst_stride + rows.end <= dst.len());
    let (s, d) = (src.as_ptr(), dst.as_mut_ptr());
    #[cfg(target_arch = "x86_64")]
    let avx = murk_core::simd::has_avx2_fma();
    for r0 in rows.clone().step_by(TILE) {
        let r1 = (r0 + TILE).min(rows.end);
        for c0 in cols.clone().step_by(TILE) {
            let c1 = (c0 + TILE).min(cols.end);
            // SAFETY: r < rows.end and c < cols.end, checked against both lengths above.
            unsafe {
                #[cfg(target_arch = "x86_64")]
                if avx && r1 - r0 == TILE && c1 - c0 == TILE {
                    for (r, c) in [(0, 0), (0, 4), (4, 0), (4, 4)] {
                        avx::transpose4(
                            s.add((r0 + r) * src_stride + c0 + c),
                            src_stride,
                            d.add((c0 + c) * dst_stride + r0 + r),
                            dst_stride,
                        );
                    }
                    continue;
                }
                if r1 - r0 == TILE && c1 - c0 == TILE {
                    for c in 0..TILE {
                        for r in 0..TILE {
                            *d.add((c0 + c) * dst_stride + r0 + r) =
                                *s.add((r0 + r) * src_stride + c0 + c);
                        }
                    }
                } else {
                    for c in c0..c1 {
                        for r in r0..r1 {
                            *d.add(c * dst_stride + r) = *s.add(r * src_stride + c);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use rustfft::num_complex::Complex32;
    use std::arch::x86_64::*;

    /// A 4 × 4 block of complex values transposed, each value moved as one 64-bit lane: rows of
    /// `src` (`src_stride` apart) become columns of `dst`.
    ///
    /// # Safety
    /// AVX must be available, and four rows of four values valid at both pointers with their strides.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn transpose4(
        src: *const Complex32,
        src_stride: usize,
        dst: *mut Complex32,
        dst_stride: usize,
    ) {
        let row = |i: usize| _mm256_loadu_pd(src.add(i * src_stride) as *const f64);
        let (a, b, c, d) = (row(0), row(1), row(2), row(3));
        // [a0 b0 a2 b2], [a1 b1 a3 b3], [c0 d0 c2 d2], [c1 d1 c3 d3].
        let (ab0, ab1) = (_mm256_unpacklo_pd(a, b), _mm256_unpackhi_pd(a, b));
        let (cd0, cd1) = (_mm256_unpacklo_pd(c, d), _mm256_unpackhi_pd(c, d));
        let out = [
            _mm256_permute2f128_pd(ab0, cd0, 0x20),
            _mm256_permute2f128_pd(ab1, cd1, 0x20),
            _mm256_permute2f128_pd(ab0, cd0, 0x31),
            _mm256_permute2f128_pd(ab1, cd1, 0x31),
        ];
        for (i, v) in out.into_iter().enumerate() {
            _mm256_storeu_pd(dst.add(i * dst_stride) as *mut f64, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_naive_dft() {
        let (fx, fy) = (6, 10);
        let f = Fft2::new(fx, fy);
        let a0: Vec<Complex32> = (0..fx * fy)
            .map(|i| Complex32::new((i as f32 * 0.37).sin(), (i as f32 * 0.11).cos()))
            .collect();
        let mut a = a0.clone();
        let mut t = vec![Complex32::default(); fx * fy];
        let mut s = f.scratch();
        f.forward(&mut a, &mut t, &mut s);
        // Spectrum entry (kx=2, ky=3) against a naive DFT.
        let (kx, ky) = (2usize, 3usize);
        let mut want = rustfft::num_complex::Complex64::default();
        for x in 0..fx {
            for y in 0..fy {
                let ph = -2.0
                    * std::f64::consts::PI
                    * ((kx * x) as f64 / fx as f64 + (ky * y) as f64 / fy as f64);
                let v = a0[x * fy + y];
                want += rustfft::num_complex::Complex64::new(v.re as f64, v.im as f64)
                    * rustfft::num_complex::Complex64::from_polar(1.0, ph);
            }
        }
        let got = t[ky * fx + kx];
        assert!((got.re as f64 - want.re).abs() < 1e-4 && (got.im as f64 - want.im).abs() < 1e-4);
        f.inverse_x(&mut t, &mut a, 2..5, fy / 2, &mut s);
        f.inverse_y(&mut a[2 * fy..5 * fy], &mut s);
        for r in 2..5 {
            for y in 0..fy {
                let d = a[r * fy + y] / (fx * fy) as f32 - a0[r * fy + y];
                assert!(d.norm() < 1e-5);
            }
        }
    }

    /// Full 8 × 8 tiles and ragged edges against the definition; entries outside the part untouched.
    #[test]
    fn transpose_part_matches_definition() {
        let (rows, cols) = (37, 29);
        let src: Vec<Complex32> = (0..rows * cols)
            .map(|i| Complex32::new(i as f32, -(i as f32)))
            .collect();
        let marker = Complex32::new(-1.0, -1.0);
        let mut dst = vec![marker; cols * rows];
        transpose_part(&src, cols, 3..35, 5..27, &mut dst, rows);
        for c in 0..cols {
            for r in 0..rows {
                let inside = (3..35).contains(&r) && (5..27).contains(&c);
                let want = if inside { src[r * cols + c] } else { marker };
                assert_eq!(dst[c * rows + r], want, "r {r}, c {c}");
            }
        }
    }

    /// With the lines beyond `lines` zero, skipping their transforms (and zero-filling them after the
    /// x half) changes nothing; with them non-zero it would (so the skip is real).
    #[test]
    fn inverse_skips_only_zero_lines() {
        let (fx, fy) = (6, 10);
        let f = Fft2::new(fx, fy);
        let mut s = f.scratch();
        let spec: Vec<Complex32> = (0..fx * fy)
            .map(|i| Complex32::new((i as f32 * 0.29).cos(), (i as f32 * 0.53).sin()))
            .collect();
        let inverse = |t: &[Complex32], lines: usize, s: &mut Vec<Complex32>| {
            let (mut t, mut a) = (t.to_vec(), vec![Complex32::new(9.0, 9.0); fx * fy]);
            f.inverse_x(&mut t, &mut a, 0..fx, lines, s);
            let [lo, hi] = kept_lines(fy, lines);
            for row in a.chunks_exact_mut(fy) {
                row[lo.end..hi.start]
                    .iter_mut()
                    .for_each(|v| *v = Complex32::default());
            }
            f.inverse_y(&mut a, s);
            a
        };
        let mut cut = spec.clone();
        for (ky, line) in cut.chunks_exact_mut(fx).enumerate() {
            if ky.min(fy - ky) > 2 {
                line.iter_mut().for_each(|v| *v = Complex32::default());
            }
        }
        let (full, skipped) = (inverse(&cut, fy / 2, &mut s), inverse(&cut, 2, &mut s));
        assert!(full
            .iter()
            .zip(&skipped)
            .all(|(a, b)| (a - b).norm() < 1e-5));
        let unzeroed = inverse(&spec, 2, &mut s);
        let full = inverse(&spec, fy / 2, &mut s);
        assert!(full
            .iter()
            .zip(&unzeroed)
            .any(|(a, b)| (a - b).norm() > 0.1));
    }
}
