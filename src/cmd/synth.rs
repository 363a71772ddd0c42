//! `murk synth`: analytic captures (first hidden bounce only) of points and planar shapes.

use crate::cmd::progress::say;
use clap::Args;
use murk_core::{Capture, DVec3, TimeAxis};
use murk_synth::{floats, synthesize, CaptureLayout, SynthOptions, Synthesis};
use std::path::PathBuf;

#[derive(Args, Clone)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
murk synth --out point.h5 --target point:0.1,-0.2,1.0\n  \
murk synth --out z.h5 --kind laser-grid --wall-size 2 --grid 128 --bins 4096 --bin-width 0.0009 --start 3.5 --target z:2.0\n  \
murk synth --out fog.h5 --target t:1.0 --mu-t 1.0 --jitter 0.003 --cosines"
)]
pub struct SynthArgs {
    /// Output capture (y-tal HDF5).
    #[arg(long)]
    pub out: PathBuf,
    /// laser-grid (grid of laser points, one SPAD point: the paper's data), single (one laser point,
    /// sensor grid), confocal, or exhaustive (every laser point × every sensor point).
    #[arg(long, default_value = "laser-grid")]
    pub kind: String,
    /// Side of the square relay wall at z = 0, centred on the origin (m).
    #[arg(long = "wall-size", value_name = "M", default_value_t = 1.0)]
    pub wall_size_m: f64,
    /// Grid points per side of the wall (pixel centres).
    #[arg(long, default_value_t = 32)]
    pub grid: usize,
    /// The single wall point (SPAD point or laser point) as x,y (m).
    #[arg(long, default_value = "0,0", value_parser = parse_xy)]
    pub point: [f64; 2],
    /// Hidden geometry, repeatable: point:X,Y,Z | z:DEPTH (the paper's Z letter, 0.8 m) |
    /// t:DEPTH (a 0.5 × 0.5 m letter T) | polygon:DEPTH:x,y;x,y;... (planar, parallel to the wall).
    #[arg(long = "target", required = true)]
    pub targets: Vec<String>,
    /// Number of time bins.
    #[arg(long, default_value_t = 2048)]
    pub bins: usize,
    /// Bin width as optical path (m); 0.003 m ≈ 10 ps.
    #[arg(long = "bin-width", value_name = "M", default_value_t = 0.003)]
    pub bin_width_m: f64,
    /// Optical path at the start of bin 0 (m).
    #[arg(long = "start", value_name = "M", default_value_t = 0.0)]
    pub start_m: f64,
    /// Laser device position x,y,z: paths then include laser → wall (needs --sensor-xyz too).
    #[arg(long, value_parser = parse_xyz, requires = "sensor_xyz")]
    pub laser_xyz: Option<DVec3>,
    /// SPAD device position x,y,z: paths then include wall → SPAD.
    #[arg(long, value_parser = parse_xyz, requires = "laser_xyz")]
    pub sensor_xyz: Option<DVec3>,
    /// Extinction of a medium filling the hidden side (1/m): ballistic attenuation exp(−μt·path).
    #[arg(long = "mu-t", value_name = "PER_M", default_value_t = 0.0)]
    pub mu_t_per_m: f64,
    /// Standard deviation of a Gaussian timing jitter (m of path).
    #[arg(long = "jitter", value_name = "M", default_value_t = 0.0)]
    pub jitter_m: f64,
    /// Apply Lambertian cosines at the wall and at surfaces.
    #[arg(long)]
    pub cosines: bool,
}

fn parse_xy(s: &str) -> Result<[f64; 2], String> {
    floats::<2>(s)
}

fn parse_xyz(s: &str) -> Result<DVec3, String> {
    floats::<3>(s).map(DVec3::from_array)
}

/// Builds the capture described by `a` (no file I/O).
pub fn build(a: &SynthArgs) -> anyhow::Result<Capture> {
    Ok(synthesize(&Synthesis {
        layout: CaptureLayout {
            kind: a.kind.parse()?,
            wall_size_m: a.wall_size_m,
            grid: a.grid,
            point: DVec3::new(a.point[0], a.point[1], 0.0),
            time: TimeAxis {
                start_m: a.start_m,
                bin_width_m: a.bin_width_m,
                bins: a.bins,
            },
            laser_xyz: a.laser_xyz,
            sensor_xyz: a.sensor_xyz,
        },
        targets: a.targets.clone(),
        options: SynthOptions {
            cosines: a.cosines,
            mu_t_per_m: a.mu_t_per_m,
            jitter_sigma_m: a.jitter_m,
        },
    })?)
}

pub fn run(a: SynthArgs, quiet: bool) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    murk_io::check_h5_output(&a.out, &[])?;
    let cap = build(&a)?;
    murk_io::write_capture(&a.out, &cap)?;
    say(
        quiet,
        format!(
            "wrote {} ({}, {} histograms × {} bins) in {:.2} s",
            a.out.display(),
            cap.kind(),
            cap.n_hist(),
            cap.time.bins,
            t0.elapsed().as_secs_f64()
        ),
    );
    Ok(())
}
