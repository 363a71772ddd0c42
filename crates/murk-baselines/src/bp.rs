//! Backprojection (Velten et al. 2012) for any capture kind and any voxel box:
//! I(v) = Σ_(l,s) w · H_ls(e_l + d_l(v) + d_s(v) + e_s), read with linear interpolation.
//!
//! Bin convention: bin n holds paths [start + nΔs, start + (n+1)Δs) (floor binning, as y-tal and
//! mitransient write it), so its value belongs to the bin centre start + (n+½)Δs and a path p is read
//! at the continuous index (p − start)/Δs − ½. Reading at (p − start)/Δs instead (y-tal's `bp`
//! truncates it, too) biases every depth by half a bin of path.

use crate::Reconstruction;
use murk_core::simd::wide;
use murk_core::{
    Capture, CaptureKind, DVec3, Error, NoProgress, Progress, RegularGrid, Result, Volume,
};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BpOptions {
    /// Weight every sample by (d_l·d_s)², undoing the inverse-square falloff of both hidden legs
    /// (y-tal's `compensate_invsq`, without the wall legs).
    pub inverse_square: bool,
}

/// Backprojection on one volume: it plans nothing ahead, so its plan is the volume and the options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BpPlan {
    pub volume: Volume,
    pub options: BpOptions,
}

impl murk_core::Reconstructor for BpPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        backproject_with(capture, &self.volume, self.options, progress)
    }
}

/// Backprojects `capture` into `volume`; output in the volume's C order [nx, ny, nz].
pub fn backproject(capture: &Capture, volume: &Volume, opts: BpOptions) -> Result<Reconstruction> {
    backproject_with(capture, volume, opts, &NoProgress)
}

/// [`backproject`], reporting to `progress` and stopping with an error once it is cancelled.
pub fn backproject_with(
    capture: &Capture,
    volume: &Volume,
    opts: BpOptions,
    progress: &dyn Progress,
) -> Result<Reconstruction> {
    capture.validate()?;
    if volume.is_empty() {
        return Err(Error::param("the volume has no voxels"));
    }
    let t = capture.time;
    let nz = volume.z.n;
    let e_l: Vec<f64> = (0..capture.illum.len())
        .map(|l| capture.first_bounce_m(l))
        .collect();
    let e_s: Vec<f64> = (0..capture.sensor.len())
        .map(|s| capture.last_bounce_m(s))
        .collect();
    let z: Vec<f64> = volume.z.values();
    let inv = 1.0 / t.bin_width_m;
    let offset = t.start_m * inv + 0.5;
    let read_of = |h: usize| {
        let (l, s) = capture.hist_pair(h);
        Read {
            inv,
            offset: offset - (e_l[l] + e_s[s]) * inv,
            opts,
        }
    };
    if let Some(lattice) = Lattice::new(capture, volume) {
        // One wall-leg offset for every scan point keeps the sum shift-invariant.
        let first = read_of(0);
        if (0..capture.n_hist()).all(|h| read_of(h).offset == first.offset) {
            let data = lattice.backproject(capture, volume, &first, progress);
            return finished(progress, *volume, data);
        }
    }
    let confocal = capture.kind() == CaptureKind::Confocal;
    let pairs: Vec<(usize, usize)> = (0..capture.n_hist())
        .map(|i| capture.hist_pair(i))
        .collect();
    let ncols = volume.x.n * volume.y.n;
    let mut data = vec![0.0f32; volume.len()];
    progress.start(ncols.div_ceil(TILE) as u64);
    // Histogram-outer over a tile of voxel columns: each histogram is read once per tile while the
    // tile's accumulators stay in cache (column-outer re-read every histogram for every column).
    data.par_chunks_mut(nz * TILE).enumerate().for_each_init(
        || ColumnScratch::new(nz, capture.time.bins),
        |sc, (tile, out)| {
            if progress.cancelled() {
                return;
            }
            let cols = tile * TILE..((tile + 1) * TILE).min(ncols);
            sc.acc.clear();
            sc.acc.resize(cols.len() * nz, 0.0);
            for (h, &(l, s)) in pairs.iter().enumerate() {
                sc.padded[1..=capture.time.bins].copy_from_slice(capture.histogram(h));
                let hist = &sc.padded;
                for (k, col) in cols.clone().enumerate() {
                    let (ix, iy) = (col / volume.y.n, col % volume.y.n);
                    let (x, y) = (volume.x.at(ix), volume.y.at(iy));
                    let legs = |p: DVec3, out: &mut [f64]| {
                        let rho2 = (p.x - x).powi(2) + (p.y - y).powi(2);
                        for (o, &zk) in out.iter_mut().zip(&z) {
                            *o = (rho2 + (zk - p.z).powi(2)).sqrt();
                        }
                    };
                    legs(capture.illum.points[l], &mut sc.leg);
                    let ds: &[f64] = if confocal {
                        &sc.leg
                    } else {
                        legs(capture.sensor.points[s], &mut sc.sensor_leg);
                        &sc.sensor_leg
                    };
                    read_of(h).accumulate(&mut sc.acc[k * nz..(k + 1) * nz], &sc.leg, ds, hist);
                }
            }
            for (o, a) in out.iter_mut().zip(&sc.acc) {
                *o = *a as f32;
            }
            progress.advance(1);
        },
    );
    finished(progress, *volume, data)
}

/// The reconstruction, unless the work was cancelled part-way (its skipped pieces left zeros).
fn finished(progress: &dyn Progress, volume: Volume, data: Vec<f32>) -> Result<Reconstruction> {
    if progress.cancelled() {
        return Err(Error::param("backprojection stopped"));
    }
    Ok(Reconstruction::new(volume, data, DESCRIPTION))
}

/// The method row of every backprojection.
const DESCRIPTION: &str = "backprojection (linear reads at bin centres)";

/// Voxel columns per parallel task (their f64 accumulators: TILE × nz × 8 bytes).
const TILE: usize = 16;

/// Confocal scans on a regular grid with voxel columns on that grid: the distance from scan point
/// (sx, sy) to voxel (ix, iy, iz) depends only on the lattice offset (|dx|, |dy|) and iz. Every depth
/// plane is then a sum over offsets of whole time planes of H, shifted by the offset and read at that
/// offset's path: long contiguous multiply-adds instead of one gather per (voxel, scan point).
struct Lattice {
    grid: RegularGrid,
    /// Grid index of each voxel column along x and along y.
    gx: Vec<usize>,
    gy: Vec<usize>,
}

impl Lattice {
    fn new(capture: &Capture, volume: &Volume) -> Option<Lattice> {
        if capture.kind() != CaptureKind::Confocal {
            return None;
        }
        let g = capture.illum.regular_grid()?;
        let along = |v: DVec3, axis: DVec3| {
            v.dot(axis) > 0.0 && (v - axis * v.dot(axis)).length() <= 1e-9 * v.length()
        };
        if !along(g.step_x, DVec3::X) || !along(g.step_y, DVec3::Y) {
            return None;
        }
        let on_grid = |axis: &murk_core::Axis, o: f64, d: f64, n: usize| -> Option<Vec<usize>> {
            axis.values()
                .iter()
                .map(|x| {
                    let t = (x - o) / d;
                    (t.round() >= 0.0 && (t.round() as usize) < n && (t - t.round()).abs() < 1e-6)
                        .then_some(t.round() as usize)
                })
                .collect()
        };
        Some(Lattice {
            gx: on_grid(&volume.x, g.origin.x, g.step_x.x, g.nx)?,
            gy: on_grid(&volume.y, g.origin.y, g.step_y.y, g.ny)?,
            grid: g,
        })
    }

    fn backproject(
        &self,
        capture: &Capture,
        volume: &Volume,
        read: &Read,
        progress: &dyn Progress,
    ) -> Vec<f32> {
        let (gnx, gny) = (self.grid.nx, self.grid.ny);
        let bins = capture.time.bins;
        // Time planes of H with a zero plane before and after (reads fade out past the window).
        // Each plane has rows of w = 2·gny − 1 values, the scan row in the last gny of them and
        // zeros before it, plus one zero row at the end: a read shifted past a row's end by up to
        // gny − 1 lands in the next row's zeros, so a whole shifted plane is one contiguous slice.
        let (w, pad) = (2 * gny - 1, gny - 1);
        let plane = (gnx + 1) * w;
        let mut planes = vec![0.0f32; (bins + 2) * plane];
        for (cell, h) in capture.h.chunks(bins).enumerate() {
            let at = (cell / gny) * w + pad + cell % gny;
            for (t, v) in h.iter().enumerate() {
                planes[(t + 1) * plane + at] = *v;
            }
        }
        let (sx, sy) = (self.grid.step_x.x, self.grid.step_y.y);
        progress.start(volume.z.n as u64);
        let per_depth: Vec<Vec<f32>> = (0..volume.z.n)
            .into_par_iter()
            .map(|iz| {
                let dz = volume.z.at(iz) - self.grid.origin.z;
                // Output rows use the same stride w; columns ≥ gny collect garbage and are dropped.
                let mut out = vec![0.0f32; gnx * w];
                if progress.cancelled() {
                    return out;
                }
                for ax in 0..gnx {
                    for ay in 0..gny {
                        let d =
                            ((ax as f64 * sx).powi(2) + (ay as f64 * sy).powi(2) + dz * dz).sqrt();
                        let (n, f) = read.index(2.0 * d, bins);
                        let weight = if read.opts.inverse_square {
                            d.powi(4) as f32
                        } else {
                            1.0
                        };
                        let (w0, w1) = ((1.0 - f) * weight, f * weight);
                        for dx in mirrored(ax) {
                            let r0 = (-dx).max(0) as usize;
                            let r1 = (gnx as i64 - dx.max(0)) as usize;
                            for dy in mirrored(ay) {
                                let src = n * plane + (r0 as i64 + dx) as usize * w;
                                let src = (src as i64 + pad as i64 + dy) as usize;
                                let len = (r1 - r0) * w;
                                let (a, b) = (
                                    &planes[src..src + len],
                                    &planes[src + plane..src + plane + len],
                                );
                                let o = &mut out[r0 * w..r0 * w + len];
                                wide(
                                    #[inline(always)]
                                    || {
                                        for ((o, a), b) in o.iter_mut().zip(a).zip(b) {
                                            *o += w0 * a + w1 * b;
                                        }
                                    },
                                );
                            }
                        }
                    }
                }
                progress.advance(1);
                out
            })
            .collect();
        let nz = volume.z.n;
        let mut data = vec![0.0f32; volume.len()];
        for (col, voxels) in data.chunks_mut(nz).enumerate() {
            let at = self.gx[col / volume.y.n] * w + self.gy[col % volume.y.n];
            for (v, plane) in voxels.iter_mut().zip(&per_depth) {
                *v = plane[at];
            }
        }
        data
    }
}

/// The signed offsets with absolute value `a`: ±a, or just 0.
fn mirrored(a: usize) -> impl Iterator<Item = i64> {
    let a = a as i64;
    [a, -a].into_iter().take(if a == 0 { 1 } else { 2 })
}

/// Per-thread buffers for one voxel column.
struct ColumnScratch {
    acc: Vec<f64>,
    leg: Vec<f64>,
    sensor_leg: Vec<f64>,
    /// The current histogram between two zeros.
    padded: Vec<f32>,
}

impl ColumnScratch {
    fn new(nz: usize, bins: usize) -> Self {
        ColumnScratch {
            padded: vec![0.0; bins + 2],
            acc: Vec::with_capacity(TILE * nz),
            leg: vec![0.0; nz],
            sensor_leg: vec![0.0; nz],
        }
    }
}

/// How one histogram is read: path p = e + d_l + d_s sits at index p·inv − offset of the bin centres
/// (`offset` already includes the pair's first- and last-bounce legs e).
struct Read {
    inv: f64,
    offset: f64,
    opts: BpOptions,
}

impl Read {
    /// Where `path` is read in H padded with one zero on each side (`bins + 2` values): index n and
    /// weight f of a linear read (1 − f)·H[n] + f·H[n + 1], clamped onto the zero padding. f32
    /// indices (within 1e-3 bin below 2^14 bins) and an i32 conversion: the saturating f64 → usize
    /// conversion costs more than the interpolation itself.
    #[inline]
    fn index(&self, path: f64, bins: usize) -> (usize, f32) {
        let u = ((path * self.inv - self.offset + 1.0) as f32).clamp(0.0, bins as f32 + 0.999_9);
        let n = (u as i32 as usize).min(bins);
        (n, u - n as f32)
    }

    /// Adds H read at the path of each depth (linear interpolation between bin centres, fading to
    /// zero over half a bin beyond the window's ends) into `acc`. `padded` is H with one zero on each
    /// side, so every read is in bounds and the loop has no branches.
    fn accumulate(&self, acc: &mut [f64], dl: &[f64], ds: &[f64], padded: &[f32]) {
        let bins = padded.len() - 2;
        for ((a, &l), &s) in acc.iter_mut().zip(dl).zip(ds) {
            let (n, f) = self.index(l + s, bins);
            let v = (padded[n] + f * (padded[n + 1] - padded[n])) as f64;
            *a += if self.opts.inverse_square {
                v * (l * s) * (l * s)
            } else {
                v
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{add_point, axis, confocal};
    use murk_core::Pairing;
    use murk_core::{Axis, DVec3, PointSet};

    /// Cancelled after its first piece of work, a backprojection (lattice and general paths) skips
    /// the rest and returns an error instead of a partial volume.
    #[test]
    fn cancelled_backprojection_stops_early_with_an_error() {
        use std::sync::atomic::Ordering::Relaxed;
        let mut c = confocal(16, 0.6, axis(0.0137, 0.01, 160));
        add_point(&mut c, DVec3::new(0.06, -0.04, 0.45));
        let g = c.illum.regular_grid().unwrap();
        let on_grid = Volume {
            x: Axis::new(g.origin.x, g.origin.x + 15.0 * g.step_x.x, 16),
            y: Axis::new(g.origin.y, g.origin.y + 15.0 * g.step_y.y, 16),
            z: Axis::new(0.3, 0.6, 31),
        };
        let off_grid = Volume {
            x: Axis::new(-0.3, 0.3, 70),
            ..on_grid
        };
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        // The lattice path reports depth planes (31), the general one tiles of 16 columns (70).
        for (vol, pieces) in [(on_grid, 31), (off_grid, 70)] {
            assert!(backproject(&c, &vol, BpOptions::default()).is_ok());
            let p = crate::testutil::Recorder::new(1);
            let e = one
                .install(|| backproject_with(&c, &vol, BpOptions::default(), &p))
                .unwrap_err();
            assert!(e.to_string().contains("stopped"), "{e}");
            assert_eq!(p.done.load(Relaxed), 1);
            assert_eq!(p.total.load(Relaxed), pieces);
        }
    }

    #[test]
    fn point_lands_on_its_voxel_for_confocal_and_laser_grid_captures() {
        let p = DVec3::new(0.06, -0.04, 0.45);
        // Voxel grid with p on voxel (9, 6, 15).
        let vol = Volume {
            x: Axis::new(-0.3, 0.3, 16),
            y: Axis::new(-0.28, 0.32, 16),
            z: Axis::new(0.3, 0.6, 31),
        };
        let mut c = confocal(16, 0.6, axis(0.0137, 0.01, 160));
        add_point(&mut c, p);
        let r = backproject(&c, &vol, BpOptions::default()).unwrap();
        assert_eq!(r.argmax(), [9, 6, 15]);

        // One SPAD point, a laser grid, devices off the wall, the wall legs in the time axis.
        let mut c = confocal(16, 0.6, axis(2.2371, 0.01, 200));
        c.sensor = PointSet::single(DVec3::new(0.1, 0.05, 0.0));
        c.pairing = Pairing::Product;
        c.laser_xyz = Some(DVec3::new(0.4, -0.3, -1.0));
        c.sensor_xyz = Some(DVec3::new(-0.2, 0.1, -0.9));
        c.t_accounts_first_and_last_bounces = true;
        add_point(&mut c, p);
        let r = backproject(
            &c,
            &vol,
            BpOptions {
                inverse_square: true,
            },
        )
        .unwrap();
        assert_eq!(r.argmax(), [9, 6, 15]);
    }

    /// The depth profile at the scatterer's column is symmetric about the truth when bins are read
    /// at their centres. Reading at (p − start)/Δs instead moves its centroid by ≈ Δs/4 = 2.5 mm.
    #[test]
    fn no_half_bin_bias() {
        let ds = 0.01;
        for z0 in [0.5, 0.503] {
            let mut c = confocal(16, 0.6, axis(0.0123, ds, 150));
            add_point(&mut c, DVec3::new(0.01875, 0.01875, z0));
            let vol = Volume {
                x: Axis::new(0.01875, 0.01875, 1),
                y: Axis::new(0.01875, 0.01875, 1),
                z: Axis::new(z0 - 0.02, z0 + 0.02, 161),
            };
            let r = backproject(&c, &vol, BpOptions::default()).unwrap();
            let max = r.intensity.iter().copied().fold(0.0, f32::max);
            let (mut w, mut wz) = (0.0, 0.0);
            for (k, &v) in r.intensity.iter().enumerate() {
                if v > 0.5 * max {
                    w += v as f64;
                    wz += v as f64 * vol.z.at(k);
                }
            }
            let centroid = wz / w;
            assert!(
                (centroid - z0).abs() < 0.05 * ds,
                "depth centroid {centroid} for a point at {z0}"
            );
        }
    }

    /// Voxel columns on the scan grid take the lattice path (shifted time planes); a volume shifted
    /// off the grid by 1e-5 of a step takes the direct path. Both must agree to 1e-3 of the maximum.
    #[test]
    fn lattice_table_matches_direct_distances() {
        let mut c = confocal(16, 0.6, axis(0.0, 0.01, 160));
        add_point(&mut c, DVec3::new(0.05, -0.1, 0.5));
        add_point(&mut c, DVec3::new(-0.2, 0.15, 0.35));
        let step = 0.6 / 16.0;
        let first = -0.3 + step / 2.0;
        let on = Volume {
            x: Axis::new(first + 2.0 * step, first + 13.0 * step, 12),
            y: Axis::new(first, first + 15.0 * step, 16),
            z: Axis::new(0.3, 0.6, 31),
        };
        let nudge = 1e-5 * step;
        let off = Volume {
            x: Axis::new(on.x.start + nudge, on.x.end + nudge, 12),
            ..on
        };
        assert!(Lattice::new(&c, &on).is_some() && Lattice::new(&c, &off).is_none());
        for inverse_square in [false, true] {
            let opts = BpOptions { inverse_square };
            let (a, b) = (
                backproject(&c, &on, opts).unwrap(),
                backproject(&c, &off, opts).unwrap(),
            );
            let max = a.intensity.iter().copied().fold(0.0, f32::max);
            for (x, y) in a.intensity.iter().zip(&b.intensity) {
                assert!((x - y).abs() <= 1e-3 * max, "{x} vs {y} ({opts:?})");
            }
        }
    }

    #[test]
    fn voxels_outside_the_time_window_are_zero() {
        let mut c = confocal(4, 0.4, axis(0.0, 0.01, 50));
        add_point(&mut c, DVec3::new(0.0, 0.0, 0.2));
        let vol = Volume {
            x: Axis::new(0.0, 0.0, 1),
            y: Axis::new(0.0, 0.0, 1),
            z: Axis::new(1.0, 2.0, 3),
        };
        let r = backproject(&c, &vol, BpOptions::default()).unwrap();
        assert_eq!(r.intensity, vec![0.0; 3]);
    }
}
