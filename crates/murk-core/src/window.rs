//! The two ends of a capture's time window.
//!
//! **The end.** A window that ends while the signal is still strong (a deep target, a medium's tail,
//! a long-range histogram cut by the hardware) ends each histogram in a step, since every
//! reconstruction reads the missing bins as zeros; band-pass steps (Phasor Fields' pulse, f-k's and
//! the diffusion model's frequency-domain steps) turn that step into a bright false surface at the
//! depths the end reaches. The handling: a smooth ramp over the histograms' last `taper_m` of path,
//! and the voxels whose every path reaches past `end − 2·taper_m` set to zero (their values come from
//! the ramp and the cut, not from the scene).
//!
//! **The start.** In a medium, backscatter near the relay is the strongest early signal, and its
//! band-limited tails light the volume's nearest voxels. A gate zeroes the paths shorter than any
//! that reaches the volume (less a margin for the pulse), with a smooth edge.
//!
//! Measurements are in `docs/window-ends.md`.

use crate::{Capture, DVec3, PointSet, Volume};

/// The end level (see [`Capture::end_level`]) from which [`WindowEnd::Auto`] handles the end.
pub const AUTO_LEVEL: f64 = 0.05;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WindowEnd {
    /// Handle the end when its level is at least [`AUTO_LEVEL`]; leave other captures untouched.
    #[default]
    Auto,
    /// Always handle the end.
    Taper,
    /// Never: the step stays (a warning says so when the level is high).
    Keep,
}

/// What was found and done at the window's end, for a reconstruction's summary.
#[derive(Clone, Debug, PartialEq)]
pub struct EndReport {
    pub level: f64,
    /// Length of the ramp (m of path); 0 when the end was left as it was.
    pub taper_m: f64,
    /// Voxels whose shortest path exceeds this were zeroed by [`EndReport::trim`].
    pub trim_from_m: Option<f64>,
    pub trimmed_voxels: usize,
}

impl EndReport {
    /// One line for a summary.
    pub fn describe(&self) -> String {
        let level = format!(
            "the last 5 % of bins carry {:.1} % of the peak",
            100.0 * self.level
        );
        match self.trim_from_m {
            Some(from) => format!(
                "{level}; tapered over the last {} m of path, {} voxels reached only by paths past {} m zeroed",
                crate::short(self.taper_m),
                self.trimmed_voxels,
                crate::short(from)
            ),
            None => level,
        }
    }

    /// A warning when the end is strong and was left as it was.
    pub fn warning(&self) -> Option<String> {
        (self.trim_from_m.is_none() && self.level >= AUTO_LEVEL).then(|| {
            format!(
                "the time window ends while the signal is strong ({:.0} % of the peak in its last 5 % of bins): expect a false surface at the far end (drop {} to handle it)",
                100.0 * self.level,
                crate::Opt::WindowEnd.set("keep")
            )
        })
    }

    /// Zeroes the voxels of `intensity` (C order over `volume`) that no path shorter than
    /// `trim_from_m` reaches.
    pub fn trim(&mut self, cap: &Capture, volume: &Volume, intensity: &mut [f32]) {
        let Some(from) = self.trim_from_m else {
            return;
        };
        let bound = PathBound::new(cap);
        let mut n = 0;
        for (i, v) in intensity.iter_mut().enumerate() {
            let (ix, iy, iz) = volume.unravel(i);
            let p = volume.centre(ix, iy, iz);
            if bound.at(p) > from {
                *v = 0.0;
                n += 1;
            }
        }
        self.trimmed_voxels = n;
    }
}

/// Measures the end and, as `mode` says, tapers `cap` over `taper_m` of path; [`EndReport::trim`]
/// then clears the far voxels of the result.
pub fn handle_end(cap: &mut Capture, mode: WindowEnd, taper_m: f64) -> EndReport {
    let level = cap.end_level();
    let act = match mode {
        WindowEnd::Auto => level >= AUTO_LEVEL,
        WindowEnd::Taper => true,
        WindowEnd::Keep => false,
    };
    if !act || taper_m <= 0.0 {
        return EndReport {
            level,
            taper_m: 0.0,
            trim_from_m: None,
            trimmed_voxels: 0,
        };
    }
    let bins = cap.taper_end(taper_m);
    let taper_m = bins as f64 * cap.time.bin_width_m;
    EndReport {
        level,
        taper_m,
        trim_from_m: Some(cap.time.end_m() - 2.0 * taper_m),
        trimmed_voxels: 0,
    }
}

/// The points' axis-aligned bounding box.
fn bounds(p: &PointSet) -> (DVec3, DVec3) {
    p.points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), q| {
            (a.min(*q), b.max(*q))
        })
}

/// What the gate removed, for a reconstruction's summary.
#[derive(Clone, Debug, PartialEq)]
pub struct GateReport {
    /// Fully open from this path (m); `None` when no gate applied.
    pub open_m: Option<f64>,
    /// Share of |H| (summed over the capture) that the gate removed.
    pub removed_share: f64,
}

impl GateReport {
    pub fn describe(&self) -> String {
        match self.open_m {
            Some(at) => format!(
                "paths shorter than {} m faded out ({:.1} % of the capture's signal removed)",
                crate::short(at),
                100.0 * self.removed_share
            ),
            None => "none".into(),
        }
    }
}

/// The shortest path (m, a lower bound) through any voxel of `volume`: the distances to the two
/// sides' bounding boxes plus the shortest first and last bounces.
pub fn shortest_path_m(cap: &Capture, volume: &Volume) -> f64 {
    let bound = PathBound::new(cap);
    // The bound grows with |z| away from the wall plane, so the nearest plane holds the minimum;
    // both end planes are scanned for volumes given in either order.
    let mut best = f64::INFINITY;
    for z in [volume.z.start, volume.z.end] {
        for x in volume.x.values() {
            for y in volume.y.values() {
                best = best.min(bound.at(DVec3::new(x, y, z)));
            }
        }
    }
    best
}

/// A lower bound of the shortest path through a point: the distances to the two sides' bounding
/// boxes plus the shortest first and last bounces.
struct PathBound {
    illum: (DVec3, DVec3),
    sensor: (DVec3, DVec3),
    bounces_m: f64,
}

impl PathBound {
    fn new(cap: &Capture) -> PathBound {
        let first = (0..cap.illum.len())
            .map(|l| cap.first_bounce_m(l))
            .fold(f64::INFINITY, f64::min);
        let last = (0..cap.sensor.len())
            .map(|s| cap.last_bounce_m(s))
            .fold(f64::INFINITY, f64::min);
        PathBound {
            illum: bounds(&cap.illum),
            sensor: bounds(&cap.sensor),
            bounces_m: first + last,
        }
    }

    fn at(&self, p: DVec3) -> f64 {
        let d = |(lo, hi): (DVec3, DVec3)| (p.clamp(lo, hi) - p).length();
        d(self.illum) + d(self.sensor) + self.bounces_m
    }
}

/// Fades out the paths shorter than `open_m`: bins before `open_m − edge_m` become 0, then a
/// half-Hann ramp rises to 1 at `open_m`. `None`, or a gate at or before the window's start, changes
/// nothing.
pub fn apply_gate(cap: &mut Capture, open_m: Option<f64>, edge_m: f64) -> GateReport {
    let t = cap.time;
    let none = GateReport {
        open_m: None,
        removed_share: 0.0,
    };
    let Some(open) = open_m.filter(|&o| o > t.start_m) else {
        return none;
    };
    // Weight of bin n (centre at start + (n + ½)·w): 0 before the edge, cos² rising across it.
    let weight = |n: usize| {
        let p = t.start_m + (n as f64 + 0.5) * t.bin_width_m;
        if p >= open {
            1.0
        } else if edge_m <= 0.0 || p <= open - edge_m {
            0.0
        } else {
            (std::f64::consts::FRAC_PI_2 * (open - p) / edge_m)
                .cos()
                .powi(2)
        }
    };
    let last = ((open - t.start_m) / t.bin_width_m)
        .ceil()
        .clamp(0.0, t.bins as f64) as usize;
    let w: Vec<f32> = (0..last).map(|n| weight(n) as f32).collect();
    let (mut total, mut removed) = (0f64, 0f64);
    for h in cap.h.chunks_exact_mut(t.bins) {
        total += h.iter().map(|v| v.abs() as f64).sum::<f64>();
        for (v, &k) in h.iter_mut().zip(&w) {
            removed += (v.abs() * (1.0 - k)) as f64;
            *v *= k;
        }
    }
    GateReport {
        open_m: Some(open),
        removed_share: if total > 0.0 { removed / total } else { 0.0 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Axis, TimeAxis};

    /// Confocal 2 × 2 points on x, y ∈ {−0.1, 0.1}, 20 bins of 0.1 m, H = 1.
    fn capture() -> Capture {
        let grid = PointSet::wall_grid(DVec3::ZERO, 0.4, 0.4, 2, 2);
        let time = TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.1,
            bins: 20,
        };
        Capture::confocal(grid, time, vec![1.0; 80], String::new())
    }

    #[test]
    fn shortest_path_is_twice_the_nearest_depth_over_the_grid() {
        let vol = Volume {
            x: Axis::new(-0.5, 0.5, 3),
            y: Axis::new(0.0, 0.0, 1),
            z: Axis::new(1.2, 0.7, 4),
        };
        // (0, 0, 0.7) lies over the grid's bounding box: 2 × 0.7.
        assert!((shortest_path_m(&capture(), &vol) - 1.4).abs() < 1e-12);
    }

    #[test]
    fn gate_zeroes_then_ramps_and_reports_what_it_removed() {
        let mut c = capture();
        // Open at 1.0 m with a 0.4 m edge: bins centred below 0.6 m are 0, then cos² rises.
        let r = apply_gate(&mut c, Some(1.0), 0.4);
        let h = c.histogram(3);
        for (n, &v) in h.iter().enumerate() {
            let p = (n as f64 + 0.5) * 0.1;
            let want = if p >= 1.0 {
                1.0
            } else if p <= 0.6 {
                0.0
            } else {
                (std::f64::consts::FRAC_PI_2 * (1.0 - p) / 0.4)
                    .cos()
                    .powi(2)
            };
            assert!((v as f64 - want).abs() < 1e-6, "bin {n}: {v} vs {want}");
        }
        let kept: f64 = h.iter().map(|&v| v as f64).sum();
        assert!((r.removed_share - (20.0 - kept) / 20.0).abs() < 1e-6);
        assert_eq!(r.open_m, Some(1.0));
        // A gate at or before the window's start changes nothing.
        let mut c = capture();
        let r = apply_gate(&mut c, Some(0.0), 0.4);
        assert_eq!((r.open_m, c.h.iter().all(|&v| v == 1.0)), (None, true));
    }
}
