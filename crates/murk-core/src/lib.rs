//! murk's data model.
//!
//! A [`Capture`] holds the impulse responses H(x_l → x_s, t) of a hidden scene measured through a relay
//! surface (a reflective wall or a transmissive diffuser) at z = 0, with the hidden volume at z > 0.
//! Time is stored as optical path length in metres (as in y-tal): bin `n` covers paths
//! `[start_m + n·bin_width_m, start_m + (n+1)·bin_width_m)`.
//!
//! Both sides are symmetric (Helmholtz reciprocity): illumination points and sensor points are two
//! [`PointSet`]s, and [`Pairing`] says whether H is measured for every (illumination, sensor) pair
//! or for the i-th illumination point with the i-th sensor point (confocal scans).
//!
//! Reconstructions live on a [`Volume`] of voxel centres, stored in C order [nx, ny, nz]:
//!
//! ```
//! use murk_core::Volume;
//! let v = Volume::parse("-1:1:3,-1:1:3,0.5:1.5:5")?; // x, y, z: from:to:count, metres
//! assert_eq!(v.len(), 45);
//! assert_eq!(v.unravel(v.index(2, 1, 4)), (2, 1, 4));
//! assert_eq!(v.centre(2, 1, 4).to_array(), [1.0, 0.0, 1.5]);
//! # Ok::<(), murk_core::Error>(())
//! ```

pub mod buffer;
mod capture;
mod density;
mod error;
mod input;
mod limits;
mod named;
mod points;
pub mod process;
mod progress;
mod reconstruction;
pub mod report;
pub mod simd;
pub mod spelling;
mod truth;
mod volume;
pub mod window;

pub use capture::{Capture, CaptureKind, Pairing, TimeAxis};
pub use density::{DensityCells, MAX_DENSITY_CELLS};
pub use error::{Error, Result};
pub use glam::DVec3;
pub use input::{open_input, read_input};
pub use limits::{non_finite, short, Limits};
pub use named::Named;
pub use points::{PointLayout, PointSet, RegularGrid};
pub use progress::{NoProgress, Progress};
pub use reconstruction::{Reconstruction, Reconstructor};
pub use spelling::{Opt, Spelling};
pub use truth::GroundTruth;
pub use volume::{Axis, Volume};

/// Median of the finite values (the mean of the middle two for an even count); NaN if none.
pub fn median(values: &[f64]) -> f64 {
    let mut finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return f64::NAN;
    }
    finite.sort_by(f64::total_cmp);
    let mid = finite.len() / 2;
    if finite.len() % 2 == 1 {
        finite[mid]
    } else {
        (finite[mid - 1] + finite[mid]) / 2.0
    }
}

/// Speed of light in vacuum (m/s), the constant y-tal uses to convert paths to seconds.
pub const SPEED_OF_LIGHT_M_PER_S: f64 = 299_792_458.0;
