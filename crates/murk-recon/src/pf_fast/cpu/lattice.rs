//! The CPU executor's inner steps, from the grid's spectra to the field at the voxels: the kernel's spectrum (folded when its
//! support is symmetric), the product and inverse transforms, and the resampling to voxel positions.

use super::Workspace;
use crate::cmul;
use crate::fft2::{kept_lines, transpose_part};
use crate::pf_fast::FastPlan;
use crate::resample::Resampler;
use murk_core::simd::wide;
use rustfft::num_complex::Complex32;
use std::ops::Range;

/// Number of distinct |q − c| for q ∈ [0, len).
pub(super) fn reach(c: i64, len: usize) -> usize {
    c.unsigned_abs().max((len as i64 - 1 - c).unsigned_abs()) as usize + 1
}

/// Where the upper run of a line of N values cut to |k| ≤ `cut` (k modulo N) starts: past the
/// lower run 0..=cut, and at N/2 + 1 or later.
fn upper(n: usize, cut: usize) -> usize {
    (n - cut).max(cut + 1)
}

/// Values of a line of `n` cut to |k| ≤ `cut`: its lower run 0..=cut and its upper run.
fn packed_len(n: usize, cut: usize) -> usize {
    cut + 1 + n - upper(n, cut)
}

/// Values a spectrum of `[fx, fy]` takes packed (see [`pack`]): its lines kept for `lines`, each
/// cut to |kx| ≤ `cut`.
pub(super) fn packed_size([fx, fy]: [usize; 2], lines: usize, cut: usize) -> usize {
    let kept: usize = kept_lines(fy, lines).iter().map(|r| r.len()).sum();
    kept * packed_len(fx, cut)
}

/// Position among the packed lines (see [`pack`]) of line ky = s, or of ky = N − s when `mirrored`.
fn packed_index(s: usize, mirrored: bool) -> usize {
    match (s, mirrored) {
        (0, _) => 0,
        (s, false) => 2 * s - 1,
        (s, true) => 2 * s,
    }
}

/// The lines of `t` ([ky][kx], `n = [fx, fy]`) kept for `lines`, each cut to |kx| ≤ `cut`, into
/// `out` in the order [`FastPlan::folded_lines`] reads them: ky = 0, then ky = s and fy − s for
/// s = 1, 2, …, so that a plane keeping fewer lines reads a prefix, and each frequency's spectrum
/// streams from one contiguous run of memory.
pub(super) fn pack(
    t: &[Complex32],
    [fx, fy]: [usize; 2],
    lines: usize,
    cut: usize,
    out: &mut [Complex32],
) {
    let len = packed_len(fx, cut);
    let top = upper(fx, cut);
    for ky in kept_lines(fy, lines).into_iter().flatten() {
        let mirrored = ky > fy / 2;
        let s = if mirrored { fy - ky } else { ky };
        let dst = &mut out[packed_index(s, mirrored) * len..][..len];
        let line = &t[ky * fx..(ky + 1) * fx];
        dst[..=cut].copy_from_slice(&line[..=cut]);
        dst[cut + 1..].copy_from_slice(&line[top..]);
    }
}

/// `dst[k] = src[k]·h[k]` for k ≤ N/2 and `dst[k] = src[N − k]·h[k]` above: a spectrum over
/// k ≤ N/2 extended to all N = dst.len() by symmetry, times a line `h` packed to |k| ≤ `cut` (see
/// [`pack`]); elsewhere, where the line is zero, the product is written as zero.
#[inline(always)]
fn unfold_mul(dst: &mut [Complex32], src: &[Complex32], h: &[Complex32], cut: usize) {
    let n = dst.len();
    debug_assert!(src.len() == n / 2 + 1 && h.len() == packed_len(n, cut));
    let hi = upper(n, cut);
    cmul::mul(&mut dst[..=cut], &src[..=cut], &h[..=cut]);
    dst[cut + 1..hi]
        .iter_mut()
        .for_each(|v| *v = Complex32::default());
    let top = &mut dst[hi..];
    for (d, s) in top.iter_mut().rev().zip(&src[1..]) {
        *d = *s;
    }
    cmul::mul_assign(top, &h[cut + 1..]);
}

/// Each line of `lines` (`len` values each) = [`mirror`] of the next `stride` values of `src` over
/// its first g, zero after, for `[g, c]`: a batch of the kernel's distinct rows or columns laid out
/// for the FFT.
fn mirror_lines(
    lines: &mut [Complex32],
    len: usize,
    src: &[Complex32],
    stride: usize,
    [g, c]: [usize; 2],
) {
    wide(
        #[inline(always)]
        || {
            for (line, s) in lines.chunks_exact_mut(len).zip(src.chunks_exact(stride)) {
                mirror(&mut line[..g], s, c as i64);
                line[g..].iter_mut().for_each(|v| *v = Complex32::default());
            }
        },
    );
}

/// `dst[q] = src[|q − c|]`: a reversed run down to |·| = 0, then a forward run.
#[inline(always)]
pub(super) fn mirror(dst: &mut [Complex32], src: &[Complex32], c: i64) {
    let split = c.clamp(0, dst.len() as i64) as usize;
    let (down, up) = dst.split_at_mut(split);
    for (d, s) in down.iter_mut().rev().zip(&src[1..]) {
        *d = *s;
    }
    let first = (-c).max(0) as usize;
    up.copy_from_slice(&src[first..first + up.len()]);
}

/// Kernel rows (y part) and spectrum lines (x part) handled per batch by [`FastPlan::folded_lines`]:
/// eight complex values fill a 64-byte cache line in each column of the transposes, and a batch's
/// buffers stay in L1.
pub(super) const BATCH: usize = 8;

/// Where [`FastPlan::folded_lines`] puts each line of the kernel's spectrum × the grid's.
pub(super) enum Sink {
    /// Transformed back along x and written transposed into `ws.g` ([x][ky]) for x in the range.
    InverseX(Range<usize>),
    /// Added into `ws.spec_acc` ([ky][kx]), for one transform back per plane.
    Accumulate,
}

impl FastPlan {
    /// For a symmetric support (see [`Fold`]): the kernel's spectrum at the current frequency times
    /// `h` (lines packed to |kx| ≤ `x_lines`, see [`pack`]) on the lines kept for `lines`, delivered
    /// to `sink`; the kernel's table (`ws.tcur`) is left advanced to the next frequency. Along y only
    /// the distinct rows |dx| ≤ cx are transformed, in batches whose columns ky ≤ min(fy/2, lines)
    /// are gathered into `ws.cols`; along x, batches of those columns are transformed, and each is
    /// unfolded into the lines ky and fy − ky as it is multiplied, so no whole-spectrum buffer is
    /// written or read.
    pub(super) fn folded_lines(
        &self,
        ws: &mut Workspace,
        h: &[Complex32],
        [gx, gy, my]: [usize; 3],
        [lines, x_lines]: [usize; 2],
        sink: &Sink,
    ) {
        let (fx, fy) = (self.fft.fx, self.fft.fy);
        let hy = (fy / 2).min(lines) + 1;
        let hx = fx / 2 + 1;
        let h_len = packed_len(fx, x_lines);
        let rows = self.cx as usize + 1;
        let (cx, cy) = (self.cx, self.cy);
        debug_assert!(cx >= 0 && cy >= 0, "a folded support is centred inside it");
        for b0 in (0..rows).step_by(BATCH) {
            let nb = BATCH.min(rows - b0);
            let block = &mut ws.kbuf[..nb * fy];
            mirror_lines(
                block,
                fy,
                &ws.tcur[b0 * my..(b0 + nb) * my],
                my,
                [gy, cy as usize],
            );
            // The rows just read, advanced to the next frequency while they are in L1.
            let read = b0 * my..(b0 + nb) * my;
            cmul::mul_assign(&mut ws.tcur[read.clone()], &ws.tstep[read]);
            self.fft.rows_y(block, &mut ws.scratch);
            // Only the hy columns that are read.
            transpose_part(block, fy, 0..nb, 0..hy, &mut ws.cols[b0..], rows);
        }
        for s0 in (0..hy).step_by(BATCH) {
            let ns = BATCH.min(hy - s0);
            let klines = &mut ws.kbuf[..ns * fx];
            let columns = &ws.cols[s0 * rows..(s0 + ns) * rows];
            mirror_lines(klines, fx, columns, rows, [gx, cx as usize]);
            self.fft.rows_x(klines, &mut ws.scratch);
            // Lines ky = s (ascending), then the mirrored ky = fy − s for the s with a distinct
            // mirror (0 < s < fy − s), s descending so ky ascends: two runs of consecutive ky for
            // the transposes.
            let mirrored = s0.max(1)..(s0 + ns).min(fy.div_ceil(2));
            let n = ns + mirrored.len();
            let batch = (s0..s0 + ns).map(|s| (s, s));
            for (i, (ky, s)) in batch
                .chain(mirrored.clone().rev().map(|s| (fy - s, s)))
                .enumerate()
            {
                let t = &mut ws.tlines[i * fx..(i + 1) * fx];
                let kline = &klines[(s - s0) * fx..(s - s0) * fx + hx];
                let hline = &h[packed_index(s, ky != s) * h_len..][..h_len];
                unfold_mul(t, kline, hline, x_lines);
            }
            let runs = [(s0, 0..ns), (fy + 1 - mirrored.end, ns..n)];
            match sink {
                Sink::InverseX(xs) => {
                    self.fft
                        .inverse_rows_x(&mut ws.tlines[..n * fx], &mut ws.scratch);
                    for (ky0, run) in runs {
                        let part = &ws.tlines[run.start * fx..run.end * fx];
                        transpose_part(part, fx, 0..run.len(), xs.clone(), &mut ws.g[ky0..], fy);
                    }
                }
                Sink::Accumulate => {
                    for (ky0, run) in runs {
                        let acc = &mut ws.spec_acc[ky0 * fx..(ky0 + run.len()) * fx];
                        cmul::add_assign(acc, &ws.tlines[run.start * fx..run.end * fx]);
                    }
                }
            }
        }
    }

    /// The field at the voxels (y-major), delivered row by row into `acc` as `into` says, from the
    /// convolution's x-transformed lattice rows in `ws.g` ([x][ky], rows [gnx−1, gnx−1+vx), kept
    /// lines only): along x first, still in ky (resampling along x and the inverse FFT along y
    /// commute), so only nx rows, not vx, are transformed along y; then along y at the voxels, with
    /// the resamplers `r` (x, y): off the lattice a windowed sinc or a Kaiser–Bessel kernel
    /// ([`FastPlan::kernels`]), on it one tap of weight 1.
    pub(super) fn field_at_voxels(
        &self,
        ws: &mut Workspace,
        lines: usize,
        r: [&Resampler; 2],
        acc: &mut [Complex32],
        into: Deliver,
    ) {
        let (nx, fy) = (self.vol.x.n, self.fft.fy);
        wide(
            #[inline(always)]
            || self.resample_x(ws, lines, r[0]),
        );
        self.fft.inverse_y(&mut ws.tmp[..nx * fy], &mut ws.scratch);
        wide(
            #[inline(always)]
            || self.resample_y(ws, r[1], acc, into),
        );
    }

    /// `ws.tmp` ([voxel x][ky]) = the taps' weighted sum of lattice rows of `ws.g`: whole rows,
    /// contiguous, so it vectorises; zeros on the skipped lines.
    #[inline(always)]
    fn resample_x(&self, ws: &mut Workspace, lines: usize, rx: &Resampler) {
        let fy = self.fft.fy;
        let x0 = self.grid.nx - 1;
        let [lo, hi] = kept_lines(fy, lines);
        for (ix, out) in ws.tmp.chunks_exact_mut(fy).enumerate() {
            let (st, w) = (rx.starts[ix], rx.weights_of(ix));
            for r in [lo.clone(), hi.clone()] {
                let rows = w.iter().enumerate().map(|(k, &wk)| {
                    let row = (x0 + st + k) * fy;
                    (&ws.g[row + r.start..row + r.end], wk)
                });
                weighted_sum(&mut out[r.clone()], rows);
            }
            out[lo.end..hi.start]
                .iter_mut()
                .for_each(|v| *v = Complex32::default());
        }
    }

    /// Each row y of the field at the voxels (into `ws.row`, then `acc` as `into` says) from the
    /// rows of `ws.tmp` ([voxel x][lattice y] after the inverse along y): a gather on the lattice,
    /// else the taps' weighted sum of transposed rows, so each tap is one more contiguous row of nx
    /// values, which vectorises where short per-voxel dot products do not. One row at a time, so
    /// the field stays in L1 on its way into `acc`.
    #[inline(always)]
    fn resample_y(&self, ws: &mut Workspace, ry: &Resampler, acc: &mut [Complex32], into: Deliver) {
        let (nx, fy) = (self.vol.x.n, self.fft.fy);
        let y0 = self.grid.ny - 1;
        if ry.taps > 1 {
            transpose_part(&ws.tmp[y0..], fy, 0..nx, 0..ry.len, &mut ws.tmp_t, nx);
        }
        let Workspace {
            tmp,
            tmp_t,
            row,
            pbase,
            pstep,
            ..
        } = ws;
        for (iy, acc) in acc.chunks_exact_mut(nx).enumerate() {
            let sy = ry.starts[iy];
            if ry.taps == 1 {
                for (v, t) in row.iter_mut().zip(tmp.chunks_exact(fy)) {
                    *v = t[y0 + sy];
                }
            } else {
                let rows = ry
                    .weights_of(iy)
                    .iter()
                    .enumerate()
                    .map(|(k, &wk)| (&tmp_t[(sy + k) * nx..(sy + k + 1) * nx], wk));
                weighted_sum(row, rows);
            }
            let voxels = iy * nx..(iy + 1) * nx;
            match into {
                Deliver::Set => acc.copy_from_slice(row),
                Deliver::AddPhased => {
                    cmul::mul_add_advance(acc, row, &mut pbase[voxels.clone()], &pstep[voxels])
                }
            }
        }
    }
}

/// How [`FastPlan::field_at_voxels`] puts the field into its accumulator.
#[derive(Clone, Copy)]
pub(super) enum Deliver {
    /// Overwrites it.
    Set,
    /// Adds it times the point-side phase (`ws.pbase`), and advances that phase to the next
    /// frequency (`ws.pstep`).
    AddPhased,
}

/// `out` = Σ weight·row over `rows`, over the interleaved (re, im) floats: plain f32 loops vectorise
/// without the shuffles that LLVM puts around a product of complex values by a real one. Blocks of
/// 32 floats are summed over all rows in registers and stored once, rather than read and written
/// once per row; the rest in blocks of 8 (one AVX register), so that only the last few floats are
/// summed one at a time.
#[inline(always)]
fn weighted_sum<'r>(out: &mut [Complex32], rows: impl Iterator<Item = (&'r [Complex32], f32)>) {
    const MAX_ROWS: usize = 2 * crate::resample::HALF_TAPS as usize;
    let out = cmul::floats_mut(out);
    let n = out.len();
    let mut taps: [(&[f32], f32); MAX_ROWS] = [(&[], 0.0); MAX_ROWS];
    let mut count = 0;
    for (row, w) in rows {
        taps[count] = (&cmul::floats(row)[..n], w);
        count += 1;
    }
    let taps = &taps[..count];
    let wide_end = n - n % 32;
    let narrow_end = n - n % 8;
    summed_blocks::<32>(out, taps, 0..wide_end);
    summed_blocks::<8>(out, taps, wide_end..narrow_end);
    summed_blocks::<1>(out, taps, narrow_end..n);
}

/// [`weighted_sum`] over `range` (a multiple of `B` floats), `B` floats at a time.
#[inline(always)]
fn summed_blocks<const B: usize>(out: &mut [f32], taps: &[(&[f32], f32)], range: Range<usize>) {
    for c in range.step_by(B) {
        let mut acc = [0f32; B];
        for &(row, w) in taps {
            let src: &[f32; B] = row[c..c + B].try_into().expect("a block of the row");
            for (a, g) in acc.iter_mut().zip(src) {
                *a += g * w;
            }
        }
        out[c..c + B].copy_from_slice(&acc);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kept line, read back where `folded_lines` looks for it, holds its values at |kx| ≤ cut
    /// in both runs, for even and odd lengths, cut or whole lines, and few or all lines kept.
    #[test]
    fn packed_lines_are_found_where_they_are_read() {
        for [fx, fy] in [[270, 270], [9, 7], [8, 10]] {
            let t: Vec<Complex32> = (0..fx * fy)
                .map(|i| Complex32::new(i as f32, -(i as f32)))
                .collect();
            for lines in [0, 1, 2, fy / 2 - 1, fy / 2, fy] {
                for cut in [0, 1, fx / 2 - 1, fx / 2] {
                    let kept = (2 * lines + 1).min(fy);
                    let len = packed_len(fx, cut);
                    let mut out = vec![Complex32::new(f32::NAN, 0.0); kept * len];
                    pack(&t, [fx, fy], lines, cut, &mut out);
                    let hy = (fy / 2).min(lines) + 1;
                    let direct = (0..hy).map(|s| (s, s, false));
                    let mirrored = (1..hy.min(fy.div_ceil(2))).map(|s| (fy - s, s, true));
                    let mut read = 0;
                    for (ky, s, m) in direct.chain(mirrored) {
                        let line = &out[packed_index(s, m) * len..][..len];
                        let row = &t[ky * fx..(ky + 1) * fx];
                        let top = upper(fx, cut);
                        assert_eq!(&line[..=cut], &row[..=cut], "{fx}×{fy}, ky {ky}");
                        assert_eq!(&line[cut + 1..], &row[top..], "{fx}×{fy}, ky {ky}");
                        read += 1;
                    }
                    assert_eq!(
                        read, kept,
                        "{fx}×{fy}, lines {lines}: every packed line is read"
                    );
                    assert!(out.iter().all(|v| !v.re.is_nan()), "nothing left unwritten");
                }
            }
        }
    }
}
