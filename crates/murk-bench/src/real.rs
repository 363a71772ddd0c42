//! `murk bench --real DIR`: every reconstruction method on each of the real 32 × 32 × 512 confocal
//! captures (Lindell & Wetzstein 2020), as `murk reconstruct` runs them: plan and run together, the
//! default volume for the voxel methods, the median of several runs per scene. A folder of the
//! boundary migration model's 64 × 64 × 256 foam captures times `bmm` on each instead.

use crate::say;
use anyhow::Context;
use murk_baselines::{CdtParams, FbpOptions, FkParams, LctParams};
use murk_core::{Axis, Capture, Volume};
use murk_io::import::{import, ImportOptions, Preset, BMM_SCENES, CDT_SCENES};
use murk_methods::default_volume;
use murk_recon::{NoProgress, PfForm, PfParams, Wavelength};
use std::path::Path;
use std::time::Instant;

/// Median seconds of `runs` calls of `f`.
fn median_secs(runs: usize, mut f: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    let mut secs = Vec::with_capacity(runs);
    for _ in 0..runs {
        let t0 = Instant::now();
        f()?;
        secs.push(t0.elapsed().as_secs_f64());
    }
    Ok(crate::median(&secs))
}

pub fn run(dir: &Path, runs: usize, quiet: bool) -> anyhow::Result<()> {
    let foam: Vec<_> = BMM_SCENES
        .iter()
        .map(|s| dir.join(format!("{}.mat", s.0)))
        .filter(|p| p.exists())
        .collect();
    if !foam.is_empty() {
        return run_bmm(&foam, runs, quiet);
    }
    // The paper's confocal Phasor Fields: λ = 4Δc of depth (8Δc of path), 8 cycles.
    let pf = PfParams {
        wavelength: Wavelength::WallFactor(8.0),
        cycles: 8.0,
        ..PfParams::default()
    };
    let cdt = CdtParams::default();
    let delay = cdt.slab.round_trip_delay_m(None)?;
    let mut table: Vec<(&str, Vec<f64>)> = Vec::new();
    let mut record = |name: &'static str, s: f64| match table.iter_mut().find(|r| r.0 == name) {
        Some(r) => r.1.push(s),
        None => table.push((name, vec![s])),
    };
    for (scene, _, _) in CDT_SCENES {
        let path = dir.join(format!("{scene}.mat"));
        let cap: Capture = import(&path, &ImportOptions::preset(Preset::Cdt))?;
        let ctx = || path.display().to_string();
        let vol = default_volume(&cap)?;
        let mut shifted = cap.clone();
        shifted.time.start_m -= delay;
        // CDT's own voxels (minus its z = 0 plane), as `murk figure real` compares them.
        let cdt_grid = murk_baselines::cdt(&cap, cdt).with_context(ctx)?.volume;
        let pf_grid = Volume {
            z: Axis::new(cdt_grid.z.at(1), cdt_grid.z.end, cdt_grid.z.n - 1),
            ..cdt_grid
        };
        let mut line = format!("{scene}:");
        let mut time = |name: &'static str, f: &mut dyn FnMut() -> anyhow::Result<()>| {
            let s = median_secs(runs, f).with_context(ctx)?;
            line += &format!(" {name} {:.1} ms,", s * 1e3);
            record(name, s);
            anyhow::Ok(())
        };
        let pf_on = |v: &Volume| {
            murk_recon::reconstruct(&shifted, v, &pf, PfForm::Fast, &NoProgress)?;
            anyhow::Ok(())
        };
        time("bp", &mut || {
            murk_baselines::backproject(&cap, &vol, Default::default())?;
            Ok(())
        })?;
        time("fbp", &mut || {
            murk_baselines::fbp(&cap, &vol, FbpOptions::default())?;
            Ok(())
        })?;
        time("lct", &mut || {
            murk_baselines::lct(&cap, LctParams::default())?;
            Ok(())
        })?;
        time("fk", &mut || {
            murk_baselines::fk(&cap, FkParams::default())?;
            Ok(())
        })?;
        time("cdt", &mut || {
            murk_baselines::cdt(&cap, cdt)?;
            Ok(())
        })?;
        time("pf", &mut || pf_on(&vol))?;
        time("pf-cdt-voxels", &mut || pf_on(&pf_grid))?;
        say(quiet, line.trim_end_matches(','));
        if scene == CDT_SCENES[0].0 {
            say(
                quiet,
                format!(
                    "  (voxels: bp, fbp, pf {}×{}×{}; pf-cdt-voxels {}×{}×{})",
                    vol.x.n, vol.y.n, vol.z.n, pf_grid.x.n, pf_grid.y.n, pf_grid.z.n
                ),
            );
        }
    }
    for (name, secs) in table {
        say(quiet, over_captures(name, &secs));
    }
    Ok(())
}

/// The line summing up one method's medians over the captures.
fn over_captures(name: &str, secs: &[f64]) -> String {
    format!(
        "{name:>14}: median over captures {:.1} ms (worst {:.1} ms)",
        crate::median(secs) * 1e3,
        secs.iter().copied().fold(0.0, f64::max) * 1e3
    )
}

/// `bmm` on each boundary-migration capture, median of `runs`.
fn run_bmm(files: &[std::path::PathBuf], runs: usize, quiet: bool) -> anyhow::Result<()> {
    let mut secs = Vec::new();
    for path in files {
        let cap: Capture = import(path, &ImportOptions::preset(Preset::Bmm))?;
        let s = median_secs(runs, || {
            murk_baselines::bmm(&cap, Default::default())?;
            Ok(())
        })
        .with_context(|| path.display().to_string())?;
        say(
            quiet,
            format!(
                "{}: bmm {:.1} ms ({} scan points × {} bins)",
                path.display(),
                s * 1e3,
                cap.illum.points.len(),
                cap.time.bins
            ),
        );
        secs.push(s);
    }
    say(quiet, over_captures("bmm", &secs));
    Ok(())
}
