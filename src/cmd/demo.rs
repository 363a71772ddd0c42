//! `murk demo`: the whole pipeline on a built-in scene, in seconds, with pictures to look at.

use crate::cmd::progress::{say, Bar};
use anyhow::Context;
use clap::Args;
use murk_core::{Axis, DVec3, TimeAxis, Volume};
use murk_recon::{PfForm, PfParams};
use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
use murk_view::pictures;
use std::path::PathBuf;

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk demo                      # writes murk-demo/ (capture, volume, pictures, index.html)\n  \
murk demo --out /tmp/z-demo")]
pub struct DemoArgs {
    /// Folder for the capture, the volume, the pictures and index.html.
    #[arg(long, default_value = "murk-demo")]
    pub out: PathBuf,
}

/// Depth of the demo letter behind the wall.
const LETTER_DEPTH_M: f64 = 1.0;

pub fn run(a: DemoArgs, quiet: bool) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    std::fs::create_dir_all(&a.out).with_context(|| a.out.display().to_string())?;
    // The paper's configuration scaled down: a laser grid on a 1 m × 1 m wall, one SPAD point at its
    // centre, a planar Z (0.4 m tall) 1 m behind it, Lambertian, 3 mm bins.
    let layout = CaptureLayout {
        kind: LayoutKind::LaserGridSinglePoint,
        wall_size_m: 1.0,
        grid: 64,
        point: DVec3::ZERO,
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.003,
            bins: 1024,
        },
        laser_xyz: None,
        sensor_xyz: None,
    };
    let mut cap = layout.empty_capture()?;
    let outline = murk_synth::z_letter_outline()
        .iter()
        .map(|p| [p[0] * 0.5, p[1] * 0.5])
        .collect();
    let letter = Target::Polygon {
        outline,
        offset: [0.0; 2],
        depth_m: LETTER_DEPTH_M,
        albedo: 1.0,
        spacing_m: 1.0 / 64.0 / 2.0,
    };
    add_first_bounce(
        &mut cap,
        &letter.scatterers()?,
        &SynthOptions {
            cosines: true,
            ..SynthOptions::default()
        },
    )?;
    cap.scene_info = format!(
        "generator: murk demo\nmurk_version: {}\ntarget: Z letter 0.4 m at {LETTER_DEPTH_M} m\n",
        env!("CARGO_PKG_VERSION")
    );
    let capture_path = a.out.join("capture.h5");
    murk_io::write_capture(&capture_path, &cap)?;
    let synth_s = t0.elapsed().as_secs_f64();

    let c = 0.5 - 0.5 / 64.0;
    let volume = Volume {
        x: Axis::new(-c, c, 64),
        y: Axis::new(-c, c, 64),
        z: Axis::new(0.5, 1.5, 51),
    };
    let bar = Bar::new("reconstruct", quiet);
    let t1 = std::time::Instant::now();
    let rec = murk_recon::reconstruct(&cap, &volume, &PfParams::default(), PfForm::Fast, &bar)?;
    bar.finish();
    let recon_s = t1.elapsed().as_secs_f64();
    let mut table = rec.summary(&capture_path.display().to_string(), cap.kind(), recon_s);
    table.insert(0, ("scene".into(), format!("planar Z letter (0.4 m) {LETTER_DEPTH_M} m behind a 1 m × 1 m wall, 64 × 64 laser points, one SPAD point at the centre, 1024 bins of 3 mm")));
    table.push((
        "synthesis + capture write seconds".into(),
        format!("{synth_s:.3}"),
    ));
    let volume_path = a.out.join("volume.npy");
    murk_io::write_volume(&volume_path, &volume, &rec.intensity, &table)?;
    let pics = pictures::write_views(&a.out, &volume, &rec.intensity)?;
    let index = pictures::write_index(
        &a.out,
        "murk demo: Phasor Fields reconstruction of a hidden Z",
        &table,
        &pics,
    )?;
    let (peak, _) = rec.peak();
    say(quiet, format!("murk demo: hidden Z at {LETTER_DEPTH_M} m; reconstruction peak at depth {:.3} m ({:.2} s synthesis, {:.2} s reconstruction)", peak[2], synth_s, recon_s));
    say(quiet, format!("  capture  {}", capture_path.display()));
    say(quiet, format!("  volume   {}", volume_path.display()));
    say(quiet, format!("  pictures {}", index.display()));
    Ok(())
}
