//! The paper's real-data comparison (its Fig. 6; `murk figure real`): the five CDT captures of
//! Lindell & Wetzstein 2020 reconstructed with CDT and with confocal Phasor Fields (λ = 4Δc,
//! 8 cycles, with λ read on the depth axis and, for comparison, on the path axis), as a PNG grid
//! (rows CDT, PF, PF; a column per scene) and an index.html with parameters, depths and timings.

use crate::figures::{check_out, depths, grid_plane};
use murk_baselines::{CdtParams, CdtPlan, Pulse};
use murk_core::{Capture, Reconstruction, Result, Volume};
use murk_io::import::{import, ImportOptions, Preset, CDT_SCENES};
use murk_recon::{Falloff, NoProgress, PfForm, PfParams, Wavelength};
use murk_view::pictures;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Median seconds of `runs` calls, and the last result.
fn timed<T>(runs: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut secs = Vec::new();
    let mut last = None;
    for _ in 0..runs.max(1) {
        let t0 = Instant::now();
        last = Some(f()?);
        secs.push(t0.elapsed().as_secs_f64());
    }
    Ok((murk_core::median(&secs), last.expect("at least one run")))
}

struct Cell {
    rec: Reconstruction,
    secs: f64,
}

fn scene(path: &Path, snr: f64, runs: usize, pfs: &[PfParams]) -> Result<Vec<Cell>> {
    let cap: Capture = import(path, &ImportOptions::preset(Preset::Cdt))?;
    let params = CdtParams {
        snr,
        ..Default::default()
    };
    let (secs, r) = timed(runs, || {
        CdtPlan::new(&cap, params, &murk_core::NoProgress)?.run(&cap, &murk_core::NoProgress)
    })?;
    let cdt = Cell { rec: r, secs };
    // PF on CDT's voxels (the scan grid laterally, the same depths) but the first: PF needs z > 0.
    let z = cdt.rec.volume.z;
    let vol = Volume {
        z: murk_core::Axis::new(z.at(1), z.end, z.n - 1),
        ..cdt.rec.volume
    };
    let mut cells = vec![cdt];
    for pf in pfs {
        // PF depth from the back of the slab: remove the slab's round-trip delay as PF's pulse sees it.
        let wavelength_m = pf.wavelength_m(&cap)?;
        let mut shifted = cap.clone();
        shifted.time.start_m -= params.slab.round_trip_delay_m(Some(Pulse {
            wavelength_m,
            sigma_m: pf.sigma_m(wavelength_m),
        }))?;
        let (secs, r) = timed(runs, || {
            murk_recon::reconstruct(&shifted, &vol, pf, PfForm::Fast, &NoProgress)
        })?;
        cells.push(Cell { rec: r, secs });
    }
    Ok(cells)
}

/// Reconstructs the five captures in `data` with CDT and PF (medians of `runs` timed runs), writes
/// `out/grid.png` and `out/index.html`, and returns the index's path; `say` receives one line per
/// reconstruction.
pub fn figure_real(data: &Path, out: &Path, runs: usize, say: &dyn Fn(&str)) -> Result<PathBuf> {
    check_out(data, out)?;
    // The paper's "λ = 4Δc, 8 cycles" for these confocal captures, read two ways. On the depth axis
    // (one-way distance, as confocal codes such as Lindell's define their wavelength) it is 8Δc of round-trip
    // path; read on the path axis, the round-trip kernel e^{2ikr} puts λ/2 = 2Δc at the lateral Nyquist
    // limit and the band's short end beyond it.
    let pf_of = |factor: f64| PfParams {
        wavelength: Wavelength::WallFactor(factor),
        cycles: 8.0,
        falloff: Falloff::None,
        ..PfParams::default()
    };
    let pfs = [pf_of(8.0), pf_of(4.0)];
    let slab = CdtParams::default().slab;
    let peak_m = slab.round_trip_delay_m(None)?;
    let mut rows = vec![
        (
            "CDT".to_string(),
            format!(
                "slab {} m, μa {} /m, μs′ {} /m, n {}, ze {} m; Wiener snr per scene; 2.0 m of path at 128 samples",
                slab.thickness_m, slab.mu_a_per_m, slab.mu_s_prime_per_m, slab.n, slab.ze_m
            ),
        ),
        (
            "PF".to_string(),
            format!(
                "confocal round-trip kernel, 8 cycles, no falloff, fast form; time shifted by the slab's round-trip delay as each row's pulse sees it (docs/slab-delay.md; the response's peak is {:.4} m of path); same voxels as CDT. Row 2: λ = 4Δc of depth (one-way distance) = 8Δc of path (--wavefactor 8). Row 3: λ = 4Δc of path (--wavefactor 4), at the Nyquist limit of the round-trip kernel",
                peak_m
            ),
        ),
        (
            "timings".to_string(),
            format!(
                "median of {} runs each (CDT: plan + run; PF: whole reconstruction), {} threads",
                runs.max(1),
                rayon::current_num_threads()
            ),
        ),
        (
            "grid.png".to_string(),
            "rows: CDT; PF λ = 4Δc of depth; PF λ = 4Δc of path. Columns: letter_s, mannequin, letter_t, cones, letters_ut; front views (from the wall, +y up, +x left), each normalised to its own range".to_string(),
        ),
    ];
    let mut cells = Vec::new();
    // The paper's order: S, mannequin, diffuse T, cones, then U+T (the order of CDT_SCENES).
    for (name, _, snr) in CDT_SCENES {
        let path = data.join(format!("{name}.mat"));
        let pair = scene(&path, snr, runs, &pfs)?;
        for (label, c) in ["CDT", "PF", "PF (λ on path)"].iter().zip(&pair) {
            let (peak, median) = depths(&c.rec);
            let line = format!(
                "peak depth {peak:.3} m, median depth {median:.3} m, {:.1} ms",
                c.secs * 1e3
            );
            say(&format!("{name} {label}: {line}"));
            let extra = if *label == "CDT" {
                format!(" (snr {snr})")
            } else {
                String::new()
            };
            rows.push((format!("{name} {label}"), line + &extra));
        }
        cells.push(pair);
    }
    let columns: Vec<Vec<Option<&Reconstruction>>> = cells
        .iter()
        .map(|scene| scene.iter().map(|c| Some(&c.rec)).collect())
        .collect();
    let grid = grid_plane(&columns, EXTENTS.into());
    murk_io::create_output_dir(out)?;
    let png = out.join("grid.png");
    pictures::write_png(&png, &grid, 0.0, 1.0)?;
    let index = pictures::write_index(
        out,
        "Real captures behind 2.54 cm of foam: CDT (top) vs Phasor Fields",
        &rows,
        &[(png, grid.extents.clone())],
    )?;
    Ok(index)
}

/// The grid's extents line: what its rows and columns hold.
const EXTENTS: &str = "rows: CDT, PF (λ = 4Δc of depth), PF (λ = 4Δc of path); columns: letter_s, mannequin, letter_t, cones, letters_ut; each a front view (from the wall, +y up, +x left), normalised to its own range";
