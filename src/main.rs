//! `murk`: simulate and reconstruct hidden scenes behind a diffuser or relay wall, inside fog, smoke or
//! turbid water. Run `murk --help` for the commands, `murk <command> --help` for each one.

use clap::{Parser, Subcommand};

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
    /// Measure reconstruction speed (paper format; side by side with y-tal when available).
    Bench(cmd::bench::BenchArgs),
    /// Render a scene file (scenes/*.toml) into a capture by time-resolved volumetric path tracing.
    Render(cmd::render::RenderArgs),
    /// Import a real confocal capture (CDT v7.3 `meas`, LCT v5 `rect_data`) into a y-tal HDF5 file.
    Import(cmd::import::ImportArgs),
    /// Reproduce a figure: `real` reconstructs the CDT captures with CDT and Phasor Fields.
    Figure(cmd::figure::FigureArgs),
    /// Run a study: `paper` renders, reconstructs and scores every experiment of Luesia et al.
    Experiment(cmd::experiment::ExperimentArgs),
    /// Sum the parts of a sharded render (`murk render --shard i/N`) into one capture.
    Merge(cmd::render::MergeArgs),
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(), // --help and --version
        Err(e) => {
            // clap's usage errors span several lines; keep murk's one-line contract.
            let text = e.to_string();
            let first = text
                .lines()
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ");
            eprintln!("murk: error: {first} (see murk --help)");
            std::process::exit(2);
        }
    };
    let result: anyhow::Result<()> = match cli.command {
        Command::Demo(a) => cmd::demo::run(a, cli.quiet),
        Command::Info(a) => cmd::info::run(a),
        Command::Synth(a) => cmd::synth::run(a, cli.quiet),
        Command::Reconstruct(a) => cmd::reconstruct::run(a, cli.quiet),
        Command::Bench(a) => cmd::bench::run(a, cli.quiet),
        Command::Render(a) => cmd::render::run(a, cli.quiet),
        Command::Import(a) => cmd::import::run(a, cli.quiet),
        Command::Figure(a) => cmd::figure::run(a, cli.quiet),
        Command::Experiment(a) => cmd::experiment::run(a, cli.quiet),
        Command::Merge(a) => cmd::render::run_merge(a, cli.quiet),
    };
    if let Err(e) = result {
        // One line, no backtrace: the chain of causes joined, outermost first.
        let msg = e
            .chain()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(": ");
        eprintln!("murk: error: {msg}");
        std::process::exit(1);
    }
}
