//! Reconstructed volumes as HDF5: `intensity` [nx, ny, nz] f32, voxel-centre axes `x`, `y`, `z`
//! (metres, f64), and the reconstruction parameters as attributes of the root group.

use crate::atomic::write_atomic;
use hdf5_pure::FileBuilder;
use murk_core::{Error, Result};
use std::path::Path;

/// A parameter stored as an HDF5 attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    Num(f64),
    Text(String),
}

/// Writes a volume of `shape` = [nx, ny, nz] (C order, voxel (ix, iy, iz) at (ix·ny + iy)·nz + iz)
/// with its voxel-centre coordinates and `attrs` as root attributes, atomically.
pub fn write_volume_h5(
    path: &Path,
    shape: [usize; 3],
    intensity: &[f32],
    x: &[f64],
    y: &[f64],
    z: &[f64],
    attrs: &[(&str, AttrValue)],
) -> Result<()> {
    let n = shape.iter().product::<usize>();
    if intensity.len() != n || [x.len(), y.len(), z.len()] != shape {
        return Err(Error::param(format!(
            "{}: volume shape {shape:?} but {} values and axes of {}, {}, {}",
            path.display(),
            intensity.len(),
            x.len(),
            y.len(),
            z.len()
        )));
    }
    let mut fb = FileBuilder::new();
    fb.create_dataset("intensity")
        .with_shape(&shape.map(|d| d as u64))
        .with_f32_data(intensity);
    for (name, axis) in [("x", x), ("y", y), ("z", z)] {
        fb.create_dataset(name).with_f64_data(axis);
    }
    for (k, v) in attrs {
        fb.set_attr(
            k,
            match v {
                AttrValue::Num(f) => hdf5_pure::AttrValue::F64(*f),
                AttrValue::Text(s) => hdf5_pure::AttrValue::String(s.clone()),
            },
        );
    }
    write_atomic(path, |w| {
        fb.finish_to(w).map_err(|e| {
            Error::format(path, crate::h5::one_line(format!("HDF5 write failed: {e}")))
        })
    })
}

/// Writes an intensity volume in the format its extension names: `.npy` (the array alone) or
/// `.h5`/`.hdf5` (the array, its x, y, z axes and `attrs` as text attributes).
pub fn write_volume(
    path: &Path,
    volume: &murk_core::Volume,
    intensity: &[f32],
    attrs: &[(String, String)],
) -> Result<()> {
    match volume_format(path)? {
        VolumeFormat::Npy => crate::write_npy_f32(path, &volume.shape(), intensity),
        VolumeFormat::Hdf5 => {
            let attrs: Vec<(&str, AttrValue)> = attrs
                .iter()
                .map(|(k, v)| (k.as_str(), AttrValue::Text(v.clone())))
                .collect();
            write_volume_h5(
                path,
                volume.shape(),
                intensity,
                &volume.x.values(),
                &volume.y.values(),
                &volume.z.values(),
                &attrs,
            )
        }
    }
}

enum VolumeFormat {
    Npy,
    Hdf5,
}

/// The volume format `path`'s extension names; callers check it before any work, so a typo costs
/// nothing.
pub fn check_volume_path(path: &Path) -> Result<()> {
    volume_format(path).map(|_| ())
}

fn volume_format(path: &Path) -> Result<VolumeFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "npy" => Ok(VolumeFormat::Npy),
        "h5" | "hdf5" => Ok(VolumeFormat::Hdf5),
        "" => Err(Error::param(format!(
            "{}: has no extension; name the volume .npy or .h5",
            path.display()
        ))),
        _ => Err(Error::param(format!(
            "{}: unknown output type '.{ext}' (use .npy or .h5)",
            path.display()
        ))),
    }
}

/// A volume written by [`write_volume_h5`]: intensity (C order over x, y, z) and the three axes.
pub struct VolumeData {
    pub intensity: Vec<f32>,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
}

/// Reads a volume file written by murk (`murk reconstruct --out v.h5`).
pub fn read_volume_h5(path: &Path) -> Result<VolumeData> {
    let limit = crate::tal::read_limit_bytes();
    let file = crate::h5::open(path)?;
    let read = |name: &str| -> Result<(Vec<usize>, Vec<f64>)> {
        let ds = crate::h5::dataset(path, &file, name)?;
        crate::h5::read_real::<f64>(path, &ds, name, limit)
    };
    let ds = crate::h5::dataset(path, &file, "intensity")?;
    let (shape, intensity) = crate::h5::read_real::<f32>(path, &ds, "intensity", limit)?;
    let (x, y, z) = (read("x")?.1, read("y")?.1, read("z")?.1);
    if shape != [x.len(), y.len(), z.len()] {
        return Err(Error::format(
            path,
            format!(
                "intensity has shape {shape:?} but the axes have {}, {}, {} values",
                x.len(),
                y.len(),
                z.len()
            ),
        ));
    }
    Ok(VolumeData { intensity, x, y, z })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volume_reads_back() {
        let dir = crate::testutil::tmpdir("vol");
        let p = dir.join("v.h5");
        let data: Vec<f32> = (0..2 * 3 * 4).map(|i| i as f32).collect();
        let attrs = [
            ("method", AttrValue::Text("pf".into())),
            ("wavelength_m", AttrValue::Num(0.05)),
        ];
        write_volume_h5(
            &p,
            [2, 3, 4],
            &data,
            &[0.0, 1.0],
            &[0.0, 0.5, 1.0],
            &[1.0, 1.25, 1.5, 1.75],
            &attrs,
        )
        .unwrap();
        let f = hdf5_pure::File::open(&p).unwrap();
        let ds = f.dataset("intensity").unwrap();
        assert_eq!(ds.shape().unwrap(), vec![2, 3, 4]);
        assert_eq!(ds.read_f32().unwrap(), data);
        assert_eq!(f.dataset("z").unwrap().read_f64().unwrap()[3], 1.75);
        let a = f.root().attrs().unwrap();
        assert_eq!(a["method"], hdf5_pure::AttrValue::String("pf".into()));
        assert_eq!(a["wavelength_m"], hdf5_pure::AttrValue::F64(0.05));
        assert!(
            write_volume_h5(&p, [2, 3, 5], &data, &[0.0; 2], &[0.0; 3], &[0.0; 5], &[]).is_err()
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
