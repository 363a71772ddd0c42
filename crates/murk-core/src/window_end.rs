//! Captures whose time window ends while the signal is still strong (a deep target, a medium's
//! tail, a long-range histogram cut by the hardware). Every reconstruction treats the missing bins as
//! zeros, so the window's end is a step in each histogram, and band-pass filters (Phasor Fields'
//! pulse, f-k's and the diffusion model's frequency-domain steps) turn that step into a bright false
//! surface at the depths the end reaches. The handling: a smooth ramp over the histograms' last
//! `taper_m` of path, and the voxels whose every path reaches past `end − 2·taper_m` set to zero
//! (their values come from the ramp and the cut, not from the scene). Measurements are in
//! `docs/window-ends.md`.

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
                "the time window ends while the signal is strong ({:.0} % of the peak in its last 5 % of bins): expect a false surface at the far end (drop --window-end keep to handle it)",
                100.0 * self.level
            )
        })
    }

    /// Zeroes the voxels of `intensity` (C order over `volume`) that no path shorter than
    /// `trim_from_m` reaches.
    pub fn trim(&mut self, cap: &Capture, volume: &Volume, intensity: &mut [f32]) {
        let Some(from) = self.trim_from_m else {
            return;
        };
        let (ny, nz) = (volume.y.n, volume.z.n);
        let first = (0..cap.illum.len())
            .map(|l| cap.first_bounce_m(l))
            .fold(f64::INFINITY, f64::min);
        let last = (0..cap.sensor.len())
            .map(|s| cap.last_bounce_m(s))
            .fold(f64::INFINITY, f64::min);
        let (il, ih) = bounds(&cap.illum);
        let (sl, sh) = bounds(&cap.sensor);
        let mut n = 0;
        for (i, v) in intensity.iter_mut().enumerate() {
            let (ix, iy, iz) = (i / (ny * nz), (i / nz) % ny, i % nz);
            let p = DVec3::new(volume.x.at(ix), volume.y.at(iy), volume.z.at(iz));
            // A lower bound of the shortest path: the distances to the two sides' bounding boxes.
            let shortest =
                (p.clamp(il, ih) - p).length() + (p.clamp(sl, sh) - p).length() + first + last;
            if shortest > from {
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
