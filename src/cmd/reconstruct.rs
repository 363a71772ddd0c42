//! `murk reconstruct`: a capture file in, a volume (.npy / .h5) and pictures out.

use crate::cmd::progress::{say, Bar};
use anyhow::Context;
use clap::{Args, ValueEnum};
use murk_baselines::{BmmParams, SlabParams};
use murk_methods::{Gate, Request, RequestArgs, METHODS};
use murk_render::Spelling;
use murk_view::pictures;
use std::path::PathBuf;

/// `--method`'s values, with their help, from the library's list.
fn method_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        METHODS
            .iter()
            .map(|m| clap::builder::PossibleValue::new(m.name).help(m.help)),
    )
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
    /// Only the wall-plane frequencies whose waves reach each depth plane, and on finely sampled depths
    /// only every other plane, the others interpolated (faster; differs from `full` by the kernel's and
    /// the data's leakage beyond them: intensity relL2 1.8e-4 on a synthetic Z, 3e-4–6e-4 on real
    /// captures).
    Propagating,
    /// Every frequency and every depth plane: the fast form equals the exact discrete RSD sum to
    /// rounding.
    Full,
}

#[derive(Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
murk reconstruct capture.h5 --out volume.npy --png pictures/\n  \
murk reconstruct capture.h5 --out volume.h5 --wavefactor 8 --cycles 4 --volume -1:1:73,-1:1:59,1.5:2.5:73\n  \
murk reconstruct fog.h5 --out v.npy --compensate paper --mu-t 1.0 --albedo 0.5\n  \
murk reconstruct fog.h5 --out v.npy --medium-removal off --depth-search off   # as before the medium-aware path\n  \
murk reconstruct letter_s.h5 --method cdt --out cdt.h5 --png cdt/\n  \
murk reconstruct letter_s.h5 --method pf --wavefactor 8 --cycles 8 --t-offset slab --out pf.h5\n\n\
Methods reconstruct on --volume, except those whose help above says \"own volume\": they need a confocal capture\n\
on a regular grid and reconstruct on their own grid (the scan points × depth k·Δs′/2; cdt and its defaults: 128\n\
depths over 1 m); they ignore --volume and write their true x, y, z axes.\n\n\
Volumes: --volume x0:x1:nx,y0:y1:ny,z0:z1:nz gives nx voxel centres from x0 to x1 inclusive (metres; z is the\n\
depth in front of the wall at z = 0). Default: the wall grid's extent and spacing in x and y, depth from 0.1 m to\n\
as deep as the capture's time window reaches. Output arrays have shape [nx, ny, nz], float32 |U|²·K, C order."
)]
pub struct ReconstructArgs {
    /// A y-tal HDF5 capture.
    pub file: PathBuf,
    /// Output volume: .npy (float32 [nx, ny, nz]) or .h5/.hdf5 (intensity + x, y, z + parameters).
    /// Methods that give surface normals (dlct) also write them, float32 [nx, ny, nz, 3]: the
    /// dataset `normals` of the .h5, or NAME-normals.npy beside NAME.npy; --png adds normals.png.
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value = "pf", value_parser = method_names())]
    pub method: String,
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
    /// Medium compensation of the intensity, with --mu-t (paper also --albedo); without --mu-t the
    /// medium is estimated from the capture as `murk medium` does (the summary's `compensated with`
    /// row says the values used).
    #[arg(long, value_enum)]
    pub compensate: Option<CompensateArg>,
    /// Extinction coefficient μt of the medium (1/m), for --compensate and --medium-removal model.
    #[arg(long = "mu-t", value_name = "PER_M")]
    pub mu_t_per_m: Option<f64>,
    /// Single-scattering albedo α of the medium, for --compensate paper (default 0) and
    /// --medium-removal model.
    #[arg(long)]
    pub albedo: Option<f64>,
    /// The density grid (.npy, the scene's `density`) of a capture's heterogeneous medium, for
    /// --compensate: the attenuation is integrated along each leg through σt = density × --mu-t over
    /// the medium's box of the scene the capture stores, instead of μt times the leg's length.
    #[arg(long, value_name = "FILE.npy", conflicts_with = "height_scale")]
    pub medium_density: Option<PathBuf>,
    /// An exponential height fog's scale (m, the scene's `height_scale`), for --compensate: σt =
    /// --mu-t × exp(−(y − floor)/M) integrated along each leg, over the medium's box of the scene the
    /// capture stores (floor: its min y). Without it or --medium-density, a capture rendered from a
    /// height fog is compensated along its own fog when --mu-t is given.
    #[arg(long, value_name = "M")]
    pub height_scale: Option<f64>,
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
    /// The medium's response: `auto` detects a medium in the early bins (signal right after every
    /// histogram's earliest path, decaying) and, for pf, pf-exact, bp and fbp, subtracts its response
    /// fitted from the capture (rings of equal laser–sensor separation, smoothed over 25 % of the
    /// path); `model` subtracts the response murk's renderer predicts for the medium (--mu-t and
    /// --albedo, else estimated as `murk medium` does; needs a capture that murk rendered); `fit`
    /// always subtracts the fitted one, for any method; `off` never. The summary's `medium` row says
    /// what was found and the share of signal removed.
    #[arg(long, value_enum, default_value = "auto")]
    pub medium_removal: MediumRemovalArg,
    /// With the default volume and a detected medium, `auto` first reconstructs the whole reach and
    /// keeps the depths within 0.5 m of the plane where the signal focuses best (the summary's `depth
    /// search` row); `off` keeps the default volume.
    #[arg(long, value_enum, default_value = "auto")]
    pub depth_search: DepthSearchArg,
    /// Where the medium's estimate (for --compensate without --mu-t, --medium-removal model without
    /// --mu-t and --albedo) keeps its table of renders: built once per geometry, then read back
    /// (as `murk medium --table-cache`).
    #[arg(long, value_name = "DIR")]
    pub table_cache: Option<PathBuf>,
    #[command(flatten)]
    pub slab: SlabArgs,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum MediumRemovalArg {
    Auto,
    Model,
    Fit,
    Off,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum DepthSearchArg {
    Auto,
    Off,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum WindowEndArg {
    Auto,
    Taper,
    Keep,
}

/// The library's name of a choice the parser accepted: the flags' value names are the library's own
/// (`value_names_are_the_librarys` checks), so the CLI keeps only their help texts.
fn name(choice: impl ValueEnum) -> anyhow::Result<String> {
    let value = choice
        .to_possible_value()
        .context("a choice without a name")?;
    Ok(value.get_name().to_string())
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
    /// Wiener signal-to-noise ratio of the methods that read it (default: the method's own, e.g. cdt 1e4,
    /// lct 0.1).
    #[arg(long)]
    pub snr: Option<f64>,
    /// LCT's radiometric weighting of the measurements: diffuse scenes fall off as t⁴, retroreflective
    /// ones (road signs, retroreflective letters) as t².
    #[arg(long, value_enum, default_value = "diffuse")]
    pub weighting: WeightingArg,
    /// bmm: the medium's refractive index (default: the capture's `medium_n`, else 1.23).
    #[arg(long)]
    pub medium_n: Option<f64>,
    /// bmm: the medium's reduced scattering coefficient μs′ (1/m; default: the capture's, else 313).
    #[arg(long)]
    pub medium_musp: Option<f64>,
    /// bmm: the medium's absorption coefficient μa (1/m; default: the capture's, else 0).
    #[arg(long)]
    pub medium_mua: Option<f64>,
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
            mu_a_per_m: self.slab_mua,
            mu_s_prime_per_m: self.slab_musp,
            n: self.slab_n,
            ..Default::default()
        }
    }
}

impl ReconstructArgs {
    /// The library request these arguments make.
    pub fn request(&self) -> anyhow::Result<Request> {
        Ok(self.request_args()?.request()?)
    }

    /// The arguments as the library takes them from the CLI and Python alike.
    fn request_args(&self) -> anyhow::Result<RequestArgs> {
        Ok(RequestArgs {
            method: self.method.clone(),
            volume: self.volume.clone(),
            wavelength_m: self.wavelength,
            wavefactor: self.wavefactor,
            cycles: self.cycles,
            compensate: self.compensate.map(name).transpose()?,
            mu_t_per_m: self.mu_t_per_m,
            albedo: self.albedo,
            falloff: name(self.falloff)?,
            lateral: name(self.lateral)?,
            snr: self.slab.snr,
            weighting: name(self.slab.weighting)?,
            slab: self.slab.slab(),
            medium: BmmParams {
                n: self.slab.medium_n,
                mu_s_prime_per_m: self.slab.medium_musp,
                mu_a_per_m: self.slab.medium_mua,
            },
            t_offset: self.t_offset.clone(),
            gate: self.gate.parse::<Gate>().context("--gate")?,
            window_end: name(self.window_end)?,
            medium_removal: name(self.medium_removal)?,
            depth_search: name(self.depth_search)?,
        })
    }
}

pub fn run(mut a: ReconstructArgs, quiet: bool) -> anyhow::Result<()> {
    murk_io::check_output(&a.out, &[&a.file])?;
    murk_io::check_volume_path(&a.out)?;
    if let Some(normals) = murk_io::normals_path(&a.out) {
        // Written only by the methods that give normals, but refused before any work all the same.
        murk_io::check_output(&normals, &[&a.file])?;
    }
    if let Some(png) = &a.png {
        // Before the reconstruction, so that a bad --png leaves no volume behind either.
        pictures::check_pictures_dir(png, &[&a.file], &a.out)?;
    }
    let model = matches!(a.medium_removal, MediumRemovalArg::Model);
    if a.compensate.is_none() && !model {
        for (given, flag) in [
            (a.mu_t_per_m.is_some(), "--mu-t"),
            (a.albedo.is_some(), "--albedo"),
        ] {
            anyhow::ensure!(
                !given,
                "{flag} sets the medium for --compensate or --medium-removal model; give one of them"
            );
        }
    }
    let given = murk_medium::density::DensityGiven {
        file: a.medium_density.clone(),
        height_scale_m: a.height_scale,
    };
    let cap = murk_io::read_capture(&a.file)?;
    let kind = cap.kind();
    let mut along = given
        .along(
            &cap,
            a.compensate.is_some(),
            a.mu_t_per_m.is_some(),
            Spelling::Cli,
        )
        .with_context(|| a.file.display().to_string())?;
    let needs_estimate = (a.compensate.is_some() && a.mu_t_per_m.is_none())
        || (model && (a.mu_t_per_m.is_none() || a.albedo.is_none()));
    let estimate = match needs_estimate {
        true => Some(estimate_medium(&a, &cap, quiet)?),
        false => None,
    };
    let compensated_with = match (&estimate, a.compensate, a.mu_t_per_m) {
        (Some(e), Some(_), None) => Some(fill_compensation(&mut a, e)),
        _ => None,
    };
    let predicted = match model {
        true => Some(
            murk_medium::model::for_removal(&cap, a.mu_t_per_m, a.albedo, estimate.as_deref())
                .with_context(|| format!("{}: --medium-removal model", a.file.display()))?,
        ),
        false => None,
    };
    let req = a.request()?;
    let assumed = model
        .then(|| murk_medium::scene::homogeneous_assumed(&cap, "--medium-removal model"))
        .flatten();
    let bar = Bar::new("reconstruct", quiet);
    let t0 = std::time::Instant::now();
    let given = murk_methods::MediumGiven {
        predicted,
        density: along.density.take(),
        searched: estimate.and_then(|e| e.searched),
    };
    let mut out = murk_methods::run_given(cap, &req, &given, &bar)
        .with_context(|| a.file.display().to_string())?;
    out.rows
        .extend(compensated_with.map(|line| ("compensated with".to_string(), line)));
    along.note(&mut out);
    out.warnings.extend(assumed);
    bar.finish();
    let secs = t0.elapsed().as_secs_f64();
    for w in out.warnings.iter().filter(|_| !quiet) {
        eprintln!("murk: warning: {w}");
    }
    let table = out.summary(&a.file.display().to_string(), kind, secs);
    let v = &out.volume;
    let normals = out.normals.as_deref();
    murk_io::write_volume(&a.out, v, &out.intensity, normals, &table)?;
    let beside = match (normals, murk_io::normals_path(&a.out)) {
        (Some(_), Some(p)) => format!(", normals in {}", p.display()),
        (Some(_), None) => ", normals beside the intensity".to_string(),
        (None, _) => String::new(),
    };
    say(
        quiet,
        format!(
            "wrote {} ({}×{}×{} voxels{beside})",
            a.out.display(),
            v.x.n,
            v.y.n,
            v.z.n
        ),
    );
    if let Some(dir) = &a.png {
        let pics = pictures::write_views(dir, v, &out.intensity, normals)?;
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

/// The medium estimated from `cap` (`murk medium`, every parameter free), for --compensate or
/// --medium-removal model without the flags that give it.
fn estimate_medium(
    a: &ReconstructArgs,
    cap: &murk_core::Capture,
    quiet: bool,
) -> anyhow::Result<Box<murk_medium::Estimate>> {
    let (why, give) = match a.compensate {
        Some(_) => ("--compensate without --mu-t", "--mu-t"),
        None => ("--medium-removal model", "--mu-t and --albedo"),
    };
    let bar = Bar::new("medium", quiet);
    let opt = murk_medium::EstimateOptions {
        table_cache: a.table_cache.clone(),
        ..murk_medium::EstimateOptions::default()
    };
    let outcome = murk_medium::estimate(cap, &opt, &|d, n| {
        if d == 0 {
            murk_recon::Progress::start(&bar, n as u64);
        } else {
            murk_recon::Progress::advance(&bar, 1);
        }
    })
    .with_context(|| format!("{}: {why}", a.file.display()))?;
    bar.finish();
    match outcome {
        murk_medium::Outcome::Fitted(e) => Ok(e),
        murk_medium::Outcome::NoMedium(s) => anyhow::bail!(
            "{}: {why}: no medium detected to estimate it from ({}); give {give}",
            a.file.display(),
            s.describe()
        ),
    }
}

/// Fills `a`'s --mu-t (and, for --compensate paper, an --albedo not given) with the estimate `e`;
/// returns the summary line saying so.
fn fill_compensation(a: &mut ReconstructArgs, e: &murk_medium::Estimate) -> String {
    a.mu_t_per_m = Some(e.mu_t_per_m.value);
    let paper = matches!(a.compensate, Some(CompensateArg::Paper));
    if paper && a.albedo.is_none() {
        a.albedo = Some(e.albedo.value);
    }
    let short = murk_core::short;
    format!(
        "μt {} ± {} /m{} estimated from the capture (murk medium; --mu-t and --albedo set them)",
        short(e.mu_t_per_m.value),
        short(e.mu_t_per_m.uncertainty),
        if paper {
            format!(", albedo {}", short(a.albedo.unwrap_or_default()))
        } else {
            String::new()
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_baselines::Reflectance;
    use murk_core::window::WindowEnd;
    use murk_core::Named;
    use murk_recon::medium::{DepthSearch, MediumRemoval};
    use murk_recon::Compensation;
    use murk_recon::{Falloff, Lateral};

    fn names<T: ValueEnum>() -> Vec<String> {
        T::value_variants()
            .iter()
            .map(|v| v.to_possible_value().unwrap().get_name().to_string())
            .collect()
    }

    fn library_names<T: Named>() -> Vec<String> {
        T::CHOICES.iter().map(|(n, _)| n.to_string()).collect()
    }

    /// Each flag offers exactly the library's names, so `library` never meets an unknown one.
    #[test]
    fn value_names_are_the_librarys() {
        assert_eq!(names::<FalloffArg>(), library_names::<Falloff>());
        assert_eq!(names::<LateralArg>(), library_names::<Lateral>());
        assert_eq!(names::<WeightingArg>(), library_names::<Reflectance>());
        assert_eq!(names::<WindowEndArg>(), library_names::<WindowEnd>());
        assert_eq!(
            names::<MediumRemovalArg>(),
            library_names::<MediumRemoval>()
        );
        assert_eq!(names::<DepthSearchArg>(), library_names::<DepthSearch>());
        let mut with_none = vec!["none".to_string()];
        with_none.extend(names::<CompensateArg>());
        assert_eq!(with_none, Compensation::NAMES);
    }
}
