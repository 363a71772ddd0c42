//! `murk medium`: the medium's μt, albedo and g estimated from a capture's medium-only bins.

use crate::cmd::progress::{say, Bar};
use anyhow::Context;
use clap::Args;
use murk_medium::{EstimateOptions, FitParams, Fixed, Outcome};
use murk_recon::Progress;
use std::path::PathBuf;

#[derive(Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
murk medium fog.h5\n  \
murk medium fog.h5 --json                       # one JSON object: mu_t_per_m, albedo, g, their uncertainties, …\n  \
murk medium fog.h5 --fit mu_t,albedo --g 0.7    # g known: fit the other two\n  \
murk medium fog.h5 --until 3.5                  # the medium-only bins end at 3.5 m of path\n  \
murk medium fog.h5 --table-cache tables         # renders the table once; later captures of this geometry reuse it\n  \
murk medium --slab-transmission ../shared/data/real/cdt_lindell2020/calibration   # a foam slab's μa, μs′\n\n\
The forward model is murk's renderer: the capture's own scene (its scene_info, as murk render writes it)\n\
without objects (a box around the whole medium, its room, stays), rendered on a grid of μt × g nodes,\n\
each an albedo sweep, and interpolated. The fit\n\
compares ring means (rings of equal laser–sensor separation) over 5 cm bins, from the window's start\n\
to where the scene's own signal begins (the medium-aware depth search of `murk reconstruct`), in\n\
ln(intensity). Uncertainties: the posterior's spread over the searched grid (flat priors, the noise\n\
taken from the residual). A capture without a medium answers 'no medium\n\
detected'. docs/medium.md has the accuracy over the paper's sweep.\n\n\
--slab-transmission DIR fits a slab's absorption μa and reduced scattering μs′ instead, from\n\
time-resolved transmission captures through slabs of several thicknesses (the CDT calibration\n\
folder: capture_direct.mat, the laser without the slab, and capture_<a>_<b>_inch.mat, each with\n\
the histogram `out` in 8 ps bins): the diffusion model of the slab's transmittance, convolved with\n\
the direct capture, fitted to every capture at once (one amplitude each, time zero from the direct\n\
capture, n given by --slab-n). See docs/medium.md, 'Foam slab'."
)]
pub struct MediumArgs {
    /// A y-tal HDF5 capture rendered by murk.
    #[arg(required_unless_present = "slab_transmission")]
    pub file: Option<PathBuf>,
    /// Fit a slab's μa and μs′ to the transmission captures in this folder (CDT calibration layout).
    #[arg(long, value_name = "DIR", conflicts_with = "file")]
    pub slab_transmission: Option<PathBuf>,
    /// The slab's refractive index, with --slab-transmission.
    #[arg(long, default_value_t = 1.12, requires = "slab_transmission")]
    pub slab_n: f64,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// The parameters to fit (comma-separated of mu_t, albedo, g); the others take --mu-t, --albedo, --g.
    #[arg(long, default_value = "mu_t,albedo,g")]
    pub fit: String,
    /// μt (1/m) when it is not fitted.
    #[arg(long = "mu-t", default_value_t = 1.0)]
    pub mu_t_per_m: f64,
    /// Albedo when it is not fitted.
    #[arg(long, default_value_t = 0.5)]
    pub albedo: f64,
    /// HG g when it is not fitted.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub g: f64,
    /// The last path (m) of the medium-only bins (default: where the scene's signal begins).
    #[arg(long, value_name = "PATH_M")]
    pub until: Option<f64>,
    /// A folder for the forward model's table of renders: built there once per geometry (the
    /// capture's scene without objects, its points and time axis, the fitted parameters), then read
    /// back by every later estimate of such a capture instead of rendered again.
    #[arg(long, value_name = "DIR")]
    pub table_cache: Option<PathBuf>,
}

pub fn run(a: MediumArgs, quiet: bool) -> anyhow::Result<()> {
    if let Some(dir) = &a.slab_transmission {
        return slab(dir, &a, quiet);
    }
    let file = a
        .file
        .clone()
        .context("give a capture, or --slab-transmission DIR")?;
    let cap = murk_io::read_capture(&file)?;
    let opt = EstimateOptions {
        fit: FitParams::parse(&a.fit).context("--fit")?,
        fixed: Fixed {
            mu_t_per_m: a.mu_t_per_m,
            albedo: a.albedo,
            g: a.g,
        },
        until_m: a.until,
        table_cache: a.table_cache.clone(),
        ..EstimateOptions::default()
    };
    let bar = Bar::new("medium", quiet || a.json);
    let t0 = std::time::Instant::now();
    let outcome = murk_medium::estimate(&cap, &opt, &|done, total| {
        if done == 0 {
            bar.start(total as u64);
        } else {
            bar.advance(1);
        }
    })
    .with_context(|| file.display().to_string())?;
    bar.finish();
    let secs = t0.elapsed().as_secs_f64();
    let assumed = murk_medium::scene::homogeneous_assumed(&cap, "the estimate");
    if let (Some(w), Outcome::Fitted(_), false) = (assumed, &outcome, quiet) {
        eprintln!("murk: warning: {w}");
    }
    match outcome {
        outcome if a.json => println!("{}", outcome.to_json()),
        Outcome::NoMedium(s) => say(quiet, format!("no medium detected: {}", s.describe())),
        Outcome::Fitted(e) => {
            say(quiet, format!("  capture: {}", file.display()));
            for (k, v) in e.rows() {
                say(quiet, format!("  {k}: {v}"));
            }
            say(quiet, format!("  seconds: {secs:.1}"));
        }
    }
    Ok(())
}

/// `--slab-transmission DIR`: the slab's μa and μs′ from its calibration captures.
fn slab(dir: &std::path::Path, a: &MediumArgs, quiet: bool) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let cal = murk_medium::slab::read_calibration(dir)?;
    let opt = murk_medium::slab::SlabOptions {
        n: a.slab_n,
        ..Default::default()
    };
    let bar = Bar::new("slab", quiet || a.json);
    let e =
        murk_medium::slab::fit_slab(&cal, &opt, &bar).with_context(|| dir.display().to_string())?;
    bar.finish();
    if a.json {
        println!("{}", e.to_json());
        return Ok(());
    }
    say(quiet, format!("  calibration: {}", dir.display()));
    for (k, v) in e.rows() {
        say(quiet, format!("  {k}: {v}"));
    }
    say(
        quiet,
        format!("  seconds: {:.1}", t0.elapsed().as_secs_f64()),
    );
    Ok(())
}
