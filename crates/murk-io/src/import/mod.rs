//! Real captures from the public NLOS datasets (and any 3-D array) into murk's capture model.
//!
//! Orientation. murk's front view looks from the wall into the scene with +y up and +x on the left;
//! a scan grid point (ix, iy) lies on a regular grid whose first axis runs along +x and second along
//! +y (what the fast confocal paths need). The datasets store their scans as arrays shown by their
//! reference code as an image: row a from top to bottom, column b from left to right. Shown that way
//! the scene reads upright, so row a becomes y (decreasing with a) and column b becomes x
//! (decreasing with b): grid point (ix, iy) = (B − 1 − b, A − 1 − a). Each [`Preset`] says which of
//! its array's axes are the displayed row and column; the generic form names the x and y axes
//! directly (index increasing along +x, +y) and flips them on request. Files that carry their own
//! wall points (Ahn et al. 2019, Z-NLOS) keep them: the coordinates, not an index convention, place
//! the scan.
//!
//! Time. murk's time is optical path length; `t0_bin` is the bin at path 0 (murk sets the time axis
//! start to −t0_bin bins rather than moving data), and `gate_bins` zeroes the first bins (direct
//! light off the wall), as the reference codes do.

mod points;
mod presets;
#[cfg(test)]
mod tests;

use crate::mat::ArrayFile;
use murk_core::{Capture, DVec3, Error, Limits, Opt, PointLayout, PointSet, Result, TimeAxis};
use std::path::{Path, PathBuf};

pub(crate) use presets::TIME_ZERO_NOT_WALL;
pub use presets::{Preset, BMM_MEDIUM, BMM_SCENES, CDT_SCENES};

/// The speed of light the reference codes convert bins with (their depths assume it).
pub const REFERENCE_C_M_PER_S: f64 = 3e8;

/// One axis of a stored 3-D capture array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// Time bins.
    T,
    /// Scan positions along murk's +x (the front view's left).
    X,
    /// Scan positions along murk's +y (up).
    Y,
}

impl Dim {
    /// `t,x,y` in any order (what `--axes` and Python's `axes` take); that each axis appears once
    /// is checked on import.
    pub fn parse_axes(s: &str) -> Result<[Dim; 3]> {
        let dims = s
            .split(',')
            .map(|a| match a.trim() {
                "t" => Ok(Dim::T),
                "x" => Ok(Dim::X),
                "y" => Ok(Dim::Y),
                other => Err(Error::param(format!(
                    "'{other}' is not an axis (t, x or y)"
                ))),
            })
            .collect::<Result<Vec<_>>>()?;
        dims.try_into().map_err(|d: Vec<Dim>| {
            Error::param(format!("name three axes (t, x and y), not {}", d.len()))
        })
    }
}

/// Axes to reverse after the layout's own mapping (a scan shown mirrored or upside down).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flip {
    pub x: bool,
    pub y: bool,
}

impl Flip {
    /// `x`, `y` or `x,y` (what `--flip` and Python's `flip` take).
    pub fn parse(s: &str) -> Result<Flip> {
        let mut flip = Flip::default();
        for a in s.split(',') {
            let axis = match a.trim() {
                "x" => &mut flip.x,
                "y" => &mut flip.y,
                other => {
                    return Err(Error::param(format!(
                        "'{other}' is not an axis to flip (x or y)"
                    )))
                }
            };
            // Twice would read as undoing the flip, or as a typo for "x,y": neither is guessed.
            if std::mem::replace(axis, true) {
                return Err(Error::param(format!("'{}' is named twice", a.trim())));
            }
        }
        Ok(flip)
    }

    fn xor(self, o: Flip) -> Flip {
        Flip {
            x: self.x != o.x,
            y: self.y != o.y,
        }
    }
}

/// A time bin width as the user or the dataset states it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BinWidth {
    Ps(f64),
    M(f64),
}

impl BinWidth {
    pub fn metres(self) -> f64 {
        match self {
            BinWidth::Ps(ps) => REFERENCE_C_M_PER_S * ps * 1e-12,
            BinWidth::M(m) => m,
        }
    }

    /// The `scene_info` line recording it, in the unit it was given in.
    fn info_line(self) -> String {
        match self {
            BinWidth::Ps(ps) => format!("bin_width_ps: {}", info_num(ps)),
            BinWidth::M(m) => format!("bin_width_m: {}", info_num(m)),
        }
    }
}

/// A number for `scene_info` as short as it reads back: a value that a file held in single precision
/// (0.85 as f32 is 0.8500000238418579 as f64) is written with f32's shortest digits.
fn info_num(v: f64) -> String {
    if v as f32 as f64 == v {
        format!("{}", v as f32)
    } else {
        format!("{v}")
    }
}

/// A layout described on the command line: one 3-D array of a confocal scan on a square grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Generic {
    /// The array's name (`a.b` for a field of struct `a`); empty for `.npy` files, which hold one.
    pub var: String,
    /// What each stored axis holds, in the array's shape order (MATLAB's for `.mat` files, the
    /// stored order for HDF5 and `.npy`).
    pub axes: [Dim; 3],
    /// Whether the scan is confocal; non-confocal generic imports are refused.
    pub confocal: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Layout {
    Preset(Preset),
    Generic(Generic),
}

impl Layout {
    /// A preset when `format` is given, else the generic form that `var`, `axes` and `confocal`
    /// describe (`axes` required).
    pub fn choose(
        format: Option<Preset>,
        var: Option<String>,
        axes: Option<[Dim; 3]>,
        confocal: bool,
    ) -> Result<Layout> {
        match (format, axes) {
            (Some(p), _) => Ok(Layout::Preset(p)),
            (None, Some(axes)) => Ok(Layout::Generic(Generic {
                var: var.unwrap_or_default(),
                axes,
                confocal,
            })),
            (None, None) => Err(Error::param(
                "give a format, or describe the array with its axes",
            )),
        }
    }
}

/// What to import and how; `None` takes the layout's published value.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    pub layout: Layout,
    /// Full side of the square scan (m), first point to last.
    pub wall_size_m: Option<f64>,
    pub bin_width: Option<BinWidth>,
    /// Bins zeroed at the start of every histogram.
    pub gate_bins: Option<usize>,
    /// Reversals on top of the layout's orientation.
    pub flip: Flip,
    /// The bin at path length 0.
    pub t0_bin: Option<usize>,
    /// f-k only: the `tof.mat` holding `tofgrid` (ps per scan point) that rectifies the scan.
    pub tof: Option<PathBuf>,
}

impl ImportOptions {
    /// A preset with every published default.
    pub fn preset(p: Preset) -> ImportOptions {
        ImportOptions {
            layout: Layout::Preset(p),
            wall_size_m: None,
            bin_width: None,
            gate_bins: None,
            flip: Flip::default(),
            t0_bin: None,
            tof: None,
        }
    }
}

/// Reads a capture in `o.layout` into murk's capture model (see the module comment for the
/// geometry). Every error is one line naming the file.
pub fn import(path: &Path, o: &ImportOptions) -> Result<Capture> {
    if o.tof.is_some() && o.layout != Layout::Preset(Preset::Fk) {
        return Err(Error::param(format!(
            "a tof grid ({}) belongs to the f-k dataset ({})",
            Opt::Tof,
            Opt::Format.set("fk")
        )));
    }
    match &o.layout {
        // The presets that carry their own wall points are read by `points`, the others as one array.
        Layout::Preset(p) => match presets::spec(*p) {
            Some(s) => presets::import(path, *p, &s, o),
            None => points::import(path, *p, o),
        },
        Layout::Generic(g) => generic(path, g, o),
    }
}

fn generic(path: &Path, g: &Generic, o: &ImportOptions) -> Result<Capture> {
    if !g.confocal {
        return Err(Error::Unsupported(format!(
            "{}: generic imports read confocal scans only (give {} if this one is); for other layouts use a {} preset",
            path.display(),
            Opt::Confocal.on(),
            Opt::Format
        )));
    }
    let mut axes = g.axes;
    axes.sort_by_key(|d| *d as u8);
    if axes != [Dim::T, Dim::X, Dim::Y] {
        return Err(Error::param(format!(
            "{} must name t, x and y once each (e.g. t,x,y)",
            Opt::Axes
        )));
    }
    let (Some(side_m), Some(bin_width)) = (o.wall_size_m, o.bin_width) else {
        return Err(Error::param(format!(
            "a generic import needs the scan side ({}) and the bin width ({} or {})",
            Opt::WallSize,
            Opt::BinWidthPs,
            Opt::BinWidthM
        )));
    };
    let file = ArrayFile::open(path)?;
    if !g.var.is_empty() && matches!(file, ArrayFile::Npy(..)) {
        return Err(Error::param(format!(
            "{}: a .npy file holds one unnamed array; {} names a variable of a MATLAB or HDF5 file",
            path.display(),
            Opt::Var
        )));
    }
    if g.var.is_empty() && !matches!(file, ArrayFile::Npy(..)) {
        return Err(Error::param(format!(
            "{}: give the array's name with {} (variables present: {})",
            path.display(),
            Opt::Var,
            file.names(path)?.join(", ")
        )));
    }
    let (shape, data) = file.require(path, &g.var)?;
    check_square(
        path,
        &g.var,
        &shape,
        g.axes,
        &format!(
            "a generic import reads square scans ({} is the side of both axes): check {}",
            Opt::WallSize,
            Opt::Axes
        ),
    )?;
    let scan = Scan::new(path, &g.var, &shape, &data, g.axes, o.flip)?;
    let axes = g.axes.map(|d| format!("{d:?}").to_lowercase()).join(", ");
    scan.confocal(
        path,
        &Framing {
            var: &g.var,
            format: &format!("generic ({} axes {axes}; x, y along +x, +y)", file.kind()),
            side_m,
            bin_width,
            gate_bins: o.gate_bins.unwrap_or(0),
            t0_bin: o.t0_bin.unwrap_or(0),
            extra: flip_line(o.flip),
        },
    )
}

/// How messages name array `var` (a .npy file's one array has no name).
fn array_name(var: &str) -> String {
    if var.is_empty() {
        "the array".to_string()
    } else {
        format!("'{var}'")
    }
}

/// Every array layout scans a square grid (one side for both axes). A scan that is not square read
/// this way is almost always a misread layout (a CDT `meas` (t, a, b) read as f-k's (a, b, t) gives
/// a 512 × 32 scan of 32 bins), so it is refused before it is read; `why` says what to check.
fn check_square(path: &Path, var: &str, shape: &[usize], axes: [Dim; 3], why: &str) -> Result<()> {
    let side: Vec<usize> = shape
        .iter()
        .zip(axes)
        .filter(|(_, d)| *d != Dim::T)
        .map(|(n, _)| *n)
        .collect();
    if shape.len() == 3 && side[0] != side[1] {
        let bins = shape[axes.iter().position(|d| *d == Dim::T).expect("a time axis")];
        let name = array_name(var);
        return Err(Error::format(
            path,
            format!(
                "{name} of shape {shape:?} is a {} × {} scan of {bins} bins, but {why}",
                side[0], side[1]
            ),
        ));
    }
    Ok(())
}

/// `scene_info` lines for the user's extra flips (none when there are none, so a preset's default
/// import records exactly what earlier versions did).
fn flip_line(flip: Flip) -> String {
    match (flip.x, flip.y) {
        (false, false) => String::new(),
        (x, y) => format!(
            "flip: '{}'\n",
            [(x, "x"), (y, "y")]
                .iter()
                .filter(|f| f.0)
                .map(|f| f.1)
                .collect::<Vec<_>>()
                .join(",")
        ),
    }
}

/// A scan array reordered into murk's histogram-major (ix, iy, t) order.
struct Scan {
    nx: usize,
    ny: usize,
    nt: usize,
    h: Vec<f32>,
}

/// What turns a [`Scan`] into a confocal capture on a regular square grid.
struct Framing<'a> {
    var: &'a str,
    /// `scene_info`'s `format` line.
    format: &'a str,
    side_m: f64,
    bin_width: BinWidth,
    gate_bins: usize,
    t0_bin: usize,
    /// Further `scene_info` lines, each ending in a newline.
    extra: String,
}

impl Scan {
    /// The scan in `data` (C order over `shape`, see [`to_xyt`]), after checking its rank, sizes
    /// and values.
    fn new(
        path: &Path,
        var: &str,
        shape: &[usize],
        data: &[f32],
        axes: [Dim; 3],
        flip: Flip,
    ) -> Result<Scan> {
        let name = array_name(var);
        let names = axes.map(|d| match d {
            Dim::T => "T",
            Dim::X | Dim::Y => "N",
        });
        let &[n0, n1, n2] = shape else {
            return Err(Error::format(
                path,
                format!(
                    "{name} should be {} × {} × {} ({}), got shape {shape:?}",
                    names[0],
                    names[1],
                    names[2],
                    axes.map(|d| format!("{d:?}").to_lowercase()).join(", ")
                ),
            ));
        };
        let dims = [n0, n1, n2];
        let len_of = |want: Dim| dims[axes.iter().position(|&d| d == want).unwrap_or(0)];
        let (nx, ny, nt) = (len_of(Dim::X), len_of(Dim::Y), len_of(Dim::T));
        if data.len() != nx * ny * nt {
            return Err(Error::format(
                path,
                format!(
                    "{name} declares shape {shape:?} but holds {} values",
                    data.len()
                ),
            ));
        }
        if nx < 2 || ny < 2 || nt < 2 {
            return Err(Error::format(
                path,
                format!("{name} has shape {shape:?}; a confocal scan needs at least 2 × 2 points and 2 time bins"),
            ));
        }
        if let Some(v) = data.iter().find(|v| !v.is_finite()) {
            return Err(Error::format(
                path,
                format!(
                    "{name} holds a non-finite value ({})",
                    murk_core::non_finite(*v)
                ),
            ));
        }
        Limits::get().elements(&format!("{}: {name}", path.display()), &[nx, ny, nt], 4)?;
        Ok(Scan {
            nx,
            ny,
            nt,
            h: to_xyt(dims, data, axes, flip),
        })
    }

    /// Zeroes the first `bins` bins of every histogram; a gate that leaves nothing is refused
    /// (every method would return zeros).
    fn gate(&mut self, path: &Path, bins: usize) -> Result<()> {
        let nt = self.nt;
        if bins >= nt {
            return Err(Error::param(format!(
                "{}: a gate of {bins} bins leaves nothing of its {nt}-bin histograms",
                path.display()
            )));
        }
        for hist in self.h.chunks_mut(nt) {
            hist[..bins].fill(0.0);
        }
        Ok(())
    }

    /// A confocal capture on murk's regular grid over [−side/2, side/2]², first point to last.
    fn confocal(mut self, path: &Path, f: &Framing) -> Result<Capture> {
        let bin_width_m = f.bin_width.metres();
        if !(f.side_m.is_finite() && f.side_m > 0.0) {
            return Err(Error::param(format!(
                "the scan side must be a positive length, got {} m",
                murk_core::short(f.side_m)
            )));
        }
        // Named in the unit it was given in: 1e300 ps is inf m.
        if !(bin_width_m.is_finite() && bin_width_m > 0.0) {
            return Err(Error::param(format!(
                "the bin width must be a positive, finite length, got {}",
                match f.bin_width {
                    BinWidth::Ps(ps) => format!("{} ps", murk_core::short(ps)),
                    BinWidth::M(m) => format!("{} m", murk_core::short(m)),
                }
            )));
        }
        self.gate(path, f.gate_bins)?;
        if f.t0_bin >= self.nt {
            return Err(Error::param(format!(
                "{}: bin {} as path 0 puts the whole {}-bin window before the wall",
                path.display(),
                f.t0_bin,
                self.nt
            )));
        }
        let (nx, ny, side) = (self.nx, self.ny, f.side_m);
        let points = square_grid(nx, ny, side);
        let grid = PointSet {
            normals: vec![DVec3::Z; points.len()],
            points,
            layout: PointLayout::Grid { nx, ny },
        };
        let t0 = if f.t0_bin == 0 {
            String::new()
        } else {
            format!("t0_bin: {}\n", f.t0_bin)
        };
        let scene_info = format!(
            "{}scan_side_m: {}\n{}\nspeed_of_light_m_per_s: {REFERENCE_C_M_PER_S}\ngated_bins: {}\norientation: 'grid (ix, iy) = scan (column {nx} - 1 - ix, row {ny} - 1 - iy)'\n{t0}{}",
            info_head(path, f.format, f.var),
            info_num(side),
            f.bin_width.info_line(),
            f.gate_bins,
            f.extra,
        );
        confocal_capture(
            path,
            grid,
            time_axis(bin_width_m, self.nt, f.t0_bin),
            self.h,
            scene_info,
        )
    }
}

/// An nx × ny grid over [−side/2, side/2]² at z = 0, first point to last, x-major (murk's order).
fn square_grid(nx: usize, ny: usize, side_m: f64) -> Vec<DVec3> {
    let at = |n: usize, i: usize| -side_m / 2.0 + side_m * i as f64 / (n - 1) as f64;
    (0..nx * ny)
        .map(|i| DVec3::new(at(nx, i / ny), at(ny, i % ny), 0.0))
        .collect()
}

/// `data` (C order over `dims`, whose axes hold `axes`, one each of x, y and t) reordered so that
/// histogram ix·ny + iy holds the scan point at (ix, iy), reversing x and/or y as `flip` says.
fn to_xyt(dims: [usize; 3], data: &[f32], axes: [Dim; 3], flip: Flip) -> Vec<f32> {
    let at = |want: Dim| axes.iter().position(|&d| d == want).unwrap_or(0);
    let (nx, ny, nt) = (dims[at(Dim::X)], dims[at(Dim::Y)], dims[at(Dim::T)]);
    let strides = [dims[1] * dims[2], dims[2], 1];
    let (sx, sy, st) = (
        strides[at(Dim::X)],
        strides[at(Dim::Y)],
        strides[at(Dim::T)],
    );
    let mut h = vec![0f32; nx * ny * nt];
    for (i, hist) in h.chunks_mut(nt.max(1)).enumerate() {
        let (ix, iy) = (i / ny, i % ny);
        let fx = if flip.x { nx - 1 - ix } else { ix };
        let fy = if flip.y { ny - 1 - iy } else { iy };
        let base = fx * sx + fy * sy;
        for (t, v) in hist.iter_mut().enumerate() {
            *v = data[base + t * st];
        }
    }
    h
}

/// The time axis of `bins` bins of `bin_width_m` with path 0 at bin `t0_bin`.
fn time_axis(bin_width_m: f64, bins: usize, t0_bin: usize) -> TimeAxis {
    TimeAxis {
        // 0 − …, not −(…): with t0 = 0 the start is +0.0, as earlier versions wrote it.
        start_m: 0.0 - t0_bin as f64 * bin_width_m,
        bin_width_m,
        bins,
    }
}

/// The first `scene_info` lines every import writes.
fn info_head(path: &Path, format: &str, var: &str) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!(
        "generator: murk import\nmurk_version: {}\nsource_file: '{}'\nformat: {format}\nscene: '{stem}'\nvariable: {var}\n",
        env!("CARGO_PKG_VERSION"),
        path.display().to_string().replace('\'', "''"),
    )
}

/// A capture measuring each point of `grid` with itself.
fn confocal_capture(
    path: &Path,
    grid: PointSet,
    time: TimeAxis,
    h: Vec<f32>,
    scene_info: String,
) -> Result<Capture> {
    checked(path, Capture::confocal(grid, time, h, scene_info))
}

/// `cap` read from `path`, once it is a valid capture with some signal. The checks name the file, as
/// the reader's own errors do; histograms of zeros (after any gate or shift) are refused, since every
/// method would return zeros.
fn checked(path: &Path, cap: Capture) -> Result<Capture> {
    cap.validate().map_err(|e| match e {
        Error::Parameter(m) | Error::Limits(m) => Error::format(path, m),
        other => other,
    })?;
    if cap.h.iter().all(|v| *v == 0.0) {
        return Err(Error::format(
            path,
            "the histograms hold only zeros (after any gate or tof shift): there is no signal to import",
        ));
    }
    Ok(cap)
}
