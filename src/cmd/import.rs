//! `murk import`: real confocal captures from MATLAB files into murk's capture model.
//!
//! Orientation. The CDT reference code shows `meas(t, a, b)` as an image with row = a (top → bottom)
//! and column = b (left → right), and the letters then read upright. murk's front view looks from the
//! wall into the scene with +y up and +x on the left, so scan row a becomes y (decreasing with a) and
//! scan column b becomes x (decreasing with b): grid point (ix, iy) = (B − 1 − b, A − 1 − a), on a
//! regular grid with its first axis along +x and its second along +y (what the fast paths need).
//! LCT's `rect_data(i, j, t)`: O'Toole's reference code permutes it to (t, j, i), reverses i and
//! shows the front view with row = j and column = reversed i, so a = j and b = N − 1 − i: grid point
//! (ix, iy) = (i, N − 1 − j).

use crate::cmd::progress::say;
use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use murk_core::{Capture, DVec3, Pairing, PointLayout, PointSet, TimeAxis};
use std::path::{Path, PathBuf};

/// The speed of light both reference codes convert bins with (their depths assume it).
const REFERENCE_C_M_PER_S: f64 = 3e8;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Lindell & Wetzstein 2020: MATLAB v7.3 (HDF5) with `meas` (t × a × b), 16 ps bins, t = 0 at
    /// the slab's front face.
    Cdt,
    /// O'Toole et al. 2018: MATLAB v5 with `rect_data` (N × N × T, 4 ps bins, t = 0 at the wall)
    /// and `width` (half the scan side).
    Lct,
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk import ../shared/data/real/cdt_lindell2020/letter_s.mat --format cdt --out letter_s.h5\n  \
murk import my_scan.mat --format cdt --wall-size 0.5 --out my_scan.h5\n  \
murk import s_u.mat --format lct --out s_u.h5\n\n\
Scan sides known by file name (cdt): letter_s 0.636 m, mannequin 0.609 m, letters_ut, letter_t and cones 0.7 m.\n\
The scan is a confocal grid at z = 0 from −side/2 to +side/2; scan row a (top → bottom in the reference\n\
display) maps to +y → −y, scan column b (left → right) to +x → −x, so murk's front view (from the wall, +y up,\n\
+x left) shows the scene as the reference code does.")]
pub struct ImportArgs {
    /// A MATLAB .mat file.
    pub file: PathBuf,
    #[arg(long, value_enum)]
    pub format: Format,
    /// Full side of the square scan (m). Required for cdt files other than the five published scenes;
    /// lct files carry it (`width` is half of it).
    #[arg(long)]
    pub wall_size: Option<f64>,
    /// Time bin width in picoseconds (default 16 for cdt, 4 for lct).
    #[arg(long)]
    pub bin_width_ps: Option<f64>,
    /// Zero the first N bins (direct light off the wall). Default 0 for cdt (the SPAD was gated),
    /// 600 for lct (as the reference code, with 4 ps bins).
    #[arg(long)]
    pub gate_bins: Option<usize>,
    /// Output capture (y-tal HDF5).
    #[arg(long)]
    pub out: PathBuf,
}

/// Published scan sides of the CDT scenes (README: scan_size × size_calibration).
pub const CDT_SCENES: [(&str, f64, f64); 5] = [
    // (file stem, scan side m, Wiener snr of the reference reconstruction)
    ("letter_s", 0.636, 1e4),
    ("mannequin", 0.609, 2e4),
    ("letter_t", 0.7, 2.5e3),
    ("cones", 0.7, 2e4),
    ("letters_ut", 0.7, 1e4),
];

/// What to import and how; `None` takes the format's defaults.
pub struct ImportOptions {
    pub format: Format,
    pub wall_size_m: Option<f64>,
    pub bin_width_ps: Option<f64>,
    pub gate_bins: Option<usize>,
}

fn header_check(path: &Path, format: Format) -> anyhow::Result<()> {
    let mut head = [0u8; 19];
    let n = std::io::Read::read(
        &mut std::fs::File::open(path).with_context(|| path.display().to_string())?,
        &mut head,
    )
    .with_context(|| path.display().to_string())?;
    let head = &head[..n];
    match format {
        Format::Cdt if head.starts_with(b"MATLAB 5.0") => bail!(
            "{}: this is a MATLAB v5 file, but CDT captures are v7.3 (HDF5); for LCT data use --format lct",
            path.display()
        ),
        Format::Lct if head.starts_with(b"MATLAB 7.3") => bail!(
            "{}: this is a MATLAB v7.3 (HDF5) file, but LCT captures are v5; for CDT data use --format cdt",
            path.display()
        ),
        _ => Ok(()),
    }
}

/// Reads a CDT or LCT capture into a confocal capture (see the module comment for the geometry).
pub fn import(path: &Path, o: &ImportOptions) -> anyhow::Result<Capture> {
    header_check(path, o.format)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (var, shape, data, side, bin_ps, gate) = match o.format {
        Format::Cdt => {
            let (shape, data) = murk_io::read_mat_v73_array(path, "meas")?;
            let known = CDT_SCENES.iter().find(|s| s.0 == stem).map(|s| s.1);
            let Some(side) = o.wall_size_m.or(known) else {
                bail!(
                    "{}: unknown scene '{stem}' (known: {}); give its scan side with --wall-size",
                    path.display(),
                    CDT_SCENES.map(|s| s.0).join(", ")
                );
            };
            // MATLAB t × a × b: already (t, a, b) row-major.
            (
                "meas",
                shape,
                data,
                side,
                o.bin_width_ps.unwrap_or(16.0),
                o.gate_bins.unwrap_or(0),
            )
        }
        Format::Lct => {
            let (shape, data) = murk_io::read_mat_v5_array(path, "rect_data")?;
            let side = match o.wall_size_m {
                Some(s) => s,
                None => {
                    let (ws, w) = murk_io::read_mat_v5_array(path, "width")
                        .context("give the scan side with --wall-size")?;
                    if w.len() != 1 {
                        bail!(
                            "{}: 'width' should be a scalar (half the scan side), got shape {ws:?}",
                            path.display()
                        );
                    }
                    2.0 * w[0] as f64
                }
            };
            // MATLAB N × N × T (i, j, t) → (t, a, b) with a = j, b = N − 1 − i.
            let [ni, nj, nt] = shape[..] else {
                bail!(
                    "{}: 'rect_data' should be N × N × T, got shape {shape:?}",
                    path.display()
                );
            };
            let mut tab = vec![0f32; data.len()];
            for (k, &v) in data.iter().enumerate() {
                let (i, j, t) = (k / (nj * nt), k / nt % nj, k % nt);
                tab[(t * nj + j) * ni + ni - 1 - i] = v;
            }
            (
                "rect_data",
                vec![nt, nj, ni],
                tab,
                side,
                o.bin_width_ps.unwrap_or(4.0),
                o.gate_bins.unwrap_or(600),
            )
        }
    };
    let [nt, na, nb] = shape[..] else {
        bail!(
            "{}: '{var}' should be a 3-D array, got shape {shape:?}",
            path.display()
        );
    };
    if na < 2 || nb < 2 || nt < 2 {
        bail!(
            "{}: '{var}' has shape {shape:?}; a confocal scan needs at least 2 × 2 points and 2 time bins",
            path.display()
        );
    }
    if let Some(v) = data.iter().find(|v| !v.is_finite()) {
        bail!("{}: '{var}' holds a non-finite value ({v})", path.display());
    }
    if !(side.is_finite() && side > 0.0 && bin_ps.is_finite() && bin_ps > 0.0) {
        bail!("scan side ({side} m) and bin width ({bin_ps} ps) must be positive");
    }
    // Grid point (ix, iy) is scan column b = nb − 1 − ix, row a = na − 1 − iy.
    let (nx, ny) = (nb, na);
    let at = |n: usize, i: usize| -side / 2.0 + side * i as f64 / (n - 1) as f64;
    let points: Vec<DVec3> = (0..nx * ny)
        .map(|i| DVec3::new(at(nx, i / ny), at(ny, i % ny), 0.0))
        .collect();
    let grid = PointSet {
        normals: vec![DVec3::Z; points.len()],
        points,
        layout: PointLayout::Grid { nx, ny },
    };
    let mut h = vec![0f32; nx * ny * nt];
    for (i, hist) in h.chunks_mut(nt).enumerate() {
        let (a, b) = (na - 1 - i % ny, nb - 1 - i / ny);
        for (t, v) in hist.iter_mut().enumerate().skip(gate) {
            *v = data[(t * na + a) * nb + b];
        }
    }
    let bin_width_m = REFERENCE_C_M_PER_S * bin_ps * 1e-12;
    let scene_info = format!(
        "generator: murk import\nmurk_version: {}\nsource_file: '{}'\nformat: {}\nscene: '{stem}'\nvariable: {var}\nscan_side_m: {side}\nbin_width_ps: {bin_ps}\nspeed_of_light_m_per_s: {REFERENCE_C_M_PER_S}\ngated_bins: {gate}\norientation: 'grid (ix, iy) = scan (column {nb} - 1 - ix, row {na} - 1 - iy)'\n",
        env!("CARGO_PKG_VERSION"),
        path.display().to_string().replace('\'', "''"),
        match o.format {
            Format::Cdt => "cdt (t = 0 at the slab front face)",
            Format::Lct => "lct (t = 0 at the wall)",
        },
    );
    let cap = Capture {
        illum: grid.clone(),
        sensor: grid,
        laser_xyz: None,
        sensor_xyz: None,
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m,
            bins: nt,
        },
        t_accounts_first_and_last_bounces: false,
        pairing: Pairing::Paired,
        h,
        scene_info,
    };
    cap.validate()?;
    Ok(cap)
}

pub fn run(a: ImportArgs, quiet: bool) -> anyhow::Result<()> {
    murk_io::refuse_overwrite(&a.out, &[&a.file])?;
    let cap = import(
        &a.file,
        &ImportOptions {
            format: a.format,
            wall_size_m: a.wall_size,
            bin_width_ps: a.bin_width_ps,
            gate_bins: a.gate_bins,
        },
    )?;
    murk_io::write_capture(&a.out, &cap)?;
    say(quiet, format!("wrote {}", a.out.display()));
    if !quiet {
        println!("{}", crate::cmd::info::describe(&cap).join("\n"));
    }
    Ok(())
}
