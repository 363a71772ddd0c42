//! `murk experiment paper`: the paper's study in one command (murk-study does the work).

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use murk_study::plan::{Figure, Scale, StudyOptions};
use murk_study::run::{Event, Observer};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StudyArg {
    /// Luesia et al.: Fig. 3a–c, 4 and 5.
    Paper,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ScaleArg {
    /// 64² laser points, 1 200 bins (minutes on a laptop).
    Quick,
    /// The paper's 128² laser points × 4096 bins (CPU-hours).
    Paper,
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk experiment paper --out study/                       # every figure, quick scale\n  \
murk experiment paper --out study/ --only fig3a,fig4 --seeds 3\n  \
murk experiment paper --out g/ --cell \"α = 0.83\" --only fig3c --seeds 2 --spp 2048\n  \
murk experiment paper --out study/ --list-tasks > tasks.sh   # run them anywhere, then:\n  \
murk experiment paper --out study/                       # picks the finished renders up\n\n\
Writes DIR/plan.json (the render tasks), DIR/renders/ (captures, keyed by their resolved scene), a PNG grid\n\
per figure and compensation, DIR/metrics.csv, DIR/objects.csv, DIR/plots/*.svg and DIR/index.html.\n\
A finished capture is reused; an interrupted one resumes from its checkpoint.")]
pub struct ExperimentArgs {
    /// Which study.
    #[arg(value_enum)]
    pub study: StudyArg,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, value_enum, default_value = "quick")]
    pub scale: ScaleArg,
    /// Only these figures (comma-separated: fig3a, fig3b, fig3c, fig4, fig5).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Only cells whose label holds these whole words (repeatable), e.g. "fig3c g = 0.7 α = 0.83" or "α = 0.5".
    #[arg(long = "cell", value_name = "TEXT")]
    pub cells: Vec<String>,
    /// Independent renders per cell (metrics get mean ± spread).
    #[arg(long, default_value_t = 1)]
    pub seeds: u64,
    /// Render tasks per capture (for spreading one capture over several machines).
    #[arg(long, default_value_t = 1)]
    pub shards: usize,
    /// Paths per laser point (default: the scale's: quick 256 for the Z, 1024 for the shelf).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=murk_core::Limits::MAX_SPP))]
    pub spp: Option<u64>,
    /// Folder with z-letter.toml and shelf.toml.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Print one `murk render` command per task (for any executor) and exit.
    #[arg(long)]
    pub list_tasks: bool,
    /// Worker threads (default: all cores). The commands of --list-tasks leave threads to their executor.
    #[arg(long, value_parser = crate::cmd::parse_threads, conflicts_with = "list_tasks")]
    pub threads: Option<usize>,
}

/// A bar per task: the cell, task i/N and the ETA of the whole list.
struct Bars {
    bar: ProgressBar,
    quiet: bool,
}

impl Observer for Bars {
    fn event(&self, e: Event) {
        match e {
            Event::Task {
                index,
                total,
                label,
                eta_s,
            } => {
                // Renders run from here until the first step after them.
                crate::cmd::RENDERING.store(true, Ordering::SeqCst);
                let eta = eta_s.map_or("…".to_string(), |s| format!("{:.0} s", s));
                let msg = format!("task {index}/{total} {label}, ETA {eta}");
                if self.bar.is_hidden() && !self.quiet {
                    eprintln!("murk: {msg}");
                }
                self.bar.set_message(msg);
            }
            Event::Units { done, total } => {
                self.bar.set_length(total as u64);
                self.bar.set_position(done as u64);
            }
            Event::Step(s) => {
                crate::cmd::RENDERING.store(false, Ordering::SeqCst);
                self.bar.set_message(s.to_string());
                self.bar.set_length(0);
                self.bar.set_position(0);
            }
            Event::Note(s) if !self.quiet => self.bar.suspend(|| eprintln!("murk: {s}")),
            Event::Note(_) => {}
        }
    }
    fn stop(&self) -> Option<&AtomicBool> {
        Some(&crate::cmd::STOP)
    }
}

pub fn run(a: ExperimentArgs, quiet: bool) -> anyhow::Result<()> {
    let only = a
        .only
        .iter()
        .map(|s| Figure::parse(s))
        .collect::<Result<Vec<_>, _>>()?;
    let opt = StudyOptions {
        scale: match a.scale {
            ScaleArg::Quick => Scale::Quick,
            ScaleArg::Paper => Scale::Paper,
        },
        only,
        cells: a.cells.clone(),
        seeds: a.seeds,
        shards: a.shards,
        spp: a.spp,
        scenes_dir: a.scenes.clone(),
    };
    if a.list_tasks {
        // This binary by its absolute path, so that the commands run without murk on PATH.
        let exe = std::env::current_exe()
            .map_err(|e| anyhow::anyhow!("cannot find the running murk binary: {e}"))?;
        let commands = murk_study::list_tasks(&a.out, &opt, &exe)?;
        for c in &commands {
            println!("{c}");
        }
        if commands.is_empty() && !quiet {
            eprintln!(
                "murk: every render of this plan is done; run without --list-tasks for the report"
            );
        }
        return Ok(());
    }
    let bar = ProgressBar::new(0);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg}\n{bar:40} {pos}/{len} units, {elapsed} elapsed")
            .expect("static template"),
    );
    if !quiet {
        let _ = crate::cmd::ON_INTERRUPT.set(crate::cmd::Interrupted {
            stopped: "interrupted: finished renders and checkpoints stay in the folder; the same command goes on from them".into(),
            at_once: "interrupted at once: the running render's units since its checkpoint's last save are lost; finished renders stay, and the same command goes on from them".into(),
        });
    }
    let pool = crate::cmd::pool(a.threads)?;
    let obs = Bars { bar, quiet };
    let index = pool.install(|| murk_study::run_study(&a.out, &opt, &obs))?;
    obs.bar.finish_and_clear();
    if !quiet {
        eprintln!("murk: study written → {}", index.display());
    }
    Ok(())
}
