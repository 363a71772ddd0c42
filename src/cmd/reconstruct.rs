//! `murk reconstruct`: a capture file in, a volume (.npy / .h5) and pictures out.

use crate::cmd::pictures;
use crate::cmd::progress::{say, Bar};
use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use murk_core::{Axis, Capture, Volume};
use murk_recon::{Compensation, Falloff, Method, PfParams, Wavelength};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Phasor Fields, fast planar form (falls back to the exact form when the wall is not a planar grid).
    Pf,
    /// Phasor Fields, exact time-domain form for any geometry (slow on big captures).
    PfExact,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CompensateArg {
    /// The paper's K(x_v) = (1 − α e^{−α d}) / e^{−μt d}, as printed.
    Paper,
    /// Undo the ballistic round-trip attenuation e^{−2μt (d_ill + d_cam)} of |U|².
    Ballistic,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FalloffArg {
    /// No amplitude factor (tal pf_dev).
    None,
    /// 1/d per leg (the paper's RSD kernel e^{ikd}/d).
    InvR,
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk reconstruct capture.h5 --out volume.npy --png pictures/\n  \
murk reconstruct capture.h5 --out volume.h5 --wavefactor 8 --cycles 4 --volume -1:1:73,-1:1:59,1.5:2.5:73\n  \
murk reconstruct fog.h5 --out v.npy --compensate paper --mu-t 1.0 --albedo 0.5\n\n\
Volumes: --volume x0:x1:nx,y0:y1:ny,z0:z1:nz gives nx voxel centres from x0 to x1 inclusive (metres; z is the\n\
depth in front of the wall at z = 0). Default: the wall grid's extent and spacing in x and y, depth from 0.1 m to\n\
as deep as the capture's time window reaches. Output arrays have shape [nx, ny, nz], float32 |U|²·K, C order.")]
pub struct ReconstructArgs {
    /// A y-tal HDF5 capture.
    pub file: PathBuf,
    /// Output volume: .npy (float32 [nx, ny, nz]) or .h5/.hdf5 (intensity + x, y, z + parameters).
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, value_enum, default_value = "pf")]
    pub method: MethodArg,
    /// Virtual wavelength λ in metres.
    #[arg(long, conflicts_with = "wavefactor")]
    pub wavelength: Option<f64>,
    /// Virtual wavelength as a multiple of the wall spacing Δc (default 4, the paper's λ = 4Δc).
    #[arg(long)]
    pub wavefactor: Option<f64>,
    /// Pulse length in wavelengths: σ = cycles·λ/6 (paper: 4 for synthetic, 8 for real data).
    #[arg(long, default_value_t = 4.0)]
    pub cycles: f64,
    /// Voxels as x0:x1:nx,y0:y1:ny,z0:z1:nz (metres, inclusive).
    #[arg(long, allow_hyphen_values = true)]
    pub volume: Option<String>,
    /// Also write front/top/side maximum projections, a depth map and index.html into this folder.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Medium compensation of the intensity (needs --mu-t; paper also --albedo).
    #[arg(long, value_enum, requires = "mu_t")]
    pub compensate: Option<CompensateArg>,
    /// Extinction coefficient μt of the medium (1/m).
    #[arg(long)]
    pub mu_t: Option<f64>,
    /// Single-scattering albedo α of the medium.
    #[arg(long, default_value_t = 0.0)]
    pub albedo: f64,
    /// Amplitude factor per leg.
    #[arg(long, value_enum, default_value = "none")]
    pub falloff: FalloffArg,
}

impl ReconstructArgs {
    pub fn params(&self) -> anyhow::Result<PfParams> {
        let wavelength = match (self.wavelength, self.wavefactor) {
            (Some(m), _) => Wavelength::Metres(m),
            (None, Some(f)) => Wavelength::WallFactor(f),
            (None, None) => Wavelength::WallFactor(4.0),
        };
        let mu = self.mu_t.unwrap_or(0.0);
        let compensation = match self.compensate {
            None => Compensation::None,
            Some(CompensateArg::Paper) => Compensation::Paper {
                mu_t_per_m: mu,
                albedo: self.albedo,
            },
            Some(CompensateArg::Ballistic) => Compensation::Ballistic { mu_t_per_m: mu },
        };
        let falloff = match self.falloff {
            FalloffArg::None => Falloff::None,
            FalloffArg::InvR => Falloff::InvR,
        };
        Ok(PfParams {
            wavelength,
            cycles: self.cycles,
            falloff,
            compensation,
        })
    }
}

/// The wall grid's extent and spacing in x and y; depth from 0.1 m to what the time window reaches.
pub fn default_volume(cap: &Capture) -> anyhow::Result<Volume> {
    let side = if cap.sensor.len() > cap.illum.len() {
        &cap.sensor
    } else {
        &cap.illum
    };
    let spacing = murk_recon::wall_spacing_m(cap)
        .context("the capture has a single wall point; give --volume")?;
    let (lo, hi) = side
        .points
        .iter()
        .fold((side.points[0], side.points[0]), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let count = |a: f64, b: f64| ((b - a) / spacing).round() as usize + 1;
    let offsets = (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.first_bounce_m(l) + cap.last_bounce_m(s)
        })
        .fold(f64::MAX, f64::min);
    // The shortest round trip to depth z is 2z (a voxel straight in front of the wall points).
    let z_max = (cap.time.end_m() - offsets) / 2.0;
    let z_min = 0.1;
    if z_max <= z_min {
        bail!("the capture's time window ends at {:.3} m of path, before any depth beyond {z_min} m; give --volume", cap.time.end_m());
    }
    let nz = (((z_max - z_min) / spacing).round() as usize + 1).clamp(2, 256);
    Ok(Volume {
        x: Axis::new(lo.x, hi.x, count(lo.x, hi.x)),
        y: Axis::new(lo.y, hi.y, count(lo.y, hi.y)),
        z: Axis::new(z_min, z_max, nz),
    })
}

/// Writes the intensity volume by extension.
pub fn write_volume(
    path: &Path,
    vol: &Volume,
    intensity: &[f32],
    params: &[(String, String)],
) -> anyhow::Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "npy" => murk_io::write_npy_f32(path, &vol.shape(), intensity)?,
        "h5" | "hdf5" => {
            let attrs: Vec<(&str, murk_io::AttrValue)> = params
                .iter()
                .map(|(k, v)| (k.as_str(), murk_io::AttrValue::Text(v.clone())))
                .collect();
            murk_io::write_volume_h5(
                path,
                vol.shape(),
                intensity,
                &vol.x.values(),
                &vol.y.values(),
                &vol.z.values(),
                &attrs,
            )?
        }
        _ => bail!(
            "{}: unknown output type '.{ext}' (use .npy or .h5)",
            path.display()
        ),
    }
    Ok(())
}

/// Peak voxel position and value of an intensity volume.
pub fn peak(vol: &Volume, intensity: &[f32]) -> ([f64; 3], f32) {
    let (i, &v) = intensity
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap_or((0, &0.0));
    let (ix, iy, iz) = (
        i / (vol.y.n * vol.z.n),
        (i / vol.z.n) % vol.y.n,
        i % vol.z.n,
    );
    (vol.centre(ix, iy, iz).to_array(), v)
}

pub fn run(a: ReconstructArgs, quiet: bool) -> anyhow::Result<()> {
    let params = a.params()?;
    let cap = murk_io::read_capture(&a.file)?;
    let volume = match &a.volume {
        Some(spec) => Volume::parse(spec)?,
        None => default_volume(&cap)?,
    };
    let method = if a.method == MethodArg::PfExact {
        Method::Exact
    } else {
        Method::Fast
    };
    let bar = Bar::new("reconstruct", quiet);
    let t0 = std::time::Instant::now();
    let rec = murk_recon::reconstruct(&cap, &volume, &params, method, &bar)
        .with_context(|| a.file.display().to_string())?;
    bar.finish();
    let secs = t0.elapsed().as_secs_f64();
    for w in &rec.info.warnings {
        eprintln!("murk: warning: {w}");
    }
    let table = summary(&a.file, &cap, &rec, secs);
    write_volume(&a.out, &volume, &rec.intensity, &table)?;
    say(
        quiet,
        format!(
            "wrote {} ({}×{}×{} voxels)",
            a.out.display(),
            volume.x.n,
            volume.y.n,
            volume.z.n
        ),
    );
    if let Some(dir) = &a.png {
        let pics = pictures::write_views(dir, &volume, &rec.intensity)?;
        let index = pictures::write_index(
            dir,
            &format!("murk reconstruction of {}", a.file.display()),
            &table,
            &pics,
        )?;
        say(quiet, format!("wrote pictures and {}", index.display()));
    }
    for (k, v) in &table {
        say(quiet, format!("  {k}: {v}"));
    }
    Ok(())
}

/// The parameters and results worth recording next to a volume.
pub fn summary(
    file: &Path,
    cap: &Capture,
    rec: &murk_recon::Reconstruction,
    secs: f64,
) -> Vec<(String, String)> {
    let v = &rec.volume;
    let (p, val) = peak(v, &rec.intensity);
    let i = &rec.info;
    vec![
        ("capture".into(), file.display().to_string()),
        ("capture kind".into(), cap.kind().to_string()),
        (
            "method".into(),
            format!("Phasor Fields ({} form)", i.evaluated_with),
        ),
        ("wavelength_m".into(), format!("{:.6}", i.wavelength_m)),
        ("sigma_m".into(), format!("{:.6}", i.sigma_m)),
        (
            "wall_spacing_m".into(),
            i.wall_spacing_m
                .map(|d| format!("{d:.6}"))
                .unwrap_or_else(|| "n/a".into()),
        ),
        (
            "frequencies".into(),
            format!("{} of a {}-point DFT", i.frequencies, i.dft_len),
        ),
        (
            "volume".into(),
            format!(
                "x {:.4}:{:.4}:{}, y {:.4}:{:.4}:{}, z {:.4}:{:.4}:{}",
                v.x.start, v.x.end, v.x.n, v.y.start, v.y.end, v.y.n, v.z.start, v.z.end, v.z.n
            ),
        ),
        (
            "peak".into(),
            format!(
                "{val:.4e} at x {:+.4}, y {:+.4}, z {:.4} m",
                p[0], p[1], p[2]
            ),
        ),
        ("seconds".into(), format!("{secs:.3}")),
        ("murk_version".into(), env!("CARGO_PKG_VERSION").into()),
    ]
}
