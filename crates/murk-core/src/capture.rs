use crate::{DVec3, Error, PointSet, Result};

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
}

impl Capture {
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
                self.h[i]
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
        Capture {
            illum: PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, nl, 1),
            sensor: PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, ns, 1),
            laser_xyz: None,
            sensor_xyz: None,
            time: TimeAxis {
                start_m: 0.0,
                bin_width_m: 0.01,
                bins: nt,
            },
            t_accounts_first_and_last_bounces: false,
            pairing: Pairing::Product,
            h: (0..nl * ns * nt).map(|v| v as f32).collect(),
            scene_info: String::new(),
        }
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
