//! An exponential height fog along straight paths: the scene's `kind = "height"` medium with μt = 1.

use murk_core::DVec3;
use murk_recon::PathDensity;
use murk_render::{Aabb, Height};

/// Density exp(−(y − min.y)/scale) over a box (1 on its floor, y up), zero outside it.
pub struct HeightDensity {
    fog: Height,
    region: Aabb,
}

impl HeightDensity {
    /// The fog of `scale_m` over `region`, as a scene's `height_scale` (checked by the caller).
    pub fn new(region: Aabb, scale_m: f64) -> HeightDensity {
        HeightDensity {
            fog: Height {
                sigma_t_floor_per_m: 1.0,
                floor_y_m: region.min.y,
                scale_m,
            },
            region,
        }
    }
}

impl PathDensity for HeightDensity {
    /// ∫ density ds along the part of the segment inside the box: the renderer's closed form.
    fn density_length_m(&self, from: DVec3, to: DVec3) -> f64 {
        super::inside(&self.region, from, to, |seg| self.fog.optical_depth(seg))
    }
}
