//! The whole pipeline on a built-in scene, in seconds, with pictures to look at (`murk demo`).

use crate::report::page;
use murk_core::{Axis, DVec3, Progress, Result, TimeAxis, Volume};
use murk_recon::{PfForm, PfParams};
use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
use murk_view::{pictures, write_grid_png, FigureGrid};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Depth of the demo letter behind the wall.
pub const LETTER_DEPTH_M: f64 = 1.0;

/// What [`demo`] wrote and measured.
pub struct Demo {
    pub capture: PathBuf,
    pub volume: PathBuf,
    pub index: PathBuf,
    /// Depth of the reconstruction's brightest voxel (the letter is at [`LETTER_DEPTH_M`]).
    pub peak_depth_m: f64,
    pub synth_s: f64,
    pub recon_s: f64,
}

/// Synthesises the paper's configuration scaled down (a 64² laser grid on a 1 m × 1 m wall, one SPAD
/// point at its centre, a planar Lambertian Z 0.4 m tall 1 m behind it, 3 mm bins), reconstructs it
/// with fast Phasor Fields, and writes the capture, the volume, the pictures and index.html into
/// `dir` (created if missing).
pub fn demo(dir: &Path, progress: &dyn Progress) -> Result<Demo> {
    let t0 = Instant::now();
    murk_io::create_output_dir(dir)?;
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
    let capture = dir.join("capture.h5");
    murk_io::write_capture(&capture, &cap)?;
    let synth_s = t0.elapsed().as_secs_f64();

    // The 64 wall points' pixel centres on the 1 m wall.
    let edge_m = 0.5 - 0.5 / 64.0;
    let volume = Volume {
        x: Axis::new(-edge_m, edge_m, 64),
        y: Axis::new(-edge_m, edge_m, 64),
        z: Axis::new(0.5, 1.5, 51),
    };
    let t1 = Instant::now();
    let rec = murk_recon::reconstruct(&cap, &volume, &PfParams::default(), PfForm::Fast, progress)?;
    let recon_s = t1.elapsed().as_secs_f64();
    let provenance: Vec<(String, String)> = crate::report::run_provenance()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    let mut params = vec![("scene".to_string(), format!("planar Z letter (0.4 m) {LETTER_DEPTH_M} m behind a 1 m × 1 m wall, 64 × 64 laser points, one SPAD point at the centre, 1024 bins of 3 mm"))];
    // The provenance already names murk's version; the summary's own row would repeat it.
    params.extend(
        rec.summary(&capture.display().to_string(), cap.kind(), recon_s)
            .into_iter()
            .filter(|(k, _)| k != "murk_version"),
    );
    params.push((
        "synthesis + capture write seconds".into(),
        format!("{synth_s:.3}"),
    ));
    let volume_path = dir.join("volume.npy");
    let table: Vec<(String, String)> = provenance.iter().chain(&params).cloned().collect();
    let normals = rec.normals.as_deref();
    murk_io::write_volume(&volume_path, &volume, &rec.intensity, normals, &table)?;
    let views = pictures::write_views(dir, &volume, &rec.intensity, normals)?;
    let index = write_page(dir, &volume, &rec.intensity, &provenance, &params, &views)?;
    Ok(Demo {
        capture,
        volume: volume_path,
        index,
        peak_depth_m: rec.peak().0[2],
        synth_s,
        recon_s,
    })
}

/// The demo's page, in the study report's look: provenance first, the three projections as figure
/// grids of one cell each (spatial axes in metres, named, and a colour bar, as the report's figures),
/// the depth map, then the reconstruction's parameters. `views` are the pictures written beside.
fn write_page(
    dir: &Path,
    volume: &Volume,
    intensity: &[f32],
    provenance: &[(String, String)],
    params: &[(String, String)],
    views: &[(PathBuf, String)],
) -> Result<PathBuf> {
    let mut h = page::head(
        "murk demo",
        "murk demo: Phasor Fields reconstruction of a hidden Z",
    );
    h.push_str(&page::key_values("provenance", provenance));
    h.push_str("<h2>Reconstruction</h2>\n");
    let v = murk_view::views(volume, intensity);
    for (name, plane, caption) in [
        (
            "front-axes.png",
            &v.front,
            "front: the maximum along depth, seen from the wall (+x on the left)",
        ),
        (
            "top-axes.png",
            &v.top,
            "top: the maximum along y, depth growing downwards",
        ),
        (
            "side-axes.png",
            &v.side,
            "side: the maximum along x, depth growing to the right",
        ),
    ] {
        let grid = FigureGrid {
            title: String::new(),
            row_labels: vec![],
            col_labels: vec![],
            cells: vec![vec![Some(plane)]],
            shared_scale: false,
        };
        write_grid_png(&dir.join(name), &grid, 320)?;
        h.push_str(&page::figure("view", &page::img(name, caption), caption));
    }
    // The depth map's colours are depths, not intensities: drawn as `murk reconstruct --pictures`
    // draws it, its range in the caption.
    if let Some((path, caption)) = views.iter().find(|(p, _)| p.ends_with("depth.png")) {
        let name = path
            .file_name()
            .map_or("depth.png".into(), |n| n.to_string_lossy());
        h.push_str(&page::figure(
            "view",
            &page::img(&name, "depth map"),
            caption,
        ));
    }
    h.push_str("<h2>Parameters</h2>\n");
    h.push_str(&page::key_values("parameters", params));
    page::write(dir, h)
}
