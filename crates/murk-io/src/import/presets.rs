//! The published dataset layouts stored as one confocal scan array on a regular square grid.

use super::{BinWidth, Dim, Flip, Framing, ImportOptions, Scan};
use crate::mat::ArrayFile;
use murk_core::{Capture, Error, Opt, Result};
use std::path::Path;

/// The public NLOS datasets murk reads. Each variant's doc states the dataset's published layout
/// and parameters, and the orientation murk gives it (see the module comment of [`super`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Lindell & Wetzstein 2020 (confocal diffuse tomography): MATLAB v7.3 `meas` (t, a, b),
    /// 512 × 32 × 32, 16 ps bins, t = 0 at the front face of the scattering slab, no gate (the SPAD
    /// was gated). Scan side by file name ([`CDT_SCENES`]) or `--wall-size`.
    Cdt,
    /// O'Toole et al. 2018 (LCT): MATLAB v5 `rect_data` (i, j, t) uint16 N × N × T and `width`
    /// (half the scan side, m); 4 ps bins, t = 0 at the wall; the reference zeroes the first 600
    /// bins. The reference front view shows row j and column N − 1 − i.
    Lct,
    /// O'Toole et al. 2018's mannequin capture: MATLAB v5 `transient` (N², T) uint8 and `lighting`
    /// (N², 3) scan points; confocal 64², x ∈ [−0.35, 0.35] m; 4 ps, the first 600 bins zeroed.
    /// `transient` reshaped column-major to N × N × T is LCT's `rect_data`, read as [`Preset::Lct`];
    /// the side is `lighting`'s x extent (0.7 m without it).
    LctTransient,
    /// Lindell et al. 2019 (f-k migration): MATLAB v7.3 or v5 `meas` (a, b, t) N × N × T, 32 ps
    /// bins, confocal over a 2 m square, t = 0 at the laser's sync. The scenes' `tof.mat` holds
    /// `tofgrid` (ps per scan point, same (a, b) indexing): with it (`--tof`) each histogram moves
    /// floor(tofgrid / bin) bins earlier (the reference code's circshift; murk fills the vacated
    /// bins with zeros instead of wrapping), which puts t = 0 at the wall. Row a and column b as
    /// CDT's.
    Fk,
    /// Ahn et al. 2019 (convolutional approximations): MATLAB v5 struct `NLOSDATA` with
    /// `transient` (Nx, Ny, Nt), `l` and `s` (Nx·Ny, 3) laser and sensor wall points (point
    /// ix·Ny + iy measures transient(ix, iy, :)), `times` (path length, m, per bin), `delta` (bin
    /// width, m), `is_confocal`, `target_dist`. Times are round-trip paths from the wall. The
    /// file's wall lies at z = target_dist with the scene on its −z side; murk turns the points
    /// half a turn about y to put the wall at z = 0 and the scene at z > 0.
    Ahn2019,
    /// Xiao et al. 2024: MATLAB v5 `sig` (a, b, t) 32 × 32 × 512 float64, normalised and
    /// background-subtracted (small negative values), 32 ps bins, confocal over 0.82 m, t = 0 at
    /// the wall. Their solver's orientation is undocumented: murk reads row a and column b as CDT's.
    Xiao2024,
    /// Wu et al. 2021: MATLAB v5 `sig_in` (a, b, t) 64 × 64 × 512 (float64 or uint8), `timeRes`
    /// (bin, s), `width` (half side, m), `pulsewidth`, `radius`; 32 ps, confocal over ±0.425 m,
    /// t = 0 at the relay wall. murk uses the file's `timeRes` and `width` where present. Their
    /// display is not CDT's: it plots index b upwards and index a to the left seen from the wall,
    /// so a runs along +x and b along +y.
    Wu2021,
    /// Zhang et al. 2023 (ABP): MATLAB v7.3 `tof_data` (a, b, t) 64 × 64 × 2048 (h5py shape
    /// (2048, 64, 64)), 5 ps bins, confocal over 0.8 m, t = 0 at the wall. Their script zeroes
    /// bins 1–500 and 1200–end: murk gates the first 500; cutting the end is left to the user.
    /// Row a and column b as CDT's (their `Z.mat` display; they show `LT.mat` transposed).
    Abp,
    /// Galindo et al. 2019 (Zaragoza Z-NLOS): HDF5 `data` (sx, sy, bounces, t, colours) or its
    /// reverse (colours, t, bounces, sy, sx) for confocal renders, with `cameraGridPositions`,
    /// `laserGridPositions` (and normals), `cameraPosition`, `laserPosition`, `deltaT` and `t0`
    /// (m). Bounces and colours are summed, times include the laser → wall and wall → camera
    /// legs, and the file's wall points are kept (wall at z = 0, scene at z > 0). Only confocal
    /// (5-D) renders are read.
    Znlos,
    /// Du, Jin, Deng et al. 2022 (boundary migration model): MATLAB v5 `raw_data` (a, b, t)
    /// N × N × 256 photon counts, 55 ps bins, a confocal scan of a scattering medium's surface
    /// (t = 0 is not marked: the surface return rises over the first bins). The reference code
    /// shows row a from top to bottom (the letter T's bar on top); row a and column b as CDT's.
    /// Scan side by file name ([`BMM_SCENES`]) or `--wall-size`. The medium's constants the
    /// reference assumes go into `scene_info` ([`BMM_MEDIUM`]).
    Bmm,
}

/// Published scan sides of the boundary migration model's captures (twice the reference code's
/// `width`, per file).
pub const BMM_SCENES: [(&str, f64); 8] = [
    ("2cmFoam_LambertianT_7cmFoam", 0.2),
    ("3cmFoam_LambertianT_7cmFoam", 0.2),
    ("4cmFoam_LambertianT_7cmFoam", 0.2),
    ("5cmFoam_LambertianT_7cmFoam", 0.1),
    ("6cmFoam_LambertianT_7cmFoam", 0.2),
    ("7cmFoam_LambertianT_7cmFoam", 0.2),
    ("8cmFoam_LambertianT_7cmFoam", 0.22),
    ("Fog_Bunny", 0.2),
];

/// The medium the boundary migration model's reference code assumes for its foam captures
/// (μs = 313 /m with g = 0, absorption ignored, n = 1.23), as the `scene_info` lines that
/// `--method bmm` reads.
pub const BMM_MEDIUM: &str = "medium_n: 1.23\nmedium_mu_s_prime_per_m: 313\nmedium_mu_a_per_m: 0\n";

/// Published scan sides of the CDT scenes (README: scan_size × size_calibration).
pub const CDT_SCENES: [(&str, f64, f64); 5] = [
    // (file stem, scan side m, Wiener snr of the reference reconstruction)
    ("letter_s", 0.636, 1e4),
    ("mannequin", 0.609, 2e4),
    ("letter_t", 0.7, 2.5e3),
    ("cones", 0.7, 2e4),
    ("letters_ut", 0.7, 1e4),
];

impl Preset {
    pub const ALL: [Preset; 10] = [
        Preset::Lct,
        Preset::LctTransient,
        Preset::Cdt,
        Preset::Fk,
        Preset::Ahn2019,
        Preset::Xiao2024,
        Preset::Wu2021,
        Preset::Abp,
        Preset::Znlos,
        Preset::Bmm,
    ];

    /// The `--format` name.
    /// The preset called `name`; an unknown name is refused listing the others.
    pub fn named(name: &str) -> Result<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
                Error::param(format!("format '{name}': expected {}", names.join(", ")))
            })
    }

    pub fn name(self) -> &'static str {
        match self {
            Preset::Cdt => "cdt",
            Preset::Lct => "lct",
            Preset::LctTransient => "lct-transient",
            Preset::Fk => "fk",
            Preset::Ahn2019 => "ahn2019",
            Preset::Xiao2024 => "xiao2024",
            Preset::Wu2021 => "wu2021",
            Preset::Abp => "abp",
            Preset::Znlos => "znlos",
            Preset::Bmm => "bmm",
        }
    }

    /// One line of published parameters, for `--help`.
    pub fn summary(self) -> &'static str {
        match self {
            Preset::Cdt => "Lindell & Wetzstein 2020, v7.3 meas (t, a, b) 512×32×32, 16 ps, t = 0 at the slab, side by scene name",
            Preset::Lct => "O'Toole et al. 2018, v5 rect_data (i, j, t) + width (half side), 4 ps, first 600 bins gated",
            Preset::LctTransient => "O'Toole 2018 mannequin, v5 transient (N², T) + lighting, 4 ps, 600 bins gated, 64² over 0.7 m",
            Preset::Fk => "Lindell et al. 2019, v7.3/v5 meas (a, b, t), 32 ps, 2 m side; --tof tof.mat rectifies",
            Preset::Ahn2019 => "Ahn et al. 2019, v5 struct NLOSDATA: transient (x, y, t), l/s points, times, delta",
            Preset::Xiao2024 => "Xiao et al. 2024, v5 sig (a, b, t) 32×32×512, 32 ps, 0.82 m side (orientation assumed as cdt)",
            Preset::Wu2021 => "Wu et al. 2021, v5 sig_in (a, b, t) 64×64×512, timeRes (s), width (half side), 32 ps, 0.85 m, a along +x",
            Preset::Abp => "Zhang et al. 2023, v7.3 tof_data (a, b, t) 64×64×2048, 5 ps, 0.8 m side, first 500 bins gated",
            Preset::Znlos => "Galindo et al. 2019 Z-NLOS HDF5: confocal data + grid positions, deltaT/t0 in m",
            Preset::Bmm => "Du et al. 2022 (BMM), v5 raw_data (a, b, t) 64×64×256, 55 ps, side by file name, foam constants",
        }
    }
}

/// Which MATLAB container a preset's files come in.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Container {
    V5,
    V73,
    Either,
}

/// Where a preset's scan side comes from when `--wall-size` is not given.
#[derive(Clone, Copy)]
enum Side {
    /// [`CDT_SCENES`], by file stem.
    CdtScene,
    /// [`BMM_SCENES`], by file stem.
    BmmScene,
    /// Twice the scalar variable named (`width`: the half side), or the fallback where absent.
    HalfSideVar(&'static str, Option<f64>),
    /// The x extent of an (N², 3) point list (`lighting`), or the fallback where absent.
    PointsExtent(&'static str, f64),
    Fixed(f64),
}

/// A preset's array layout and published parameters.
pub(super) struct Spec {
    var: &'static str,
    container: Container,
    /// The stored axes and the reversals that put the displayed row a and column b on murk's
    /// front view (CDT-like: row and column both reversed).
    axes: [Dim; 3],
    flip: Flip,
    /// The variable is (N², T): read it column-major as N × N × T first.
    square_split: bool,
    bin_ps: f64,
    /// A scalar variable holding the bin width in seconds, used where present.
    bin_var_s: Option<&'static str>,
    gate_bins: usize,
    side: Side,
    /// `scene_info`'s `format` line.
    format: &'static str,
    /// `scene_info` lines of the medium the dataset's reference code assumes.
    medium: &'static str,
}

/// Row a, column b: murk's x is the reversed column, y the reversed row.
const DISPLAYED: Flip = Flip { x: true, y: true };

/// f-k's raw `meas` starts at the laser's sync: its README says `tofgrid` is what puts t = 0 at
/// the wall for every scan point (computational-imaging/nlos-fk, README.md, "Description of Files").
const FK_RECTIFIED: &str = "fk (t = 0 at the wall: rectified by --tof)";
const FK_RAW: &str =
    "fk (not rectified: t = 0 is the laser's sync, not the wall; depths read long without --tof)";

/// The `scene_info` line of a scan whose t = 0 is not the wall, which `murk info`'s depth axis reads.
pub(crate) const TIME_ZERO_NOT_WALL: &str =
    "time_zero: not the wall (an unrectified scan: import it with --tof)";

/// The layout of an array preset; `None` for the presets that carry their own wall points.
pub(super) fn spec(p: Preset) -> Option<Spec> {
    let display_abt = |var, bin_ps, side, format| Spec {
        var,
        container: Container::V5,
        axes: [Dim::Y, Dim::X, Dim::T],
        flip: DISPLAYED,
        square_split: false,
        bin_ps,
        bin_var_s: None,
        gate_bins: 0,
        side,
        format,
        medium: "",
    };
    Some(match p {
        Preset::Cdt => Spec {
            container: Container::V73,
            axes: [Dim::T, Dim::Y, Dim::X],
            ..display_abt(
                "meas",
                16.0,
                Side::CdtScene,
                "cdt (t = 0 at the slab front face)",
            )
        },
        // rect_data(i, j, t) is shown with row j and column N − 1 − i: x = i, y = reversed j.
        Preset::Lct => Spec {
            axes: [Dim::X, Dim::Y, Dim::T],
            flip: Flip { x: false, y: true },
            gate_bins: 600,
            ..display_abt(
                "rect_data",
                4.0,
                Side::HalfSideVar("width", None),
                "lct (t = 0 at the wall)",
            )
        },
        // transient(i + N·j, t) read in C order as [N, N, T] has axes (j, i, t).
        Preset::LctTransient => Spec {
            axes: [Dim::Y, Dim::X, Dim::T],
            flip: Flip { x: false, y: true },
            square_split: true,
            gate_bins: 600,
            ..display_abt(
                "transient",
                4.0,
                Side::PointsExtent("lighting", 0.7),
                "lct-transient (t = 0 at the wall)",
            )
        },
        Preset::Fk => Spec {
            container: Container::Either,
            ..display_abt("meas", 32.0, Side::Fixed(2.0), FK_RECTIFIED)
        },
        Preset::Xiao2024 => display_abt(
            "sig",
            32.0,
            Side::Fixed(0.82),
            "xiao2024 (t = 0 at the wall; orientation assumed as cdt)",
        ),
        // Their solver works on sig_in permuted to (b, a, t) and draw3D plots b on the vertical
        // axis, a on the one that MATLAB's default 3-D view (az −37.5°) shows leftwards from the
        // wall side (nzhang1218/NLOS_imaging_over_1.43km, fcns/sp1400.m and fcns/draw3D.m).
        Preset::Wu2021 => Spec {
            axes: [Dim::X, Dim::Y, Dim::T],
            flip: Flip::default(),
            bin_var_s: Some("timeRes"),
            ..display_abt(
                "sig_in",
                32.0,
                Side::HalfSideVar("width", Some(0.85)),
                "wu2021 (t = 0 at the relay wall)",
            )
        },
        Preset::Abp => Spec {
            container: Container::V73,
            gate_bins: 500,
            ..display_abt("tof_data", 5.0, Side::Fixed(0.8), "abp (t = 0 at the wall)")
        },
        Preset::Bmm => Spec {
            medium: BMM_MEDIUM,
            ..display_abt(
                "raw_data",
                55.0,
                Side::BmmScene,
                "bmm (confocal scan of the medium's surface; t = 0 not marked)",
            )
        },
        Preset::Ahn2019 | Preset::Znlos => return None,
    })
}

/// The container a preset's files come in.
pub(super) fn container(p: Preset) -> Container {
    match (p, spec(p)) {
        (_, Some(s)) => s.container,
        (Preset::Znlos, None) => Container::V73,
        _ => Container::V5,
    }
}

/// The presets whose files come in `c`, as `--format a, b or c` (in the front end's spelling).
fn presets_in(c: Container) -> String {
    let names: Vec<&str> = Preset::ALL
        .iter()
        .filter(|&&p| container(p) == c || container(p) == Container::Either)
        .map(|p| p.name())
        .collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => {
            format!("{} {} or {last}", Opt::Format, rest.join(", "))
        }
        _ => format!("{} {}", Opt::Format, names.join("")),
    }
}

/// Refuses a file in the other MATLAB container before reading it, naming the presets that fit.
pub(super) fn check_container(path: &Path, p: Preset, file: &ArrayFile) -> Result<()> {
    let want = container(p);
    let (found, is) = match file {
        ArrayFile::V5(_) => (Container::V5, "a MATLAB v5 file"),
        ArrayFile::Hdf5 { .. } => (Container::V73, "a MATLAB v7.3 (HDF5) file"),
        ArrayFile::Npy(..) => {
            return Err(Error::format(
                path,
                format!(
                    "this is a .npy array, not a {} capture; read it with {}/{} (the generic form)",
                    p.name(),
                    Opt::Var,
                    Opt::Axes
                ),
            ))
        }
    };
    if want == Container::Either || want == found {
        return Ok(());
    }
    let (needs, other) = match want {
        Container::V5 => ("v5", "v7.3"),
        _ if p == Preset::Znlos => ("HDF5", "v5"),
        _ => ("v7.3 (HDF5)", "v5"),
    };
    Err(Error::format(
        path,
        format!(
            "this is {is}, but {} captures are {needs}; for {other} data use {}",
            p.name(),
            presets_in(found)
        ),
    ))
}

/// A scalar variable, if the file has it.
pub(super) fn scalar(path: &Path, file: &ArrayFile, var: &str) -> Result<Option<f64>> {
    match file.get(path, var)? {
        None => Ok(None),
        Some((_, v)) if v.len() == 1 => Ok(Some(v[0] as f64)),
        Some((shape, _)) => Err(Error::format(
            path,
            format!("'{var}' should be a scalar, got shape {shape:?}"),
        )),
    }
}

/// `v`, read from the file's variable `var` (`what` it holds, in `unit`), if it is positive and
/// finite (as the f32 the file is read as: 1e300 is inf).
pub(super) fn positive(path: &Path, var: &str, what: &str, v: f64, unit: &str) -> Result<f64> {
    if v > 0.0 && v.is_finite() {
        return Ok(v);
    }
    Err(Error::format(
        path,
        format!(
            "'{var}' ({what}) must be positive and finite, got {} {unit}",
            murk_core::short(v)
        ),
    ))
}

/// `points`: the data's scan points, which a point list must hold as many of.
fn scan_side_m(path: &Path, file: &ArrayFile, side: Side, points: usize) -> Result<f64> {
    match side {
        Side::Fixed(s) => Ok(s),
        Side::CdtScene => by_stem(path, &CDT_SCENES.map(|s| (s.0, s.1))),
        Side::BmmScene => by_stem(path, &BMM_SCENES),
        Side::HalfSideVar(var, fallback) => match (scalar(path, file, var)?, fallback) {
            (Some(half), _) => Ok(2.0 * positive(path, var, "half the scan side", half, "m")?),
            (None, Some(s)) => Ok(s),
            (None, None) => Err(Error::format(
                path,
                format!(
                    "no variable '{var}' (half the scan side; variables present: {}); give the scan side with {}",
                    file.names(path)?.join(", "),
                    Opt::WallSize
                ),
            )),
        },
        Side::PointsExtent(var, fallback) => match file.get(path, var)? {
            None => Ok(fallback),
            Some((shape, xyz)) if shape.len() == 2 && shape[1] == 3 && shape[0] == points => {
                if let Some(v) = xyz.iter().find(|v| !v.is_finite()) {
                    return Err(Error::format(
                        path,
                        format!("'{var}' holds a coordinate that is {}", murk_core::non_finite(*v)),
                    ));
                }
                let xs = xyz.chunks_exact(3).map(|p| p[0] as f64);
                let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
                positive(path, var, "the scan's x extent", hi - lo, "m")
            }
            Some((shape, _)) => Err(Error::format(
                path,
                format!("'{var}' should be the {points} × 3 scan points, got shape {shape:?}"),
            )),
        },
    }
}

/// The scan side of a known file, by its stem.
fn by_stem(path: &Path, scenes: &[(&str, f64)]) -> Result<f64> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    scenes
        .iter()
        .find(|s| s.0 == stem)
        .map(|s| s.1)
        .ok_or_else(|| {
            Error::param(format!(
                "{}: unknown scene '{stem}' (known: {}); give its scan side with {}",
                path.display(),
                scenes.iter().map(|s| s.0).collect::<Vec<_>>().join(", "),
                Opt::WallSize
            ))
        })
}

/// `[N², T]` as `[N, N, T]` (a column-major reshape is, in C order, axes (j, i, t)).
fn split_square(path: &Path, var: &str, shape: &[usize]) -> Result<Vec<usize>> {
    let &[points, nt] = shape else {
        return Err(Error::format(
            path,
            format!("'{var}' should be N² × T, got shape {shape:?}"),
        ));
    };
    let n = (points as f64).sqrt().round() as usize;
    if n * n != points {
        return Err(Error::format(
            path,
            format!("'{var}' has {points} scan points, not a square number (shape {shape:?})"),
        ));
    }
    Ok(vec![n, n, nt])
}

/// Reads the array preset `p`, whose layout is `s` ([`spec`]).
pub(super) fn import(path: &Path, p: Preset, s: &Spec, o: &ImportOptions) -> Result<Capture> {
    let file = ArrayFile::open(path)?;
    check_container(path, p, &file)?;
    let (mut shape, data) = file.require(path, s.var)?;
    if s.square_split {
        shape = split_square(path, s.var, &shape)?;
    }
    super::check_square(
        path,
        s.var,
        &shape,
        s.axes,
        &format!(
            "{} scans are square: is this a file of another dataset ({})?",
            p.name(),
            Opt::Format
        ),
    )?;
    let flip = s.flip.xor(o.flip);
    let mut scan = Scan::new(path, s.var, &shape, &data, s.axes, flip)?;
    drop(data);
    let side_m = match o.wall_size_m {
        Some(side) => side,
        None => scan_side_m(path, &file, s.side, scan.nx * scan.ny)?,
    };
    let bin_width = match (o.bin_width, s.bin_var_s) {
        (Some(b), _) => b,
        (None, Some(var)) => match scalar(path, &file, var)? {
            Some(secs) => BinWidth::Ps(positive(path, var, "the bin width", secs, "s")? * 1e12),
            None => BinWidth::Ps(s.bin_ps),
        },
        (None, None) => BinWidth::Ps(s.bin_ps),
    };
    let mut extra = super::flip_line(o.flip);
    extra += s.medium;
    if p == Preset::Fk && o.tof.is_none() {
        extra += TIME_ZERO_NOT_WALL;
        extra += "\n";
    }
    if let Some(tof) = &o.tof {
        let BinWidth::Ps(bin_ps) = bin_width else {
            return Err(Error::param(format!(
                "{} needs the bin width in ps (tofgrid is in ps)",
                Opt::Tof
            )));
        };
        rectify(&mut scan, tof, s.axes, flip, bin_ps)?;
        extra += &format!(
            "tof_file: '{}'\n",
            tof.display().to_string().replace('\'', "''")
        );
    }
    scan.confocal(
        path,
        &Framing {
            var: s.var,
            format: match (p, &o.tof) {
                (Preset::Fk, None) => FK_RAW,
                _ => s.format,
            },
            side_m,
            bin_width,
            gate_bins: o.gate_bins.unwrap_or(s.gate_bins),
            t0_bin: o.t0_bin.unwrap_or(0),
            extra,
        },
    )
}

/// Moves each histogram floor(tofgrid / bin) bins earlier (f-k's `tof.mat`: the time the light
/// takes from the laser to each scan point and back to the SPAD), filling with zeros at the end.
fn rectify(scan: &mut Scan, tof: &Path, axes: [Dim; 3], flip: Flip, bin_ps: f64) -> Result<()> {
    let (shape, grid_ps) = ArrayFile::open(tof)?.require(tof, "tofgrid")?;
    // tofgrid(a, b) has the scan axes of meas(a, b, t): order it as a one-bin scan.
    let spatial: Vec<Dim> = axes.iter().copied().filter(|&d| d != Dim::T).collect();
    let want = [scan_len(scan, spatial[0]), scan_len(scan, spatial[1])];
    if shape != want {
        return Err(Error::format(
            tof,
            format!("'tofgrid' has shape {shape:?}, but the scan is {want:?}"),
        ));
    }
    let shifts_ps = super::to_xyt(
        [shape[0], shape[1], 1],
        &grid_ps,
        [spatial[0], spatial[1], Dim::T],
        flip,
    );
    let nt = scan.nt;
    for (hist, &ps) in scan.h.chunks_mut(nt).zip(&shifts_ps) {
        let shift = (ps as f64 / bin_ps).floor();
        if !shift.is_finite() {
            return Err(Error::format(tof, format!("'tofgrid' holds {ps}")));
        }
        let k = shift.abs().min(nt as f64) as usize;
        if shift >= 0.0 {
            hist.copy_within(k.., 0);
            hist[nt - k..].fill(0.0);
        } else {
            hist.copy_within(..nt - k, k);
            hist[..k].fill(0.0);
        }
    }
    Ok(())
}

fn scan_len(scan: &Scan, d: Dim) -> usize {
    match d {
        Dim::X => scan.nx,
        Dim::Y => scan.ny,
        Dim::T => scan.nt,
    }
}
