//! The fast form's plan: what is computed. From the capture's geometry and the volume: the wall
//! grid and which side it is, the resamplers and Kaiser–Bessel kernels that read the convolution at
//! the voxels, the FFT sizes and the kernel's fold; per run, the depth planes, their slabs and time
//! windows (the slab cost model) and how each band frequency is read. Nothing here runs in
//! parallel or in SIMD: that is the executor's (see the module docs of `pf_fast`).

use super::depths::{self, Depths};
use super::Executor;
use crate::fft2::Fft2;
use crate::resample::{KaiserBessel, Resampler};
use crate::spectrum::{next_fast_len, path_range, Window};
use crate::{Falloff, Lateral};
use murk_core::{Axis, Capture, CaptureKind, DVec3, Error, RegularGrid, Result, Volume};
use rustfft::num_complex::{Complex32, Complex64};
use std::ops::Range;

/// Which histogram feeds grid cell `c` for a given point-side index.
#[derive(Clone, Copy)]
pub(super) enum GridSide {
    Illum,
    Sensor,
    Confocal,
}

/// Axis indices of per-axis pairs.
pub(super) const X: usize = 0;
pub(super) const Y: usize = 1;

/// Relative aliasing the Kaiser–Bessel kernels are shaped for: below the 16-tap windowed sinc's
/// (3e-4 at a quarter of the Nyquist band, 1e-2 at 0.77 of it) over every band they serve.
const KB_ALIASING: f64 = 1e-4;

/// A Kaiser–Bessel kernel along one axis: its resampler on the plan's lattice and the factor 1/φ̂ per
/// FFT bin that the grid's spectra take beforehand.
pub(super) struct Kb {
    kernel: KaiserBessel,
    resampler: Resampler,
    pub(super) inverse: Vec<f32>,
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

/// The fast form's plan for one capture geometry and volume (see the module docs of `pf_fast`): what
/// each run computes, for an [`Executor`] to carry out.
pub struct FastPlan {
    /// The capture's geometry (no histograms).
    pub(super) cap: Capture,
    pub(super) vol: Volume,
    pub(super) falloff: Falloff,
    pub(super) grid: RegularGrid,
    pub(super) side: GridSide,
    pub(super) rx: Resampler,
    pub(super) ry: Resampler,
    /// Per axis (x, y), the shorter kernels that replace `rx`/`ry` for a band frequency whose lateral
    /// band is cut along that axis (see [`FastPlan::kernels`]); empty on the lattice, for confocal data
    /// (one resampling per plane after the frequency sum) and with [`Lateral::Full`].
    pub(super) kb: [Vec<Kb>; 2],
    pub(super) fft: Fft2,
    /// Lattice index, within the kernel's support, of the zero offset along x and y.
    pub(super) cx: i64,
    pub(super) cy: i64,
    /// Phases that fold a symmetric kernel's spectrum onto its non-negative frequencies.
    pub(super) fold: Option<Fold>,
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
    pub(super) fn lines(&self, k: f64, dz: f64) -> usize {
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
    pub(super) fn reading(&self, k: f64, dz_min: f64) -> Reading {
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
    pub(super) fn resamplers(&self, chosen: [Option<usize>; 2]) -> [&Resampler; 2] {
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
    pub(super) fn sources(&self) -> Vec<Option<usize>> {
        match self.side {
            GridSide::Confocal => vec![None],
            GridSide::Illum => (0..self.cap.sensor.len()).map(Some).collect(),
            GridSide::Sensor => (0..self.cap.illum.len()).map(Some).collect(),
        }
    }

    pub(super) fn hist_index(&self, cell: usize, src: Option<usize>) -> usize {
        let ns = self.cap.sensor.len();
        match (self.side, src) {
            (GridSide::Illum, Some(s)) => cell * ns + s,
            (GridSide::Sensor, Some(l)) => l * ns + cell,
            _ => cell,
        }
    }

    pub(super) fn source_point(&self, src: usize) -> DVec3 {
        match self.side {
            GridSide::Illum => self.cap.sensor.points[src],
            _ => self.cap.illum.points[src],
        }
    }

    /// The depth planes to evaluate, with their slabs and time windows, for `exec`: every other
    /// plane (see [`Depths`]) where the fast form may approximate ([`Lateral::Propagating`]) and the field's
    /// depth band allows, else every plane.
    pub(super) fn schedule(
        &self,
        sigma_m: f64,
        wavelength_m: f64,
        exec: Executor,
    ) -> Result<Schedule> {
        let halved = match self.lateral {
            Lateral::Propagating => Depths::halved(&self.vol, self.grid.origin.z),
            Lateral::Full => None,
        };
        if let Some(mut depths) = halved {
            // Planes past the ends lengthen the window; where that fails, every plane is evaluated.
            if let Ok((slabs, windows)) = self.slabs(&depths.z, sigma_m, wavelength_m, exec) {
                if depths.design(self.depth_band(&depths, &windows)) {
                    return Ok(Schedule {
                        depths,
                        slabs,
                        windows,
                    });
                }
            }
        }
        let depths = Depths::every(&self.vol);
        let (slabs, windows) = self.slabs(&depths.z, sigma_m, wavelength_m, exec)?;
        Ok(Schedule {
            depths,
            slabs,
            windows,
        })
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
    /// planes shared among the executor's workers, by dynamic programming over slab ends.
    fn slabs(
        &self,
        zs: &[f64],
        sigma_m: f64,
        wavelength_m: f64,
        exec: Executor,
    ) -> Result<(Vec<Range<usize>>, Vec<Window>)> {
        const MAX_PLANES: usize = 256;
        let nz = zs.len();
        let paths: Vec<(f64, f64)> = exec.each(zs, |z| {
            let plane = Volume {
                z: Axis::new(z, z, 1),
                ..self.vol
            };
            path_range(&self.cap, &plane)
        });
        let threads = exec.workers();
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
}

/// How one band frequency's field is read (see [`FastPlan::reading`]).
pub(super) struct Reading {
    /// Per axis, the Kaiser–Bessel kernel of `FastPlan::kb` or `None` for the windowed sinc.
    pub(super) kernels: [Option<usize>; 2],
    /// The lines the slab's shallowest plane keeps (see [`FastPlan::lines`]): those of the grid's
    /// spectrum.
    pub(super) lines: usize,
    /// The grid's spectrum is zero at kx further than this from 0 (fx/2: nowhere).
    pub(super) x_lines: usize,
}

/// What one run evaluates: the depth planes, their slabs (ranges of evaluated planes) and each
/// slab's time window (its band of frequencies).
pub(super) struct Schedule {
    pub(super) depths: Depths,
    pub(super) slabs: Vec<Range<usize>>,
    pub(super) windows: Vec<Window>,
}

impl Schedule {
    /// The slabs as reported in [`crate::ReconInfo`].
    pub(super) fn reported(&self) -> Vec<Slab> {
        self.slabs
            .iter()
            .zip(&self.windows)
            .map(|(planes, w)| Slab {
                planes: planes.clone(),
                frequencies: w.band.len(),
                dft_len: w.band.nf,
            })
            .collect()
    }
}

/// The largest lateral wavenumber (rad/m) the kernel of wavenumber `k` carries to a plane at `dz`
/// within 1e-4 (see [`Lateral::Propagating`]).
fn kappa(k: f64, dz: f64) -> f64 {
    k.hypot(1e4f64.ln() / dz)
}

/// How many times the kernel's leg is travelled: twice for confocal data (no point-side index), whose
/// legs share the wall point.
pub(super) fn legs(src: Option<usize>) -> f64 {
    if src.is_none() {
        2.0
    } else {
        1.0
    }
}

pub(super) fn amplitude(f: Falloff, d: f64) -> f64 {
    match f {
        Falloff::None => 1.0,
        Falloff::InvR => 1.0 / d.max(1e-9),
    }
}

/// A kernel K(|dx|, |dy|) whose support is symmetric about its centre (volume columns spanning the
/// wall lattice symmetrically) has K̂(N − k) = e^{4πi·k·c/N}·K̂(k) along each axis, so only the
/// non-negative frequencies k ≤ N/2 need transforming: about half the row and column FFTs. The
/// phases for k > N/2 are folded into the data's spectra once, and the kernel's spectrum is unfolded
/// by mirroring.
pub(super) struct Fold {
    /// The data's factor per spectrum entry ([ky][kx]): both axes' phases and the inverse FFT's
    /// 1/(fx·fy), applied in one product per frequency.
    pub(super) phases: Vec<Complex32>,
}

impl Fold {
    pub(super) fn new(fx: usize, fy: usize, cx: i64, cy: i64) -> Fold {
        let axis = |n: usize, c: i64| -> Vec<Complex64> {
            (0..n)
                .map(|k| {
                    if k <= n / 2 {
                        Complex64::new(1.0, 0.0)
                    } else {
                        let turns = 2.0 * ((n - k) as i64 * c) as f64 / n as f64;
                        Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * turns)
                    }
                })
                .collect()
        };
        let (px, py) = (axis(fx, cx), axis(fy, cy));
        let norm = 1.0 / (fx * fy) as f64;
        Fold {
            phases: py
                .iter()
                .flat_map(|y| px.iter().map(move |x| c32(x * y * norm)))
                .collect(),
        }
    }
}

pub(super) fn c32(v: Complex64) -> Complex32 {
    Complex32::new(v.re as f32, v.im as f32)
}
