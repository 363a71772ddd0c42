//! MATLAB `.mat` imports for real captures. Both readers return the array in MATLAB's own shape
//! (as `scipy.io.loadmat` or MATLAB's `size` report it) with the values in C (row-major) order over
//! that shape. For a capture stored as MATLAB `t × a × b`, element (t, a, b) is at
//! `(t·A + a)·B + b`. The CDT `meas` arrays (h5py shape (32, 32, 512)) come back as shape
//! [512, 32, 32] = (t, a, b), the same array as the CDT code's `np.array(f['meas']).transpose(2, 1, 0)`.

use crate::h5;
use crate::mat5::MatValue;
use crate::npy::fortran_to_c;
use crate::tal::DEFAULT_READ_LIMIT_BYTES;
use murk_core::{Error, Result};
use std::path::Path;

/// What the first bytes of a file say it is.
#[derive(PartialEq)]
enum Kind {
    V5,
    V73,
    Other,
}

fn sniff(path: &Path) -> Result<Kind> {
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut head = [0u8; 128];
    let n = h5::read_prefix(&mut f, &mut head).map_err(|e| Error::io(path, e))?;
    let head = &head[..n];
    Ok(if head.starts_with(b"MATLAB 7.3 MAT-file") {
        Kind::V73
    } else if head.starts_with(b"MATLAB 5.0 MAT-file") {
        Kind::V5
    } else if hdf5_pure::is_hdf5(path).map_err(|e| Error::io(path, e))? {
        Kind::V73
    } else {
        Kind::Other
    })
}

fn missing_var(path: &Path, var: &str, present: &[String]) -> Error {
    Error::format(
        path,
        format!(
            "no variable '{var}' (variables present: {})",
            if present.is_empty() {
                "none".to_string()
            } else {
                present.join(", ")
            }
        ),
    )
}

/// Reads numeric variable `var` of a MATLAB v7.3 (HDF5-based) `.mat` file as f32.
pub fn read_mat_v73_array(path: &Path, var: &str) -> Result<(Vec<usize>, Vec<f32>)> {
    match sniff(path)? {
        Kind::V5 => {
            return Err(Error::format(
                path,
                "this is a MATLAB v5 .mat file (not HDF5-based v7.3); use read_mat_v5_array",
            ))
        }
        Kind::Other => {
            return Err(Error::format(
                path,
                "not a MATLAB v7.3 .mat file (no HDF5 signature)",
            ))
        }
        Kind::V73 => {}
    }
    let file = h5::open(path)?;
    let names = h5::root_datasets(path, &file)?;
    if !names.iter().any(|n| n == var) {
        return Err(missing_var(path, var, &names));
    }
    let ds = h5::dataset(path, &file, var)?;
    let (h5_shape, data) = h5::read_real::<f32>(path, &ds, var, DEFAULT_READ_LIMIT_BYTES)?;
    // HDF5 stores MATLAB's column-major array with the axes reversed.
    let shape: Vec<usize> = h5_shape.iter().rev().copied().collect();
    let data = fortran_to_c(&shape, &data);
    Ok((shape, data))
}

/// Reads numeric variable `var` of a MATLAB v5 (v6/v7, non-HDF5) `.mat` file as f32, e.g. the
/// LCT data's `rect_data` (N × N × T uint16) or the scalar `width` (shape [1, 1]); `a.b` reads
/// field `b` of a 1×1 struct `a` (Ahn 2019's `NLOSDATA.transient`).
pub fn read_mat_v5_array(path: &Path, var: &str) -> Result<(Vec<usize>, Vec<f32>)> {
    match sniff(path)? {
        Kind::V73 => {
            return Err(Error::format(
                path,
                "this is a MATLAB v7.3 (HDF5) file; use read_mat_v73_array",
            ))
        }
        Kind::Other => {
            return Err(Error::format(
                path,
                "not a MATLAB v5 .mat file (no 'MATLAB 5.0 MAT-file' header)",
            ))
        }
        Kind::V5 => {}
    }
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    if len > DEFAULT_READ_LIMIT_BYTES {
        return Err(Error::Limits(format!(
            "{}: {} MiB .mat file is over the read limit",
            path.display(),
            len >> 20
        )));
    }
    let vars = crate::mat5::read_mat_v5(path)?;
    match crate::mat5::lookup(&vars, var) {
        Some(MatValue::Numeric { dims, values }) => {
            let col_major: Vec<f32> = values.iter().map(|&v| v as f32).collect();
            Ok((dims.clone(), fortran_to_c(dims, &col_major)))
        }
        Some(other) => Err(Error::format(
            path,
            format!(
                "variable '{var}' is a {}, not a numeric array",
                other.describe()
            ),
        )),
        None => {
            let present: Vec<String> = vars
                .iter()
                .map(|(n, v)| format!("{n} ({})", v.describe()))
                .collect();
            Err(missing_var(path, var, &present))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CDT: &str = "/work/shared/data/real/cdt_lindell2020";

    /// The real CDT capture matches its lossless `.npy` copy (made with h5py + transpose(2, 1, 0)).
    #[test]
    fn cdt_letter_s_matches_npy_copy() {
        let mat = Path::new(CDT).join("letter_s.mat");
        if !mat.exists() {
            return println!("skipped: {} not present", mat.display());
        }
        let (shape, data) = read_mat_v73_array(&mat, "meas").unwrap();
        assert_eq!(shape, vec![512, 32, 32]);
        let (nshape, ndata) =
            crate::read_npy_f32(&Path::new(CDT).join("npy/letter_s.meas_t_a_b.u16.npy")).unwrap();
        assert_eq!(nshape, shape);
        assert_eq!(ndata, data);
        let e = read_mat_v73_array(&mat, "nope").unwrap_err().to_string();
        assert!(e.contains("variables present: meas"), "{e}");
        let e = read_mat_v5_array(&mat, "meas").unwrap_err().to_string();
        assert!(
            e.contains("MATLAB v7.3 (HDF5)") && e.contains("read_mat_v73_array"),
            "{e}"
        );
    }

    #[test]
    fn non_mat_files_are_named() {
        let dir = crate::tal::tests::tmpdir("mat");
        let p = dir.join("x.mat");
        std::fs::write(&p, b"MATLAB 5.0 MAT-file, truncated").unwrap();
        let e = read_mat_v5_array(&p, "a").unwrap_err().to_string();
        assert!(e.contains("x.mat") && !e.contains('\n'), "{e}");
        let e = read_mat_v73_array(&p, "a").unwrap_err().to_string();
        assert!(e.contains("use read_mat_v5_array"), "{e}");
        std::fs::write(&p, b"hello").unwrap();
        assert!(read_mat_v5_array(&p, "a").is_err());
        assert!(read_mat_v73_array(&p, "a").is_err());
        std::fs::remove_dir_all(dir).ok();
    }
}
