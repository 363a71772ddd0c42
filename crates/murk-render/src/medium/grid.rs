//! A density grid from a `.npy` file: nx × ny × nz cells of constant density filling the medium's
//! box, σt = density × μt. Constant cells make the optical depth along a segment an exact sum over
//! the cells it crosses (a 3-D DDA), which the balance heuristic's free-flight densities need.

use super::Segment;
use crate::geometry::Aabb;
use murk_core::{DVec3, DensityCells, Error, Result};
use std::path::Path;

/// The most cells a density grid may have (256³: 64 MiB of f32).
pub const MAX_CELLS: u64 = murk_core::MAX_DENSITY_CELLS;

/// FNV-1a of the cell counts and densities: a short name for a density grid (a scene's key records
/// it; the medium's estimate names a capture's own cells by it).
pub fn density_fingerprint(cells: &DensityCells) -> u64 {
    let dims = cells
        .dims()
        .into_iter()
        .flat_map(|d| (d as u64).to_le_bytes());
    let values = cells.values().iter().flat_map(|v| v.to_le_bytes());
    crate::hash::fnv1a(dims.chain(values))
}

#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Cell counts along x, y, z.
    dims: [usize; 3],
    min: DVec3,
    cell_m: DVec3,
    /// The densities in the file's C order: cell (i, j, k) at (i·ny + j)·nz + k.
    cells: DensityCells,
    mu_t_per_m: f64,
    /// The largest σt of any cell: the majorant of null-collision tracking.
    pub majorant_per_m: f64,
}

impl Grid {
    /// The grid of `path` (shape (nx, ny, nz), x slowest) stretched over `region`, with σt =
    /// density × `mu_t_per_m`. Errors name the file: a rank other than 3, more than `MAX_CELLS`
    /// (256³), a density that is negative or not finite, or no density above zero.
    pub fn load(path: &Path, mu_t_per_m: f64, region: &Aabb) -> Result<Grid> {
        let (shape, density) = murk_io::read_npy_f32_with_limit(path, MAX_CELLS * 4)?;
        let cells = DensityCells::new(&shape, density).map_err(|e| Error::format(path, e))?;
        Ok(Grid::from_cells(cells, mu_t_per_m, region))
    }

    /// The grid of `cells` stretched over `region`, with σt = density × `mu_t_per_m`.
    pub fn from_cells(cells: DensityCells, mu_t_per_m: f64, region: &Aabb) -> Grid {
        let dims = cells.dims();
        let [nx, ny, nz] = dims.map(|d| d as f64);
        Grid {
            dims,
            min: region.min,
            cell_m: (region.max - region.min) / DVec3::new(nx, ny, nz),
            majorant_per_m: cells.max() as f64 * mu_t_per_m,
            cells,
            mu_t_per_m,
        }
    }

    /// The density cells (what a capture rendered through the grid stores).
    pub fn cells(&self) -> &DensityCells {
        &self.cells
    }

    /// What the scene's key records of the file: [`density_fingerprint`] of its cells.
    pub fn fingerprint(&self) -> u64 {
        density_fingerprint(&self.cells)
    }

    /// The cell holding `p` along each axis (points on or past the box's faces in its outer cells).
    fn index(&self, p: DVec3) -> [usize; 3] {
        let rel = (p - self.min) / self.cell_m;
        [0, 1, 2].map(|a| (rel[a].max(0.0) as usize).min(self.dims[a] - 1))
    }

    pub fn sigma_t_at(&self, p: DVec3) -> f64 {
        let [i, j, k] = self.index(p);
        self.cells.values()[(i * self.dims[1] + j) * self.dims[2] + k] as f64 * self.mu_t_per_m
    }

    /// ∫σt along `seg` (inside the box): each crossed cell's σt times the length within it
    /// (Amanatides & Woo's traversal). Connections make it the renderer's innermost loop in a grid: it
    /// steps the flat cell index and counts the cells left along each axis instead of bounds checks.
    pub fn optical_depth(&self, seg: &Segment) -> f64 {
        let start = seg.o + seg.d * seg.t0;
        let at = self.index(start);
        let [_, ny, nz] = self.dims;
        let stride = [ny * nz, nz, 1];
        let mut flat = (at[0] * ny + at[1]) * nz + at[2];
        let mut next = [f64::INFINITY; 3];
        let mut delta = [0.0; 3];
        let mut left = [0usize; 3];
        let mut step = [0isize; 3];
        for a in 0..3 {
            let d = seg.d[a];
            let face = |i: usize| self.min[a] + i as f64 * self.cell_m[a];
            if d > 0.0 {
                next[a] = seg.t0 + (face(at[a] + 1) - start[a]) / d;
                delta[a] = self.cell_m[a] / d;
                left[a] = self.dims[a] - 1 - at[a];
                step[a] = stride[a] as isize;
            } else if d < 0.0 {
                next[a] = seg.t0 + (face(at[a]) - start[a]) / d;
                delta[a] = -self.cell_m[a] / d;
                left[a] = at[a];
                step[a] = -(stride[a] as isize);
            }
        }
        let density = self.cells.values();
        let (mut t, mut sum) = (seg.t0, 0.0);
        loop {
            let a = if next[0] < next[1] {
                if next[0] < next[2] {
                    0
                } else {
                    2
                }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            let end = next[a];
            let here = density[flat] as f64;
            // Past the last cell along an axis only rounding is left: the rest lies in this cell.
            if end >= seg.t1 || left[a] == 0 {
                return (sum + here * (seg.t1 - t).max(0.0)) * self.mu_t_per_m;
            }
            sum += here * (end - t).max(0.0);
            t = end;
            left[a] -= 1;
            flat = flat.wrapping_add_signed(step[a]);
            next[a] += delta[a];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5 × 4 × 3 grid of uneven densities: the cell walk's optical depth against a 200 000-step
    /// midpoint sum of the cell lookups, along axis-parallel, diagonal and through-corner segments.
    #[test]
    fn optical_depth_matches_point_sum() {
        let dims = [5, 4, 3];
        let region = Aabb {
            min: DVec3::new(-1.0, -0.5, 0.2),
            max: DVec3::new(1.0, 1.5, 1.7),
        };
        let density: Vec<f32> = (0..60).map(|i| ((i * 37 % 11) as f32) / 7.0).collect();
        let g = Grid::from_cells(DensityCells::new(&dims, density).unwrap(), 1.5, &region);
        let from = |o: DVec3, to: DVec3| {
            let v = to - o;
            let (t0, t1) = region.clip(o, v.normalize(), v.length()).unwrap();
            Segment {
                o,
                d: v.normalize(),
                t0,
                t1,
            }
        };
        for seg in [
            from(DVec3::new(-2.0, 0.1, 0.9), DVec3::new(2.0, 0.1, 0.9)),
            from(DVec3::new(0.9, 1.4, 1.6), DVec3::new(-0.9, -0.4, 0.3)),
            // Through the cell corner (0.2, 0.5, 0.7) exactly.
            from(DVec3::new(-0.6, -0.3, 0.3), DVec3::new(1.0, 1.3, 1.1)),
            from(DVec3::new(0.3, 0.3, 0.25), DVec3::new(0.3, 0.3, 0.26)),
        ] {
            let n = 200_000;
            let dt = seg.len_m() / n as f64;
            let sum: f64 = (0..n)
                .map(|i| g.sigma_t_at(seg.o + seg.d * (seg.t0 + (i as f64 + 0.5) * dt)) * dt)
                .sum();
            let walk = g.optical_depth(&seg);
            // The sum misplaces each cell face by under dt: at most 12 faces × dt × the largest σt.
            assert!(
                (walk - sum).abs() <= 12.0 * dt * 1.5 * 10.0 / 7.0,
                "{walk} vs {sum}"
            );
        }
    }
}
