//! `murk bench --confocal-vs-tal`: murk's f-k and LCT next to y-tal's `fk` and `lct` on y-tal's own
//! 64 × 64 × 512 confocal benchmark capture (docs/benchmarks.md, "y-tal's benchmark case"), against the targets (≥ 20× faster,
//! ≥ 5× less memory). Speed: the median of in-process calls, plan and run together, as `murk
//! reconstruct` makes them. Memory: the peak RSS of a whole `murk reconstruct` process, since the
//! bench process itself has already held other cases' buffers; y-tal's figure is likewise its whole
//! subprocess (tal_bench.py's ru_maxrss, interpreter and imports included).

use crate::say;
use crate::{json_line, json_numbers, median, tal_command, Scratch};
use anyhow::{bail, Context};
use murk_baselines::{FkParams, LctParams, Reconstruction};
use murk_core::{Capture, DVec3};
use murk_synth::{add_first_bounce, LayoutKind, SynthOptions, Target};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// tal_synth.py's hidden point, off-centre in x and y so a swapped or flipped axis shows.
const POINT: DVec3 = DVec3::new(0.10, -0.20, 1.00);

/// GNU time: its `%M` is the kernel's ru_maxrss of the child from wait4, which std cannot read.
const GNU_TIME: &str = "/usr/bin/time";

/// One of murk's methods with the defaults `murk reconstruct` uses.
type Solve = fn(&Capture) -> murk_core::Result<Reconstruction>;

/// Speed and memory of murk and y-tal on the capture. `python` is None when no y-tal Python was
/// found (murk's side is still measured).
pub fn run(
    python: Option<&Path>,
    tal_bench: Option<&Path>,
    runs: usize,
    quiet: bool,
) -> anyhow::Result<()> {
    let scratch = Scratch::new("confocal")?;
    // The name matters: tal_bench.py reports its peak error for files named point_*.
    let file = scratch.0.join("point_confocal_N64_T512.hdf5");
    murk_io::write_capture(&file, &capture()?)
        .with_context(|| format!("writing {}", file.display()))?;
    // Read back, so murk times what the child and y-tal read: the file's f32 samples.
    let cap = murk_io::read_capture(&file)?;
    let tal_repeats = runs.clamp(1, 2); // y-tal fk takes ~10 s and ~3.8 GB a run
    say(quiet, format!(
        "confocal 64×64×512 point capture (y-tal's benchmark case, point at 1 m): murk median of {runs} in-process runs, peak RSS of a `murk reconstruct` process; y-tal best of {tal_repeats} via {}",
        tal_bench.map_or("no --tal-bench".into(), |p| p.display().to_string())
    ));
    let methods: [(&str, Solve); 2] = [
        ("fk", |c| murk_baselines::fk(c, FkParams::default())),
        ("lct", |c| murk_baselines::lct(c, LctParams::default())),
    ];
    for (name, solve) in methods {
        let mut secs = Vec::with_capacity(runs);
        let mut rec = None;
        for _ in 0..runs {
            let t = Instant::now();
            rec = Some(solve(&cap).with_context(|| format!("murk {name}"))?);
            secs.push(t.elapsed().as_secs_f64());
        }
        let murk_s = median(&secs);
        let murk_err = peak_error_m(&rec.expect("runs ≥ 1"));
        let murk_mib = murk_peak_rss_mib(&file, name, &scratch.0)?;
        let mut line = format!(
            "{name:>4}: murk {:.1} ms, {}",
            murk_s * 1e3,
            murk_mib.map_or("peak RSS n/a (no /usr/bin/time)".into(), |m| format!(
                "{m:.0} MiB"
            ))
        );
        let tal = match (python, tal_bench) {
            (Some(py), Some(script)) => y_tal(py, script, &file, name, tal_repeats),
            (None, _) => Err("no --tal-python and no .venv/bin/python".into()),
            (_, None) => Err("no --tal-bench SCRIPT (y-tal's tal_bench.py)".into()),
        };
        match tal {
            Ok(t) => {
                line += &format!(
                    " | y-tal {} {:.2} s, {:.0} MiB | {:.0}× faster, {}",
                    t.version,
                    t.secs,
                    t.peak_mib,
                    t.secs / murk_s,
                    murk_mib.map_or("memory ratio n/a".into(), |m| format!(
                        "{:.1}× less memory",
                        t.peak_mib / m
                    ))
                );
                line += &format!(
                    " | peak off by {murk_err:.4} m (murk), {} m (y-tal)",
                    t.peak_err_m
                );
            }
            Err(why) => {
                line += &format!(" | peak off by {murk_err:.4} m; y-tal {name}: skipped ({why})")
            }
        }
        say(quiet, line);
    }
    Ok(())
}

/// tal_synth.py's point_confocal_N64_T512: 1 m × 1 m wall at z = 0, 64 × 64 pixel-centre grid,
/// 512 bins of 1 cm from 0, no first and last bounce, 1/r⁴ falloff and no cosines. One difference:
/// murk splats each pulse linearly over two bins where tal_synth.py floors it into one; the
/// reconstructions' cost does not depend on it.
fn capture() -> anyhow::Result<Capture> {
    let mut cap = crate::tal_case_layout(LayoutKind::Confocal).empty_capture()?;
    let point = Target::Point {
        pos: POINT,
        albedo: 1.0,
    };
    add_first_bounce(&mut cap, &point.scatterers()?, &SynthOptions::default())?;
    Ok(cap)
}

/// Distance from the brightest voxel to the true point: a method that ran fast but wrong shows here.
fn peak_error_m(rec: &Reconstruction) -> f64 {
    let [ix, iy, iz] = rec.argmax();
    rec.volume.centre(ix, iy, iz).distance(POINT)
}

/// Peak RSS (MiB) of `murk reconstruct FILE --method METHOD` in its own process, or None without
/// GNU time.
fn murk_peak_rss_mib(file: &Path, method: &str, scratch: &Path) -> anyhow::Result<Option<f64>> {
    if !Path::new(GNU_TIME).exists() {
        return Ok(None);
    }
    // `murk` is built next to `murk-bench` (cargo build --release --workspace).
    let exe = std::env::current_exe()
        .context("locating murk-bench")?
        .with_file_name(format!("murk{}", std::env::consts::EXE_SUFFIX));
    if !exe.exists() {
        anyhow::bail!(
            "{} not found: build it too (cargo build --release --workspace)",
            exe.display()
        );
    }
    let report = scratch.join(format!("{method}.rss"));
    let out = Command::new(GNU_TIME)
        .args(["-f", "%M", "-o"])
        .arg(&report)
        .arg(&exe)
        .arg("reconstruct")
        .arg(file)
        .args(["--method", method, "--quiet", "--out"])
        .arg(scratch.join(format!("{method}.npy")))
        .output()
        .with_context(|| format!("running {GNU_TIME} {}", exe.display()))?;
    if !out.status.success() {
        bail!(
            "murk reconstruct --method {method} in a child failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let text = std::fs::read_to_string(&report)
        .with_context(|| format!("reading {}", report.display()))?;
    let kib: f64 = text
        .trim()
        .parse()
        .with_context(|| format!("{GNU_TIME} -f %M wrote {:?}, not KiB", text.trim()))?;
    Ok(Some(kib / 1024.0))
}

/// y-tal's side of one method, as tal_bench.py `one` reports it.
struct TalRun {
    version: String,
    /// Best solve() wall time of the repeats.
    secs: f64,
    peak_mib: f64,
    peak_err_m: String,
}

/// Runs `tal_bench.py one FILE METHOD native` in its own Python process; Err says why it was skipped.
fn y_tal(
    python: &Path,
    script: &Path,
    file: &Path,
    method: &str,
    repeats: usize,
) -> Result<TalRun, String> {
    if !script.exists() {
        return Err(format!("no {} (--tal-bench)", script.display()));
    }
    let out = tal_command(python)
        .map_err(|e| format!("{e:#}"))?
        .arg(script)
        .args(["one"])
        .arg(file)
        .args([method, "native", "--repeat", &repeats.to_string()])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let Some(result) = stdout.lines().rev().find_map(|l| l.strip_prefix("RESULT ")) else {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let last = stderr.lines().last().unwrap_or("no output");
        return Err(format!("{} {}: {last}", python.display(), script.display()));
    };
    let result = json_line(result).map_err(|e| e.to_string())?;
    let text = |key: &str| match result.get(key) {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => "?".into(),
    };
    let version = text("tal");
    if result.get("ok") != Some(&serde_json::Value::Bool(true)) {
        let error = result
            .get("error")
            .and_then(|e| e.as_str())
            .unwrap_or("failed");
        // y-tal 0.20.0 on PyPI predates tal.reconstruct.lct (it arrived in y-tal's git HEAD).
        let hint = if error.contains("has no attribute 'lct'") {
            "; set MURK_TAL_PYTHONPATH to a folder with y-tal HEAD's tal package"
        } else {
            ""
        };
        return Err(format!("y-tal {version}: {error}{hint}"));
    }
    let number = |key: &str| {
        json_numbers(&result, key)
            .first()
            .copied()
            .ok_or_else(|| format!("no {key} in tal_bench.py's RESULT line: {result}"))
    };
    Ok(TalRun {
        secs: number("solve_s")?,
        peak_mib: number("peak_rss_mb")?,
        peak_err_m: text("peak_err_m"),
        version,
    })
}
