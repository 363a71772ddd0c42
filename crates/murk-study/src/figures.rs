//! What the figures of real captures share (`murk figure real`, `murk figure media`): the output
//! folder's checks, a reconstruction's surface depth, and front views side by side in one PNG.

use murk_core::{Error, Reconstruction, Result};
use murk_view::pictures::{self, Plane};
use std::path::Path;

/// Screen pixels per voxel of the largest front view in a grid, and the gap between cells.
const ZOOM: usize = 6;
const GAP: usize = 6;

/// Refuses an `out` that cannot become the figure's folder: a file, or the data folder itself
/// (results do not go among the captures they are made from). The folder is made only once there
/// is something to put in it, so a failed or interrupted run leaves none behind.
pub(crate) fn check_out(data: &Path, out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        return Err(Error::param(format!(
            "{}: is a file; the figure needs a folder",
            out.display()
        )));
    }
    if murk_io::same_target(out, data) {
        return Err(Error::param(format!(
            "{}: is the --data folder; the figure needs a folder of its own",
            out.display()
        )));
    }
    Ok(())
}

/// Depth of the brightest voxel, and the median per-pixel argmax depth over pixels whose
/// maximum-intensity projection exceeds half of its maximum (NaN when no pixel does: an all-zero
/// reconstruction).
pub(crate) fn depths(rec: &Reconstruction) -> (f64, f64) {
    let (p, _) = rec.peak();
    let v = pictures::views(&rec.volume, &rec.intensity);
    let max = v.front.values.iter().cloned().fold(f32::MIN, f32::max);
    let zs: Vec<f64> = v
        .front
        .values
        .iter()
        .zip(&v.depth.values)
        .filter(|(f, _)| **f > 0.5 * max)
        .map(|(_, d)| *d as f64)
        .collect();
    (p[2], murk_core::median(&zs))
}

/// Front views in a grid, `columns[c][r]` at column c and row r, each scaled to the largest one's
/// cell (nearest voxel) and normalised to [0, 1]; NaN (black) between cells and for a missing one.
pub(crate) fn grid_plane(columns: &[Vec<Option<&Reconstruction>>], extents: String) -> Plane {
    let front = |r: &Reconstruction| pictures::views(&r.volume, &r.intensity).front;
    let fronts: Vec<Vec<_>> = columns
        .iter()
        .map(|col| col.iter().map(|c| c.map(front)).collect())
        .collect();
    let (cw, ch) = fronts.iter().flatten().flatten().fold((1, 1), |(w, h), f| {
        (w.max(f.width * ZOOM), h.max(f.height * ZOOM))
    });
    let rows = columns.iter().map(Vec::len).max().unwrap_or(0);
    let (w, h) = (
        (columns.len() * (cw + GAP)).saturating_sub(GAP).max(1),
        (rows * (ch + GAP)).saturating_sub(GAP).max(1),
    );
    let mut values = vec![f32::NAN; w * h];
    for (col, cells) in fronts.iter().enumerate() {
        for (row, f) in cells.iter().enumerate() {
            let Some(f) = f else { continue };
            let max = f.values.iter().copied().fold(f32::MIN, f32::max);
            let min = f.values.iter().copied().fold(f32::MAX, f32::min);
            let span = (max - min).max(f32::MIN_POSITIVE);
            for y in 0..ch {
                for x in 0..cw {
                    let v = f.values[(y * f.height / ch) * f.width + x * f.width / cw];
                    values[(row * (ch + GAP) + y) * w + col * (cw + GAP) + x] = (v - min) / span;
                }
            }
        }
    }
    Plane {
        width: w,
        height: h,
        values,
        extents,
        axes: None,
    }
}
