//! Backprojection (Velten et al. 2012) for any capture kind and any voxel box:
//! I(v) = Σ_(l,s) w · H_ls(e_l + d_l(v) + d_s(v) + e_s), read with linear interpolation.
//!
//! Bin convention: bin n holds paths [start + nΔs, start + (n+1)Δs) (floor binning, as y-tal and
//! mitransient write it), so its value belongs to the bin centre start + (n+½)Δs and a path p is read
//! at the continuous index (p − start)/Δs − ½. Reading at (p − start)/Δs instead (y-tal's `bp`
//! truncates it, too) biases every depth by half a bin of path.

use crate::Reconstruction;
use murk_core::{Capture, CaptureKind, DVec3, Error, Result, Volume};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BpOptions {
    /// Weight every sample by (d_l·d_s)², undoing the inverse-square falloff of both hidden legs
    /// (y-tal's `compensate_invsq`, without the wall legs).
    pub inverse_square: bool,
}

/// Backprojects `capture` into `volume`; output in the volume's C order [nx, ny, nz].
pub fn backproject(capture: &Capture, volume: &Volume, opts: BpOptions) -> Result<Reconstruction> {
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
    let confocal = capture.kind() == CaptureKind::Confocal;
    let table = if confocal {
        LegTable::new(capture, volume)
    } else {
        None
    };
    let pairs: Vec<(usize, usize)> = (0..capture.n_hist())
        .map(|i| capture.hist_pair(i))
        .collect();
    let ncols = volume.x.n * volume.y.n;
    let mut data = vec![0.0f32; volume.len()];
    // Histogram-outer over a tile of voxel columns: each histogram is read once per tile while the
    // tile's accumulators stay in cache (column-outer re-read every histogram for every column).
    data.par_chunks_mut(nz * TILE).enumerate().for_each_init(
        || ColumnScratch::new(nz, capture.time.bins),
        |sc, (tile, out)| {
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
                    let dl: &[f64] = match &table {
                        Some(t) => t.legs(ix, iy, l),
                        None => {
                            legs(capture.illum.points[l], &mut sc.leg);
                            &sc.leg
                        }
                    };
                    let ds: &[f64] = if confocal {
                        dl
                    } else {
                        legs(capture.sensor.points[s], &mut sc.sensor_leg);
                        &sc.sensor_leg
                    };
                    let read = Read {
                        inv,
                        offset: offset - (e_l[l] + e_s[s]) * inv,
                        opts,
                    };
                    read.accumulate(&mut sc.acc[k * nz..(k + 1) * nz], dl, ds, hist);
                }
            }
            for (o, a) in out.iter_mut().zip(&sc.acc) {
                *o = *a as f32;
            }
        },
    );
    Ok(Reconstruction {
        volume: *volume,
        data,
    })
}

/// Voxel columns per parallel task (their f64 accumulators: TILE × nz × 8 bytes).
const TILE: usize = 16;

/// Confocal scans on a regular grid with voxel columns on that grid: the distance from scan point
/// (sx, sy) to voxel (ix, iy, iz) depends only on (|gx(ix) − sx|, |gy(iy) − sy|, iz), so the square
/// roots are taken once per lattice offset instead of once per (voxel, scan point).
struct LegTable {
    /// Grid index of each voxel column along x and along y.
    gx: Vec<usize>,
    gy: Vec<usize>,
    grid_ny: usize,
    /// Offsets span [0, span_y) along y.
    span_y: usize,
    nz: usize,
    d: Vec<f64>,
}

impl LegTable {
    fn new(capture: &Capture, volume: &Volume) -> Option<LegTable> {
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
        let gx = on_grid(&volume.x, g.origin.x, g.step_x.x, g.nx)?;
        let gy = on_grid(&volume.y, g.origin.y, g.step_y.y, g.ny)?;
        let (span_x, span_y, nz) = (g.nx, g.ny, volume.z.n);
        let mut d = Vec::with_capacity(span_x * span_y * nz);
        for ax in 0..span_x {
            for ay in 0..span_y {
                let rho2 = (ax as f64 * g.step_x.x).powi(2) + (ay as f64 * g.step_y.y).powi(2);
                d.extend((0..nz).map(|k| (rho2 + (volume.z.at(k) - g.origin.z).powi(2)).sqrt()));
            }
        }
        Some(LegTable {
            gx,
            gy,
            grid_ny: g.ny,
            span_y,
            nz,
            d,
        })
    }

    /// Distances from scan point `i` to the voxels of column (ix, iy), one per depth.
    fn legs(&self, ix: usize, iy: usize, i: usize) -> &[f64] {
        let (sx, sy) = (i / self.grid_ny, i % self.grid_ny);
        let (ax, ay) = (self.gx[ix].abs_diff(sx), self.gy[iy].abs_diff(sy));
        &self.d[(ax * self.span_y + ay) * self.nz..][..self.nz]
    }
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
    /// Adds H read at the path of each depth (linear interpolation between bin centres, fading to
    /// zero over half a bin beyond the window's ends) into `acc`. `padded` is H with one zero on each
    /// side, so every read is in bounds and the loop has no branches.
    fn accumulate(&self, acc: &mut [f64], dl: &[f64], ds: &[f64], padded: &[f32]) {
        // f32 indices (within 1e-3 bin below 2^14 bins) and an i32 conversion: the saturating
        // f64 → usize conversion costs more than the interpolation itself.
        let top = padded.len() - 2;
        for ((a, &l), &s) in acc.iter_mut().zip(dl).zip(ds) {
            // Index into `padded` (shifted by its leading zero), clamped onto the zero padding.
            let u =
                (((l + s) * self.inv - self.offset + 1.0) as f32).clamp(0.0, top as f32 + 0.999_9);
            let n = (u as i32 as usize).min(top);
            let f = u - n as f32;
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
            let max = r.data.iter().copied().fold(0.0, f32::max);
            let (mut w, mut wz) = (0.0, 0.0);
            for (k, &v) in r.data.iter().enumerate() {
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

    /// Voxel columns on the scan grid use the lattice distance table; a volume shifted off the grid by
    /// 1e-5 of a step takes the direct path. Both must agree to f32 precision.
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
        assert!(LegTable::new(&c, &on).is_some() && LegTable::new(&c, &off).is_none());
        let (a, b) = (
            backproject(&c, &on, BpOptions::default()).unwrap(),
            backproject(&c, &off, BpOptions::default()).unwrap(),
        );
        let max = a.data.iter().copied().fold(0.0, f32::max);
        for (x, y) in a.data.iter().zip(&b.data) {
            assert!((x - y).abs() <= 1e-3 * max, "{x} vs {y}");
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
        assert_eq!(r.data, vec![0.0; 3]);
    }
}
