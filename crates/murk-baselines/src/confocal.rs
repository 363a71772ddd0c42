//! Confocal preparation shared by LCT, f-k and CDT: the scan grid, and the histograms re-sampled so
//! that sample k holds the transient at wall-relative path k·Δs′ (t = 0 when light leaves and
//! returns to the scanned wall point), with t_start and the first/last bounces removed by
//! fractional shifts.

use crate::Reconstruction;
use murk_core::{Axis, Capture, CaptureKind, Error, Result, Volume};
use rayon::prelude::*;

/// Which time samples a confocal method works on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeGrid {
    /// The capture's own bin width, over the whole recorded window.
    Native,
    /// `bins` samples over wall-relative paths [0, `max_path_m`), each the average of the capture
    /// over its own width (a box filter, so coarser grids do not alias). CDT's reference code keeps
    /// 2.0 m of path at 128 samples.
    Resample { max_path_m: f64, bins: usize },
}

/// As a summary prints it: "the capture's own bins" or "128 bins over 0–2 m of path".
impl std::fmt::Display for TimeGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            TimeGrid::Native => write!(f, "the capture's own bins"),
            TimeGrid::Resample { max_path_m, bins } => {
                write!(f, "{bins} bins over 0–{max_path_m} m of path")
            }
        }
    }
}

/// The geometry a confocal plan is built for; `run` rejects captures that differ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConfocalGeometry {
    pub nx: usize,
    pub ny: usize,
    /// Lateral axes of the scan (world x along the grid's first index, world y along the second).
    pub x: Axis,
    pub y: Axis,
    pub wall_z: f64,
    /// Path step between samples (Δs′).
    pub ds: f64,
    /// Samples per histogram.
    pub nt: usize,
}

impl ConfocalGeometry {
    pub fn new(capture: &Capture, grid: TimeGrid) -> Result<Self> {
        capture.validate_geometry()?;
        if capture.kind() != CaptureKind::Confocal {
            return Err(Error::Unsupported(format!(
                "this method needs a confocal capture, got {}",
                capture.kind()
            )));
        }
        let g = capture.illum.regular_grid().ok_or_else(|| {
            Error::Unsupported("confocal methods need a regular scan grid of at least 2×2".into())
        })?;
        let tol = 1e-6 * g.step_x.length().min(g.step_y.length());
        if g.step_x.y.abs() > tol
            || g.step_x.z.abs() > tol
            || g.step_y.x.abs() > tol
            || g.step_y.z.abs() > tol
        {
            return Err(Error::Unsupported(
                "confocal methods need a scan grid in a plane z = const with rows along world x and columns along world y".into(),
            ));
        }
        let far = g.point(g.nx - 1, g.ny - 1);
        let t = &capture.time;
        let (ds, nt) = match grid {
            TimeGrid::Native => (
                t.bin_width_m,
                samples_to(latest_path_m(capture), t.bin_width_m),
            ),
            TimeGrid::Resample { max_path_m, bins } => {
                if !(max_path_m > 0.0 && max_path_m.is_finite()) || bins == 0 {
                    return Err(Error::param(format!(
                        "time resampling needs a positive path window and bin count, got {max_path_m} m, {bins} bins"
                    )));
                }
                (max_path_m / bins as f64, bins)
            }
        };
        const MAX_SAMPLES: usize = 1 << 16;
        if nt > MAX_SAMPLES {
            return Err(Error::Limits(format!(
                "{nt} time samples after removing the time offsets (over {MAX_SAMPLES}); crop the capture or resample"
            )));
        }
        Ok(ConfocalGeometry {
            nx: g.nx,
            ny: g.ny,
            x: Axis::new(g.origin.x, far.x, g.nx),
            y: Axis::new(g.origin.y, far.y, g.ny),
            wall_z: g.origin.z,
            ds,
            nt,
        })
    }

    /// This grid's samples, continued up to the latest wall-relative path `capture` recorded, or
    /// `max` samples if fewer (never fewer than the grid's own).
    pub fn recorded(&self, capture: &Capture, max: usize) -> ConfocalGeometry {
        let nt = samples_to(latest_path_m(capture), self.ds).clamp(self.nt, max.max(self.nt));
        ConfocalGeometry { nt, ..*self }
    }

    /// Lateral spacings |Δx|, |Δy|.
    pub fn spacing(&self) -> [f64; 2] {
        [self.x.step().abs(), self.y.step().abs()]
    }

    /// Fails unless `capture` has this geometry (what a plan was built for).
    pub fn check_same(&self, capture: &Capture, grid: TimeGrid) -> Result<()> {
        capture.validate()?;
        let other = ConfocalGeometry::new(capture, grid)?;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()));
        let same = self.nx == other.nx
            && self.ny == other.ny
            && self.nt == other.nt
            && close(self.ds, other.ds)
            && close(self.x.start, other.x.start)
            && close(self.x.end, other.x.end)
            && close(self.y.start, other.y.start)
            && close(self.y.end, other.y.end)
            && close(self.wall_z, other.wall_z);
        if same {
            Ok(())
        } else {
            Err(Error::param(format!(
                "the plan was built for a {}×{}×{} confocal grid with Δs = {} m; this capture gives {}×{}×{} with Δs = {} m",
                self.nx, self.ny, self.nt, self.ds, other.nx, other.ny, other.nt, other.ds
            )))
        }
    }

    /// The output of a method with `nz` depth samples: voxel (ix, iy, k) at the scan point (ix, iy),
    /// k·Δs′/2 in front of the wall.
    pub fn reconstruction(&self, nz: usize, data: Vec<f32>, method: &str) -> Reconstruction {
        let dz = 0.5 * self.ds;
        let volume = Volume {
            x: self.x,
            y: self.y,
            z: Axis::new(self.wall_z, self.wall_z + dz * (nz as f64 - 1.0), nz),
        };
        debug_assert_eq!(volume.len(), data.len());
        Reconstruction::new(volume, data, method)
    }

    /// The capture on this grid: `out[(ix·ny + iy)·nt + k]` = transient of scan point (ix, iy) at
    /// wall-relative path k·Δs′.
    pub fn sample(&self, capture: &Capture) -> Vec<f32> {
        let t = capture.time;
        let (ds, nt) = (self.ds, self.nt);
        let mut out = vec![0.0f32; self.nx * self.ny * nt];
        out.par_chunks_mut(nt).enumerate().for_each_init(
            Vec::new,
            |cum: &mut Vec<f64>, (i, dst)| {
                let h = capture.histogram(i);
                // cum[n] = Σ_{m<n} H[m]: the integral of the piecewise-constant histogram up to bin edge n.
                cum.clear();
                cum.push(0.0);
                let mut acc = 0.0f64;
                for &v in h {
                    acc += v as f64;
                    cum.push(acc);
                }
                let integral = |u: f64| -> f64 {
                    let u = u.clamp(0.0, h.len() as f64);
                    let n = (u as usize).min(h.len() - 1);
                    cum[n] + (u - n as f64) * h[n] as f64
                };
                // Bin n covers paths [start + nΔs, start + (n+1)Δs) (floor binning), so the
                // box average of width Δs′ centred on path p is exact for any shift; at Δs′ = Δs
                // it equals linear interpolation between bin centres.
                let shift = (round_trip_offset(capture, i) - t.start_m) / t.bin_width_m;
                let half = 0.5 * ds / t.bin_width_m;
                for (k, d) in dst.iter_mut().enumerate() {
                    let u = k as f64 * ds / t.bin_width_m + shift;
                    *d = ((integral(u + half) - integral(u - half)) / (2.0 * half)) as f32;
                }
            },
        );
        out
    }
}

/// The latest wall-relative path any histogram of `capture` recorded (m).
fn latest_path_m(capture: &Capture) -> f64 {
    (0..capture.n_hist())
        .map(|i| capture.time.end_m() - round_trip_offset(capture, i))
        .fold(f64::MIN, f64::max)
}

/// Samples of `step_m` that cover paths 0 to `path_m` (at least one).
fn samples_to(path_m: f64, step_m: f64) -> usize {
    (path_m / step_m).ceil().max(1.0) as usize
}

/// Laser→wall plus wall→SPAD path of histogram `i` (zero unless the time axis includes them).
fn round_trip_offset(capture: &Capture, i: usize) -> f64 {
    let (l, s) = capture.hist_pair(i);
    capture.first_bounce_m(l) + capture.last_bounce_m(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Summaries print the grid in words, not as Rust's `Resample { max_path_m: 2.0, bins: 128 }`.
    #[test]
    fn time_grids_read_as_words() {
        let r = TimeGrid::Resample {
            max_path_m: 2.0,
            bins: 128,
        };
        assert_eq!(r.to_string(), "128 bins over 0–2 m of path");
        assert_eq!(TimeGrid::Native.to_string(), "the capture's own bins");
    }
    use crate::testutil::{axis, confocal};
    use murk_core::DVec3;

    #[test]
    fn samples_are_bin_averages_at_wall_relative_paths() {
        let mut c = confocal(2, 0.2, axis(0.25, 0.01, 20));
        c.laser_xyz = Some(DVec3::new(0.05, 0.05, -0.1));
        c.sensor_xyz = Some(DVec3::new(0.05, 0.05, -0.1));
        c.t_accounts_first_and_last_bounces = true;
        // Scan point 3 is (0.05, 0.05): both wall legs are 0.1 m, so bin 4 (paths [0.29, 0.30) m)
        // holds wall-relative paths [0.09, 0.10) m.
        c.h[3 * 20 + 4] = 1.0;
        let g = ConfocalGeometry::new(&c, TimeGrid::Native).unwrap();
        // The latest wall-relative path among all scan points decides the length: 0.45 − 2·0.1 m.
        assert_eq!(g.nt, 25);
        let s = g.sample(&c);
        let col = &s[3 * g.nt..][..g.nt];
        // Sample k is the box [k − ½, k + ½]·Δs: samples 9 and 10 each see half of the bin.
        for (k, &v) in col.iter().enumerate() {
            let want = if k == 9 || k == 10 { 0.5 } else { 0.0 };
            assert!((v - want).abs() < 1e-5, "sample {k}: {v}");
        }
        // Resampled to 5 cm: the bin falls inside the box of sample 2 ([0.075, 0.125) m), averaged.
        let g = ConfocalGeometry::new(
            &c,
            TimeGrid::Resample {
                max_path_m: 0.3,
                bins: 6,
            },
        )
        .unwrap();
        let s = g.sample(&c);
        assert!(
            (s[3 * 6 + 2] - 0.2).abs() < 1e-5 && s[3 * 6..][..6].iter().sum::<f32>() - 0.2 < 1e-5
        );
    }
}
