//! murk's file formats.
//!
//! * y-tal HDF5 captures ([`read_capture`], [`write_capture`]), murk's native capture format;
//! * reconstructed volumes as HDF5 ([`write_volume_h5`]) and `.npy` ([`write_npy_f32`], [`read_npy_f32`]);
//! * MATLAB imports of real captures ([`read_mat_v73_array`], [`read_mat_v5_array`]).
//!
//! Everything is pure Rust (hdf5-pure, and murk's own MATLAB v5 reader): no system HDF5 library. Every error is a
//! [`murk_core::Error`] whose message is one line naming the file and the problem; declared sizes
//! are checked before allocating, and writes are atomic (temporary file + rename).
//!
//! ```
//! use murk_core::{Capture, DVec3, Pairing, PointSet, TimeAxis};
//!
//! // One laser and one sensor point, four bins of 1/128 m (the file stores the axis as f32, as y-tal
//! // does: this width survives exactly).
//! let cap = Capture::new(
//!     PointSet::single(DVec3::ZERO),
//!     PointSet::single(DVec3::new(0.5, 0.0, 0.0)),
//!     Pairing::Product,
//!     TimeAxis { start_m: 0.0, bin_width_m: 0.0078125, bins: 4 },
//!     vec![0.0, 1.0, 0.5, 0.0],
//! );
//! let path = std::env::temp_dir().join(format!("murk-io-doc-{}.h5", std::process::id()));
//! murk_io::write_capture(&path, &cap)?;
//! let back = murk_io::read_capture(&path)?;
//! assert_eq!((back.h, back.time), (cap.h, cap.time));
//! std::fs::remove_file(&path).ok();
//! # Ok::<(), murk_core::Error>(())
//! ```

mod atomic;
mod describe;
mod h5;
pub mod import;
mod mat;
pub mod mat5;
pub use mat5::{write_mat_v5, MatArray, MatClass};
mod npy;
mod scene_info;
mod tal;
#[cfg(test)]
mod testutil;
mod truth;
mod volume;

pub use atomic::{
    check_h5_name, check_h5_output, check_output, create_output_dir, remove_stale_temporaries,
    remove_temporaries, same_target, write_atomic,
};
pub use describe::describe;
pub use mat::{read_mat_v5_array, read_mat_v73_array, ArrayFile};
pub use npy::{read_npy_f32, read_npy_f32_with_limit, write_npy_f32};
pub use scene_info::scene_info_summary;
pub use tal::{
    read_capture, read_capture_with_limit, write_capture, write_capture_compressed,
    DEFAULT_READ_LIMIT_BYTES, TAL_FIELDS,
};
pub use truth::{describe_truth, looks_like_truth, read_truth_h5, write_truth_h5};
pub use volume::{
    check_volume_path, normals_path, read_volume_h5, write_volume, write_volume_h5, AttrValue,
    VolumeData,
};
