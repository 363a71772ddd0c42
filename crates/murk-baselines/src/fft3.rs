//! 3-D FFT of real C-order `[nx][ny][nt]` data (t contiguous), planned once. Real-to-complex along
//! t keeps only the `nt/2 + 1` non-negative temporal frequencies (the rest is their conjugate
//! mirror), so the x and y passes transform half as many lines; the spectrum is `[nx][ny][nt/2 + 1]`.
//! With pruning: the confocal methods zero-pad the data into one octant and keep one octant of the
//! result, so the forward transform skips the all-zero lines and the inverse skips lines that are
//! cropped away.

use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

pub(crate) type C32 = Complex32;

/// Along x or y, this many temporal frequencies are gathered and transformed as one block, so the
/// block stays in cache.
const T_BLOCK: usize = 32;

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
    ) -> Vec<C32> {
        let [nx, ny, nt] = self.dims;
        let nh = self.half();
        let mut spec = vec![C32::default(); nx * ny * nh];
        spec.par_chunks_mut(ny * nh)
            .take(support[0])
            .enumerate()
            .for_each_init(
                || (vec![0.0f32; nt], self.r2c.make_scratch_vec()),
                |(line, scratch), (ix, slab)| {
                    for (iy, out) in slab.chunks_mut(nh).take(support[1]).enumerate() {
                        line.fill(0.0);
                        fill(ix, iy, line);
                        self.r2c
                            .process_with_scratch(line, out, scratch)
                            .expect("realfft lengths match their plan");
                    }
                },
            );
        self.along_y(&mut spec, &self.fwd[1], support[0]);
        self.along_x(&mut spec, &self.fwd[0]);
        spec
    }

    /// Inverse transform of a Hermitian spectrum (that of real data), scaled by 1/len, into `out`
    /// = `[keep[0]][keep[1]][n]`: the first n ≤ nt samples of the lines x < `keep[0]`,
    /// y < `keep[1]`. `spec` is used as scratch.
    pub fn inverse(&self, spec: &mut [C32], keep: [usize; 2], out: &mut [f32]) {
        let nt = self.dims[2];
        let s = 1.0 / self.len() as f32;
        self.inverse_lines(
            spec,
            keep,
            out,
            || (vec![0.0f32; nt], self.c2r.make_scratch_vec()),
            |(line, scratch), freq, o| {
                self.to_real(freq, line, scratch);
                o.iter_mut().zip(line.iter()).for_each(|(o, v)| *o = v * s);
            },
        );
    }

    /// Replaces the Hermitian spectrum `spec` by that of f(x), x its inverse transform (scaled by
    /// 1/len), on the whole grid: the inverse and forward transforms without a real volume between.
    pub fn map_real(&self, spec: &mut [C32], f: impl Fn(f32) -> f32 + Sync) {
        let [nx, _, nt] = self.dims;
        let s = 1.0 / self.len() as f32;
        self.along_x(spec, &self.inv[0]);
        self.along_y(spec, &self.inv[1], nx);
        let scratch_len = self.c2r.get_scratch_len().max(self.r2c.get_scratch_len());
        spec.par_chunks_mut(self.half()).for_each_init(
            || (vec![0.0f32; nt], vec![C32::default(); scratch_len]),
            |(line, scratch), freq| {
                self.to_real(freq, line, scratch);
                line.iter_mut().for_each(|v| *v = f(*v * s));
                self.r2c
                    .process_with_scratch(line, freq, scratch)
                    .expect("realfft lengths match their plan");
            },
        );
        self.along_y(spec, &self.fwd[1], nx);
        self.along_x(spec, &self.fwd[0]);
    }

    /// |inverse transform|², scaled by 1/len², of a spectrum that is zero at negative temporal
    /// frequencies (an analytic signal: `spec` holds its non-negative half); output and scratch as
    /// in [`Fft3::inverse`].
    pub fn inverse_power_one_sided(&self, spec: &mut [C32], keep: [usize; 2], out: &mut [f32]) {
        let nt = self.dims[2];
        let nh = self.half();
        let s2 = (1.0 / self.len() as f32).powi(2);
        self.inverse_lines(
            spec,
            keep,
            out,
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
        spec: &mut [C32],
        keep: [usize; 2],
        out: &mut [f32],
        scratch: impl Fn() -> S + Sync + Send,
        along_t: impl Fn(&mut S, &mut [C32], &mut [f32]) + Sync + Send,
    ) {
        let [_, ny, nt] = self.dims;
        let nh = self.half();
        let n = out.len() / (keep[0] * keep[1]);
        assert!(n <= nt && n * keep[0] * keep[1] == out.len());
        self.along_x(spec, &self.inv[0]);
        self.along_y(spec, &self.inv[1], keep[0]);
        spec.par_chunks_mut(ny * nh)
            .zip(out.par_chunks_mut(keep[1] * n))
            .for_each_init(scratch, |s, (slab, o)| {
                slab.chunks_mut(nh)
                    .zip(o.chunks_mut(n))
                    .for_each(|(freq, o)| along_t(s, freq, o))
            });
    }

    fn along_y(&self, spec: &mut [C32], fft: &Arc<dyn Fft<f32>>, x_lines: usize) {
        let ny = self.dims[1];
        let nh = self.half();
        spec.par_chunks_mut(ny * nh).take(x_lines).for_each_init(
            || Scratch::new(fft, ny),
            |s, slab| s.across_rows(fft, slab.chunks_mut(nh).collect()),
        );
    }

    fn along_x(&self, spec: &mut [C32], fft: &Arc<dyn Fft<f32>>) {
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
        rows.into_par_iter().for_each_init(
            || Scratch::new(fft, nx),
            |s, group| s.across_rows(fft, group),
        );
    }
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

    /// Direct O(n²) DFT along each axis, as the reference for the pruned transforms.
    fn dft3(x: &[C32], d: [usize; 3], sign: f64) -> Vec<C32> {
        let mut out = x.to_vec();
        for axis in 0..3 {
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

    #[test]
    fn pruned_transforms_match_the_direct_dft() {
        let d = [6, 4, 40];
        let (nt, n_out) = (d[2], 30);
        let plan = Fft3::new(d);
        let nh = plan.half();
        let value =
            |ix: usize, iy: usize, t: usize| ((ix * 7 + iy * 3 + t) % 11) as f32 - 0.1 * t as f32;
        let mut x = vec![C32::default(); d.iter().product()];
        for ix in 0..3 {
            for iy in 0..2 {
                for t in 0..nt {
                    x[(ix * 4 + iy) * nt + t] = C32::new(value(ix, iy, t), 0.0);
                }
            }
        }
        let want = dft3(&x, d, -1.0);
        let spec = plan.forward([3, 2], |ix, iy, line| {
            line.iter_mut()
                .enumerate()
                .for_each(|(t, v)| *v = value(ix, iy, t))
        });
        // Relative to the largest value, f32 rounding: 1e-5 for spectra, 1e-5 after the round
        // trip, 1e-4 for the squared magnitudes.
        let scale = want.iter().map(|v| v.norm()).fold(0.0, f32::max);
        for (i, a) in spec.iter().enumerate() {
            let b = want[i / nh * nt + i % nh];
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
        let kept = |out: &[f32], f: &dyn Fn(usize, usize, usize) -> f32, tol: f32| {
            for ix in 0..3 {
                for iy in 0..2 {
                    for t in 0..n_out {
                        let (a, b) = (out[(ix * 2 + iy) * n_out + t], f(ix, iy, t));
                        assert!((a - b).abs() < tol, "({ix}, {iy}, {t}): {a} vs {b}");
                    }
                }
            }
        };
        let mut out = vec![0.0f32; 3 * 2 * n_out];
        plan.inverse(&mut spec.clone(), [3, 2], &mut out);
        let peak = x.iter().map(|v| v.re.abs()).fold(0.0, f32::max);
        kept(&out, &|ix, iy, t| value(ix, iy, t), 1e-5 * peak);
        // The analytic signal: the direct inverse of the spectrum without negative frequencies.
        let mut one_sided = want.clone();
        one_sided
            .iter_mut()
            .enumerate()
            .filter(|(i, _)| i % nt >= nh)
            .for_each(|(_, v)| *v = C32::default());
        let len = x.len() as f32;
        let z: Vec<f32> = dft3(&one_sided, d, 1.0)
            .iter()
            .map(|v| (v / len).norm_sqr())
            .collect();
        plan.inverse_power_one_sided(&mut spec.clone(), [3, 2], &mut out);
        let peak = z.iter().copied().fold(0.0, f32::max);
        kept(&out, &|ix, iy, t| z[(ix * 4 + iy) * nt + t], 1e-4 * peak);
        // A pointwise map between the inverse and forward transforms: the spectrum of x².
        let mut squared = spec;
        plan.map_real(&mut squared, |v| v * v);
        let x2: Vec<C32> = x.iter().map(|v| v * v).collect();
        let want = dft3(&x2, d, -1.0);
        let scale = want.iter().map(|v| v.norm()).fold(0.0, f32::max);
        for (i, a) in squared.iter().enumerate() {
            let b = want[i / nh * nt + i % nh];
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
    }
}
