//! Synthetic confocal captures for the tests (point scatterers splatted linearly around bin centres),
//! and a progress sink that records what a method reports.

use crate::Reconstruction;
use murk_core::{Capture, DVec3, PointSet, Progress, TimeAxis};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// A progress sink that records the announced total and the work done, and asks to stop once
/// `stop_at` units are done.
pub struct Recorder {
    pub total: AtomicU64,
    pub done: AtomicU64,
    stop_at: u64,
}

impl Recorder {
    pub fn new(stop_at: u64) -> Self {
        Recorder {
            total: AtomicU64::new(0),
            done: AtomicU64::new(0),
            stop_at,
        }
    }
}

impl Progress for Recorder {
    fn start(&self, total: u64) {
        self.total.store(total, Relaxed);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.done.load(Relaxed) >= self.stop_at
    }
}

/// A confocal scan of `n × n` points over a `wall` m square centred on the origin, with empty histograms.
pub fn confocal(n: usize, wall: f64, time: TimeAxis) -> Capture {
    let grid = PointSet::wall_grid(DVec3::ZERO, wall, wall, n, n);
    Capture::confocal(grid, time, vec![0.0; n * n * time.bins], String::new())
}

pub fn axis(start_m: f64, bin_width_m: f64, bins: usize) -> TimeAxis {
    TimeAxis {
        start_m,
        bin_width_m,
        bins,
    }
}

/// Adds a unit-albedo point at `p` with 1/r⁴ falloff. The path (including the wall legs) lands at
/// continuous index (path − start)/Δs − ½ relative to bin centres and is shared linearly between the
/// two neighbouring bins, which keeps its first moment.
pub fn add_point(c: &mut Capture, p: DVec3) {
    let t = c.time;
    for i in 0..c.n_hist() {
        let (l, s) = c.hist_pair(i);
        let (dl, ds) = (
            (c.illum.points[l] - p).length(),
            (c.sensor.points[s] - p).length(),
        );
        let path = c.first_bounce_m(l) + dl + ds + c.last_bounce_m(s);
        let u = (path - t.start_m) / t.bin_width_m - 0.5;
        let n = u.floor();
        let f = (u - n) as f32;
        let w = 1.0 / (dl * dl * ds * ds) as f32;
        let h = &mut c.h[i * t.bins..(i + 1) * t.bins];
        for (k, wk) in [(n as isize, 1.0 - f), (n as isize + 1, f)] {
            if k >= 0 && (k as usize) < t.bins {
                h[k as usize] += w * wk;
            }
        }
    }
}

/// A square plane of points, parallel to the wall at depth `z`, `side` m wide, `n × n` points.
pub fn add_plane(c: &mut Capture, z: f64, side: f64, n: usize) {
    for i in 0..n {
        for j in 0..n {
            let f = |k: usize| -side / 2.0 + side * (k as f64 + 0.5) / n as f64;
            add_point(c, DVec3::new(f(i), f(j), z));
        }
    }
}

/// Every column of the central region (`margin` columns in from each side) has its depth maximum
/// within ±1 sample of `k`.
pub fn assert_plane_depth(r: &Reconstruction, k: usize, margin: usize) {
    let [nx, ny, nz] = r.volume.shape();
    for ix in margin..nx - margin {
        for iy in margin..ny - margin {
            let col = &r.intensity[r.volume.index(ix, iy, 0)..][..nz];
            let kmax = col
                .iter()
                .enumerate()
                .fold(0, |b, (i, &v)| if v > col[b] { i } else { b });
            assert!(
                kmax.abs_diff(k) <= 1,
                "column ({ix}, {iy}): depth index {kmax}, expected {k}"
            );
        }
    }
}
