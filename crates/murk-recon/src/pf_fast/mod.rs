//! Fast Phasor Fields for planar wall grids (docs/reconstruction.md): for each frequency and depth plane, the
//! camera-side RSD sum over the wall grid is a 2-D linear convolution, done by zero-padded FFTs and
//! cropped where no wrap-around can reach. The single point of the other side gets its exact per-voxel
//! phase afterwards; confocal captures use the round-trip kernel e^{2ikr}. Volumes whose lateral samples
//! are not on the wall lattice read the convolution through a windowed-sinc resampler.

use crate::cmul;
use crate::fft2::{kept_lines, kept_spans, Fft2};
use crate::phase;
use crate::resample::{KaiserBessel, Resampler};
use crate::spectrum::{next_fast_len, path_range, Part, Window};
use crate::{Falloff, Lateral, Progress};
use lattice::{mirror, reach, Deliver, Fold, Sink, BATCH};
use murk_core::simd::wide;
use murk_core::{Axis, Capture, CaptureKind, DVec3, Error, RegularGrid, Result, Volume};
use rayon::prelude::*;
use rustfft::num_complex::{Complex32, Complex64};
use std::ops::Range;

mod depths;
mod lattice;
use depths::Depths;
use std::sync::Mutex;

/// Which histogram feeds grid cell `c` for a given point-side index.
#[derive(Clone, Copy)]
enum GridSide {
    Illum,
    Sensor,
    Confocal,
}

/// Axis indices of per-axis pairs.
const X: usize = 0;
const Y: usize = 1;

/// Relative aliasing the Kaiser–Bessel kernels are shaped for: below the 16-tap windowed sinc's
/// (3e-4 at a quarter of the Nyquist band, 1e-2 at 0.77 of it) over every band they serve.
const KB_ALIASING: f64 = 1e-4;

/// A Kaiser–Bessel kernel along one axis: its resampler on the plan's lattice and the factor 1/φ̂ per
/// FFT bin that the grid's spectra take beforehand.
struct Kb {
    kernel: KaiserBessel,
    resampler: Resampler,
    inverse: Vec<f32>,
}

impl Kb {
    fn new(
        kernel: &KaiserBessel,
        positions: &[f64],
        centre: f64,
        sinc: &Resampler,
        f: usize,
    ) -> Kb {
        let inverse = (0..f)
            .map(|q| {
                let omega = 2.0 * std::f64::consts::PI * q.min(f - q) as f64 / f as f64;
                (1.0 / kernel.spectrum(omega)) as f32
            })
            .collect();
        Kb {
            kernel: kernel.clone(),
            resampler: Resampler::kaiser_bessel(positions, centre, kernel)
                .rebased(sinc.lo, sinc.len),
            inverse,
        }
    }
}

/// Depth planes evaluated together over one time window.
#[derive(Clone, Debug)]
pub struct Slab {
    /// Indices among the evaluated planes, which are every volume plane or every other one and a
    /// few past the ends (see [`Lateral::Propagating`]).
    pub planes: Range<usize>,
    pub frequencies: usize,
    pub dft_len: usize,
}

pub struct FastPlan {
    /// The capture's geometry (no histograms).
    cap: Capture,
    vol: Volume,
    falloff: Falloff,
    grid: RegularGrid,
    side: GridSide,
    rx: Resampler,
    ry: Resampler,
    /// Per axis (x, y), the shorter kernels that replace `rx`/`ry` for a band frequency whose lateral
    /// band is cut along that axis (see [`FastPlan::kernels`]); empty on the lattice, for confocal data
    /// (one resampling per plane after the frequency sum) and with [`Lateral::Full`].
    kb: [Vec<Kb>; 2],
    fft: Fft2,
    /// Lattice index, within the kernel's support, of the zero offset along x and y.
    cx: i64,
    cy: i64,
    /// Phases that fold a symmetric kernel's spectrum onto its non-negative frequencies.
    fold: Option<Fold>,
    lateral: Lateral,
}

impl FastPlan {
    /// Checks the preconditions of the fast form; the error says why it does not apply.
    pub fn new(
        cap: &Capture,
        kind: CaptureKind,
        vol: &Volume,
        falloff: Falloff,
        lateral: Lateral,
    ) -> Result<FastPlan> {
        let unsupported = |why: &str| Error::Unsupported(why.into());
        let regular = |p: &murk_core::PointSet| p.regular_grid();
        let (grid, side) = match kind {
            CaptureKind::Confocal => (regular(&cap.illum), GridSide::Confocal),
            CaptureKind::LaserGridSinglePoint => (regular(&cap.illum), GridSide::Illum),
            CaptureKind::SinglePointSensorGrid => (regular(&cap.sensor), GridSide::Sensor),
            CaptureKind::Exhaustive => match regular(&cap.sensor) {
                Some(g) => (Some(g), GridSide::Sensor),
                None => (regular(&cap.illum), GridSide::Illum),
            },
            CaptureKind::Paired => return Err(unsupported("paired, non-confocal capture")),
        };
        let grid =
            grid.ok_or_else(|| unsupported("the wall points are not a regular planar grid"))?;
        let along = |v: DVec3, axis: DVec3| {
            v.dot(axis) > 0.0 && (v - axis * v.dot(axis)).length() <= 1e-9 * v.length()
        };
        if !along(grid.step_x, DVec3::X) || !along(grid.step_y, DVec3::Y) {
            return Err(unsupported("the wall grid's axes are not world +x and +y"));
        }
        let wall_z = grid.origin.z;
        if vol.z.start.min(vol.z.end) <= wall_z {
            return Err(unsupported(
                "the volume is not entirely in front of the wall plane",
            ));
        }
        // Voxel positions in lattice units and the lattice's centre, per axis.
        let lattice = |axis: &murk_core::Axis, o: f64, d: f64, n: usize| {
            let positions: Vec<f64> = axis.values().iter().map(|x| (x - o) / d).collect();
            (positions, (n as f64 - 1.0) / 2.0)
        };
        let (px, ox) = lattice(&vol.x, grid.origin.x, grid.step_x.x, grid.nx);
        let (py, oy) = lattice(&vol.y, grid.origin.y, grid.step_y.y, grid.ny);
        let (rx, ry) = (Resampler::new(&px, ox), Resampler::new(&py, oy));
        let fft = Fft2::new(
            next_fast_len(grid.nx + rx.len - 1),
            next_fast_len(grid.ny + ry.len - 1),
        );
        let family = match (kind, lateral) {
            (CaptureKind::Confocal, _) | (_, Lateral::Full) => Vec::new(),
            _ => KaiserBessel::family(KB_ALIASING),
        };
        let kernels = |positions: &[f64], centre: f64, sinc: &Resampler, f: usize| {
            if sinc.taps == 1 {
                return Vec::new();
            }
            family
                .iter()
                .map(|kernel| Kb::new(kernel, positions, centre, sinc, f))
                .collect()
        };
        let kb = [kernels(&px, ox, &rx, fft.fx), kernels(&py, oy, &ry, fft.fy)];
        if fft.fx * fft.fy > 1 << 24 {
            return Err(unsupported(&format!(
                "the convolution would need {}×{} FFTs",
                fft.fx, fft.fy
            )));
        }
        let cx = grid.nx as i64 - 1 - rx.lo;
        let cy = grid.ny as i64 - 1 - ry.lo;
        let (gx, gy) = (grid.nx + rx.len - 1, grid.ny + ry.len - 1);
        let fold = (2 * cx + 1 == gx as i64 && 2 * cy + 1 == gy as i64)
            .then(|| Fold::new(fft.fx, fft.fy, cx, cy));
        Ok(FastPlan {
            cap: cap.geometry(),
            vol: *vol,
            falloff,
            grid,
            side,
            rx,
            ry,
            kb,
            fft,
            cx,
            cy,
            fold,
            lateral,
        })
    }

    /// How many spectrum lines on each side of ky = 0 a plane at `dz` from the wall keeps for the
    /// kernel wavenumber `k` (rad/m; see [`Lateral`]); fy/2 keeps all.
    fn lines(&self, k: f64, dz: f64) -> usize {
        self.lines_along(Y, k, dz)
    }

    /// [`FastPlan::lines`] along `axis` (X or Y): the lines of the other axis' transform it keeps.
    fn lines_along(&self, axis: usize, k: f64, dz: f64) -> usize {
        let (step, f) = match axis {
            X => (self.grid.step_x.x, self.fft.fx),
            _ => (self.grid.step_y.y, self.fft.fy),
        };
        match self.lateral {
            Lateral::Full => f / 2,
            Lateral::Propagating => {
                let line = kappa(k, dz) * step * f as f64 / (2.0 * std::f64::consts::PI);
                (line.ceil() as usize + 6).min(f / 2)
            }
        }
    }

    /// Per axis, which of `kb` reads the field of wavenumber `k` on planes at `dz` or deeper: the
    /// shortest whose band holds the lines kept along that axis, which the grid's spectra are then
    /// cut to and divided by the kernel's spectrum along. `None`: the windowed sinc, uncut.
    fn kernels(&self, k: f64, dz: f64) -> [Option<usize>; 2] {
        if self.lateral == Lateral::Full {
            return [None, None];
        }
        let kappa = kappa(k, dz);
        [X, Y].map(|axis| {
            let step = [self.grid.step_x.x, self.grid.step_y.y][axis];
            let band = kappa * step / std::f64::consts::PI;
            self.kb[axis].iter().position(|kb| kb.kernel.band >= band)
        })
    }

    /// How the field of wavenumber `k` is read on planes at `dz_min` or deeper: its kernels and the
    /// band along x its grid spectra are cut to.
    fn reading(&self, k: f64, dz_min: f64) -> Reading {
        let kernels = self.kernels(k, dz_min);
        let half = self.fft.fx / 2;
        Reading {
            kernels,
            lines: self.lines(k, dz_min),
            x_lines: match kernels[X] {
                Some(_) => self.lines_along(X, k, dz_min).min(half),
                None => half,
            },
        }
    }

    /// The resamplers that read the field of a frequency with kernels `chosen` (x, y).
    fn resamplers(&self, chosen: [Option<usize>; 2]) -> [&Resampler; 2] {
        let pick = |axis: usize, sinc| chosen[axis].map_or(sinc, |i| &self.kb[axis][i].resampler);
        [pick(X, &self.rx), pick(Y, &self.ry)]
    }

    /// Whether the field of wavenumber `k` on planes at `dz` is read by Kaiser–Bessel kernels along
    /// both axes (see [`FastPlan::kernels`]).
    #[cfg(test)]
    pub fn reads_kaiser_bessel(&self, k: f64, dz: f64) -> bool {
        self.kernels(k, dz).iter().all(Option::is_some)
    }

    /// Whether the kernel's spectrum is folded (see [`Fold`]).
    #[cfg(test)]
    pub fn folds(&self) -> bool {
        self.fold.is_some()
    }

    /// Point-side indices: one pass per point of the non-gridded side (none for confocal).
    fn sources(&self) -> Vec<Option<usize>> {
        match self.side {
            GridSide::Confocal => vec![None],
            GridSide::Illum => (0..self.cap.sensor.len()).map(Some).collect(),
            GridSide::Sensor => (0..self.cap.illum.len()).map(Some).collect(),
        }
    }

    fn hist_index(&self, cell: usize, src: Option<usize>) -> usize {
        let ns = self.cap.sensor.len();
        match (self.side, src) {
            (GridSide::Illum, Some(s)) => cell * ns + s,
            (GridSide::Sensor, Some(l)) => l * ns + cell,
            _ => cell,
        }
    }

    fn source_point(&self, src: usize) -> DVec3 {
        match self.side {
            GridSide::Illum => self.cap.sensor.points[src],
            _ => self.cap.illum.points[src],
        }
    }

    /// The field at every voxel from `data` (a capture of this plan's geometry), and the depth slabs
    /// it was computed in.
    pub fn run(
        &self,
        data: &Capture,
        sigma_m: f64,
        wavelength_m: f64,
        progress: &dyn Progress,
    ) -> Result<(Vec<Complex32>, Vec<Slab>)> {
        let (nx, ny, nz) = (self.vol.x.n, self.vol.y.n, self.vol.z.n);
        let sources = self.sources();
        let (depths, slabs, windows) = self.depths(sigma_m, wavelength_m)?;
        let ne = depths.z.len();
        progress.start((sources.len() * ne) as u64);
        let nxy = nx * ny;
        // The evaluated planes, [xy][plane]. Zero pages from the OS, first touched by the threads
        // that write them.
        let mut field: Vec<Complex32> = murk_core::buffer::zeroed(nxy * ne);
        // A slab's planes summed over the point-side sources in f64 ([xy][plane], so each voxel's
        // run of planes is contiguous) before the one rounding to f32.
        let mut sum: Vec<Complex64> = Vec::new();
        let all = crate::spectrum::spectra(data, &windows);
        let mut grid = GridBuffers::default();
        // One workspace per worker thread for the whole run (planes of every slab reuse them).
        let pool: Vec<Mutex<Workspace>> = (0..rayon::current_num_threads().max(1))
            .map(|_| Mutex::new(Workspace::new(self)))
            .collect();
        for (k, planes) in slabs.iter().enumerate() {
            let spectra = all.part(k);
            let np = planes.len();
            murk_core::buffer::grow(&mut sum, nxy * np, Complex64::default());
            // The shallowest plane keeps the most lines: grid spectra on its lines serve all.
            let dz_min = depths.z[planes.clone()]
                .iter()
                .map(|z| z - self.grid.origin.z)
                .fold(f64::INFINITY, f64::min);
            for (i, &src) in sources.iter().enumerate() {
                let reads: Vec<Reading> = (0..spectra.band.len())
                    .map(|j| self.reading(legs(src) * spectra.band.k(j), dz_min))
                    .collect();
                let hspec = self.grid_spectra(&spectra, src, &reads, &mut grid, &pool);
                let out: Vec<Vec<Complex32>> = planes
                    .clone()
                    .into_par_iter()
                    .map(|iz| {
                        let mut ws = lock(&pool);
                        let z = depths.z[iz];
                        let plane = self.plane(&mut ws, &spectra, &hspec, &reads, src, z);
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
        let slabs = slabs
            .into_iter()
            .zip(windows)
            .map(|(planes, w)| Slab {
                planes,
                frequencies: w.band.len(),
                dft_len: w.band.nf,
            })
            .collect();
        if !depths.interpolates() {
            return Ok((field, slabs));
        }
        let mut volume: Vec<Complex32> = murk_core::buffer::zeroed(nxy * nz);
        volume
            .par_chunks_mut(nz)
            .zip(field.par_chunks(ne))
            .for_each(|(col, evaluated)| depths.read(evaluated, col));
        Ok((volume, slabs))
    }

    /// The depth planes to evaluate, with their slabs and time windows: every other plane (see
    /// [`Depths`]) where the fast form may approximate ([`Lateral::Propagating`]) and the field's
    /// depth band allows, else every plane.
    fn depths(
        &self,
        sigma_m: f64,
        wavelength_m: f64,
    ) -> Result<(Depths, Vec<Range<usize>>, Vec<Window>)> {
        let halved = match self.lateral {
            Lateral::Propagating => Depths::halved(&self.vol, self.grid.origin.z),
            Lateral::Full => None,
        };
        if let Some(mut d) = halved {
            // Planes past the ends lengthen the window; where that fails, every plane is evaluated.
            if let Ok((slabs, windows)) = self.slabs(&d.z, sigma_m, wavelength_m) {
                if d.design(self.depth_band(&d, &windows)) {
                    return Ok((d, slabs, windows));
                }
            }
        }
        let d = Depths::every(&self.vol);
        let (slabs, windows) = self.slabs(&d.z, sigma_m, wavelength_m)?;
        Ok((d, slabs, windows))
    }

    /// The band (rad/m) of depth frequencies of the field over the planes of `d`: the band's
    /// wavenumbers times the range of the path's depth rate.
    fn depth_band(&self, d: &Depths, windows: &[Window]) -> (f64, f64) {
        let g = &self.grid;
        let corner = g.point(g.nx - 1, g.ny - 1);
        let wall = [
            (g.origin.x.min(corner.x), g.origin.x.max(corner.x)),
            (g.origin.y.min(corner.y), g.origin.y.max(corner.y)),
        ];
        let points: Vec<DVec3> = self
            .sources()
            .into_iter()
            .flatten()
            .map(|s| self.source_point(s))
            .collect();
        let z = (d.z[0], d.z[d.z.len() - 1]);
        let legs = if points.is_empty() { 2.0 } else { 1.0 };
        let (r0, r1) = depths::depth_rate(&self.vol, z, wall, g.origin.z, &points, legs);
        let k0 = windows
            .iter()
            .map(|w| w.band.k(0))
            .fold(f64::INFINITY, f64::min);
        let k1 = windows
            .iter()
            .map(|w| w.band.k(w.band.len() - 1))
            .fold(0.0, f64::max);
        ((k0 * r0).min(k1 * r0), (k0 * r1).max(k1 * r1))
    }

    /// Splits the planes at depths `zs` into contiguous slabs, each with its own time window. A
    /// slab's paths span less than the whole volume's, so its DFT is shorter and holds fewer band
    /// frequencies (the plane work is proportional to them), but each slab transforms the data and
    /// the grid spectra once more. The split minimises a cost model in FFT point-operations, with
    /// planes shared among the worker threads, by dynamic programming over slab ends.
    fn slabs(
        &self,
        zs: &[f64],
        sigma_m: f64,
        wavelength_m: f64,
    ) -> Result<(Vec<Range<usize>>, Vec<Window>)> {
        const MAX_PLANES: usize = 256;
        let nz = zs.len();
        let paths: Vec<(f64, f64)> = zs
            .par_iter()
            .map(|&z| {
                let plane = Volume {
                    z: Axis::new(z, z, 1),
                    ..self.vol
                };
                path_range(&self.cap, &plane)
            })
            .collect();
        let threads = rayon::current_num_threads().max(1);
        let n = (self.fft.fx * self.fft.fy) as f64;
        let fft2 = n * n.log2();
        // Costs per frequency, relative to one FFT2: a plane (kernel spectrum, inverse FFT,
        // resampling; confocal planes skip the per-frequency inverse), and the grid's spectra
        // (gather, forward FFT2) per source; a histogram's transform costs about its n·log2 n. The
        // constants are fitted to the Z-letter bench (docs/benchmarks.md, "Constants of the fast PF").
        let per_plane = if matches!(self.side, GridSide::Confocal) {
            1.5
        } else {
            2.5
        } * fft2;
        let per_freq = 4.0 * fft2 / threads as f64;
        let sources = self.sources().len() as f64;
        let cost = |planes: usize, w: &Window| {
            let nf = w.band.nf as f64;
            let data = self.cap.n_hist() as f64 * nf * nf.log2() / threads as f64;
            let waves = planes.div_ceil(threads) as f64;
            w.band.len() as f64 * sources * (waves * per_plane + per_freq) + data
        };
        let window = |lo: f64, hi: f64| Window::new(&self.cap, (lo, hi), sigma_m, wavelength_m);
        // best[i]: cost of planes 0..i, where its last slab starts, and that slab's window.
        let mut best: Vec<(f64, usize, Option<Window>)> =
            (0..=nz).map(|_| (f64::INFINITY, 0, None)).collect();
        best[0].0 = 0.0;
        for j in 0..nz {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in j + 1..=(j + MAX_PLANES).min(nz) {
                lo = lo.min(paths[i - 1].0);
                hi = hi.max(paths[i - 1].1);
                let w = window(lo, hi)?;
                let c = best[j].0 + cost(i - j, &w);
                if c < best[i].0 {
                    best[i] = (c, j, Some(w));
                }
            }
        }
        let (mut ranges, mut windows) = (Vec::new(), Vec::new());
        let mut i = nz;
        while i > 0 {
            let (_, j, w) = std::mem::replace(&mut best[i], (0.0, 0, None));
            ranges.push(j..i);
            windows.push(w.expect("every reachable end has a window"));
            i = j;
        }
        ranges.reverse();
        windows.reverse();
        Ok((ranges, windows))
    }

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

/// How one band frequency's field is read (see [`FastPlan::reading`]).
struct Reading {
    /// Per axis, the Kaiser–Bessel kernel of `FastPlan::kb` or `None` for the windowed sinc.
    kernels: [Option<usize>; 2],
    /// The lines the slab's shallowest plane keeps (see [`FastPlan::lines`]): those of the grid's
    /// spectrum.
    lines: usize,
    /// The grid's spectrum is zero at kx further than this from 0 (fx/2: nowhere).
    x_lines: usize,
}

/// The largest lateral wavenumber (rad/m) the kernel of wavenumber `k` carries to a plane at `dz`
/// within 1e-4 (see [`Lateral::Propagating`]).
fn kappa(k: f64, dz: f64) -> f64 {
    k.hypot(1e4f64.ln() / dz)
}

/// How many times the kernel's leg is travelled: twice for confocal data (no point-side index), whose
/// legs share the wall point.
fn legs(src: Option<usize>) -> f64 {
    if src.is_none() {
        2.0
    } else {
        1.0
    }
}

fn amplitude(f: Falloff, d: f64) -> f64 {
    match f {
        Falloff::None => 1.0,
        Falloff::InvR => 1.0 / d.max(1e-9),
    }
}

fn c32(v: Complex64) -> Complex32 {
    Complex32::new(v.re as f32, v.im as f32)
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
struct Workspace {
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
