//! `murk-bench`: reconstruction speed on the paper's Z-letter configuration, and side by side with
//! y-tal's pf_dev, fk and lct on its own benchmark captures when a Python with y-tal is available;
//! every method on the real captures (`--real`); the renderer next to mitransient (`--render`).

mod confocal;
mod medium;
mod paper_cells;
mod real;
mod render;

use anyhow::{bail, Context};
use clap::Parser;
use murk_core::report::{clap_one_line, error_line};
use murk_core::{Axis, DVec3, TimeAxis, Volume};
use murk_recon::{NoProgress, PfForm, PfParams, Wavelength};
use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "murk-bench",
    version,
    about = "murk's benchmarks: speed and error, side by side with y-tal and mitransient",
    after_help = "Examples:\n  \
cargo run --release -p murk-bench                               # PF on the paper's formats (and y-tal with .venv)\n  \
cargo run --release -p murk-bench -- --runs 9 --skip-z\n  \
cargo run --release -p murk-bench -- --paper-only shelf          # the shelf's 142³ volume alone\n  \
cargo run --release -p murk-bench -- --render --only z-letter   # the renderer on the paper's format\n  \
cargo run --release -p murk-bench -- --render --only anisotropy --set render.target_lobe=0.9   # forward scattering's cost\n  \
cargo run --release -p murk-bench -- --render --only 'paper cells' --runs 3   # the paper-scale study's CPU at 6 % error\n  \
cargo run --release -p murk-bench -- --real ../shared/data/real/cdt_lindell2020\n  \
cargo run --release -p murk-bench -- --medium fog.h5 --runs 3      # the medium-aware path's cost\n  \
cargo run --release -p murk-bench -- --confocal-vs-tal --tal-bench ../shared/reference/tal_bench.py"
)]
pub struct BenchArgs {
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Python interpreter with y-tal installed, for the side-by-side case (default: .venv/bin/python if present).
    #[arg(long)]
    pub tal_python: Option<PathBuf>,
    /// Skip the paper-format Z-letter and shelf cases.
    #[arg(long)]
    pub skip_z: bool,
    /// Only the paper formats: the Z letter and the shelf, or the one whose name is given.
    #[arg(long, value_name = "CASE", num_args = 0..=1, default_missing_value = "all",
          value_parser = ["all", "z", "shelf"])]
    pub paper_only: Option<String>,
    /// Benchmark the renderer instead: the T-letter scenes next to mitransient, and the paper format.
    #[arg(long)]
    pub render: bool,
    /// Benchmark every reconstruction method on the real captures in this folder instead
    /// (letter_s.mat … letters_ut.mat of Lindell & Wetzstein 2020).
    #[arg(long)]
    pub real: Option<PathBuf>,
    /// Benchmark the medium-aware path on this capture (one in a medium, rendered by murk) instead:
    /// the plain reconstruction, the default one, and the medium's estimate.
    #[arg(long, value_name = "CAPTURE")]
    pub medium: Option<PathBuf>,
    /// With --medium: keep the medium's tables in this folder (one there for the capture's geometry
    /// is read back, else written) and leave out the estimate that renders its table: what follows
    /// the table, timed without rendering one per run.
    #[arg(long, value_name = "DIR", requires = "medium")]
    pub medium_tables: Option<PathBuf>,
    /// Where the renderer benchmark finds its scene files.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// With --render: a scene override KEY=VALUE for every case (repeatable), e.g.
    /// render.target_lobe=0.9, to measure what a sampling setting does.
    #[arg(long, value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// With --render: only the cases whose scene file name contains this (e.g. t-wall-single;
    /// z-letter for the paper format; 'paper cells', run only when named, for every capture of the
    /// paper-scale study at 6 % error, without --set).
    #[arg(long)]
    pub only: Option<String>,
    /// Only f-k and LCT next to y-tal's fk and lct on a 64 × 64 × 512 confocal capture: speed and
    /// peak memory (y-tal's lct needs its git HEAD: put it in MURK_TAL_PYTHONPATH).
    #[arg(long)]
    pub confocal_vs_tal: bool,
    /// With --render: a Python with mitransient 1.3.1 and mitsuba (pip install mitransient mitsuba; Dr.Jit 1.5 needs Debian's libllvm19), to render
    /// the T-letter cases with mitransient in the same run instead of quoting its recorded figures
    /// (about 5 minutes more: 10 000 spp and a 100 000-spp reference per case).
    #[arg(long)]
    pub mitransient_python: Option<PathBuf>,
    /// mitransient's benchmark script (mitransient_bench.py), needed with --mitransient-python.
    #[arg(long, value_name = "SCRIPT")]
    pub mitransient_bench: Option<PathBuf>,
    /// y-tal's benchmark script (tal_bench.py), run with the y-tal Python for the confocal case;
    /// without it that case measures murk alone and says why.
    #[arg(long, value_name = "SCRIPT")]
    pub tal_bench: Option<PathBuf>,
}

pub use murk_core::median;

/// `python` ready to import y-tal, with `$MURK_TAL_PYTHONPATH` in front of `PYTHONPATH` (as in
/// tests/interop_baselines.rs) so a checkout of y-tal's git HEAD, which has lct, can shadow the
/// PyPI wheel.
pub fn tal_command(python: &Path) -> anyhow::Result<Command> {
    let mut cmd = Command::new(python);
    if let Some(overlay) = std::env::var_os("MURK_TAL_PYTHONPATH") {
        let old = std::env::var_os("PYTHONPATH").unwrap_or_default();
        let paths = std::iter::once(PathBuf::from(overlay)).chain(std::env::split_paths(&old));
        let joined = std::env::join_paths(paths).context("MURK_TAL_PYTHONPATH")?;
        cmd.env("PYTHONPATH", joined);
    }
    Ok(cmd)
}

/// One line of `json.dumps` output from a peer's benchmark script.
pub fn json_line(line: &str) -> anyhow::Result<serde_json::Value> {
    serde_json::from_str(line).with_context(|| format!("not a JSON line: {line}"))
}

/// The number, or the numbers of the list, at `key`; empty when absent.
pub fn json_numbers(v: &serde_json::Value, key: &str) -> Vec<f64> {
    match v.get(key) {
        Some(serde_json::Value::Array(a)) => a.iter().filter_map(|x| x.as_f64()).collect(),
        Some(x) => x.as_f64().into_iter().collect(),
        None => Vec::new(),
    }
}

/// Prints `line` unless `quiet`.
pub fn say(quiet: bool, line: impl AsRef<str>) {
    if !quiet {
        println!("{}", line.as_ref());
    }
}

/// The wall and time axis of y-tal's benchmark captures (docs/benchmarks.md): a 1 m wall with a
/// 64 × 64 pixel-centre grid, 512 bins of 1 cm from 0.
pub fn tal_case_layout(kind: LayoutKind) -> CaptureLayout {
    CaptureLayout {
        kind,
        wall_size_m: 1.0,
        grid: 64,
        point: DVec3::ZERO,
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.01,
            bins: 512,
        },
        laser_xyz: None,
        sensor_xyz: None,
    }
}

/// A scratch folder under the system temp dir, removed when dropped (early returns included).
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(tag: &str) -> anyhow::Result<Scratch> {
        let dir = std::env::temp_dir().join(format!("murk-bench-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(Scratch(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn main() {
    let a = match BenchArgs::try_parse() {
        Ok(a) => a,
        Err(e) if !e.use_stderr() => e.exit(), // --help and --version
        Err(e) => {
            eprintln!(
                "murk-bench: error: {} (see murk-bench --help)",
                clap_one_line(&e.to_string(), std::env::args_os())
            );
            std::process::exit(2);
        }
    };
    if let Err(e) = run(&a) {
        eprintln!("murk-bench: error: {}", error_line(e.as_ref()));
        std::process::exit(1);
    }
}

fn run(a: &BenchArgs) -> anyhow::Result<()> {
    let quiet = a.quiet;
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    say(
        quiet,
        format!(
            "murk-bench: {} rayon threads, median of {} runs",
            rayon::current_num_threads(),
            a.runs
        ),
    );
    if let Some(dir) = &a.real {
        return crate::real::run(dir, a.runs, quiet);
    }
    if let Some(cap) = &a.medium {
        return crate::medium::run(cap, a.medium_tables.as_deref(), a.runs, quiet);
    }
    if a.render {
        let mit = match (&a.mitransient_python, &a.mitransient_bench) {
            (Some(python), Some(script)) => {
                for p in [python, script] {
                    if !p.exists() {
                        bail!("{}: no such file", p.display());
                    }
                }
                Some(crate::render::Mitransient { python, script })
            }
            (Some(_), None) => bail!("--mitransient-python needs --mitransient-bench SCRIPT"),
            (None, _) => None,
        };
        return crate::render::run(
            &a.scenes,
            a.runs,
            (a.only.as_deref(), &a.set),
            mit.as_ref(),
            quiet,
        );
    }
    // Given explicitly, a missing file is an error (the default venv's absence only skips y-tal);
    // a bare command name is looked up on PATH when it runs.
    for p in a.tal_python.iter().chain(&a.tal_bench) {
        if p.components().count() > 1 && !p.is_file() {
            bail!("{}: no such file", p.display());
        }
    }
    let python = a
        .tal_python
        .clone()
        .or_else(|| Some(PathBuf::from(".venv/bin/python")).filter(|p| p.exists()));
    if a.confocal_vs_tal {
        return crate::confocal::run(python.as_deref(), a.tal_bench.as_deref(), a.runs, quiet);
    }
    if let Some(case) = &a.paper_only {
        return paper_formats(case, a.runs, quiet);
    }
    if a.skip_z && python.is_none() {
        // --skip-z leaves only the side-by-side cases, which need y-tal.
        bail!("--skip-z leaves only the side-by-side cases with y-tal, and there is no --tal-python and no .venv/bin/python");
    }
    if !a.skip_z {
        paper_formats("all", a.runs, quiet)?;
    }
    match python {
        Some(py) => {
            versus_tal(&py, a.runs, quiet)?;
            crate::confocal::run(Some(&py), a.tal_bench.as_deref(), a.runs, quiet)?;
        }
        None => say(
            quiet,
            "side by side with y-tal: skipped (no --tal-python and no .venv/bin/python)",
        ),
    }
    Ok(())
}

/// The paper's synthetic setups: 128 × 128 laser grid on a 2 m wall, one SPAD point at the centre, a
/// planar Z 2 m away (the content does not change the time); the Z's 73 × 59 × 73 voxels from 4096 bins of
/// 0.9 mm from 3.5 m, and the shelf's 142³ voxels from the study's 4096 bins of 1.5 mm from 2.0 m.
/// `case`: "z", "shelf" or "all".
fn paper_formats(case: &str, runs: usize, quiet: bool) -> anyhow::Result<()> {
    if case != "shelf" {
        z_letter(runs, quiet)?;
    }
    if case != "z" {
        shelf(runs, quiet)?;
    }
    Ok(())
}

fn z_letter(runs: usize, quiet: bool) -> anyhow::Result<()> {
    let c = 1.0 - 1.0 / 128.0;
    paper_case(
        "Z letter, 128² laser grid × 4096 bins → 73×59×73 voxels",
        TimeAxis {
            start_m: 3.5,
            bin_width_m: 0.0009,
            bins: 4096,
        },
        Volume {
            x: Axis::new(-c, c, 73),
            y: Axis::new(-c, c, 59),
            z: Axis::new(1.5, 2.5, 73),
        },
        runs,
        quiet,
    )
}

fn shelf(runs: usize, quiet: bool) -> anyhow::Result<()> {
    paper_case(
        "shelf format, 128² laser grid × 4096 bins → 142³ voxels",
        TimeAxis {
            start_m: 2.0,
            bin_width_m: 0.0015,
            bins: 4096,
        },
        Volume {
            x: Axis::new(-0.99, 0.99, 142),
            y: Axis::new(-0.99, 0.99, 142),
            z: Axis::new(1.5, 2.5, 142),
        },
        runs,
        quiet,
    )
}

fn paper_case(
    label: &str,
    time: TimeAxis,
    vol: Volume,
    runs: usize,
    quiet: bool,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let layout = CaptureLayout {
        kind: LayoutKind::LaserGridSinglePoint,
        wall_size_m: 2.0,
        grid: 128,
        point: DVec3::ZERO,
        time,
        laser_xyz: None,
        sensor_xyz: None,
    };
    let mut cap = layout.empty_capture()?;
    let z = Target::Polygon {
        outline: murk_synth::z_letter_outline(),
        offset: [0.0; 2],
        depth_m: 2.0,
        albedo: 1.0,
        spacing_m: 2.0 / 128.0 / 2.0,
    };
    add_first_bounce(
        &mut cap,
        &z.scatterers()?,
        &SynthOptions {
            cosines: true,
            ..SynthOptions::default()
        },
    )?;
    let synth_s = t0.elapsed().as_secs_f64();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        // The field and its intensity: the work of `murk_recon::reconstruct`, keeping the field's info.
        let t = Instant::now();
        let params = PfParams::default();
        let f = murk_recon::field(&cap, &vol, &params, PfForm::Fast, &NoProgress)?;
        let intensity = murk_recon::intensity(&cap, &vol, &f.values, params.compensation);
        times.push(t.elapsed().as_secs_f64());
        last = Some((f.info, intensity));
    }
    let (info, intensity) = last.expect("runs ≥ 1");
    let (p, _) = murk_core::Reconstruction::new(vol, intensity, "pf").peak();
    say(quiet, format!(
        "{label} (fast PF; {} of {} depth planes evaluated, in {} slabs of {:.1} frequencies per plane on average, against {} over the whole volume's window): median {:.3} s (runs {:?}); synthesis {:.2} s; peak depth {:.3} m (Z at 2.000 m); peak RSS {:.0} MiB",
        info.planes_evaluated(),
        vol.z.n,
        info.slabs.len(),
        info.frequencies_per_plane(),
        info.frequencies,
        median(&times),
        times.iter().map(|t| (t * 1000.0).round() / 1000.0).collect::<Vec<_>>(),
        synth_s,
        p[2],
        murk_core::process::peak_rss_mib().unwrap_or(f64::NAN)
    ));
    Ok(())
}

/// y-tal's benchmark case (docs/benchmarks.md): 64 × 64 single-laser capture, 512 bins of 1 cm, point at
/// (0.1, −0.2, 1.0); 32 planes of 64 × 64 at z = 0.85…1.16; λ = σ = 0.06 m. tal's pf_dev needs one call
/// per plane for several planes (its multi-plane DIRECT_LIGHT path fails), as in its own benchmark.
fn versus_tal(python: &Path, runs: usize, quiet: bool) -> anyhow::Result<()> {
    let mut cap = tal_case_layout(LayoutKind::SinglePointSensorGrid).empty_capture()?;
    add_first_bounce(
        &mut cap,
        &Target::Point {
            pos: DVec3::new(0.1, -0.2, 1.0),
            albedo: 1.0,
        }
        .scatterers()?,
        &SynthOptions::default(),
    )?;
    let scratch = Scratch::new("single")?;
    let file = scratch.0.join("point_single_N64_T512.h5");
    murk_io::write_capture(&file, &cap)?;
    let c = 0.5 - 0.5 / 64.0;
    let vol = Volume {
        x: Axis::new(-c, c, 64),
        y: Axis::new(-c, c, 64),
        z: Axis::new(0.85, 1.16, 32),
    };
    // cycles = 6 makes σ = λ = 0.06 m, tal's wl_mean = wl_sigma = 0.06.
    let params = PfParams {
        wavelength: Wavelength::Metres(0.06),
        cycles: 6.0,
        ..PfParams::default()
    };
    let loaded = murk_io::read_capture(&file)?;
    let mut murk_times = Vec::new();
    for _ in 0..runs.max(3) {
        let t = Instant::now();
        murk_recon::reconstruct(&loaded, &vol, &params, PfForm::Fast, &NoProgress)?;
        murk_times.push(t.elapsed().as_secs_f64());
    }
    let script = format!(
        r#"
import time, json, inspect, numpy as np, tal
tal.set_log_level(tal.LogLevel.WARNING)
d = tal.io.read_capture({file:?})
vol = tal.reconstruct.get_volume_project_rw(d, depths=list(np.round(0.85 + 0.01*np.arange(32), 4)))
kw = {{}}
if 'nt' in inspect.signature(tal.reconstruct.pf_dev.solve).parameters:
    kw['nt'] = d.H.shape[0]
times = []
for _ in range({reps}):
    t = time.perf_counter()
    for iz in range(vol.shape[2]):
        tal.reconstruct.pf_dev.solve(d, wl_mean=0.06, wl_sigma=0.06, volume_xyz=vol[:, :, iz:iz+1, :],
            camera_system=tal.enums.CameraSystem.DIRECT_LIGHT, progress=False, **kw)
    times.append(time.perf_counter() - t)
print(json.dumps({{"times": times, "version": tal.__version__}}))
"#,
        file = file.display().to_string(),
        reps = runs.clamp(1, 3)
    );
    let out = tal_command(python)?
        .arg("-c")
        .arg(&script)
        .output()
        .with_context(|| python.display().to_string())?;
    let murk_med = median(&murk_times);
    if !out.status.success() {
        say(
            quiet,
            format!(
                "y-tal side by side: skipped ({} could not run tal: {})",
                python.display(),
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            ),
        );
        say(
            quiet,
            format!("murk on the same case: median {murk_med:.4} s"),
        );
        return Ok(());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().last().unwrap_or("");
    let times = json_line(line)
        .map(|v| json_numbers(&v, "times"))
        .unwrap_or_default();
    if times.is_empty() {
        bail!("could not parse tal's timing output: {line}");
    }
    let tal_med = median(&times);
    say(quiet, format!(
        "64×64×512 single-laser capture → 32 planes of 64×64 (λ = σ = 0.06 m): y-tal pf_dev median {tal_med:.3} s, murk fast PF median {murk_med:.4} s: {:.0}× faster",
        tal_med / murk_med
    ));
    Ok(())
}
