//! `murk reconstruct`: a capture file in, a volume (.npy / .h5) and pictures out.

use crate::cmd::progress::{say, Bar};
use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use murk_baselines::{CdtParams, FbpOptions, FkParams, LctParams, Pulse, Reflectance, SlabParams};
use murk_core::window::{apply_gate, handle_end, shortest_path_m, WindowEnd};
use murk_core::{Axis, Capture, Volume};
use murk_recon::{Compensation, Falloff, Lateral, Method, PfParams, Wavelength};
use murk_view::pictures;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Phasor Fields, fast planar form (falls back to the exact form when the wall is not a planar grid).
    Pf,
    /// Phasor Fields, exact time-domain form for any geometry (slow on big captures).
    PfExact,
    /// Backprojection (any capture kind, on --volume).
    Bp,
    /// Filtered backprojection: BP then a −∇²G filter (any capture kind, on --volume).
    Fbp,
    /// Light-cone transform with Wiener deconvolution (confocal grid; own volume).
    Lct,
    /// f-k (Stolt) migration (confocal grid; own volume).
    Fk,
    /// Confocal diffuse tomography: slab deconvolution, then f-k (confocal grid behind a slab; own volume).
    Cdt,
}

impl MethodArg {
    /// Methods that reconstruct on the confocal scan grid and ignore --volume.
    pub fn own_grid(self) -> bool {
        matches!(self, MethodArg::Lct | MethodArg::Fk | MethodArg::Cdt)
    }

    pub fn is_pf(self) -> bool {
        matches!(self, MethodArg::Pf | MethodArg::PfExact)
    }
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LateralArg {
    /// Only the wall-plane frequencies whose waves reach each depth plane (faster; differs from `full`
    /// by the kernel's and the data's leakage beyond them: intensity relL2 7e-5 on a synthetic Z,
    /// 3e-4–6e-4 on real captures).
    Propagating,
    /// Every frequency: the fast form equals the exact discrete RSD sum to rounding.
    Full,
}

#[derive(Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
murk reconstruct capture.h5 --out volume.npy --png pictures/\n  \
murk reconstruct capture.h5 --out volume.h5 --wavefactor 8 --cycles 4 --volume -1:1:73,-1:1:59,1.5:2.5:73\n  \
murk reconstruct fog.h5 --out v.npy --compensate paper --mu-t 1.0 --albedo 0.5\n  \
murk reconstruct letter_s.h5 --method cdt --out cdt.h5 --png cdt/\n  \
murk reconstruct letter_s.h5 --method pf --wavefactor 4 --cycles 8 --t-offset slab --out pf.h5\n\n\
Methods pf, pf-exact, bp and fbp reconstruct on --volume. lct, fk and cdt need a confocal capture on a regular\n\
grid and reconstruct on their own grid (the scan points × depth k·Δs′/2; cdt and its defaults: 128 depths over\n\
1 m); they ignore --volume and write their true x, y, z axes.\n\n\
Volumes: --volume x0:x1:nx,y0:y1:ny,z0:z1:nz gives nx voxel centres from x0 to x1 inclusive (metres; z is the\n\
depth in front of the wall at z = 0). Default: the wall grid's extent and spacing in x and y, depth from 0.1 m to\n\
as deep as the capture's time window reaches. Output arrays have shape [nx, ny, nz], float32 |U|²·K, C order."
)]
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
    /// Virtual wavelength as a multiple of the wall spacing Δc. Default: 4 (the paper's λ = 4Δc); for
    /// confocal captures 8, i.e. λ = 4Δc of depth (one-way distance), because their round-trip kernel
    /// e^{2ikr} halves the lateral wavelength (4Δc of path sits at the Nyquist limit and speckles).
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
    /// Lateral frequencies the fast PF form keeps.
    #[arg(long, value_enum, default_value = "propagating")]
    pub lateral: LateralArg,
    /// Subtract this much optical path (m) from every time stamp before reconstructing (shifts the
    /// capture's time start), or `slab`: the delay of the slab's round trip (--slab-* flags) so that
    /// depth is measured from the back of the slab: for pf and pf-exact the delay of the response
    /// as their pulse sees it, for the others its peak.
    #[arg(long, allow_hyphen_values = true)]
    pub t_offset: Option<String>,
    /// The end of the time window: `auto` tapers it and clears the voxels only its last paths reach
    /// when the last 5 % of bins carry ≥ 5 % of the peak (a cut signal, which otherwise shows as a
    /// false far surface); `taper` always does; `keep` never does.
    #[arg(long, value_enum, default_value = "auto")]
    pub window_end: WindowEndArg,
    /// Fade out the paths shorter than PATH_M (m), with a smooth edge before it: a medium's
    /// backscatter near the relay is the strongest early signal and lights the nearest voxels.
    /// `auto` opens three edge widths (PF: its pulse σ) before the shortest path that reaches the
    /// volume; `off` keeps every path.
    #[arg(long, default_value = "auto", value_name = "PATH_M|auto|off")]
    pub gate: String,
    #[command(flatten)]
    pub slab: SlabArgs,
}

/// How many edge widths before the volume's shortest path `--gate auto` opens.
const GATE_MARGIN_EDGES: f64 = 3.0;

enum Gate {
    Off,
    At(f64),
    Auto,
}

fn parse_gate(text: &str) -> anyhow::Result<Gate> {
    Ok(match text {
        "off" => Gate::Off,
        "auto" => Gate::Auto,
        t => match t.parse::<f64>() {
            Ok(p) if p.is_finite() => Gate::At(p),
            _ => bail!("--gate {t}: expected a path in metres, auto or off"),
        },
    })
}

/// Ramp length (bins) at a window's end for the methods without a pulse: measured on the CDT letter S
/// cut at 1.44 m of path (docs/window-ends.md).
const BASELINE_TAPER_BINS: usize = 20;

#[derive(Clone, Copy, ValueEnum)]
pub enum WindowEndArg {
    Auto,
    Taper,
    Keep,
}

impl From<WindowEndArg> for WindowEnd {
    fn from(a: WindowEndArg) -> WindowEnd {
        match a {
            WindowEndArg::Auto => WindowEnd::Auto,
            WindowEndArg::Taper => WindowEnd::Taper,
            WindowEndArg::Keep => WindowEnd::Keep,
        }
    }
}

/// The scattering slab in front of the scene (CDT; `--t-offset slab`). Defaults: the 2.54 cm foam
/// of Lindell & Wetzstein 2020.
#[derive(Args, Clone, Copy)]
pub struct SlabArgs {
    /// Slab thickness (m).
    #[arg(long, default_value_t = 0.0254)]
    pub slab_thickness: f64,
    /// Absorption coefficient μa (1/m).
    #[arg(long, default_value_t = 0.53)]
    pub slab_mua: f64,
    /// Reduced scattering coefficient μs′ (1/m).
    #[arg(long, default_value_t = 262.0)]
    pub slab_musp: f64,
    /// Refractive index.
    #[arg(long, default_value_t = 1.12)]
    pub slab_n: f64,
    /// Wiener signal-to-noise ratio (cdt default 1e4; lct default 0.1).
    #[arg(long)]
    pub snr: Option<f64>,
    /// LCT's radiometric weighting of the measurements: diffuse scenes fall off as t⁴, retroreflective
    /// ones (road signs, retroreflective letters) as t².
    #[arg(long, value_enum, default_value = "diffuse")]
    pub weighting: WeightingArg,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum WeightingArg {
    Diffuse,
    Retroreflective,
}

impl SlabArgs {
    pub fn slab(&self) -> SlabParams {
        SlabParams {
            thickness_m: self.slab_thickness,
            mu_a: self.slab_mua,
            mu_s_prime: self.slab_musp,
            n: self.slab_n,
            ..Default::default()
        }
    }
}

impl ReconstructArgs {
    /// Phasor Fields parameters for `cap` (the default wavelength depends on whether it is confocal).
    pub fn params(&self, cap: &Capture) -> anyhow::Result<PfParams> {
        let confocal = cap.kind() == murk_core::CaptureKind::Confocal;
        let wavelength = match (self.wavelength, self.wavefactor) {
            (Some(m), _) => Wavelength::Metres(m),
            (None, Some(f)) => Wavelength::WallFactor(f),
            (None, None) => Wavelength::WallFactor(if confocal { 8.0 } else { 4.0 }),
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
            lateral: match self.lateral {
                LateralArg::Propagating => Lateral::Propagating,
                LateralArg::Full => Lateral::Full,
            },
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
    let v = Volume {
        x: Axis::new(lo.x, hi.x, count(lo.x, hi.x)),
        y: Axis::new(lo.y, hi.y, count(lo.y, hi.y)),
        z: Axis::new(z_min, z_max, nz),
    };
    v.validate()?;
    Ok(v)
}

/// Writes the intensity volume by extension.
/// Output volume formats, chosen by the file extension.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum VolumeFormat {
    Npy,
    Hdf5,
}

impl VolumeFormat {
    /// Checked before any work so a typo costs nothing.
    pub fn of(path: &Path) -> anyhow::Result<VolumeFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "npy" => Ok(VolumeFormat::Npy),
            "h5" | "hdf5" => Ok(VolumeFormat::Hdf5),
            _ => bail!(
                "{}: unknown output type '.{ext}' (use .npy or .h5)",
                path.display()
            ),
        }
    }
}

/// Writes the intensity volume in the format its extension names.
pub fn write_volume(
    path: &Path,
    vol: &Volume,
    intensity: &[f32],
    params: &[(String, String)],
) -> anyhow::Result<()> {
    match VolumeFormat::of(path)? {
        VolumeFormat::Npy => murk_io::write_npy_f32(path, &vol.shape(), intensity)?,
        VolumeFormat::Hdf5 => {
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

/// In a medium the backscatter near the relay is the strongest early signal: a peak on the volume's
/// nearest plane, with no gate, usually images it rather than the scene.
fn near_face_warning(vol: &Volume, intensity: &[f32], gated: bool) -> Option<String> {
    let (p, _) = peak(vol, intensity);
    let near = vol.z.start.min(vol.z.end);
    (!gated && vol.z.n > 2 && (p[2] - near).abs() < 1e-9).then(|| {
        format!(
            "the brightest voxel lies on the volume's nearest plane (z = {} m): if the capture is in a medium, that is its backscatter near the relay; start the volume further away or fade out the early paths with --gate PATH_M",
            murk_core::short(near)
        )
    })
}

/// The optical path `--t-offset` asks to remove (0 without it).
/// `pulse`: PF's, whose band-pass moves the slab's apparent delay (see
/// [`SlabParams::round_trip_delay_m`]); `None` for the other methods.
pub fn t_offset_m(
    spec: Option<&str>,
    slab: &SlabParams,
    pulse: Option<Pulse>,
) -> anyhow::Result<f64> {
    match spec {
        None => Ok(0.0),
        Some("slab") => Ok(slab.round_trip_delay_m(pulse)),
        Some(s) => {
            let v: f64 = s
                .parse()
                .map_err(|_| anyhow::anyhow!("--t-offset '{s}': expected metres or 'slab'"))?;
            if !v.is_finite() {
                bail!("--t-offset must be finite, got {v}");
            }
            Ok(v)
        }
    }
}

/// A reconstruction by any method, with the rows that describe how it was made.
pub struct Output {
    pub volume: Volume,
    pub intensity: Vec<f32>,
    pub method_rows: Vec<(String, String)>,
    pub warnings: Vec<String>,
}

/// Runs `method` on `cap`; `volume` is used by pf, pf-exact, bp and fbp.
pub fn reconstruct_any(
    cap: &Capture,
    method: MethodArg,
    pf: &PfParams,
    slab: &SlabArgs,
    volume: &Volume,
    bar: &Bar,
) -> anyhow::Result<Output> {
    let row = |k: &str, v: String| (k.to_string(), v);
    let baseline = |r: murk_baselines::Reconstruction, rows: Vec<(String, String)>| Output {
        volume: r.volume,
        intensity: r.data,
        method_rows: rows,
        warnings: Vec::new(),
    };
    Ok(match method {
        MethodArg::Pf | MethodArg::PfExact => {
            let m = if method == MethodArg::PfExact {
                Method::Exact
            } else {
                Method::Fast
            };
            let rec = murk_recon::reconstruct(cap, volume, pf, m, bar)?;
            let mut rows = pf_rows(&rec.info);
            if rec.info.evaluated_with == "fast" {
                rows.push(row("lateral", format!("{:?}", pf.lateral).to_lowercase()));
            }
            Output {
                volume: rec.volume,
                intensity: rec.intensity,
                method_rows: rows,
                warnings: rec.info.warnings,
            }
        }
        MethodArg::Bp => baseline(
            murk_baselines::backproject(cap, volume, Default::default())?,
            vec![row(
                "method",
                "backprojection (linear reads at bin centres)".into(),
            )],
        ),
        MethodArg::Fbp => baseline(
            murk_baselines::fbp(cap, volume, FbpOptions::default())?,
            vec![row(
                "method",
                "filtered backprojection (−∇²G, 5³ voxels, σ = 1 voxel)".into(),
            )],
        ),
        MethodArg::Lct => {
            let p = LctParams {
                snr: slab.snr.unwrap_or(LctParams::default().snr),
                reflectance: match slab.weighting {
                    WeightingArg::Diffuse => Reflectance::Diffuse,
                    WeightingArg::Retroreflective => Reflectance::Retroreflective,
                },
                ..Default::default()
            };
            baseline(
                murk_baselines::lct(cap, p)?,
                vec![
                    row("method", "light-cone transform (Wiener)".into()),
                    row("snr", format!("{}", p.snr)),
                    row("reflectance", format!("{:?}", p.reflectance)),
                ],
            )
        }
        MethodArg::Fk => baseline(
            murk_baselines::fk(cap, FkParams::default())?,
            vec![row("method", "f-k migration".into())],
        ),
        MethodArg::Cdt => {
            let p = CdtParams {
                slab: slab.slab(),
                snr: slab.snr.unwrap_or(CdtParams::default().snr),
                ..Default::default()
            };
            let s = p.slab;
            baseline(
                murk_baselines::cdt(cap, p)?,
                vec![
                    row(
                        "method",
                        "confocal diffuse tomography (slab Wiener + f-k)".into(),
                    ),
                    row(
                        "slab",
                        format!(
                            "{} m, μa {} /m, μs′ {} /m, n {}, ze {} m",
                            s.thickness_m, s.mu_a, s.mu_s_prime, s.n, s.ze_m
                        ),
                    ),
                    row("snr", format!("{}", p.snr)),
                    row("time grid", format!("{:?}", p.grid)),
                ],
            )
        }
    })
}

pub fn run(a: ReconstructArgs, quiet: bool) -> anyhow::Result<()> {
    VolumeFormat::of(&a.out)?;
    murk_io::refuse_overwrite(&a.out, &[&a.file])?;
    if let Some(png) = &a.png {
        murk_io::refuse_overwrite(png, &[&a.file])?;
    }
    let mut cap = murk_io::read_capture(&a.file)?;
    let params = a.params(&cap)?;
    let pulse = if a.method.is_pf() {
        let wavelength_m = params.wavelength_m(&cap)?;
        Some(Pulse {
            wavelength_m,
            sigma_m: params.sigma_m(wavelength_m),
        })
    } else {
        None
    };
    let offset = t_offset_m(a.t_offset.as_deref(), &a.slab.slab(), pulse)?;
    cap.time.start_m -= offset;
    // The ramp at either end of the window: PF's pulse σ, or a fixed number of bins.
    let edge_m = if a.method.is_pf() {
        params.sigma_m(params.wavelength_m(&cap)?)
    } else {
        BASELINE_TAPER_BINS as f64 * cap.time.bin_width_m
    };
    let volume = match &a.volume {
        Some(_) if a.method.own_grid() => {
            if !quiet {
                eprintln!("murk: warning: --volume is ignored by {:?}: it reconstructs on the capture's scan grid", a.method);
            }
            None
        }
        Some(spec) => Some(Volume::parse(spec)?),
        None if a.method.own_grid() => None,
        None => Some(default_volume(&cap).with_context(|| a.file.display().to_string())?),
    };
    let open_m = match (parse_gate(&a.gate)?, &volume) {
        (Gate::Auto, Some(v)) => Some(shortest_path_m(&cap, v) - GATE_MARGIN_EDGES * edge_m),
        // Own-grid methods have no volume to derive it from.
        (Gate::Auto, None) | (Gate::Off, _) => None,
        (Gate::At(p), _) => Some(p),
    };
    let gated = apply_gate(&mut cap, open_m, edge_m);
    let mut end = handle_end(&mut cap, a.window_end.into(), edge_m);
    let bar = Bar::new("reconstruct", quiet);
    let t0 = std::time::Instant::now();
    // Own-grid methods never read the volume; an empty one stands in.
    let empty = Volume {
        x: Axis::new(0.0, 0.0, 1),
        y: Axis::new(0.0, 0.0, 1),
        z: Axis::new(0.0, 0.0, 1),
    };
    let out = reconstruct_any(
        &cap,
        a.method,
        &params,
        &a.slab,
        volume.as_ref().unwrap_or(&empty),
        &bar,
    )
    .with_context(|| a.file.display().to_string())?;
    bar.finish();
    let mut out = out;
    end.trim(&cap, &out.volume, &mut out.intensity);
    let secs = t0.elapsed().as_secs_f64();
    let near_face = near_face_warning(&out.volume, &out.intensity, gated.open_m.is_some());
    for w in out
        .warnings
        .iter()
        .chain(&end.warning())
        .chain(&near_face)
        .filter(|_| !quiet)
    {
        eprintln!("murk: warning: {w}");
    }
    let mut rows = out.method_rows.clone();
    rows.push(("t_offset_m".into(), format!("{offset:.6}")));
    rows.push(("gate".into(), gated.describe()));
    rows.push(("window_end".into(), end.describe()));
    let table = table(&a.file, &cap, rows, &out.volume, &out.intensity, secs);
    let v = &out.volume;
    write_volume(&a.out, v, &out.intensity, &table)?;
    say(
        quiet,
        format!(
            "wrote {} ({}×{}×{} voxels)",
            a.out.display(),
            v.x.n,
            v.y.n,
            v.z.n
        ),
    );
    if let Some(dir) = &a.png {
        let pics = pictures::write_views(dir, v, &out.intensity)?;
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

fn pf_rows(i: &murk_recon::ReconInfo) -> Vec<(String, String)> {
    vec![
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
            if i.slabs.len() > 1 {
                format!(
                    "{:.1} per plane over {} depth slabs with their own time windows (the whole volume's window: {} of a {}-point DFT)",
                    i.frequencies_per_plane(),
                    i.slabs.len(),
                    i.frequencies,
                    i.dft_len
                )
            } else {
                format!("{} of a {}-point DFT", i.frequencies, i.dft_len)
            },
        ),
    ]
}

/// The parameters and results of a Phasor Fields reconstruction worth recording next to a volume.
pub fn summary(
    file: &Path,
    cap: &Capture,
    rec: &murk_recon::Reconstruction,
    secs: f64,
) -> Vec<(String, String)> {
    table(
        file,
        cap,
        pf_rows(&rec.info),
        &rec.volume,
        &rec.intensity,
        secs,
    )
}

/// Capture, method rows, volume, peak and time as a key/value table.
pub fn table(
    file: &Path,
    cap: &Capture,
    method_rows: Vec<(String, String)>,
    v: &Volume,
    intensity: &[f32],
    secs: f64,
) -> Vec<(String, String)> {
    let (p, val) = peak(v, intensity);
    let mut t = vec![
        ("capture".into(), file.display().to_string()),
        ("capture kind".into(), cap.kind().to_string()),
    ];
    t.extend(method_rows);
    t.extend([
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
    ]);
    t
}
