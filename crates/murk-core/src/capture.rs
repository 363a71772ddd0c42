use crate::{DVec3, DensityCells, Error, PointSet, Result};
use std::sync::Arc;

/// The time axis, as optical path length in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeAxis {
    /// Path length at the start of bin 0 (y-tal's `t_start`).
    pub start_m: f64,
    /// Width of one bin (y-tal's `delta_t`, c·Δt).
    pub bin_width_m: f64,
    pub bins: usize,
}

impl TimeAxis {
    pub fn end_m(&self) -> f64 {
        self.start_m + self.bins as f64 * self.bin_width_m
    }
    /// Whether two axes are the same once written: the capture format keeps `start_m` and
    /// `bin_width_m` as f32 (as y-tal does), so a capture in memory and its file must match.
    pub fn same_as_stored(&self, other: &TimeAxis) -> bool {
        self.bins == other.bins
            && self.start_m as f32 == other.start_m as f32
            && self.bin_width_m as f32 == other.bin_width_m as f32
    }
}

/// Which (illumination, sensor) combinations H holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// Every illumination point with every sensor point: histogram index = l·n_sensor + s.
    Product,
    /// The i-th illumination point with the i-th sensor point (confocal scans): histogram index = i.
    Paired,
}

/// The capture kinds a user meets, derived from the point sets and the pairing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaptureKind {
    /// Illumination and sensor at the same wall points (paired, equal positions).
    Confocal,
    /// Paired but at different positions.
    Paired,
    /// Many illumination points, one sensor point (the paper's synthetic data).
    LaserGridSinglePoint,
    /// One illumination point, many sensor points (y-tal's "single").
    SinglePointSensorGrid,
    /// Many × many.
    Exhaustive,
}

impl std::fmt::Display for CaptureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CaptureKind::Confocal => "confocal",
            CaptureKind::Paired => "paired (one laser point per sensor point)",
            CaptureKind::LaserGridSinglePoint => "laser grid + one SPAD point",
            CaptureKind::SinglePointSensorGrid => "one laser point + sensor grid",
            CaptureKind::Exhaustive => "exhaustive (every laser point × every sensor point)",
        })
    }
}

/// A transient NLOS capture. `h` holds one histogram of `time.bins` samples per measured pair,
/// contiguous in time (histogram-major), so filtering a histogram touches contiguous memory.
#[derive(Clone, Debug)]
pub struct Capture {
    pub illum: PointSet,
    pub sensor: PointSet,
    /// Laser device position (needed when the time axis includes the first bounce).
    pub laser_xyz: Option<DVec3>,
    /// SPAD device position (needed when the time axis includes the last bounce).
    pub sensor_xyz: Option<DVec3>,
    pub time: TimeAxis,
    /// Whether path lengths include laser→wall and wall→SPAD (y-tal's flag of the same name).
    pub t_accounts_first_and_last_bounces: bool,
    pub pairing: Pairing,
    pub h: Vec<f32>,
    /// Free-form metadata as YAML text (y-tal's `scene_info`), kept opaque.
    pub scene_info: String,
    /// The density cells of the heterogeneous medium (`kind = "grid"`) the capture was rendered
    /// through, over the box its `scene_info` names; `None` for any other capture. Shared, since
    /// captures are cloned and the cells may be large.
    pub medium_density: Option<Arc<DensityCells>>,
}

impl Capture {
    /// A capture of `h` between `illum` and `sensor` without device positions, scene text or medium
    /// (not validated: see [`Capture::validate`]). Other fields are set by struct update
    /// (`Capture { scene_info, ..Capture::new(..) }`), so a new field only needs a default here.
    pub fn new(
        illum: PointSet,
        sensor: PointSet,
        pairing: Pairing,
        time: TimeAxis,
        h: Vec<f32>,
    ) -> Capture {
        Capture {
            illum,
            sensor,
            laser_xyz: None,
            sensor_xyz: None,
            time,
            t_accounts_first_and_last_bounces: false,
            pairing,
            h,
            scene_info: String::new(),
            medium_density: None,
        }
    }

    /// The capture without its histograms and metadata: what a reconstruction plan is built from.
    pub fn geometry(&self) -> Capture {
        Capture {
            illum: self.illum.clone(),
            sensor: self.sensor.clone(),
            h: Vec::new(),
            scene_info: String::new(),
            medium_density: None,
            ..*self
        }
    }

    /// Whether `other` has the same points, pairing, device positions and time axis, so that a plan
    /// built for one serves the other.
    pub fn same_geometry(&self, other: &Capture) -> bool {
        self.illum == other.illum
            && self.sensor == other.sensor
            && self.laser_xyz == other.laser_xyz
            && self.sensor_xyz == other.sensor_xyz
            && self.time == other.time
            && self.t_accounts_first_and_last_bounces == other.t_accounts_first_and_last_bounces
            && self.pairing == other.pairing
    }

    pub fn n_hist(&self) -> usize {
        match self.pairing {
            Pairing::Product => self.illum.len() * self.sensor.len(),
            Pairing::Paired => self.illum.len(),
        }
    }

    /// (illumination index, sensor index) of histogram `i`.
    pub fn hist_pair(&self, i: usize) -> (usize, usize) {
        match self.pairing {
            Pairing::Product => (i / self.sensor.len(), i % self.sensor.len()),
            Pairing::Paired => (i, i),
        }
    }

    pub fn histogram(&self, i: usize) -> &[f32] {
        let nt = self.time.bins;
        &self.h[i * nt..(i + 1) * nt]
    }

    /// A confocal capture: each point of `grid` is measured with itself, one histogram per point in
    /// `h` (not validated: see [`Capture::validate`]).
    pub fn confocal(grid: PointSet, time: TimeAxis, h: Vec<f32>, scene_info: String) -> Capture {
        Capture {
            scene_info,
            ..Capture::new(grid.clone(), grid, Pairing::Paired, time, h)
        }
    }

    /// This capture with its time window cut after `bins` bins (all of them when there are fewer).
    pub fn first_bins(&self, bins: usize) -> Capture {
        let nt = self.time.bins;
        let n = bins.min(nt);
        let h = self
            .h
            .chunks_exact(nt)
            .flat_map(|hist| &hist[..n])
            .copied()
            .collect();
        Capture {
            h,
            time: TimeAxis {
                bins: n,
                ..self.time
            },
            ..self.clone()
        }
    }

    /// Multiplies each histogram by the visible side's radiometry, which H between wall points leaves
    /// out: cos θ/d² from the laser device to the illumination point (a projector's irradiance) and
    /// from the sensor point to the SPAD device (an aperture's collection), θ from the wall point's
    /// normal. Renders then compare with renderers and hardware that include the devices.
    pub fn apply_device_radiometry(&mut self, laser: DVec3, spad: DVec3) {
        let leg = |dev: DVec3, p: DVec3, n: DVec3| {
            let v = dev - p;
            let d2 = v.length_squared();
            if d2 == 0.0 {
                0.0
            } else {
                (n.dot(v).abs() / d2.sqrt() / d2) as f32
            }
        };
        let nt = self.time.bins;
        for i in 0..self.n_hist() {
            let (l, s) = self.hist_pair(i);
            let f = leg(laser, self.illum.points[l], self.illum.normals[l])
                * leg(spad, self.sensor.points[s], self.sensor.normals[s]);
            self.h[i * nt..(i + 1) * nt]
                .iter_mut()
                .for_each(|v| *v *= f);
        }
    }

    /// How strong the signal still is where the time window ends: the largest value of the summed
    /// histogram over its last 5 % of bins (at least one), relative to its peak (0 for an all-zero
    /// capture). A window cut while a return or a medium's tail is strong reads near 1.
    pub fn end_level(&self) -> f64 {
        let nt = self.time.bins;
        let mut sum = vec![0f64; nt];
        for h in self.h.chunks_exact(nt) {
            for (s, &v) in sum.iter_mut().zip(h) {
                *s += v as f64;
            }
        }
        let peak = sum.iter().fold(0f64, |m, v| m.max(v.abs()));
        if peak == 0.0 {
            return 0.0;
        }
        let tail = (nt / 20).max(1);
        sum[nt - tail..].iter().fold(0f64, |m, v| m.max(v.abs())) / peak
    }

    /// Multiplies the last `length_m` of path of every histogram by a half-Hann ramp that falls from
    /// 1 to 0 at the window's end, so that a window cut while the signal is strong ends smoothly
    /// instead of in a step (which band-pass filters turn into a bright false surface at the far
    /// end). Returns the number of bins the ramp covers.
    pub fn taper_end(&mut self, length_m: f64) -> usize {
        let nt = self.time.bins;
        let n = ((length_m / self.time.bin_width_m).round().max(0.0) as usize).min(nt);
        if n == 0 {
            return 0;
        }
        // Bin nt − n + j (j = 0..n) gets cos²(π/2 · (j + 1)/(n + 1)): the ramp reaches 0 just past the
        // last bin, and is 1 just before the first.
        let ramp: Vec<f32> = (0..n)
            .map(|j| {
                let u = (j + 1) as f64 / (n + 1) as f64;
                (std::f64::consts::FRAC_PI_2 * u).cos().powi(2) as f32
            })
            .collect();
        for h in self.h.chunks_exact_mut(nt) {
            for (v, r) in h[nt - n..].iter_mut().zip(&ramp) {
                *v *= r;
            }
        }
        n
    }

    pub fn kind(&self) -> CaptureKind {
        match self.pairing {
            Pairing::Paired => {
                let same = self
                    .illum
                    .points
                    .iter()
                    .zip(&self.sensor.points)
                    .all(|(a, b)| (*a - *b).length() <= 1e-6 * (1.0 + a.length()));
                if same {
                    CaptureKind::Confocal
                } else {
                    CaptureKind::Paired
                }
            }
            Pairing::Product => match (self.illum.len(), self.sensor.len()) {
                (_, 1) => CaptureKind::LaserGridSinglePoint,
                (1, _) => CaptureKind::SinglePointSensorGrid,
                _ => CaptureKind::Exhaustive,
            },
        }
    }

    /// Path from the laser device to illumination point `l` (0 unless the time axis includes it).
    pub fn first_bounce_m(&self, l: usize) -> f64 {
        match (self.t_accounts_first_and_last_bounces, self.laser_xyz) {
            (true, Some(x)) => (self.illum.points[l] - x).length(),
            _ => 0.0,
        }
    }

    /// Path from sensor point `s` to the SPAD device (0 unless the time axis includes it).
    pub fn last_bounce_m(&self, s: usize) -> f64 {
        match (self.t_accounts_first_and_last_bounces, self.sensor_xyz) {
            (true, Some(x)) => (self.sensor.points[s] - x).length(),
            _ => 0.0,
        }
    }

    /// A copy with the roles of illumination and sensor swapped (reciprocity). Confocal and paired
    /// captures keep their layout; product captures are transposed.
    pub fn swapped_roles(&self) -> Capture {
        let mut out = self.clone();
        std::mem::swap(&mut out.illum, &mut out.sensor);
        std::mem::swap(&mut out.laser_xyz, &mut out.sensor_xyz);
        if self.pairing == Pairing::Product {
            let (nl, ns, nt) = (self.illum.len(), self.sensor.len(), self.time.bins);
            for l in 0..nl {
                for s in 0..ns {
                    let src = (l * ns + s) * nt;
                    let dst = (s * nl + l) * nt;
                    out.h[dst..dst + nt].copy_from_slice(&self.h[src..src + nt]);
                }
            }
        }
        out
    }

    /// Checks every invariant a reconstructor relies on; the message names the offending field.
    pub fn validate(&self) -> Result<()> {
        self.validate_geometry()?;
        self.validate_data()
    }

    /// The checks of [`Capture::validate`] that do not read H: what a plan needs.
    pub fn validate_geometry(&self) -> Result<()> {
        self.illum.validate("illumination points")?;
        self.sensor.validate("sensor points")?;
        let t = &self.time;
        if !(t.bin_width_m.is_finite() && t.bin_width_m > 0.0) {
            return Err(Error::param(format!(
                "bin width must be a positive number of metres, got {}",
                crate::short(t.bin_width_m)
            )));
        }
        if !t.start_m.is_finite() {
            return Err(Error::param(format!(
                "time start must be finite, got {}",
                t.start_m
            )));
        }
        if t.bins == 0 {
            return Err(Error::param("the time axis has no bins"));
        }
        let limits = crate::Limits::get();
        limits.length("the time start", t.start_m)?;
        limits.length("the time window's end", t.end_m())?;
        if t.bin_width_m < limits.min_bin_width_m {
            return Err(Error::Limits(format!(
                "the bin width is {} m; murk accepts bins of at least {} m",
                crate::short(t.bin_width_m),
                crate::short(limits.min_bin_width_m)
            )));
        }
        for (name, p) in [
            ("laser position", self.laser_xyz),
            ("SPAD position", self.sensor_xyz),
        ] {
            if let Some(p) = p {
                // max_element skips NaN, so finiteness is checked on its own.
                if !p.is_finite() {
                    return Err(Error::param(format!(
                        "the {name} has a non-finite coordinate: {p}"
                    )));
                }
                limits.length(
                    &format!("the {name}'s largest |coordinate|"),
                    p.abs().max_element(),
                )?;
            }
        }
        if self.pairing == Pairing::Paired && self.illum.len() != self.sensor.len() {
            return Err(Error::param(format!(
                "paired capture with {} illumination points but {} sensor points",
                self.illum.len(),
                self.sensor.len()
            )));
        }
        Ok(())
    }

    /// The checks of [`Capture::validate`] on H: for a reader that checked the geometry before
    /// reading H.
    pub fn validate_data(&self) -> Result<()> {
        let t = &self.time;
        let want = self.n_hist().saturating_mul(t.bins);
        if self.h.len() != want {
            return Err(Error::param(format!(
                "H has {} samples, expected {} histograms × {} bins = {want}",
                self.h.len(),
                self.n_hist(),
                t.bins
            )));
        }
        // Branch-free per chunk (all-ones exponent means Inf or NaN) so the scan vectorises; the
        // position is looked up only in a chunk that has one.
        const CHUNK: usize = 1 << 14;
        let non_finite = |c: &[f32]| {
            c.iter().fold(false, |bad, v| {
                bad | (v.to_bits() & 0x7f80_0000 == 0x7f80_0000)
            })
        };
        if let Some(i) = self.h.chunks(CHUNK).position(non_finite).and_then(|c| {
            let start = c * CHUNK;
            self.h[start..]
                .iter()
                .position(|v| !v.is_finite())
                .map(|o| start + o)
        }) {
            let (hist, bin) = (i / t.bins, i % t.bins);
            let (l, s) = self.hist_pair(hist);
            return Err(Error::param(format!(
                "H contains a non-finite value ({}) at illumination {l}, sensor {s}, bin {bin}",
                crate::non_finite(self.h[i])
            )));
        }
        if self.t_accounts_first_and_last_bounces
            && (self.laser_xyz.is_none() || self.sensor_xyz.is_none())
        {
            return Err(Error::param(
                "t_accounts_first_and_last_bounces is set but the laser or SPAD device position is missing",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn product(nl: usize, ns: usize, nt: usize) -> Capture {
        Capture::new(
            PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, nl, 1),
            PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, ns, 1),
            Pairing::Product,
            TimeAxis {
                start_m: 0.0,
                bin_width_m: 0.01,
                bins: nt,
            },
            (0..nl * ns * nt).map(|v| v as f32).collect(),
        )
    }

    /// Two histograms of 40 bins: H = 1 everywhere but a peak of 4 at bin 10 of the first.
    fn flat(nt: usize) -> Capture {
        let mut c = product(2, 1, nt);
        c.h.iter_mut().for_each(|v| *v = 1.0);
        c.h[10] = 4.0;
        c
    }

    #[test]
    fn non_finite_device_positions_are_refused() {
        let mut c = flat(40);
        c.laser_xyz = Some(DVec3::new(0.0, f64::NAN, 1.0));
        let e = c.validate().unwrap_err().to_string();
        assert!(
            e.contains("laser position has a non-finite coordinate"),
            "{e}"
        );
        c.laser_xyz = None;
        c.sensor_xyz = Some(DVec3::new(f64::INFINITY, 0.0, 1.0));
        let e = c.validate().unwrap_err().to_string();
        assert!(
            e.contains("SPAD position has a non-finite coordinate"),
            "{e}"
        );
    }

    #[test]
    fn end_level_reads_the_summed_tail_against_the_peak() {
        let mut c = flat(40);
        // Summed: peak 5 at bin 10, 2 elsewhere; the last 5 % (2 bins) carry 2.
        assert!((c.end_level() - 0.4).abs() < 1e-12);
        c.h.iter_mut().for_each(|v| *v = 0.0);
        assert_eq!(c.end_level(), 0.0);
    }

    #[test]
    fn taper_is_a_half_hann_ramp_over_the_last_bins() {
        let mut c = flat(40);
        // 0.05 m of 0.01 m bins: 5 bins, cos²(π/2·j/6) for j = 1..5.
        assert_eq!(c.taper_end(0.05), 5);
        for (j, &v) in c.histogram(1)[35..].iter().enumerate() {
            let want = (std::f64::consts::FRAC_PI_2 * (j + 1) as f64 / 6.0)
                .cos()
                .powi(2);
            assert!((v as f64 - want).abs() < 1e-6, "bin {j}: {v} vs {want}");
        }
        assert!(c.histogram(1)[..35].iter().all(|&v| v == 1.0));
        // The last two bins keep cos²(π/2·4/6) = 1/4 and less: 2·(1/4)/5 of the peak.
        assert!((c.end_level() - 0.1).abs() < 1e-6);
        let cut = c.first_bins(12);
        assert_eq!((cut.time.bins, cut.h.len()), (12, 24));
        assert_eq!(cut.histogram(0)[10], 4.0);
        assert_eq!(cut.histogram(1), &c.histogram(1)[..12]);
    }

    #[test]
    fn handling_follows_the_mode_and_trims_the_far_voxels() {
        use crate::window::{handle_end, WindowEnd};
        use crate::{Axis, Volume};
        let mut c = flat(40);
        let untouched = c.clone();
        let r = handle_end(&mut c, WindowEnd::Keep, 0.05);
        assert_eq!((r.taper_m, c.h == untouched.h), (0.0, true));
        assert!(r.warning().is_some());
        let mut r = handle_end(&mut c, WindowEnd::Auto, 0.05);
        assert!((r.taper_m - 0.05).abs() < 1e-12 && r.warning().is_none());
        // The window ends at 0.40 m: voxels whose shortest path exceeds 0.30 m are cleared. Points lie
        // on x ∈ [−0.25, 0.25] (illumination) and at x = 0 (sensor), both at z = 0, so the shortest
        // path to (0, 0, z) is 2z: 0.20, 0.32, 0.44 m.
        let vol = Volume {
            x: Axis::new(0.0, 0.0, 1),
            y: Axis::new(0.0, 0.0, 1),
            z: Axis::new(0.1, 0.22, 3),
        };
        let mut v = vec![1.0f32; 3];
        r.trim(&c, &vol, &mut v);
        assert_eq!((v, r.trimmed_voxels), (vec![1.0, 0.0, 0.0], 2));
    }

    #[test]
    fn device_radiometry_is_cos_over_d_squared_on_each_leg() {
        let mut c = product(2, 1, 3);
        c.h.iter_mut().for_each(|v| *v = 1.0);
        // Laser 1 m in front of illumination point 0 at x = −0.25; SPAD 2 m in front of the sensor
        // point at x = 0, both along the wall normal +z (cos = 1).
        let laser = c.illum.points[0] + DVec3::new(0.0, 0.0, 1.0);
        let spad = c.sensor.points[0] + DVec3::new(0.0, 0.0, 2.0);
        c.apply_device_radiometry(laser, spad);
        let want0 = 1.0 * (1.0 / 4.0);
        // Point 1 at x = +0.25 sees the laser 0.5 m off axis: cos = 1/√1.25, d² = 1.25.
        let want1 = (1.0 / 1.25f64.sqrt() / 1.25) * (1.0 / 4.0);
        assert!((c.histogram(0)[1] as f64 - want0).abs() < 1e-6);
        assert!((c.histogram(1)[2] as f64 - want1).abs() < 1e-6);
    }

    #[test]
    fn swap_transposes_histograms() {
        let c = product(3, 2, 4);
        let s = c.swapped_roles();
        assert_eq!(s.illum.len(), 2);
        // Histogram (l=2, s=1) of the original, index l·2 + s, is (l=1, s=2) of the swapped one,
        // index l·3 + s.
        let (orig, swapped) = (2 * 2 + 1, 3 + 2);
        assert_eq!(c.histogram(orig), s.histogram(swapped));
        assert_eq!(s.swapped_roles().h, c.h);
    }

    #[test]
    fn validate_names_the_problem() {
        let mut c = product(2, 2, 4);
        c.h[9] = f32::NAN;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("illumination 1, sensor 0, bin 1"), "{e}");
        let mut c = product(2, 2, 4);
        c.time.bin_width_m = 0.0;
        assert!(c.validate().unwrap_err().to_string().contains("bin width"));
    }

    #[test]
    fn kinds() {
        assert_eq!(product(4, 1, 2).kind(), CaptureKind::LaserGridSinglePoint);
        assert_eq!(product(1, 4, 2).kind(), CaptureKind::SinglePointSensorGrid);
        assert_eq!(product(2, 3, 2).kind(), CaptureKind::Exhaustive);
        let mut c = product(3, 3, 2);
        c.pairing = Pairing::Paired;
        c.h.truncate(6);
        assert_eq!(c.kind(), CaptureKind::Confocal);
    }
}
