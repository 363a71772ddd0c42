//! The CPU executor of a [`FastPlan`]: a workspace per worker thread, planes and frequencies shared
//! among rayon's workers, and the products and resampling in wide (AVX) loops. The plan says what
//! each step computes; this module only how.

use super::plan::{amplitude, c32, legs, Reading, Schedule, X, Y};
use super::FastPlan;
use crate::cmul;
use crate::fft2::{kept_lines, kept_spans};
use crate::phase;
use crate::spectrum::Part;
use crate::Progress;
use lattice::{mirror, reach, Deliver, Sink, BATCH};
use murk_core::simd::wide;
use murk_core::{Capture, DVec3};
use rayon::prelude::*;
use rustfft::num_complex::{Complex32, Complex64};
use std::sync::Mutex;

mod lattice;

/// Workers that share a slab's planes: rayon's threads.
pub(super) fn workers() -> usize {
    rayon::current_num_threads().max(1)
}

/// `f` at each of `zs`, in parallel.
pub(super) fn each<T: Send>(zs: &[f64], f: impl Fn(f64) -> T + Sync) -> Vec<T> {
    zs.par_iter().map(|&z| f(z)).collect()
}

/// The field at every voxel (x-major, planes contiguous) from `data` (a capture of `plan`'s
/// geometry), evaluated on `schedule`'s planes slab by slab, then interpolated to the volume's
/// planes where the schedule evaluates every other one.
pub(super) fn run(
    plan: &FastPlan,
    schedule: &Schedule,
    data: &Capture,
    progress: &dyn Progress,
) -> Vec<Complex32> {
    let (nx, ny, nz) = (plan.vol.x.n, plan.vol.y.n, plan.vol.z.n);
    let sources = plan.sources();
    let Schedule {
        depths,
        slabs,
        windows,
    } = schedule;
    let ne = depths.z.len();
    progress.start((sources.len() * ne) as u64);
    let nxy = nx * ny;
    // The evaluated planes, [xy][plane]. Zero pages from the OS, first touched by the threads
    // that write them.
    let mut field: Vec<Complex32> = murk_core::buffer::zeroed(nxy * ne);
    // A slab's planes summed over the point-side sources in f64 ([xy][plane], so each voxel's
    // run of planes is contiguous) before the one rounding to f32.
    let mut sum: Vec<Complex64> = Vec::new();
    let all = crate::spectrum::spectra(data, windows);
    let mut grid = GridBuffers::default();
    // One workspace per worker thread for the whole run (planes of every slab reuse them).
    let pool: Vec<Mutex<Workspace>> = (0..rayon::current_num_threads().max(1))
        .map(|_| Mutex::new(Workspace::new(plan)))
        .collect();
    for (k, planes) in slabs.iter().enumerate() {
        let spectra = all.part(k);
        let np = planes.len();
        murk_core::buffer::grow(&mut sum, nxy * np, Complex64::default());
        // The shallowest plane keeps the most lines: grid spectra on its lines serve all.
        let dz_min = depths.z[planes.clone()]
            .iter()
            .map(|z| z - plan.grid.origin.z)
            .fold(f64::INFINITY, f64::min);
        for (i, &src) in sources.iter().enumerate() {
            let reads: Vec<Reading> = (0..spectra.band.len())
                .map(|j| plan.reading(legs(src) * spectra.band.k(j), dz_min))
                .collect();
            let hspec = plan.grid_spectra(&spectra, src, &reads, &mut grid, &pool);
            let out: Vec<Vec<Complex32>> = planes
                .clone()
                .into_par_iter()
                .map(|iz| {
                    let mut ws = lock(&pool);
                    let z = depths.z[iz];
                    let plane = plan.plane(&mut ws, &spectra, &hspec, &reads, src, z);
                    progress.advance(1);
                    plane
                })
                .collect();
            // The first source sets the sum, so it needs no zeroing between slabs.
            sum.par_chunks_mut(np).enumerate().for_each(|(ixy, s)| {
                for (a, plane) in s.iter_mut().zip(&out) {
                    let v = Complex64::new(plane[ixy].re as f64, plane[ixy].im as f64);
                    *a = if i == 0 { v } else { *a + v };
                }
            });
        }
        field
            .par_chunks_mut(ne)
            .zip(sum.par_chunks(np))
            .for_each(|(col, s)| {
                for (d, a) in col[planes.clone()].iter_mut().zip(s) {
                    *d = c32(*a);
                }
            });
    }
    if !depths.interpolates() {
        return field;
    }
    let mut volume: Vec<Complex32> = murk_core::buffer::zeroed(nxy * nz);
    volume
        .par_chunks_mut(nz)
        .zip(field.par_chunks(ne))
        .for_each(|(col, evaluated)| depths.read(evaluated, col));
    volume
}

impl FastPlan {
    /// FFT2 of each band frequency's spectrum laid out on the wall grid, in the transposed layout, on
    /// the lines its `reads` entry keeps (the slab's shallowest plane's), divided by the spectra of
    /// the kernels it chose and cut to their bands: with a folded kernel only those lines and kx,
    /// packed (see [`lattice::pack`]), else whole (the lines not kept are garbage). The buffers are
    /// reused across slabs.
    fn grid_spectra<'b>(
        &self,
        spectra: &Part,
        src: Option<usize>,
        reads: &[Reading],
        buf: &'b mut GridBuffers,
        pool: &[Mutex<Workspace>],
    ) -> GridSpectra<'b> {
        let (fx, fy) = (self.fft.fx, self.fft.fy);
        let (gnx, gny) = (self.grid.nx, self.grid.ny);
        let cells = gnx * gny;
        let nb = spectra.band.len();
        // Frequency-major copy of the grid's spectra, so each frequency reads contiguous memory;
        // split by frequency ranges so each task reads one contiguous run per histogram.
        let by_freq = &mut buf.by_freq;
        murk_core::buffer::grow(by_freq, nb * cells, Complex32::default());
        let per_task = nb.div_ceil(4 * rayon::current_num_threads()).max(1);
        by_freq[..nb * cells]
            .par_chunks_mut(per_task * cells)
            .enumerate()
            .for_each(|(task, block)| {
                let (j0, nj) = (task * per_task, block.len() / cells);
                for cell in 0..cells {
                    let h = &spectra.hist(self.hist_index(cell, src))[j0..j0 + nj];
                    for (dj, v) in h.iter().enumerate() {
                        block[dj * cells + cell] = *v;
                    }
                }
            });
        let mut offsets = vec![0];
        for r in reads {
            let size = match self.fold {
                Some(_) => lattice::packed_size([fx, fy], r.lines, r.x_lines),
                None => fx * fy,
            };
            offsets.push(offsets[offsets.len() - 1] + size);
        }
        let out = &mut buf.spec;
        murk_core::buffer::grow(out, offsets[nb], Complex32::default());
        let mut parts = Vec::with_capacity(nb);
        let mut rest = &mut out[..offsets[nb]];
        for w in offsets.windows(2) {
            let (part, tail) = std::mem::take(&mut rest).split_at_mut(w[1] - w[0]);
            parts.push(part);
            rest = tail;
        }
        parts
            .into_par_iter()
            .zip(by_freq[..nb * cells].par_chunks(cells))
            .enumerate()
            .for_each(|(j, (part, cells))| {
                let read = &reads[j];
                let mut ws = lock(pool);
                let Workspace {
                    grid_in: a,
                    g,
                    scratch,
                    ..
                } = &mut *ws;
                let spectrum = [a, scratch];
                match self.fold {
                    // Transformed whole, then packed.
                    Some(_) => {
                        self.grid_spectrum(cells, read, spectrum, g);
                        lattice::pack(g, [fx, fy], read.lines, read.x_lines, part);
                    }
                    None => self.grid_spectrum(cells, read, spectrum, part),
                }
            });
        GridSpectra {
            data: &out[..offsets[nb]],
            offsets,
        }
    }

    /// FFT2 of one frequency's `cells` (the grid's spectra, [x][y]) into `t` ([ky][kx]) on the lines
    /// `read` keeps, normalised (and folded, see [`Fold`]) for the inverse, and divided by the kernels
    /// it chose; `a` holds the zero-padded grid and `scratch` the FFT's scratch.
    fn grid_spectrum(
        &self,
        cells: &[Complex32],
        read: &Reading,
        [a, scratch]: [&mut Vec<Complex32>; 2],
        t: &mut [Complex32],
    ) {
        let (fx, fy) = (self.fft.fx, self.fft.fy);
        let (gnx, gny) = (self.grid.nx, self.grid.ny);
        let lines = read.lines;
        // Rows x ≥ gnx stay zero: only the grid's rows are written and transformed.
        for ix in 0..gnx {
            let row = &mut a[ix * fy..(ix + 1) * fy];
            row[..gny].copy_from_slice(&cells[ix * gny..(ix + 1) * gny]);
            row[gny..]
                .iter_mut()
                .for_each(|v| *v = Complex32::default());
        }
        self.fft.forward_lines(a, gnx, t, lines, scratch);
        // The inverse FFT is unnormalised: fold 1/(fx·fy) in here, once.
        let norm = 1.0 / (fx * fy) as f32;
        for span in kept_spans(fy, lines, fx) {
            match &self.fold {
                Some(f) => cmul::mul_assign(&mut t[span.clone()], &f.phases[span]),
                None => t[span].iter_mut().for_each(|v| *v *= norm),
            }
        }
        self.divide_by_kernels(t, read);
    }

    /// `t` ([ky][kx], on the lines `read` keeps) divided by the spectra of the kernels it chose, and
    /// zero past its `x_lines` along x (where a kernel is chosen for x, its band ends there).
    fn divide_by_kernels(&self, t: &mut [Complex32], read: &Reading) {
        let lines = read.lines;
        let chosen = read.kernels;
        if chosen == [None, None] {
            return;
        }
        let (fx, fy) = (self.fft.fx, self.fft.fy);
        // Along x: the kernel's 1/φ̂ on the bins within x_lines of kx = 0, zero between them.
        let cut = read.x_lines;
        let along_x = chosen[X].map(|i| &self.kb[X][i].inverse);
        for ky in kept_lines(fy, lines).into_iter().flatten() {
            let y = chosen[Y].map_or(1.0, |i| self.kb[Y][i].inverse[ky]);
            let line = &mut t[ky * fx..(ky + 1) * fx];
            let Some(inv) = along_x else {
                line.iter_mut().for_each(|v| *v *= y);
                continue;
            };
            for (q, v) in line.iter_mut().enumerate() {
                *v *= if q.min(fx - q) <= cut {
                    inv[q] * y
                } else {
                    0.0
                };
            }
        }
    }

    fn plane(
        &self,
        ws: &mut Workspace,
        spectra: &Part,
        hspec: &GridSpectra,
        reads: &[Reading],
        src: Option<usize>,
        z: f64,
    ) -> Vec<Complex32> {
        let band = &spectra.band;
        let (fx, fy) = (self.fft.fx, self.fft.fy);
        let (gnx, gny) = (self.grid.nx, self.grid.ny);
        let (vx, vy) = (self.rx.len, self.ry.len);
        let (gx, gy) = (gnx + vx - 1, gny + vy - 1);
        let (nx, ny) = (self.vol.x.n, self.vol.y.n);
        // The lattice rows x of the convolution that the resampler reads.
        let xs = gnx - 1..gnx - 1 + vx;
        let dz = z - self.grid.origin.z;
        let (dxs, dys) = (self.grid.step_x.x, self.grid.step_y.y);
        let legs = legs(src);
        // k_0 = m_lo·Δk: a phase at k_0 is m_lo times the per-frequency step's.
        let (m0, dk) = (band.m_lo, band.dk());
        // The kernel depends on |dx| and |dy| only: its sines, cosines and per-frequency recurrence
        // live in a table over the distinct (|dx|, |dy|) (a quarter of the support when the volume is
        // centred on the wall) that is mirrored into the FFT input.
        let (cx, cy) = (self.cx, self.cy);
        let (mx, my) = (reach(cx, gx), reach(cy, gy));
        // Angles and amplitudes first, then their phasors in one vectorised pass. On a square lattice
        // the table comes out symmetric bit for bit (the same products, summed commutatively).
        ws.theta.clear();
        ws.amp.clear();
        for ax in 0..mx {
            let dx = ax as f64 * dxs;
            for ay in 0..my {
                let dy = ay as f64 * dys;
                let r = (dx * dx + dy * dy + dz * dz).sqrt();
                ws.theta.push(dk * legs * r);
                ws.amp.push(amplitude(self.falloff, r).powf(legs));
            }
        }
        ws.tcur.resize(mx * my, Complex32::default());
        ws.tstep.resize(mx * my, Complex32::default());
        phase::phasors(&ws.theta, &ws.amp, m0 as f64, &mut ws.tcur, &mut ws.tstep);
        // Exact phase of the point-side leg, per voxel (y-major, like the summed field); confocal
        // data have none.
        if let Some(s) = src {
            let point = self.source_point(s);
            ws.theta.clear();
            ws.amp.clear();
            for iy in 0..ny {
                for ix in 0..nx {
                    let v = DVec3::new(self.vol.x.at(ix), self.vol.y.at(iy), z);
                    let d = (v - point).length();
                    ws.theta.push(dk * d);
                    ws.amp.push(amplitude(self.falloff, d));
                }
            }
            phase::phasors(&ws.theta, &ws.amp, m0 as f64, &mut ws.pbase, &mut ws.pstep);
        }
        // Confocal data has no point-side phase, so the sum over frequencies commutes with the inverse
        // FFT and the resampling: accumulate spectra and transform back once per plane.
        let confocal = src.is_none();
        if confocal {
            ws.spec_acc
                .iter_mut()
                .for_each(|v| *v = Complex32::default());
        }
        // Summed field, y-major ([y][x]).
        let mut acc = vec![Complex32::default(); nx * ny];
        for (j, read) in reads.iter().enumerate() {
            let lines = self.lines(legs * band.k(j), dz);
            let h = hspec.at(j);
            if self.fold.is_some() {
                let sink = match confocal {
                    true => Sink::Accumulate,
                    false => Sink::InverseX(xs.clone()),
                };
                self.folded_lines(ws, h, [gx, gy, my], [lines, read.x_lines], &sink);
            } else {
                wide(
                    #[inline(always)]
                    || {
                        for p in 0..fx {
                            let row = &mut ws.g[p * fy..(p + 1) * fy];
                            if p < gx {
                                let ax = (p as i64 - cx).unsigned_abs() as usize;
                                mirror(&mut row[..gy], &ws.tcur[ax * my..(ax + 1) * my], cy);
                                row[gy..].iter_mut().for_each(|v| *v = Complex32::default());
                            } else {
                                row.iter_mut().for_each(|v| *v = Complex32::default());
                            }
                        }
                    },
                );
                self.fft
                    .forward_lines(&mut ws.g, gx, &mut ws.t, lines, &mut ws.scratch);
                // Lines of ws.t outside the kept ones are left as they are: nothing reads them.
                for span in kept_spans(fy, lines, fx) {
                    cmul::mul_assign(&mut ws.t[span.clone()], &h[span.clone()]);
                    if confocal {
                        cmul::add_assign(&mut ws.spec_acc[span.clone()], &ws.t[span]);
                    }
                }
                if !confocal {
                    self.fft
                        .inverse_x(&mut ws.t, &mut ws.g, xs.clone(), lines, &mut ws.scratch);
                }
                // The kernel's table at the next frequency.
                cmul::mul_assign(&mut ws.tcur, &ws.tstep);
            }
            if confocal {
                continue;
            }
            // With the exact phase of the point-side leg.
            let r = self.resamplers(read.kernels);
            self.field_at_voxels(ws, lines, r, &mut acc, Deliver::AddPhased);
        }
        if confocal {
            self.fft
                .inverse_x(&mut ws.spec_acc, &mut ws.g, xs, fy / 2, &mut ws.scratch);
            let r = [&self.rx, &self.ry];
            self.field_at_voxels(ws, fy / 2, r, &mut acc, Deliver::Set);
        }
        // The voxels' order in the volume: x-major.
        let mut out = vec![Complex32::default(); nx * ny];
        transpose::transpose(&acc, &mut out, nx, ny);
        out
    }
}

/// The calling worker thread's workspace (uncontended: one slot per thread, and no rayon call is
/// made while it is held).
fn lock(pool: &[Mutex<Workspace>]) -> std::sync::MutexGuard<'_, Workspace> {
    let slot = rayon::current_thread_index().unwrap_or(0) % pool.len();
    pool[slot].lock().unwrap_or_else(|e| e.into_inner())
}

/// The grid's spectrum of each band frequency (see [`FastPlan::grid_spectra`]).
struct GridSpectra<'a> {
    data: &'a [Complex32],
    /// Where frequency j's spectrum starts in `data`, and past the last, where it ends.
    offsets: Vec<usize>,
}

impl GridSpectra<'_> {
    fn at(&self, j: usize) -> &[Complex32] {
        &self.data[self.offsets[j]..self.offsets[j + 1]]
    }
}

/// The grid's spectra: the frequency-major copy and its FFT2s, kept across slabs.
#[derive(Default)]
struct GridBuffers {
    by_freq: Vec<Complex32>,
    spec: Vec<Complex32>,
}

/// Per-thread buffers, reused across planes and frequencies.
pub(super) struct Workspace {
    /// The grid's spectrum at one frequency, zero-padded: rows x ≥ the grid's stay zero.
    grid_in: Vec<Complex32>,
    g: Vec<Complex32>,
    /// The unfolded kernel's spectrum, then its product with the grid's ([ky][kx]).
    t: Vec<Complex32>,
    scratch: Vec<Complex32>,
    /// Kernel value at the current frequency and its per-frequency phase step, per distinct
    /// (|dx|, |dy|) (f32 recurrence: the drift over a band of a few hundred frequencies stays below
    /// 1e-5).
    tcur: Vec<Complex32>,
    tstep: Vec<Complex32>,
    /// Angles (rad) and amplitudes of the kernel's table or the point-side phases, before their
    /// phasors.
    theta: Vec<f64>,
    amp: Vec<f64>,
    /// Confocal: the plane's spectrum summed over frequencies.
    spec_acc: Vec<Complex32>,
    /// Folded kernel spectrum: the y-transformed distinct rows, transposed.
    cols: Vec<Complex32>,
    /// Folded kernel spectrum: a batch of rows along y, then of lines along x.
    kbuf: Vec<Complex32>,
    /// Folded kernel spectrum: a batch of lines of the product (both halves of the spectrum).
    tlines: Vec<Complex32>,
    /// Point-side phase per voxel and its per-frequency step (f32 recurrence, as for the kernel).
    pbase: Vec<Complex32>,
    pstep: Vec<Complex32>,
    /// One row (y) of the camera-side field at the voxels for the current frequency.
    row: Vec<Complex32>,
    /// The field resampled along x ([voxel x][ky], then [voxel x][lattice y]) and the part of it that
    /// the voxels read, transposed ([lattice y][voxel x]).
    tmp: Vec<Complex32>,
    tmp_t: Vec<Complex32>,
}

impl Workspace {
    fn new(plan: &FastPlan) -> Self {
        let (fx, fy) = (plan.fft.fx, plan.fft.fy);
        let nv = plan.vol.x.n * plan.vol.y.n;
        // Buffers of one path only (the unfolded spectrum, or the folded one's batches) stay empty
        // on the other.
        let folds = plan.fold.is_some();
        let only = |used: bool, n: usize| vec![Complex32::default(); if used { n } else { 0 }];
        Workspace {
            grid_in: vec![Complex32::default(); fx * fy],
            g: vec![Complex32::default(); fx * fy],
            t: only(!folds, fx * fy),
            scratch: plan.fft.scratch(),
            tcur: Vec::new(),
            tstep: Vec::new(),
            theta: Vec::new(),
            amp: Vec::new(),
            spec_acc: vec![Complex32::default(); fx * fy],
            // Folded kernel spectrum: the distinct rows' columns ky ≤ fy/2, the most it keeps.
            cols: only(folds, (fy / 2 + 1) * (plan.cx as usize + 1)),
            kbuf: only(folds, BATCH * fx.max(fy)),
            tlines: only(folds, 2 * BATCH * fx),
            pbase: vec![Complex32::default(); nv],
            pstep: vec![Complex32::default(); nv],
            row: vec![Complex32::default(); plan.vol.x.n],
            tmp: vec![Complex32::default(); plan.vol.x.n * fy],
            tmp_t: vec![Complex32::default(); plan.vol.x.n * plan.ry.len],
        }
    }
}
