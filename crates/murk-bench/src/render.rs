//! `murk bench --render`: the renderer's efficiency on the T-letter scenes of docs/benchmarks.md, next to
//! mitransient 1.3.1 (its figures recorded in docs/benchmarks.md, or rendered in the same run), and
//! the paper-format Z-letter capture.

use crate::median;
use crate::say;
use crate::{json_line, json_numbers, Scratch};
use anyhow::{bail, Context};
use murk_core::process::peak_rss_mib;
use murk_core::TimeAxis;
use murk_render::bench::timed_render;
use murk_render::{Overrides, Plan, Scene};
use murk_study::render_error::{rel_l2, split_rel_l2, window_mask};
use std::path::Path;
use std::process::Command;

/// One T-letter case: scene file, spp, reference spp, object window (m; `None`: all bins),
/// mitransient's relL2 and CPU seconds for it as recorded in docs/benchmarks.md (10 000 spp against a
/// 100 000-spp reference, 2 vCPU EPYC; `transient_nlos_path` without a medium, `transient_prbvolpath`
/// with one), and the arguments of mitransient_bench.py that render the same case live.
struct Case {
    file: &'static str,
    spp: u64,
    ref_spp: u64,
    window: Option<(f64, f64)>,
    mitransient: (f64, f64),
    mit_args: &'static [&'static str],
}

/// mitransient's spp and reference spp in the live comparison (those of docs/benchmarks.md).
const MIT_SPP: u64 = 10_000;
const MIT_REF_SPP: u64 = 100_000;

/// A Python with mitransient and mitsuba, and mitransient_bench.py, for the live comparison.
pub struct Mitransient<'a> {
    pub python: &'a Path,
    pub script: &'a Path,
}

impl Case {
    /// Which entries of a `[hist][bin]` (or `[x][y][bin]`) array of `n` values the error is taken over.
    fn mask(&self, time: &TimeAxis, n: usize) -> Vec<bool> {
        window_mask(
            time,
            n,
            self.window.unwrap_or((f64::NEG_INFINITY, f64::INFINITY)),
        )
    }
}

/// A run's relL2 against a reference of `ref_spp` with the reference's own noise (spp/ref_spp of the
/// run's variance) taken out.
fn without_reference_noise(e: f64, spp: u64, ref_spp: u64) -> f64 {
    e / (1.0 + spp as f64 / ref_spp as f64).sqrt()
}

/// The T in fog, the case whose anisotropy [`anisotropy`] measures.
const FOG: &Case = &CASES[2];

const CASES: [Case; 3] = [
    Case {
        file: "t-wall-single.toml",
        spp: 1000,
        ref_spp: 16_000,
        window: Some((1.98, 2.70)),
        mitransient: (0.058, 2.64),
        mit_args: &["--mode", "nlos", "--capture", "single"],
    },
    // mitransient's recorded confocal error is over all bins only; compared over all bins.
    Case {
        file: "t-wall-confocal.toml",
        spp: 1000,
        ref_spp: 16_000,
        window: None,
        mitransient: (0.065, 2.42),
        mit_args: &["--mode", "nlos", "--capture", "confocal"],
    },
    Case {
        file: "t-wall-medium.toml",
        spp: 256,
        ref_spp: 4096,
        window: Some((1.98, 2.70)),
        mitransient: (0.624, 16.48),
        mit_args: &["--mode", "vol", "--capture", "single", "--medium"],
    },
];

/// `only`: run just the cases whose scene file name contains it. `mit`: render each T case with
/// mitransient in this run too, instead of quoting its recorded figures.
/// The anisotropy cases' names for `--only` (the T's also runs with `--only t-wall-medium`; the Z's
/// name leaves it out of `--only z-letter`, the paper format).
const ANISOTROPY: &str = "t-wall-medium.toml anisotropy";
const ANISOTROPY_Z: &str = "z quick anisotropy";
/// Every capture of the paper-scale study, to 6 % ([`crate::paper_cells`]); only by name (hours of
/// CPU at the study's spp, minutes at the measured one).
const PAPER_CELLS: &str = "paper cells";

/// `only`: run just the cases whose name contains it; `set`: scene overrides for every case. `mit`:
/// render each T case with mitransient in this run too, instead of quoting its recorded figures.
pub fn run(
    scenes: &Path,
    runs: usize,
    (only, set): (Option<&str>, &[String]),
    mit: Option<&Mitransient>,
    quiet: bool,
) -> anyhow::Result<()> {
    let wanted = |name: &str| only.is_none_or(|o| name.contains(o));
    let names: Vec<&str> = CASES
        .iter()
        .map(|c| c.file)
        .chain([ANISOTROPY, ANISOTROPY_Z, "z-letter.toml", PAPER_CELLS])
        .collect();
    if !names.iter().any(|n| wanted(n)) {
        bail!(
            "--only {}: matches none of the cases ({})",
            only.unwrap_or_default(),
            names.join(", ")
        );
    }
    let scenes = Scenes { dir: scenes, set };
    for c in CASES.iter().filter(|c| wanted(c.file)) {
        t_case(&scenes, c, runs, mit, quiet)?;
    }
    if wanted(ANISOTROPY) {
        anisotropy(&scenes, &FOG_T, runs, quiet)?;
    }
    if wanted(ANISOTROPY_Z) {
        anisotropy(&scenes, &FOG_Z, runs, quiet)?;
    }
    if wanted("z-letter.toml") {
        paper_format(&scenes, runs, quiet)?;
    }
    if only.is_some() && wanted(PAPER_CELLS) {
        crate::paper_cells::paper_cells(scenes.dir, runs, quiet)?;
    }
    Ok(())
}

/// Where the scene files are, and the overrides every case gets.
struct Scenes<'a> {
    dir: &'a Path,
    set: &'a [String],
}

impl Scenes<'_> {
    /// `file` with `extra` overrides, then the user's.
    fn load(&self, file: &str, extra: &[String]) -> anyhow::Result<Scene> {
        let path = self.dir.join(file);
        let ov = Overrides {
            set: extra.iter().chain(self.set).cloned().collect(),
            ..Overrides::default()
        };
        Scene::load(&path, &ov).with_context(|| format!("{} (use --scenes DIR)", path.display()))
    }
}

fn t_case(
    scenes: &Scenes,
    c: &Case,
    runs: usize,
    mit: Option<&Mitransient>,
    quiet: bool,
) -> anyhow::Result<()> {
    let scene = scenes.load(c.file, &[])?;
    let plan = Plan::new(&scene);
    let reference = timed_render(&plan, c.ref_spp, 1_000_000, None)?;
    let mask = c.mask(&scene.capture.time, reference.h.len());
    let mut rows = Vec::new();
    for seed in 0..runs as u64 {
        let r = timed_render(&plan, c.spp, seed, None)?;
        let e = without_reference_noise(rel_l2(&r.h, &reference.h, &mask), c.spp, c.ref_spp);
        rows.push((e, r.cpu_s, r.paths / r.cpu_s));
    }
    let (e, cpu, rate) = (
        median(&rows.iter().map(|r| r.0).collect::<Vec<_>>()),
        median(&rows.iter().map(|r| r.1).collect::<Vec<_>>()),
        median(&rows.iter().map(|r| r.2).collect::<Vec<_>>()),
    );
    let ((em, cm), source) = match mit {
        Some(m) => (mitransient_live(m, c, &mask, quiet)?, "measured now"),
        None => (c.mitransient, "recorded in docs/benchmarks.md"),
    };
    // CPU time to mitransient's error, by error ∝ CPU^−½.
    let ours = cpu * (e / em).powi(2);
    say(quiet, format!(
        "{}: {} points × {} spp, median of {runs}: relL2 {e:.4} ({}), CPU {cpu:.2} s, {:.2} M paths/CPU-s; to mitransient's {em:.4} ({source}) we need {ours:.2} CPU-s vs its {cm:.2} s: {:.1}× less CPU",
        c.file,
        plan.n_points(),
        c.spp,
        c.window.map_or("all bins".to_string(), |w| format!("object window {}–{} m", w.0, w.1)),
        rate / 1e6,
        cm / ours
    ));
    Ok(())
}

/// Phase-function anisotropies and albedos of issue 47's table: the cost of forward scattering is CPU ×
/// error² at each g relative to g = 0 at the same albedo (a ratio that does not depend on spp).
const GS: [f64; 3] = [0.0, 0.7, 0.9];
const ALBEDOS: [f64; 2] = [0.5, 0.83];

/// A scene whose cost of forward scattering [`anisotropy`] measures: its file, the overrides that make
/// it, spp and object window (m).
struct Fog {
    file: &'static str,
    set: &'static [&'static str],
    spp: u64,
    window: (f64, f64),
}

/// The fog T of docs/benchmarks.md.
const FOG_T: Fog = Fog {
    file: FOG.file,
    set: &[],
    spp: FOG.spp,
    window: (1.98, 2.70),
};

/// The paper's Z (2 m deep, μt = 1) at the study's quick window (1 200 bins of 5 mm from 2 m) on a 32²
/// laser grid, the error over its direct returns (4.0–4.9 m), as in issue 47.
const FOG_Z: Fog = Fog {
    file: "z-letter.toml",
    set: &[
        "capture.grid=[32, 32]",
        "capture.bins=1200",
        "capture.bin_width=0.005",
        "capture.start=2.0",
    ],
    spp: 128,
    window: (4.0, 4.9),
};

/// `fog` at each g and albedo: CPU seconds × relL2² over the object window, the error from pairs of
/// independent renders (no reference, whose own noise grows with g), the median of `runs` pairs.
fn anisotropy(scenes: &Scenes, fog: &Fog, runs: usize, quiet: bool) -> anyhow::Result<()> {
    for albedo in ALBEDOS {
        let costs = GS
            .iter()
            .map(|&g| {
                let set: Vec<String> = fog
                    .set
                    .iter()
                    .map(|s| s.to_string())
                    .chain([format!("medium.g={g}"), format!("medium.albedo={albedo}")])
                    .collect();
                let scene = scenes.load(fog.file, &set)?;
                let plan = Plan::new(&scene);
                let pairs = (0..runs.max(1) as u64)
                    .map(|p| {
                        let a = timed_render(&plan, fog.spp, 2 * p, None)?;
                        let b = timed_render(&plan, fog.spp, 2 * p + 1, None)?;
                        let mask = window_mask(&scene.capture.time, a.h.len(), fog.window);
                        let e = split_rel_l2(&a.h, &b.h, &mask);
                        Ok(0.5 * (a.cpu_s + b.cpu_s) * e * e)
                    })
                    .collect::<anyhow::Result<Vec<_>>>()?;
                Ok(median(&pairs))
            })
            .collect::<anyhow::Result<Vec<f64>>>()?;
        let row: Vec<String> = GS
            .iter()
            .zip(&costs)
            .map(|(g, c)| format!("g {g}: {c:.3e} ({:.1}×)", c / costs[0]))
            .collect();
        say(
            quiet,
            format!(
                "{}{} at α {albedo}, {} spp, CPU-s × relL2² over the object window {}–{} m (median of {} pairs; × g = 0): {}",
                fog.file,
                if fog.set.is_empty() { "" } else { " (32² quick)" },
                fog.spp,
                fog.window.0,
                fog.window.1,
                runs.max(1),
                row.join(", ")
            ),
        );
    }
    Ok(())
}

/// mitransient's relL2 (over `mask`, murk's mask of the case: mitransient's `[x][y][bin]` transient has the
/// layout of murk's histograms; against its own 100 000-spp reference, the reference's noise taken out
/// as for murk) and CPU seconds of its warm 10 000-spp render, measured by running mitransient_bench.py
/// now.
fn mitransient_live(
    m: &Mitransient,
    c: &Case,
    mask: &[bool],
    quiet: bool,
) -> anyhow::Result<(f64, f64)> {
    let dir = Scratch::new("mitransient")?;
    let render = |spp: u64, repeats: u32, tag: &str| -> anyhow::Result<(Vec<f32>, f64)> {
        say(
            quiet,
            format!("  mitransient {} at {spp} spp …", c.mit_args.join(" ")),
        );
        let out = Command::new(m.python)
            .arg(m.script)
            .args(c.mit_args)
            .args([
                "--spp",
                &spp.to_string(),
                "--repeats",
                &repeats.to_string(),
                "--tag",
                tag,
            ])
            .arg("--outdir")
            .arg(&dir.0)
            .arg("--results")
            .arg(dir.0.join("results.jsonl"))
            .output()
            .with_context(|| format!("running {}", m.python.display()))?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        let line = stdout.lines().rev().find(|l| l.starts_with('{'));
        let Some(line) = line.filter(|_| out.status.success()) else {
            let err = String::from_utf8_lossy(&out.stderr);
            bail!(
                "{} {} failed: {}",
                m.python.display(),
                m.script.display(),
                err.lines().last().unwrap_or("no output")
            );
        };
        let line = json_line(line)?;
        let cpu = *json_numbers(&line, "cpu_s")
            .last()
            .context("no cpu_s in its output")?;
        let npy = line
            .get("npy")
            .and_then(|v| v.as_str())
            .context("no npy in its output")?;
        let (shape, h) = murk_io::read_npy_f32(Path::new(npy))?;
        // [x, y, bins, channels]: channel 0 is the transient.
        let [_, _, _, ch] = shape[..] else {
            bail!("{npy}: unexpected transient shape {shape:?}");
        };
        let h: Vec<f32> = h.iter().step_by(ch).copied().collect();
        if h.len() != mask.len() {
            bail!(
                "{npy}: shape {shape:?} does not match the scene's {} histogram values",
                mask.len()
            );
        }
        Ok((h, cpu))
    };
    let (reference, _) = render(MIT_REF_SPP, 1, "_murkref")?;
    let (h, cpu) = render(MIT_SPP, 2, "_murkrun")?;
    let e = without_reference_noise(rel_l2(&h, &reference, mask), MIT_SPP, MIT_REF_SPP);
    Ok((e, cpu))
}

/// The paper's format (`scenes/z-letter.toml`: 128² laser grid, one SPAD point, 4096 bins, fog μt = 1/m,
/// α = 0.5). A full render to 6 % takes hours here, so: the error of one run is measured on 1024 central
/// laser points (shard 8/16: rows 64–71) from pairs of independent runs, and the CPU time to 6 % over the whole grid
/// is extrapolated with error ∝ spp^−½ and CPU ∝ laser points × spp. Peak memory: a full-grid render.
fn paper_format(scenes: &Scenes, runs: usize, quiet: bool) -> anyhow::Result<()> {
    const SPP: u64 = 128;
    // The Z's direct returns: 2 m + 2 m at the centre to 2.81 m + 2.08 m from a grid corner.
    const WINDOW: (f64, f64) = (4.0, 4.9);
    let scene = scenes.load("z-letter.toml", &[])?;
    let plan = Plan::new(&scene);
    let shard = Some((8, 16));
    let pairs: Vec<_> = (0..runs.max(1) as u64)
        .map(|p| {
            let a = timed_render(&plan, SPP, 2 * p, shard)?;
            let b = timed_render(&plan, SPP, 2 * p + 1, shard)?;
            let mask = window_mask(&scene.capture.time, a.h.len(), WINDOW);
            // Histograms outside the shard are zero in both runs and drop out of both sums.
            let e = split_rel_l2(&a.h, &b.h, &mask);
            Ok((e, (a.cpu_s + b.cpu_s) / (a.paths + b.paths)))
        })
        .collect::<anyhow::Result<_>>()?;
    let e = median(&pairs.iter().map(|p| p.0).collect::<Vec<_>>());
    let cpu_per_path = median(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
    let spp6 = SPP as f64 * (e / 0.06).powi(2);
    let cpu6 = cpu_per_path * plan.n_points() as f64 * spp6;
    // Peak memory of a whole render at 1 spp (the histograms do not grow with spp).
    timed_render(&plan, 1, 0, None)?;
    say(quiet, format!(
        "paper format (z-letter.toml, {} laser points × {} bins): {SPP} spp gives object-window ({}–{} m) relL2 {e:.3} (median of {} pairs, 1024 central laser points), {:.3} M paths/CPU-s; extrapolated (error ∝ spp^−½): 6 % needs {spp6:.0} spp = {:.2} CPU-hours; peak RSS of a full-grid render {:.0} MiB",
        plan.n_points(),
        scene.capture.time.bins,
        WINDOW.0,
        WINDOW.1,
        pairs.len(),
        1e-6 / cpu_per_path,
        cpu6 / 3600.0,
        peak_rss_mib().unwrap_or(f64::NAN)
    ));
    Ok(())
}
