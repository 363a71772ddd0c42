use murk_core::{short, Capture, DVec3, Error, Pairing, PointSet, Result, TimeAxis};

/// Which capture to build; the wall is a square at z = 0 centred on the origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutKind {
    /// `grid²` laser points, one SPAD point (the paper's synthetic data).
    LaserGridSinglePoint,
    /// One laser point, `grid²` sensor points (y-tal's "single").
    SinglePointSensorGrid,
    /// `grid²` confocal points.
    Confocal,
    /// `grid²` laser points × `grid²` sensor points.
    Exhaustive,
}

impl std::fmt::Display for LayoutKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LayoutKind::LaserGridSinglePoint => "laser-grid",
            LayoutKind::SinglePointSensorGrid => "single",
            LayoutKind::Confocal => "confocal",
            LayoutKind::Exhaustive => "exhaustive",
        })
    }
}

impl std::str::FromStr for LayoutKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "laser-grid" | "paper" => Ok(LayoutKind::LaserGridSinglePoint),
            "single" | "sensor-grid" => Ok(LayoutKind::SinglePointSensorGrid),
            "confocal" => Ok(LayoutKind::Confocal),
            "exhaustive" => Ok(LayoutKind::Exhaustive),
            _ => Err(Error::param(format!(
                "unknown capture kind '{s}' (expected laser-grid, single, confocal or exhaustive)"
            ))),
        }
    }
}

/// Geometry and time axis of a synthetic capture.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureLayout {
    pub kind: LayoutKind,
    /// Side of the square wall (the grid is pixel-centred over it).
    pub wall_size_m: f64,
    /// Points per side of the wall grid.
    pub grid: usize,
    /// The single wall point (SPAD point or laser point) for the one-point kinds.
    pub point: DVec3,
    pub time: TimeAxis,
    /// Device positions; when set, the time axis includes the first and last bounce.
    pub laser_xyz: Option<DVec3>,
    pub sensor_xyz: Option<DVec3>,
}

impl CaptureLayout {
    /// A capture with these points and an all-zero H.
    pub fn empty_capture(&self) -> Result<Capture> {
        if !(self.wall_size_m > 0.0 && self.wall_size_m.is_finite()) {
            return Err(Error::param(format!(
                "wall size must be > 0 m, got {}",
                self.wall_size_m
            )));
        }
        if self.grid == 0 || self.grid > 1024 {
            return Err(Error::param(format!(
                "grid must be 1..=1024 points per side, got {}",
                self.grid
            )));
        }
        if self.time.bins == 0 {
            return Err(Error::param("bins must be at least 1, got 0"));
        }
        let half = self.wall_size_m / 2.0;
        if self.point.x.abs() > half || self.point.y.abs() > half || self.point.z != 0.0 {
            return Err(Error::param(format!(
                "the single wall point ({}, {}, {}) is not on the {} m wall at z = 0",
                short(self.point.x),
                short(self.point.y),
                short(self.point.z),
                short(self.wall_size_m)
            )));
        }
        let grid = PointSet::wall_grid(
            DVec3::ZERO,
            self.wall_size_m,
            self.wall_size_m,
            self.grid,
            self.grid,
        );
        let one = PointSet::single(self.point);
        let (illum, sensor, pairing) = match self.kind {
            LayoutKind::LaserGridSinglePoint => (grid, one, Pairing::Product),
            LayoutKind::SinglePointSensorGrid => (one, grid, Pairing::Product),
            LayoutKind::Confocal => (grid.clone(), grid, Pairing::Paired),
            LayoutKind::Exhaustive => (grid.clone(), grid, Pairing::Product),
        };
        let accounts = self.laser_xyz.is_some() || self.sensor_xyz.is_some();
        let mut cap = Capture {
            laser_xyz: self.laser_xyz.or(accounts.then_some(DVec3::ZERO)),
            sensor_xyz: self.sensor_xyz.or(accounts.then_some(DVec3::ZERO)),
            t_accounts_first_and_last_bounces: accounts,
            ..Capture::new(illum, sensor, pairing, self.time, Vec::new())
        };
        let n = murk_core::Limits::get().capture_h(cap.n_hist(), self.time.bins)?;
        if n > 1 << 31 {
            return Err(Error::Limits(format!(
                "{} histograms × {} bins is over 2^31 samples",
                cap.n_hist(),
                self.time.bins
            )));
        }
        cap.h = vec![0.0; n];
        cap.validate()?;
        Ok(cap)
    }
}
