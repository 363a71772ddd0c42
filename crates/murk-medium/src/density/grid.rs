//! A density grid along straight paths: the scene's `kind = "grid"` medium with μt = 1.

use murk_core::{DVec3, DensityCells, Result};
use murk_recon::PathDensity;
use murk_render::{Aabb, Grid};
use std::path::Path;

/// A density grid over a box, zero outside it.
pub struct GridDensity {
    grid: Grid,
    region: Aabb,
}

impl GridDensity {
    /// The grid of `file` (as a scene's `density`) over `region`.
    pub fn load(file: &Path, region: Aabb) -> Result<GridDensity> {
        Ok(GridDensity {
            grid: Grid::load(file, 1.0, &region)?,
            region,
        })
    }
}

impl GridDensity {
    /// The grid of `cells` (a capture's own) over `region`.
    pub fn from_cells(cells: &DensityCells, region: Aabb) -> GridDensity {
        GridDensity {
            grid: Grid::from_cells(cells.clone(), 1.0, &region),
            region,
        }
    }
}

impl PathDensity for GridDensity {
    /// ∫ density ds along the part of the segment inside the box (the renderer's cell walk).
    fn density_length_m(&self, from: DVec3, to: DVec3) -> f64 {
        super::inside(&self.region, from, to, |seg| self.grid.optical_depth(seg))
    }
}
