//! 3-D FFT on a C-order `[nx][ny][nt]` complex buffer (t contiguous), planned once, with pruning:
//! the confocal methods zero-pad the data into one octant and keep one octant of the result, so the
//! forward transform skips the all-zero lines and the inverse skips lines that are cropped away.

use rayon::prelude::*;
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

pub(crate) type C32 = Complex32;

/// Lines along t are batched in blocks of this many when transforming along x or y, so the
/// gathered block stays in cache.
const T_BLOCK: usize = 32;

pub(crate) struct Fft3 {
    pub dims: [usize; 3],
    fwd: [Arc<dyn Fft<f32>>; 3],
    inv: [Arc<dyn Fft<f32>>; 3],
}

impl Fft3 {
    pub fn new(dims: [usize; 3]) -> Self {
        let mut planner = FftPlanner::new();
        let fwd = dims.map(|n| planner.plan_fft_forward(n));
        let inv = dims.map(|n| planner.plan_fft_inverse(n));
        Fft3 { dims, fwd, inv }
    }

    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Unnormalised forward transform of data that is zero outside x < `support[0]`, y < `support[1]`.
    pub fn forward(&self, buf: &mut [C32], support: [usize; 2]) {
        self.along_t(buf, &self.fwd[2], support);
        self.along_y(buf, &self.fwd[1], support[0]);
        self.along_x(buf, &self.fwd[0]);
    }

    /// Inverse transform scaled by 1/len, exact only on x < `keep[0]`, y < `keep[1]` (the rest of the
    /// buffer is left partially transformed).
    pub fn inverse(&self, buf: &mut [C32], keep: [usize; 2]) {
        self.along_x(buf, &self.inv[0]);
        self.along_y(buf, &self.inv[1], keep[0]);
        self.along_t(buf, &self.inv[2], keep);
        let s = 1.0 / self.len() as f32;
        let [_, ny, nt] = self.dims;
        buf.par_chunks_mut(ny * nt)
            .take(keep[0])
            .for_each(|slab| slab[..keep[1] * nt].iter_mut().for_each(|v| *v *= s));
    }

    fn along_t(&self, buf: &mut [C32], fft: &Arc<dyn Fft<f32>>, lines: [usize; 2]) {
        let [_, ny, nt] = self.dims;
        buf.par_chunks_mut(ny * nt).take(lines[0]).for_each_init(
            || vec![C32::default(); fft.get_inplace_scratch_len()],
            |scratch, slab| fft.process_with_scratch(&mut slab[..lines[1] * nt], scratch),
        );
    }

    fn along_y(&self, buf: &mut [C32], fft: &Arc<dyn Fft<f32>>, x_lines: usize) {
        let [_, ny, nt] = self.dims;
        buf.par_chunks_mut(ny * nt).take(x_lines).for_each_init(
            || Scratch::new(fft, ny),
            |s, slab| s.across_rows(fft, slab.chunks_mut(nt).collect()),
        );
    }

    fn along_x(&self, buf: &mut [C32], fft: &Arc<dyn Fft<f32>>) {
        let [nx, ny, nt] = self.dims;
        // rows[y][x] borrows the t-line at (x, y): groups of rows with equal y are disjoint and
        // can be transformed in parallel without unsafe code.
        let mut rows: Vec<Vec<&mut [C32]>> = (0..ny).map(|_| Vec::with_capacity(nx)).collect();
        for slab in buf.chunks_mut(ny * nt) {
            for (y, line) in slab.chunks_mut(nt).enumerate() {
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

    /// Transforms across the rows (element t of every row forms one signal), a block of t at a time.
    fn across_rows(&mut self, fft: &Arc<dyn Fft<f32>>, mut rows: Vec<&mut [C32]>) {
        let n = rows.len();
        let nt = rows[0].len();
        for t0 in (0..nt).step_by(T_BLOCK) {
            let tb = T_BLOCK.min(nt - t0);
            let block = &mut self.block[..tb * n];
            for (r, row) in rows.iter().enumerate() {
                for (j, v) in row[t0..t0 + tb].iter().enumerate() {
                    block[j * n + r] = *v;
                }
            }
            fft.process_with_scratch(block, &mut self.fft);
            for (r, row) in rows.iter_mut().enumerate() {
                for (j, v) in row[t0..t0 + tb].iter_mut().enumerate() {
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
        let plan = Fft3::new(d);
        let mut x = vec![C32::default(); plan.len()];
        for ix in 0..3 {
            for iy in 0..2 {
                for t in 0..40 {
                    x[(ix * 4 + iy) * 40 + t] = C32::new(((ix * 7 + iy * 3 + t) % 11) as f32, 0.5);
                }
            }
        }
        let want = dft3(&x, d, -1.0);
        let mut y = x.clone();
        plan.forward(&mut y, [3, 2]);
        let scale = want.iter().map(|v| v.norm()).fold(0.0, f32::max);
        for (a, b) in y.iter().zip(&want) {
            assert!((a - b).norm() < 1e-5 * scale, "{a} vs {b}");
        }
        plan.inverse(&mut y, [3, 2]);
        for ix in 0..3 {
            for iy in 0..2 {
                for t in 0..40 {
                    let i = (ix * 4 + iy) * 40 + t;
                    assert!((y[i] - x[i]).norm() < 1e-4, "{} vs {}", y[i], x[i]);
                }
            }
        }
    }
}
