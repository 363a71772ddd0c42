//! `murk render` and `murk merge`: Monte Carlo captures of scene files (see `scenes/`).

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use murk_render::{checkpoint_path, merge, Outputs, Overrides, Scene, StoredRender};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk render scenes/t-wall-medium.toml --out fog.h5 --spp 64\n  \
murk render scenes/z-letter.toml --out z.h5 --grid 32 --bins 1024 --set capture.bin_width=0.0036 --set medium.albedo=0.83 --set medium.g=0.7\n  \
murk render scenes/shelf.toml --out shelf.h5 --truth shelf-truth.h5\n  \
murk render scenes/z-letter.toml --out part0.h5 --shard 0/4   # then murk merge part*.h5 --out z.h5\n  \
murk render scenes/z-letter.toml --out z.h5 --resume          # continue from z.h5.ckpt\n  \
murk render scenes/z-letter.toml --out z.h5 --albedos 0.15,0.5,0.83   # z-albedo0.15.h5, z-albedo0.5.h5, …")]
pub struct RenderArgs {
    /// Scene file (TOML; examples in scenes/).
    pub scene: PathBuf,
    /// Output capture (y-tal HDF5), written atomically.
    #[arg(long)]
    pub out: PathBuf,
    /// Paths per traced wall point (per laser point for a laser grid); default: the scene's [render] spp.
    #[arg(long, conflicts_with = "time_budget", value_parser = clap::value_parser!(u64).range(1..=murk_core::Limits::MAX_SPP))]
    pub spp: Option<u64>,
    /// Pick the spp that fits this many seconds (measured on a short pilot run, then rendered
    /// deterministically). Not with --resume: each run would pick another spp.
    #[arg(long, value_name = "SECONDS", value_parser = parse_budget, conflicts_with = "resume")]
    pub time_budget: Option<f64>,
    /// Random seed; a seeded render gives identical bytes for any --threads and any sharding.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = crate::cmd::parse_threads)]
    pub threads: Option<usize>,
    /// Override the grid with N × N points.
    #[arg(long, value_name = "N")]
    pub grid: Option<usize>,
    /// Override the number of time bins.
    #[arg(long, value_name = "N")]
    pub bins: Option<usize>,
    /// Override any key of the scene file (repeatable): a dotted key and a TOML value, e.g.
    /// `medium.albedo=0.83`, `object[0].center=[0, 0, 1.5]`, `relay.kind=wall`. Recorded in the capture's
    /// scene_info and covered by --resume's check.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Also write the scene's ground truth (HDF5): per wall-grid point the depth of the first hidden surface
    /// along the relay normal and its object, plus the geometry's bounds.
    #[arg(long, value_name = "OUT.h5")]
    pub truth: Option<PathBuf>,
    /// Render only part i of N (0-based), for `murk merge`.
    #[arg(long, value_name = "i/N", value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Seconds between checkpoints (OUT.ckpt); 0 keeps none, except that --resume still reads an
    /// existing one and appends to it if the render stops early or cannot write its captures.
    #[arg(long, default_value_t = 60.0, value_name = "SECONDS", value_parser = parse_seconds)]
    pub checkpoint_every: f64,
    /// Continue from OUT.ckpt left by an interrupted run with the same scene, spp, seed and shard.
    #[arg(long)]
    pub resume: bool,
    /// Render one capture per medium albedo from the same paths (OUT with `-albedo<α>` before its
    /// extension): each equals, to float rounding, a render with `--set medium.albedo=α` and the same
    /// seed, for the tracing cost of one render plus one histogram write per albedo.
    #[arg(long, value_delimiter = ',', value_name = "α,α,…")]
    pub albedos: Option<Vec<f64>>,
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk merge part0.h5 part1.h5 part2.h5 part3.h5 --out z.h5\n  \
murk merge renders/z.part*.h5 --out z.h5      # the parts of murk render --shard i/4, any order")]
pub struct MergeArgs {
    /// The parts written by `murk render --shard i/N` (all N of them).
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output capture; identical bytes to an unsharded render.
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or("expected i/N, e.g. 0/4")?;
    let (i, n): (usize, usize) = (
        i.trim()
            .parse()
            .map_err(|_| format!("'{i}' is not a shard index"))?,
        n.trim()
            .parse()
            .map_err(|_| format!("'{n}' is not a shard count"))?,
    );
    murk_render::check_shard(i, n)?;
    Ok((i, n))
}

/// A number of seconds that the library's `check` accepts.
fn parse_seconds_with<T>(
    s: &str,
    check: impl Fn(f64) -> murk_core::Result<T>,
) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number of seconds"))?;
    check(v).map_err(|e| e.to_string())?;
    Ok(v)
}

/// A time budget in seconds, as the library takes it.
fn parse_budget(s: &str) -> Result<f64, String> {
    parse_seconds_with(s, murk_render::time_budget)
}

/// A checkpoint interval in seconds, as the library takes it.
fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_seconds_with(s, murk_render::checkpoint_interval)
}

pub fn run(a: RenderArgs, quiet: bool) -> anyhow::Result<()> {
    let ov = Overrides {
        grid: a.grid,
        bins: a.bins,
        set: a.set.clone(),
        ..Overrides::default()
    };
    let scene = Scene::load(&a.scene, &ov)?;
    let outputs = Outputs::Beside {
        out: &a.out,
        resume: a.resume,
        every_s: a.checkpoint_every,
    };
    let stored = StoredRender::new(&scene, Some(&a.scene), a.albedos.as_deref(), outputs)?;
    if let Some(t) = &a.truth {
        murk_io::check_h5_output(t, &stored.taken())?;
        anyhow::ensure!(
            !stored.outputs().iter().any(|o| murk_io::same_target(o, t)),
            "{}: --truth and the capture name the same file",
            t.display()
        );
    }
    crate::cmd::pool(a.threads)?.install(|| render(&a, &stored, quiet))?;
    // After the render, so that a refused or failed one leaves no file but its checkpoint.
    if let Some(t) = &a.truth {
        murk_io::write_truth_h5(t, &scene.ground_truth())?;
    }
    Ok(())
}

fn render(a: &RenderArgs, stored: &StoredRender, quiet: bool) -> anyhow::Result<()> {
    let plan = stored.plan();
    let spp = match (a.spp, a.time_budget) {
        (Some(s), _) => s,
        (None, Some(b)) => plan.spp_for_budget(b, a.shard)?,
        (None, None) => plan.scene.settings.spp,
    };
    let ckpt_path = checkpoint_path(&a.out);
    let had_checkpoint = ckpt_path.exists();
    if a.resume && !had_checkpoint && !quiet {
        eprintln!(
            "murk: no checkpoint at {}; starting from scratch",
            ckpt_path.display()
        );
    }
    if !quiet {
        let note = match stored.checkpoint() {
            Some(path) => crate::cmd::Interrupted {
                stopped: format!(
                    "interrupted: {} keeps the finished work units; the same command with --resume goes on from them",
                    path.display()
                ),
                at_once: format!(
                    "interrupted at once: {} keeps only the units saved before (every --checkpoint-every seconds); the same command with --resume goes on from them",
                    path.display()
                ),
            },
            None => {
                let none = "interrupted: no checkpoint is kept (--checkpoint-every 0), so the render starts over";
                crate::cmd::Interrupted {
                    stopped: none.into(),
                    at_once: none.into(),
                }
            }
        };
        let _ = crate::cmd::ON_INTERRUPT.set(note);
    }
    let units = plan.shard_units(a.shard).len();
    let bar = ProgressBar::new(units as u64);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    // The bar counts work units (rows of laser points), the summary points: the bar says which.
    let template = format!(
        "{{bar:40}} {{pos}}/{{len}} units ({} laser points)  {{elapsed}} elapsed, ETA {{eta}}",
        plan.shard_points(a.shard)
    );
    bar.set_style(
        ProgressStyle::with_template(&template)
            .expect("static template")
            .with_key("eta", crate::cmd::progress::eta),
    );
    // The render's first progress call gives the units its checkpoint already held.
    let reused = std::sync::OnceLock::new();
    let say_reused = |done: usize| {
        if a.resume && had_checkpoint && !quiet {
            bar.suspend(|| {
                eprintln!(
                    "murk: --resume: {done} of {units} units reused from {}, {} to render",
                    ckpt_path.display(),
                    units - done.min(units)
                )
            });
        }
        done
    };
    let t0 = Instant::now();
    crate::cmd::RENDERING.store(true, Ordering::SeqCst);
    let rendered = stored.run(
        &stored.options(spp, a.seed, a.shard),
        &|done, _| {
            reused.get_or_init(|| say_reused(done));
            bar.set_position(done as u64)
        },
        &crate::cmd::STOP,
    );
    crate::cmd::RENDERING.store(false, Ordering::SeqCst);
    rendered?;
    bar.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    if !quiet {
        let points = plan.shard_points(a.shard);
        let paths = points as f64 * spp as f64;
        eprintln!(
            "murk: {} points × {spp} spp in {secs:.2} s ({:.2} M paths/s) → {}",
            points,
            paths / secs / 1e6,
            stored
                .outputs()
                .iter()
                .map(|o| o.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}

pub fn run_merge(a: MergeArgs, quiet: bool) -> anyhow::Result<()> {
    let inputs: Vec<&Path> = a.parts.iter().map(|p| p.as_path()).collect();
    murk_io::check_h5_output(&a.out, &inputs)?;
    let parts = a
        .parts
        .iter()
        .map(|p| Ok((p.clone(), murk_io::read_capture(p)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let cap = merge(&parts)?;
    murk_io::write_capture(&a.out, &cap)?;
    if !quiet {
        eprintln!("murk: merged {} parts → {}", parts.len(), a.out.display());
    }
    Ok(())
}
