//! Classic NLOS reconstruction baselines for murk captures.
//!
//! * [`bp`](mod@bp) and [`fbp`](mod@fbp): any capture kind, any voxel box.
//! * [`lct`](mod@lct), [`dlct`](mod@dlct), [`fk`](mod@fk), [`cdt`](mod@cdt): confocal captures on a regular, axis-aligned scan grid. They work on
//!   the capture's own grid: output [nx, ny, nt] with voxel (ix, iy, k) at scan point (ix, iy) and
//!   k·Δs′/2 in front of the wall, after t_start and the laser/SPAD legs have been removed by
//!   fractional shifts ([`TimeGrid`] chooses Δs′). Each has a plan (FFT plans, filters) built once
//!   per geometry and run per capture.
//!
//! Bins: bin n of a histogram holds paths [start + nΔs, start + (n+1)Δs) (floor binning), so its
//! value is read as belonging to the bin centre; see [`bp`].
//!
//! ```
//! use murk_baselines::{fk, FkParams};
//! use murk_core::DVec3;
//! use murk_synth::testutil::point_capture;
//! use murk_synth::LayoutKind;
//!
//! // f-k migration of a confocal scan of one point 0.5 m behind the wall, on the scan's own grid.
//! let point = DVec3::new(0.1, -0.2, 0.5);
//! let rec = fk(&point_capture(LayoutKind::Confocal, 0.0, false, point), FkParams::default())?;
//! let (peak, _) = rec.peak();
//! assert!((DVec3::from_array(peak) - point).length() < 0.04, "{peak:?}");
//! # Ok::<(), murk_core::Error>(())
//! ```

pub mod bmm;
pub mod bp;
pub mod cdt;
mod confocal;
pub mod dlct;
pub mod fbp;
mod fft3;
pub mod fk;
pub mod lct;
#[cfg(test)]
mod progress_tests;
#[cfg(test)]
mod testutil;

pub use bmm::{bmm, bmm_with, BmmParams, BmmPlan, Medium, FOAM};
pub use bp::{backproject, backproject_with, BpOptions, BpPlan};
pub use cdt::{cdt, through_slab, CdtParams, CdtPlan, Pulse, SlabParams};
pub use confocal::TimeGrid;
pub use dlct::{dlct, DlctParams, DlctPlan};
pub use fbp::{fbp, fbp_with, FbpFilter, FbpOptions, FbpPlan};
pub use fk::{fk, FkParams, FkPlan};
pub use lct::{lct, LctParams, LctPlan, Reflectance};

pub use murk_core::Reconstruction;
