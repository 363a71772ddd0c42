//! A heterogeneous medium's density along straight paths, for the compensation
//! (docs/media-heterogeneous.md): a density grid or an exponential height fog over the medium's box
//! of the scene that `murk render` stored in the capture, zero outside it.

mod grid;
mod height;

pub use grid::GridDensity;
pub use height::HeightDensity;

use crate::scene::{check_height_scale, stored_medium, Modelled};
use murk_core::Opt;
use murk_core::{Capture, DVec3, Error, Result};
use murk_recon::PathDensity;
use murk_render::{Aabb, Segment, Spelling};
use std::path::PathBuf;
use std::sync::Arc;

/// The medium's density as the caller gives it, in the scene file's terms: `murk reconstruct`'s
/// `--medium-density` and `--height-scale`, `murk.reconstruct`'s `medium_density` and
/// `height_scale`.
#[derive(Clone, Debug, Default)]
pub struct DensityGiven {
    /// A density grid (.npy), as the scene's `density`.
    pub file: Option<PathBuf>,
    /// An exponential height fog's scale (m), as the scene's `height_scale`.
    pub height_scale_m: Option<f64>,
}

/// What a compensation integrates along its legs, with the summary's line and the warnings.
#[derive(Default)]
pub struct Along {
    pub density: Option<Arc<dyn PathDensity>>,
    /// The summary's `compensated along` line.
    pub row: Option<String>,
    pub warnings: Vec<String>,
}

impl DensityGiven {
    /// The density that a compensation (`compensates`) reads along each leg of `cap`. In order: the
    /// grid or height fog given, over the box of the capture's stored scene, read only with a given
    /// μt (`mu_t_given`); else the stored scene's own height fog or density grid (whose cells the
    /// capture holds), with μt given or estimated (the estimate keeps that shape, so either is σt
    /// where the density is 1); else none (every metre counts as density 1, the homogeneous
    /// medium). A stored grid whose cells the capture does not hold (rendered before murk stored
    /// them) is compensated as homogeneous with a warning saying so. `spelling` names the flags or
    /// keywords.
    pub fn along(
        &self,
        cap: &Capture,
        compensates: bool,
        mu_t_given: bool,
        spelling: Spelling,
    ) -> Result<Along> {
        let flag = |opt: Opt| opt.spelled(spelling);
        let given = match (&self.file, self.height_scale_m) {
            (Some(_), Some(_)) => {
                return Err(Error::param(format!(
                    "{} and {} each give the medium's density; give one",
                    flag(Opt::MediumDensity),
                    flag(Opt::HeightScale)
                )))
            }
            (Some(_), None) => Some(Opt::MediumDensity),
            (None, Some(_)) => Some(Opt::HeightScale),
            (None, None) => None,
        };
        if let Some(name) = given.filter(|_| !(compensates && mu_t_given)) {
            return Err(Error::param(format!(
                "{} is read by {} with {} (σt where the density is 1); give both",
                flag(name),
                flag(Opt::Compensate),
                flag(Opt::MuT)
            )));
        }
        if let Some(h) = self.height_scale_m {
            check_height_scale(Some(h), &flag(Opt::HeightScale))?;
        }
        if let Some(file) = &self.file {
            let region = stored_medium(cap)?.region;
            return Ok(Along {
                density: Some(Arc::new(GridDensity::load(file, region)?)),
                row: Some(format!(
                    "σt = density × μt along each leg, density from {}",
                    file.display()
                )),
                warnings: Vec::new(),
            });
        }
        if let Some(scale_m) = self.height_scale_m {
            let region = stored_medium(cap)?.region;
            return Ok(height(region, scale_m, &flag(Opt::HeightScale)));
        }
        // Captures that murk did not render, or rendered without a medium, keep the homogeneous
        // compensation they always had.
        let stored = match stored_medium(cap) {
            Ok(s) if compensates => s,
            _ => return Ok(Along::default()),
        };
        match stored.shape.modelled(cap) {
            Some(Modelled::Grid { cells }) => {
                let [nx, ny, nz] = cells.dims();
                return Ok(Along {
                    density: Some(Arc::new(GridDensity::from_cells(&cells, stored.region))),
                    row: Some(format!(
                        "σt = density × μt along each leg, density from the capture's own grid ({nx} × {ny} × {nz} cells)"
                    )),
                    warnings: Vec::new(),
                });
            }
            Some(Modelled::Height { scale_m }) => {
                return Ok(height(stored.region, scale_m, "the capture's scene"))
            }
            None => {}
        }
        let Some(what) = stored.shape.describe() else {
            return Ok(Along::default());
        };
        // Only a grid without its cells is left: an estimated μt was then fitted as homogeneous.
        let give = match mu_t_given {
            true => format!("{} FILE.npy", flag(Opt::MediumDensity)),
            false => format!(
                "{} and {} FILE.npy",
                flag(Opt::MuT),
                flag(Opt::MediumDensity)
            ),
        };
        Ok(Along {
            warnings: vec![format!(
                "the capture's medium is {what}, whose cells the capture does not hold (rendered before murk stored them): the compensation assumes a homogeneous medium of μt; give {give} to integrate σt along each leg"
            )],
            ..Along::default()
        })
    }
}

impl Along {
    /// Adds the summary's `compensated along` row and the warnings to `out` (the density taken).
    pub fn note(self, out: &mut murk_core::Reconstruction) {
        out.rows
            .extend(self.row.map(|line| ("compensated along".to_string(), line)));
        out.warnings.extend(self.warnings);
    }
}

/// The height fog of `scale_m` over `region`, from `source`.
fn height(region: Aabb, scale_m: f64, source: &str) -> Along {
    Along {
        density: Some(Arc::new(HeightDensity::new(region, scale_m))),
        row: Some(format!(
            "σt = μt × exp(−(y − floor)/{} m) along each leg, floor y = {} m, the height fog of {source}",
            murk_core::short(scale_m),
            murk_core::short(region.min.y)
        )),
        warnings: Vec::new(),
    }
}

/// `along(segment)` over the part of the segment `from`..`to` inside `region` (0 where it misses it).
fn inside(region: &Aabb, from: DVec3, to: DVec3, along: impl Fn(&Segment) -> f64) -> f64 {
    let len = (to - from).length();
    if len == 0.0 {
        return 0.0;
    }
    let d = (to - from) / len;
    region
        .clip(from, d, len)
        .map_or(0.0, |(t0, t1)| along(&Segment { o: from, d, t0, t1 }))
}

#[cfg(test)]
mod tests;
