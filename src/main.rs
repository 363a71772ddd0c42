//! `murk`: simulate and reconstruct hidden scenes behind a diffuser or relay wall, inside fog, smoke or
//! turbid water. Run `murk --help` for the commands, `murk <command> --help` for each one.

use clap::{Parser, Subcommand};
use murk_core::report::{clap_one_line, error_line};
use std::sync::atomic::Ordering;

mod cmd;

#[derive(Parser)]
#[command(
    name = "murk",
    version,
    about = "Non-line-of-sight imaging through scattering media: simulate, reconstruct, study",
    long_about = "murk simulates time-resolved captures of scenes hidden behind a relay wall or a diffuser, \
optionally inside a scattering medium (fog, smoke, turbid water), and reconstructs them with Phasor Fields \
and classic baselines. Captures are y-tal HDF5 files (time as optical path in metres).\n\n\
Start with `murk demo`, then `murk synth --help` and `murk reconstruct --help`.",
    propagate_version = true
)]
struct Cli {
    /// Print nothing but errors (no progress bars, no summaries).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build a capture of a hidden Z letter, reconstruct it and write pictures into murk-demo/.
    Demo(cmd::demo::DemoArgs),
    /// Describe a capture file: kind, points, time axis, H statistics, scene_info.
    Info(cmd::info::InfoArgs),
    /// Make an analytic capture (first hidden bounce) of points and planar shapes.
    Synth(cmd::synth::SynthArgs),
    /// Reconstruct a capture into a volume (.npy / .h5) and pictures.
    Reconstruct(cmd::reconstruct::ReconstructArgs),
    /// Estimate the medium (μt, albedo, HG g) from a capture's medium-only bins.
    Medium(cmd::medium::MediumArgs),
    /// Render a scene file (scenes/*.toml) into a capture by time-resolved volumetric path tracing.
    Render(cmd::render::RenderArgs),
    /// Import a real capture (a public NLOS dataset with --format, or any 3-D array) into y-tal HDF5.
    Import(cmd::import::ImportArgs),
    /// Reproduce a figure: `real` reconstructs the CDT captures with CDT and Phasor Fields; `media`
    /// the foam captures with every method.
    Figure(cmd::figure::FigureArgs),
    /// Run a study: `paper` renders, reconstructs and scores every experiment of Luesia et al.
    Experiment(cmd::experiment::ExperimentArgs),
    /// Sum the parts of a sharded render (`murk render --shard i/N`) into one capture.
    Merge(cmd::render::MergeArgs),
}

fn main() {
    restore_default_sigpipe();
    // The library's messages name options as this front end spells them: flags.
    murk_core::spelling::set_front_end(murk_core::Spelling::Cli);
    // Ctrl-C and SIGTERM: during a render, the first one stops it after the units in progress, whose
    // checkpoint then keeps every finished unit (main ends the process once the render returns).
    // Otherwise, or the second time, remove the temporaries of writes in progress (finished outputs
    // and render checkpoints stay), then end as a shell expects of an interrupted command.
    let _ = ctrlc::set_handler(|| {
        let again = cmd::STOP.swap(true, Ordering::SeqCst);
        if cmd::RENDERING.load(Ordering::SeqCst) && !again {
            if cmd::ON_INTERRUPT.get().is_some() {
                eprintln!(
                    "murk: stopping after the work units in progress (Ctrl-C again ends at once)"
                );
            }
            return;
        }
        let _held = murk_io::remove_temporaries();
        if let Some(note) = cmd::ON_INTERRUPT.get() {
            eprintln!(
                "murk: {}",
                if again { &note.at_once } else { &note.stopped }
            );
        }
        std::process::exit(130);
    });
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(), // --help and --version
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // clap's text here is the help, whose first line is no error.
            eprintln!("murk: error: no command given (see murk --help)");
            std::process::exit(2);
        }
        Err(e) => {
            eprintln!(
                "murk: error: {} (see murk --help)",
                clap_one_line(&e.to_string(), std::env::args_os())
            );
            std::process::exit(2);
        }
    };
    if let Err(e) = murk_core::Limits::check_env() {
        eprintln!("murk: error: {e}");
        std::process::exit(2);
    }
    let result: anyhow::Result<()> = match cli.command {
        Command::Demo(a) => cmd::demo::run(a, cli.quiet),
        Command::Info(a) => cmd::info::run(a),
        Command::Synth(a) => cmd::synth::run(a, cli.quiet),
        Command::Reconstruct(a) => cmd::reconstruct::run(a, cli.quiet),
        Command::Medium(a) => cmd::medium::run(a, cli.quiet),
        Command::Render(a) => cmd::render::run(a, cli.quiet),
        Command::Import(a) => cmd::import::run(a, cli.quiet),
        Command::Figure(a) => cmd::figure::run(a, cli.quiet),
        Command::Experiment(a) => cmd::experiment::run(a, cli.quiet),
        Command::Merge(a) => cmd::render::run_merge(a, cli.quiet),
    };
    if let Err(e) = result {
        if cmd::STOP.load(Ordering::SeqCst) {
            // A render stopped by Ctrl-C: its checkpoint is whole.
            if let Some(note) = cmd::ON_INTERRUPT.get() {
                eprintln!("murk: {}", note.stopped);
            }
            std::process::exit(130);
        }
        eprintln!("murk: error: {}", error_line(e.as_ref()));
        std::process::exit(1);
    }
}

/// Rust ignores SIGPIPE, so writing to a closed pipe (`murk info x.h5 | head -1`) would fail and
/// `println!` panic; with the default action the process ends quietly, like other command-line tools.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is always valid.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
