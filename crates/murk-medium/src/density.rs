//! A heterogeneous medium's density along straight paths, for the compensation: the capture's
//! density grid (`murk reconstruct --medium-density`) over the medium's box from its stored scene.

use crate::scene::{medium_table, stored_table};
use murk_core::{DVec3, Error, Result};
use murk_recon::PathDensity;
use murk_render::{Aabb, Grid, Segment};
use std::path::Path;
use std::sync::Arc;

/// A density grid over a box, zero outside it: the scene's `kind = "grid"` medium with μt = 1.
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

    /// The grid of `file` over the medium's box of the scene that `murk render` stored in `cap`.
    pub fn for_capture(cap: &murk_core::Capture, file: &Path) -> Result<Arc<dyn PathDensity>> {
        let mut table = stored_table(cap)?;
        let medium = medium_table(&mut table)?;
        let corner = |key: &str| -> Result<DVec3> {
            let v: Option<Vec<f64>> = medium.get(key).and_then(|v| {
                v.as_array()?
                    .iter()
                    .map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                    .collect()
            });
            match v.as_deref() {
                Some(&[x, y, z]) => Ok(DVec3::new(x, y, z)),
                _ => Err(Error::param(format!(
                    "scene_info.scene's [medium] has no {key} = [x, y, z]: the density grid's box is unknown"
                ))),
            }
        };
        let region = Aabb {
            min: corner("min")?,
            max: corner("max")?,
        };
        if !(0..3).all(|a| region.min[a] < region.max[a]) {
            return Err(Error::param(format!(
                "scene_info.scene's [medium] box {}..{} is empty",
                region.min, region.max
            )));
        }
        Ok(Arc::new(GridDensity::load(file, region)?))
    }
}

impl PathDensity for GridDensity {
    /// ∫ density ds along the part of the segment inside the box (the renderer's cell walk).
    fn density_length_m(&self, from: DVec3, to: DVec3) -> f64 {
        let len = (to - from).length();
        if len == 0.0 {
            return 0.0;
        }
        let d = (to - from) / len;
        self.region.clip(from, d, len).map_or(0.0, |(t0, t1)| {
            self.grid.optical_depth(&Segment { o: from, d, t0, t1 })
        })
    }
}

#[cfg(test)]
mod tests;
