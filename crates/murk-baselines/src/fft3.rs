//! 3-D FFT of real C-order `[nx][ny][nt]` data (t contiguous), planned once. Real-to-complex along
//! t keeps only the `nt/2 + 1` non-negative temporal frequencies (the rest is their conjugate
//! mirror), so the x and y passes transform half as many lines; the spectrum is `[nx][ny][nt/2 + 1]`.
//! With pruning: the confocal methods zero-pad the data into one octant and keep one octant of the
//! result, so the forward transform skips the all-zero lines and the inverse skips lines that are
//! cropped away.
//! With symmetry: a convolution with a kernel that is even in x and y (the LCT's light cone) needs
//! only a quarter of the kernel's spectrum, and goes one temporal frequency plane at a time.

use murk_core::buffer::zeroed;
use murk_core::{Error, NoProgress, Progress, Result};
use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::sync::Arc;

pub(crate) type C32 = Complex32;

/// Along x or y, this many temporal frequencies are gathered and transformed as one block, so the
/// block stays in cache.
const T_BLOCK: usize = 32;

/// [`Fft3::convolve_even`] stores its spectrum as groups of GROUP lines, sample f of the lines of
/// a group side by side, and transforms laterally PLANE_BLOCK frequencies at a time: a block of a
/// group is 512 contiguous bytes, and a group stays in cache along t.
const GROUP: usize = 8;
const PLANE_BLOCK: usize = 8;

/// A method's passes through its data, for the progress bar and for stopping part-way: each pass
/// counts [`Steps::UNITS`] of the bar whatever its number of pieces, and each piece first asks
/// whether the caller wants to stop (a stopped method skips its remaining pieces and returns an
/// error, not a partial result).
pub(crate) struct Steps<'p> {
    progress: &'p dyn Progress,
    declared: usize,
    started: AtomicUsize,
}

impl<'p> Steps<'p> {
    const UNITS: usize = 1000;

    /// Starts the bar for `passes` passes.
    pub fn start(progress: &'p dyn Progress, passes: usize) -> Self {
        progress.start((passes * Self::UNITS) as u64);
        Steps {
            progress,
            declared: passes,
            started: AtomicUsize::new(0),
        }
    }

    /// For work that reports to no bar and is not stopped (`through_slab`, tests).
    pub fn none() -> Steps<'static> {
        Steps::start(&NoProgress, 0)
    }

    /// The next pass, of `pieces` pieces of parallel work.
    pub fn pass(&self, pieces: usize) -> Pass<'_> {
        self.started.fetch_add(1, Relaxed);
        if pieces == 0 {
            self.progress.advance(Self::UNITS as u64);
        }
        Pass {
            progress: self.progress,
            pieces,
            done: AtomicUsize::new(0),
        }
    }

    /// An error naming `method` where the caller asked to stop part-way.
    pub fn finish(&self, method: &str) -> Result<()> {
        if self.progress.cancelled() {
            return Err(Error::param(format!("{method} stopped")));
        }
        // A method that declares another number of passes than it runs leaves its bar short or
        // overruns it.
        debug_assert!(
            self.declared == 0 || self.started.load(Relaxed) == self.declared,
            "{method}: {} passes run, {} declared",
            self.started.load(Relaxed),
            self.declared
        );
        Ok(())
    }
}

/// One pass of [`Steps`].
pub(crate) struct Pass<'s> {
    progress: &'s dyn Progress,
    pieces: usize,
    done: AtomicUsize,
}

impl Pass<'_> {
    /// Called before each piece: counts it, and says whether to do it (not once the caller has
    /// asked to stop).
    pub fn piece(&self) -> bool {
        if self.progress.cancelled() {
            return false;
        }
        let c = self.done.fetch_add(1, Relaxed) + 1;
        let units = |c: usize| c * Steps::UNITS / self.pieces;
        self.progress.advance((units(c) - units(c - 1)) as u64);
        true
    }
}

pub(crate) struct Fft3 {
    /// Real-domain shape.
    pub dims: [usize; 3],
    r2c: Arc<dyn RealToComplex<f32>>,
    c2r: Arc<dyn ComplexToReal<f32>>,
    /// Complex inverse along t, for spectra that are not Hermitian.
    inv_t: Arc<dyn Fft<f32>>,
    /// Along x and along y.
    fwd: [Arc<dyn Fft<f32>>; 2],
    inv: [Arc<dyn Fft<f32>>; 2],
}

impl Fft3 {
    /// Passes through the data of [`Fft3::forward`], [`Fft3::forward_even`],
    /// [`Fft3::convolve_even`], [`Fft3::map_real`], and of [`Fft3::inverse`] and
    /// [`Fft3::inverse_power_one_sided`], for [`Steps::start`].
    pub const FORWARD_PASSES: usize = 3;
    pub const FORWARD_EVEN_PASSES: usize = 1;
    pub const CONVOLVE_PASSES: usize = 3;
    pub const MAP_REAL_PASSES: usize = 5;
    pub const INVERSE_PASSES: usize = 3;

    pub fn new(dims: [usize; 3]) -> Self {
        let mut planner = FftPlanner::new();
        let mut real = RealFftPlanner::new();
        let [nx, ny, nt] = dims;
        Fft3 {
            dims,
            r2c: real.plan_fft_forward(nt),
            c2r: real.plan_fft_inverse(nt),
            inv_t: planner.plan_fft_inverse(nt),
            fwd: [nx, ny].map(|n| planner.plan_fft_forward(n)),
            inv: [nx, ny].map(|n| planner.plan_fft_inverse(n)),
        }
    }

    /// Samples per spectrum line: the non-negative temporal frequencies.
    pub fn half(&self) -> usize {
        self.dims[2] / 2 + 1
    }

    /// Unnormalised forward transform of the real data that is zero outside x < `support[0]`,
    /// y < `support[1]`; `fill(x, y, line)` writes line (x, y) into a zeroed buffer of nt samples.
    pub fn forward(
        &self,
        support: [usize; 2],
        fill: impl Fn(usize, usize, &mut [f32]) + Sync,
        steps: &Steps,
    ) -> Vec<C32> {
        let [nx, ny, nt] = self.dims;
        let nh = self.half();
        let mut spec = zeroed(nx * ny * nh);
        let pass = steps.pass(support[0]);
        spec.par_chunks_mut(ny * nh)
            .take(support[0])
            .enumerate()
            .for_each_init(
                || (vec![0.0f32; nt], self.r2c.make_scratch_vec()),
                |(line, scratch), (ix, slab)| {
                    if !pass.piece() {
                        return;
                    }
                    for (iy, out) in slab.chunks_mut(nh).take(support[1]).enumerate() {
                        line.fill(0.0);
                        fill(ix, iy, line);
                        self.r2c
                            .process_with_scratch(line, out, scratch)
                            .expect("realfft lengths match their plan");
                    }
                },
            );
        self.along_y(&mut spec, &self.fwd[1], support[0], steps);
        self.along_x(&mut spec, &self.fwd[0], steps);
        spec
    }

    /// Quarter spectrum of real data that is even in x and in y about index 0 (line (x, y) =
    /// line (nx − x, y) = line (x, ny − y), indices mod n), whose spectrum is even in kx and ky
    /// alike, so the rest is its mirror image. Plane by plane, `[nt/2 + 1][ny/2 + 1][nx/2 + 1]`
    /// (f, ky, kx), as [`Fft3::convolve_even`] reads it. `t_spectrum(f, plane)` writes the
    /// temporal spectrum at frequency f of the lines x ≤ nx/2, y ≤ ny/2 into
    /// `plane[x·(ny/2 + 1) + y]`.
    pub fn forward_even(
        &self,
        t_spectrum: impl Fn(usize, &mut [C32]) + Sync,
        steps: &Steps,
    ) -> Vec<C32> {
        let [nx, ny, _] = self.dims;
        let (hx, hy) = (nx / 2 + 1, ny / 2 + 1);
        let mut planes = zeroed(self.half() * hx * hy);
        let pass = steps.pass(self.half());
        planes.par_chunks_mut(hx * hy).enumerate().for_each_init(
            || self.plane(),
            |p, (f, plane)| {
                if !pass.piece() {
                    return;
                }
                t_spectrum(f, plane);
                // The y pass needs only the distinct x rows, and the x pass only ky ≤ ny/2.
                for (row, quarter) in p.xy[..hx * ny].chunks_mut(ny).zip(plane.chunks(hy)) {
                    row[..hy].copy_from_slice(quarter);
                    unfold(row, hy);
                }
                self.fwd[1].process_with_scratch(&mut p.xy[..hx * ny], &mut p.scratch);
                transpose(&p.xy, ny, &mut p.yx, nx, [hx, hy]);
                for row in p.yx[..hy * nx].chunks_mut(nx) {
                    unfold(row, hx);
                }
                self.fwd[0].process_with_scratch(&mut p.yx[..hy * nx], &mut p.scratch);
                for (out, row) in plane.chunks_mut(hx).zip(p.yx.chunks(nx)) {
                    out.copy_from_slice(&row[..hx]);
                }
            },
        );
        planes
    }

    /// Circular convolution of the real data that is zero outside x < `support[0]`, y <
    /// `support[1]` (`fill` as in [`Fft3::forward`]) with a kernel that is even in x and y, given
    /// by its quarter spectrum from [`Fft3::forward_even`]. For each line of the support, in
    /// order, `emit(result line, out line)` gets the result (nt samples, scaled by 1/len) and
    /// the next n samples of `out`. The padded spectrum is never stored: the lateral passes go
    /// one temporal frequency plane at a time, in cache, on the support's spectrum.
    pub fn convolve_even(
        &self,
        support: [usize; 2],
        fill: impl Fn(usize, usize, &mut [f32]) + Sync,
        kernel: &[C32],
        out: &mut [f32],
        emit: impl Fn(&[f32], &mut [f32]) + Sync,
        steps: &Steps,
    ) {
        let [nx, ny, nt] = self.dims;
        let [sx, sy] = support;
        let (hx, nh) = (nx / 2 + 1, self.half());
        let k_len = hx * (ny / 2 + 1);
        assert_eq!(kernel.len(), nh * k_len);
        let n = out.len() / (sx * sy);
        assert_eq!(n * sx * sy, out.len());
        // [group][f][line in group], f padded to whole blocks.
        let group_len = nh.next_multiple_of(PLANE_BLOCK) * GROUP;
        let mut spec = zeroed((sx * sy).div_ceil(GROUP) * group_len);
        let pass = steps.pass(spec.len() / group_len);
        spec.par_chunks_mut(group_len).enumerate().for_each_init(
            || {
                (
                    vec![0.0f32; nt],
                    vec![C32::default(); nh],
                    self.r2c.make_scratch_vec(),
                )
            },
            |(line, freq, scratch), (g, group)| {
                if !pass.piece() {
                    return;
                }
                for l in 0..GROUP.min(sx * sy - g * GROUP) {
                    let i = g * GROUP + l;
                    line.fill(0.0);
                    fill(i / sy, i % sy, line);
                    self.r2c
                        .process_with_scratch(line, freq, scratch)
                        .expect("realfft lengths match their plan");
                    for (f, v) in freq.iter().enumerate() {
                        group[f * GROUP + l] = *v;
                    }
                }
            },
        );
        // blocks[b] borrows block b of every group: disjoint, so they can be transformed in
        // parallel without unsafe code.
        let mut blocks: Vec<Vec<&mut [C32]>> = (0..group_len / (PLANE_BLOCK * GROUP))
            .map(|_| Vec::with_capacity(spec.len() / group_len))
            .collect();
        for group in spec.chunks_mut(group_len) {
            for (b, block) in group.chunks_mut(PLANE_BLOCK * GROUP).enumerate() {
                blocks[b].push(block);
            }
        }
        let pass = steps.pass(blocks.len());
        blocks.into_par_iter().enumerate().for_each_init(
            || self.plane(),
            |p, (b, mut groups)| {
                if !pass.piece() {
                    return;
                }
                for j in 0..PLANE_BLOCK.min(nh - b * PLANE_BLOCK) {
                    // Sample (j, l) of the block of group g is line g·GROUP + l at f.
                    let at = |x: usize, y: usize| {
                        let i = x * sy + y;
                        (i / GROUP, j * GROUP + i % GROUP)
                    };
                    for (x, row) in p.xy[..sx * ny].chunks_mut(ny).enumerate() {
                        for (y, v) in row[..sy].iter_mut().enumerate() {
                            let (g, k) = at(x, y);
                            *v = groups[g][k];
                        }
                        row[sy..].fill(C32::default());
                    }
                    self.fwd[1].process_with_scratch(&mut p.xy[..sx * ny], &mut p.scratch);
                    transpose(&p.xy, ny, &mut p.yx, nx, [sx, ny]);
                    for row in p.yx.chunks_mut(nx) {
                        row[sx..].fill(C32::default());
                    }
                    self.fwd[0].process_with_scratch(&mut p.yx, &mut p.scratch);
                    let k = &kernel[(b * PLANE_BLOCK + j) * k_len..][..k_len];
                    for (ky, row) in p.yx.chunks_mut(nx).enumerate() {
                        // kx ≤ nx/2, then the mirrored rest: plain zips, which vectorise.
                        let k = &k[mirror(ky, ny) * hx..][..hx];
                        let (low, high) = row.split_at_mut(hx);
                        low.iter_mut().zip(k).for_each(|(v, k)| *v *= k);
                        high.iter_mut()
                            .zip(k[1..=nx - hx].iter().rev())
                            .for_each(|(v, k)| *v *= k);
                    }
                    self.inv[0].process_with_scratch(&mut p.yx, &mut p.scratch);
                    transpose(&p.yx, nx, &mut p.xy, ny, [ny, sx]);
                    self.inv[1].process_with_scratch(&mut p.xy[..sx * ny], &mut p.scratch);
                    for (x, row) in p.xy[..sx * ny].chunks(ny).enumerate() {
                        for (y, v) in row[..sy].iter().enumerate() {
                            let (g, k) = at(x, y);
                            groups[g][k] = *v;
                        }
                    }
                }
            },
        );
        let s = 1.0 / self.len() as f32;
        let pass = steps.pass(spec.len() / group_len);
        spec.par_chunks_mut(group_len)
            .zip(out.par_chunks_mut(GROUP * n))
            .for_each_init(
                || {
                    (
                        vec![C32::default(); nh],
                        vec![0.0f32; nt],
                        self.c2r.make_scratch_vec(),
                    )
                },
                |(freq, line, scratch), (group, o)| {
                    if !pass.piece() {
                        return;
                    }
                    for (l, o) in o.chunks_mut(n).enumerate() {
                        // Scaled here: half as many samples as after the transform.
                        for (f, v) in freq.iter_mut().enumerate() {
                            *v = group[f * GROUP + l] * s;
                        }
                        self.to_real(freq, line, scratch);
                        emit(line, o);
                    }
                },
            );
    }

    /// Inverse transform of a Hermitian spectrum (that of real data), scaled by 1/len, into `out`
    /// = `[keep[0]][keep[1]][n]`: the first n ≤ nt samples of the lines x < `keep[0]`,
    /// y < `keep[1]`. `spec` is used as scratch.
    pub fn inverse(&self, spec: &mut [C32], keep: [usize; 2], out: &mut [f32], steps: &Steps) {
        let nt = self.dims[2];
        let s = 1.0 / self.len() as f32;
        self.inverse_lines(
            (spec, keep, out),
            steps,
            || (vec![0.0f32; nt], self.c2r.make_scratch_vec()),
            |(line, scratch), freq, o| {
                self.to_real(freq, line, scratch);
                o.iter_mut().zip(line.iter()).for_each(|(o, v)| *o = v * s);
            },
        );
    }

    /// Replaces the Hermitian spectrum `spec` by that of f(x), x its inverse transform (scaled by
    /// 1/len), on the whole grid: the inverse and forward transforms without a real volume between.
    pub fn map_real(&self, spec: &mut [C32], f: impl Fn(f32) -> f32 + Sync, steps: &Steps) {
        let [nx, ny, nt] = self.dims;
        let s = 1.0 / self.len() as f32;
        self.along_x(spec, &self.inv[0], steps);
        self.along_y(spec, &self.inv[1], nx, steps);
        let scratch_len = self.c2r.get_scratch_len().max(self.r2c.get_scratch_len());
        let pass = steps.pass(nx);
        spec.par_chunks_mut(ny * self.half()).for_each_init(
            || (vec![0.0f32; nt], vec![C32::default(); scratch_len]),
            |(line, scratch), slab| {
                if !pass.piece() {
                    return;
                }
                for freq in slab.chunks_mut(self.half()) {
                    self.to_real(freq, line, scratch);
                    line.iter_mut().for_each(|v| *v = f(*v * s));
                    self.r2c
                        .process_with_scratch(line, freq, scratch)
                        .expect("realfft lengths match their plan");
                }
            },
        );
        self.along_y(spec, &self.fwd[1], nx, steps);
        self.along_x(spec, &self.fwd[0], steps);
    }

    /// |inverse transform|², scaled by 1/len², of a spectrum that is zero at negative temporal
    /// frequencies (an analytic signal: `spec` holds its non-negative half); output and scratch as
    /// in [`Fft3::inverse`].
    pub fn inverse_power_one_sided(
        &self,
        spec: &mut [C32],
        keep: [usize; 2],
        out: &mut [f32],
        steps: &Steps,
    ) {
        let nt = self.dims[2];
        let nh = self.half();
        let s2 = (1.0 / self.len() as f32).powi(2);
        self.inverse_lines(
            (spec, keep, out),
            steps,
            || {
                let scratch = vec![C32::default(); self.inv_t.get_inplace_scratch_len()];
                (vec![C32::default(); nt], scratch)
            },
            |(line, scratch), freq, o| {
                line[..nh].copy_from_slice(freq);
                line[nh..].fill(C32::default());
                self.inv_t.process_with_scratch(line, scratch);
                o.iter_mut()
                    .zip(line.iter())
                    .for_each(|(o, v)| *o = v.norm_sqr() * s2);
            },
        );
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Scratch for the lateral passes of one plane.
    fn plane(&self) -> Plane {
        let [nx, ny, _] = self.dims;
        let lateral = self.fwd.iter().chain(&self.inv);
        let scratch = lateral.map(|f| f.get_inplace_scratch_len()).max();
        Plane {
            xy: vec![C32::default(); nx * ny],
            yx: vec![C32::default(); nx * ny],
            scratch: vec![C32::default(); scratch.unwrap_or(0)],
        }
    }

    /// Unnormalised complex-to-real transform of one line of a Hermitian spectrum (used as scratch).
    fn to_real(&self, freq: &mut [C32], line: &mut [f32], scratch: &mut [C32]) {
        // The imaginary parts at DC (and Nyquist) of a Hermitian spectrum are zero; what is there
        // is rounding noise, which realfft would reject.
        freq[0].im = 0.0;
        let nt = self.dims[2];
        if nt.is_multiple_of(2) {
            freq[nt / 2].im = 0.0;
        }
        self.c2r
            .process_with_scratch(freq, line, scratch)
            .expect("realfft lengths match their plan");
    }

    /// The lateral inverse passes (exact on x < `keep[0]`), then `along_t(scratch, spectrum line,
    /// output line)` on every kept line.
    fn inverse_lines<S>(
        &self,
        (spec, keep, out): (&mut [C32], [usize; 2], &mut [f32]),
        steps: &Steps,
        scratch: impl Fn() -> S + Sync + Send,
        along_t: impl Fn(&mut S, &mut [C32], &mut [f32]) + Sync + Send,
    ) {
        let [_, ny, nt] = self.dims;
        let nh = self.half();
        let n = out.len() / (keep[0] * keep[1]);
        assert!(n <= nt && n * keep[0] * keep[1] == out.len());
        self.along_x(spec, &self.inv[0], steps);
        self.along_y(spec, &self.inv[1], keep[0], steps);
        let pass = steps.pass(keep[0]);
        spec.par_chunks_mut(ny * nh)
            .zip(out.par_chunks_mut(keep[1] * n))
            .for_each_init(scratch, |s, (slab, o)| {
                if !pass.piece() {
                    return;
                }
                slab.chunks_mut(nh)
                    .zip(o.chunks_mut(n))
                    .for_each(|(freq, o)| along_t(s, freq, o))
            });
    }

    fn along_y(&self, spec: &mut [C32], fft: &Arc<dyn Fft<f32>>, x_lines: usize, steps: &Steps) {
        let ny = self.dims[1];
        let nh = self.half();
        let pass = steps.pass(x_lines);
        spec.par_chunks_mut(ny * nh).take(x_lines).for_each_init(
            || Scratch::new(fft, ny),
            |s, slab| {
                if pass.piece() {
                    s.across_rows(fft, slab.chunks_mut(nh).collect())
                }
            },
        );
    }

    fn along_x(&self, spec: &mut [C32], fft: &Arc<dyn Fft<f32>>, steps: &Steps) {
        let [nx, ny, _] = self.dims;
        let nh = self.half();
        // rows[y][x] borrows the spectrum line at (x, y): groups of rows with equal y are disjoint
        // and can be transformed in parallel without unsafe code.
        let mut rows: Vec<Vec<&mut [C32]>> = (0..ny).map(|_| Vec::with_capacity(nx)).collect();
        for slab in spec.chunks_mut(ny * nh) {
            for (y, line) in slab.chunks_mut(nh).enumerate() {
                rows[y].push(line);
            }
        }
        let pass = steps.pass(ny);
        rows.into_par_iter().for_each_init(
            || Scratch::new(fft, nx),
            |s, group| {
                if pass.piece() {
                    s.across_rows(fft, group)
                }
            },
        );
    }
}

/// One lateral plane of a spectrum, laid out for the y pass (`xy` = `[x][y]`) and for the x pass
/// (`yx` = `[y][x]`).
struct Plane {
    xy: Vec<C32>,
    yx: Vec<C32>,
    scratch: Vec<C32>,
}

/// `dst[c·dst_row + r]` = `src[r·src_row + c]` for r < `size[0]`, c < `size[1]`, in tiles that
/// stay in L1.
fn transpose(src: &[C32], src_row: usize, dst: &mut [C32], dst_row: usize, size: [usize; 2]) {
    const TILE: usize = 8;
    for r0 in (0..size[0]).step_by(TILE) {
        for c0 in (0..size[1]).step_by(TILE) {
            for r in r0..(r0 + TILE).min(size[0]) {
                for c in c0..(c0 + TILE).min(size[1]) {
                    dst[c * dst_row + r] = src[r * src_row + c];
                }
            }
        }
    }
}

/// Fills `row[h..]` with the mirror image of `row[..h]`, h = n/2 + 1: an even sequence from its
/// first half.
fn unfold(row: &mut [C32], h: usize) {
    let n = row.len();
    let (low, high) = row.split_at_mut(h);
    high.iter_mut()
        .zip(low[1..=n - h].iter().rev())
        .for_each(|(v, m)| *v = *m);
}

/// i or its mirror image n − i, whichever is at most n/2: where data or spectra that are even
/// along an axis of n samples keep sample i (mod n).
fn mirror(i: usize, n: usize) -> usize {
    i.min(n - i)
}

struct Scratch {
    block: Vec<C32>,
    fft: Vec<C32>,
}

impl Scratch {
    fn new(fft: &Arc<dyn Fft<f32>>, n: usize) -> Self {
        Scratch {
            block: vec![C32::default(); n * T_BLOCK],
            fft: vec![C32::default(); fft.get_inplace_scratch_len()],
        }
    }

    /// Transforms across the rows (element j of every row forms one signal), a block of j at a time.
    fn across_rows(&mut self, fft: &Arc<dyn Fft<f32>>, mut rows: Vec<&mut [C32]>) {
        let n = rows.len();
        let len = rows[0].len();
        for j0 in (0..len).step_by(T_BLOCK) {
            let jb = T_BLOCK.min(len - j0);
            let block = &mut self.block[..jb * n];
            for (r, row) in rows.iter().enumerate() {
                for (j, v) in row[j0..j0 + jb].iter().enumerate() {
                    block[j * n + r] = *v;
                }
            }
            fft.process_with_scratch(block, &mut self.fft);
            for (r, row) in rows.iter_mut().enumerate() {
                for (j, v) in row[j0..j0 + jb].iter_mut().enumerate() {
                    *v = block[j * n + r];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct O(n²) DFT along each of `axes`, as the reference for the pruned transforms.
    fn dft(x: &[C32], d: [usize; 3], sign: f64, axes: std::ops::Range<usize>) -> Vec<C32> {
        let mut out = x.to_vec();
        for axis in axes {
            let stride = d[axis + 1..].iter().product::<usize>();
            let n = d[axis];
            let src = out.clone();
            for (i, o) in out.iter_mut().enumerate() {
                let k = (i / stride) % n;
                let base = i - k * stride;
                let mut acc = rustfft::num_complex::Complex64::default();
                for j in 0..n {
                    let ph = sign * 2.0 * std::f64::consts::PI * (j * k) as f64 / n as f64;
                    let v = src[base + j * stride];
                    acc += rustfft::num_complex::Complex64::new(v.re as f64, v.im as f64)
                        * rustfft::num_complex::Complex64::from_polar(1.0, ph);
                }
                *o = C32::new(acc.re as f32, acc.im as f32);
            }
        }
        out
    }

    /// The test grid, the data's support and the samples compared after inverse transforms.
    const D: [usize; 3] = [6, 4, 40];
    const SUPPORT: [usize; 2] = [3, 2];
    const N_OUT: usize = 30;

    fn value(ix: usize, iy: usize, t: usize) -> f32 {
        ((ix * 7 + iy * 3 + t) % 11) as f32 - 0.1 * t as f32
    }

    /// `f` on the lines x < `support[0]`, y < `support[1]` of the grid, zero elsewhere.
    fn dense(support: [usize; 2], f: impl Fn(usize, usize, usize) -> f32) -> Vec<C32> {
        let [_, ny, nt] = D;
        let mut x = vec![C32::default(); D.iter().product()];
        for ix in 0..support[0] {
            for iy in 0..support[1] {
                for t in 0..nt {
                    x[(ix * ny + iy) * nt + t] = C32::new(f(ix, iy, t), 0.0);
                }
            }
        }
        x
    }

    /// `f` as the `fill` of the transforms.
    fn lines(
        f: impl Fn(usize, usize, usize) -> f32 + Sync,
    ) -> impl Fn(usize, usize, &mut [f32]) + Sync {
        move |ix, iy, line| {
            line.iter_mut()
                .enumerate()
                .for_each(|(t, v)| *v = f(ix, iy, t))
        }
    }

    /// `out` = [SUPPORT[0]][SUPPORT[1]][N_OUT] holds `f` within `tol`.
    fn assert_kept(out: &[f32], f: impl Fn(usize, usize, usize) -> f32, tol: f32) {
        for ix in 0..SUPPORT[0] {
            for iy in 0..SUPPORT[1] {
                for t in 0..N_OUT {
                    let (a, b) = (out[(ix * SUPPORT[1] + iy) * N_OUT + t], f(ix, iy, t));
                    assert!((a - b).abs() < tol, "({ix}, {iy}, {t}): {a} vs {b}");
                }
            }
        }
    }

    fn peak_norm(x: &[C32]) -> f32 {
        x.iter().map(|v| v.norm()).fold(0.0, f32::max)
    }

    // Tolerances below are relative to the largest value, for f32 rounding: 1e-5 for spectra and
    // after round trips, 1e-4 for squared magnitudes.

    #[test]
    fn pruned_transforms_match_the_direct_dft() {
        let [_, ny, nt] = D;
        let plan = Fft3::new(D);
        let nh = plan.half();
        let x = dense(SUPPORT, value);
        let want = dft(&x, D, -1.0, 0..3);
        let spec = plan.forward(SUPPORT, lines(value), &Steps::none());
        let scale = peak_norm(&want);
        for (i, a) in spec.iter().enumerate() {
            let b = want[i / nh * nt + i % nh];
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
        let mut out = vec![0.0f32; SUPPORT[0] * SUPPORT[1] * N_OUT];
        plan.inverse(&mut spec.clone(), SUPPORT, &mut out, &Steps::none());
        assert_kept(&out, value, 1e-5 * peak_norm(&x));
        // The analytic signal: the direct inverse of the spectrum without negative frequencies.
        let mut one_sided = want.clone();
        one_sided
            .iter_mut()
            .enumerate()
            .filter(|(i, _)| i % nt >= nh)
            .for_each(|(_, v)| *v = C32::default());
        let len = x.len() as f32;
        let z: Vec<f32> = dft(&one_sided, D, 1.0, 0..3)
            .iter()
            .map(|v| (v / len).norm_sqr())
            .collect();
        plan.inverse_power_one_sided(&mut spec.clone(), SUPPORT, &mut out, &Steps::none());
        let peak = z.iter().copied().fold(0.0, f32::max);
        assert_kept(&out, |ix, iy, t| z[(ix * ny + iy) * nt + t], 1e-4 * peak);
        // A pointwise map between the inverse and forward transforms: the spectrum of x².
        let mut squared = spec;
        plan.map_real(&mut squared, |v| v * v, &Steps::none());
        let x2: Vec<C32> = x.iter().map(|v| v * v).collect();
        let want = dft(&x2, D, -1.0, 0..3);
        let scale = peak_norm(&want);
        for (i, a) in squared.iter().enumerate() {
            let b = want[i / nh * nt + i % nh];
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
    }

    #[test]
    fn even_transforms_match_the_direct_dft() {
        let [nx, ny, nt] = D;
        let plan = Fft3::new(D);
        let (hx, hy, nh) = (nx / 2 + 1, ny / 2 + 1, plan.half());
        // Even in x and y: a function of the mirrored indices.
        let kernel =
            |ix: usize, iy: usize, t: usize| value(mirror(ix, nx), 3 * mirror(iy, ny), t * t);
        let k = dense([nx, ny], kernel);
        let k_t = dft(&k, D, -1.0, 2..3);
        let quarter = plan.forward_even(
            |f, plane| {
                for (x, row) in plane.chunks_mut(hy).enumerate() {
                    for (y, v) in row.iter_mut().enumerate() {
                        *v = k_t[(x * ny + y) * nt + f];
                    }
                }
            },
            &Steps::none(),
        );
        let k_spec = dft(&k_t, D, -1.0, 0..2);
        let scale = peak_norm(&k_spec);
        for (i, b) in k_spec.iter().enumerate().filter(|(i, _)| i % nt < nh) {
            let (kx, ky) = (mirror(i / (ny * nt), nx), mirror(i / nt % ny, ny));
            let a = quarter[((i % nt) * hy + ky) * hx + kx];
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
        // The direct circular convolution: the inverse of the product of the spectra.
        let x = dense(SUPPORT, value);
        let product: Vec<C32> = dft(&x, D, -1.0, 0..3)
            .iter()
            .zip(&k_spec)
            .map(|(a, b)| a * b)
            .collect();
        let len = x.len() as f32;
        let want: Vec<f32> = dft(&product, D, 1.0, 0..3)
            .iter()
            .map(|v| v.re / len)
            .collect();
        let mut out = vec![0.0f32; SUPPORT[0] * SUPPORT[1] * N_OUT];
        plan.convolve_even(
            SUPPORT,
            lines(value),
            &quarter,
            &mut out,
            |line, o| o.copy_from_slice(&line[..N_OUT]),
            &Steps::none(),
        );
        let peak = want.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        assert_kept(&out, |ix, iy, t| want[(ix * ny + iy) * nt + t], 1e-5 * peak);
    }
}
