//! Reconstructed volumes as HDF5: `intensity` [nx, ny, nz] f32, voxel-centre axes `x`, `y`, `z`
//! (metres, f64), and the reconstruction parameters as attributes of the root group.

use crate::atomic::write_atomic;
use hdf5_pure::FileBuilder;
use murk_core::{Error, Result, Volume};
use std::path::{Path, PathBuf};

/// A parameter stored as an HDF5 attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    Num(f64),
    Text(String),
}

/// Writes `intensity` on `volume` (C order, voxel (ix, iy, iz) at (ix·ny + iy)·nz + iz) with its
/// voxel-centre coordinates, the `normals` where the method gave them (dataset `normals`
/// [nx, ny, nz, 3]) and `attrs` as root attributes, atomically.
pub fn write_volume_h5(
    path: &Path,
    volume: &Volume,
    intensity: &[f32],
    normals: Option<&[[f32; 3]]>,
    attrs: &[(&str, AttrValue)],
) -> Result<()> {
    check_lengths(path, volume, intensity, normals)?;
    let shape = volume.shape().map(|d| d as u64);
    let mut fb = FileBuilder::new();
    fb.create_dataset("intensity")
        .with_shape(&shape)
        .with_f32_data(intensity);
    if let Some(normals) = normals {
        fb.create_dataset(NORMALS)
            .with_shape(&[shape[0], shape[1], shape[2], 3])
            .with_f32_data(normals.as_flattened());
    }
    for (name, axis) in [("x", &volume.x), ("y", &volume.y), ("z", &volume.z)] {
        fb.create_dataset(name).with_f64_data(&axis.values());
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

/// The HDF5 dataset of the normals beside `intensity`.
const NORMALS: &str = "normals";

fn check_lengths(
    path: &Path,
    volume: &Volume,
    intensity: &[f32],
    normals: Option<&[[f32; 3]]>,
) -> Result<()> {
    let n = volume.len();
    if intensity.len() != n || normals.is_some_and(|v| v.len() != n) {
        return Err(Error::param(format!(
            "{}: volume shape {:?} but {} values and {} normals",
            path.display(),
            volume.shape(),
            intensity.len(),
            normals.map_or(0, |v| v.len())
        )));
    }
    Ok(())
}

/// Where a `.npy` volume's normals go: beside it, `<stem>-normals.npy` ([nx, ny, nz, 3] float32).
/// An `.h5` volume holds them (`None`).
pub fn normals_path(path: &Path) -> Option<PathBuf> {
    match volume_format(path) {
        Ok(VolumeFormat::Npy) => {
            let stem = path.file_stem().unwrap_or_default().to_string_lossy();
            Some(path.with_file_name(format!("{stem}-normals.npy")))
        }
        _ => None,
    }
}

/// Writes an intensity volume in the format its extension names: `.npy` (the array alone, the
/// normals in [`normals_path`]) or `.h5`/`.hdf5` (the array, the normals, its x, y, z axes and
/// `attrs` as text attributes).
pub fn write_volume(
    path: &Path,
    volume: &Volume,
    intensity: &[f32],
    normals: Option<&[[f32; 3]]>,
    attrs: &[(String, String)],
) -> Result<()> {
    match volume_format(path)? {
        VolumeFormat::Npy => {
            check_lengths(path, volume, intensity, normals)?;
            crate::write_npy_f32(path, &volume.shape(), intensity)?;
            match (normals, normals_path(path)) {
                (Some(n), Some(to)) => {
                    let [nx, ny, nz] = volume.shape();
                    crate::write_npy_f32(&to, &[nx, ny, nz, 3], n.as_flattened())
                }
                _ => Ok(()),
            }
        }
        VolumeFormat::Hdf5 => {
            let attrs: Vec<(&str, AttrValue)> = attrs
                .iter()
                .map(|(k, v)| (k.as_str(), AttrValue::Text(v.clone())))
                .collect();
            write_volume_h5(path, volume, intensity, normals, &attrs)
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

/// A volume written by [`write_volume_h5`]: intensity (C order over x, y, z), the normals where
/// it holds them, and the three axes.
pub struct VolumeData {
    pub intensity: Vec<f32>,
    pub normals: Option<Vec<[f32; 3]>>,
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
    let normals = match crate::h5::root_datasets(path, &file)?
        .iter()
        .any(|d| d == NORMALS)
    {
        false => None,
        true => {
            let ds = crate::h5::dataset(path, &file, NORMALS)?;
            let (n_shape, flat) = crate::h5::read_real::<f32>(path, &ds, NORMALS, limit)?;
            if n_shape != [&shape[..], &[3]].concat() {
                return Err(Error::format(
                    path,
                    format!("normals have shape {n_shape:?}, the intensity {shape:?}: expected the intensity's and 3"),
                ));
            }
            Some(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        }
    };
    Ok(VolumeData {
        intensity,
        normals,
        x,
        y,
        z,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::Axis;

    #[test]
    fn volume_reads_back() {
        let dir = crate::testutil::tmpdir("vol");
        let p = dir.join("v.h5");
        let data: Vec<f32> = (0..2 * 3 * 4).map(|i| i as f32).collect();
        let attrs = [
            ("method", AttrValue::Text("pf".into())),
            ("wavelength_m", AttrValue::Num(0.05)),
        ];
        let vol = Volume {
            x: Axis::new(0.0, 1.0, 2),
            y: Axis::new(0.0, 1.0, 3),
            z: Axis::new(1.0, 1.75, 4),
        };
        write_volume_h5(&p, &vol, &data, None, &attrs).unwrap();
        let f = hdf5_pure::File::open(&p).unwrap();
        let ds = f.dataset("intensity").unwrap();
        assert_eq!(ds.shape().unwrap(), vec![2, 3, 4]);
        assert_eq!(ds.read_f32().unwrap(), data);
        assert_eq!(f.dataset("z").unwrap().read_f64().unwrap()[3], 1.75);
        let a = f.root().attrs().unwrap();
        assert_eq!(a["method"], hdf5_pure::AttrValue::String("pf".into()));
        assert_eq!(a["wavelength_m"], hdf5_pure::AttrValue::F64(0.05));
        assert!(read_volume_h5(&p).unwrap().normals.is_none());
        let longer = Volume {
            z: Axis::new(1.0, 2.0, 5),
            ..vol
        };
        assert!(write_volume_h5(&p, &longer, &data, None, &[]).is_err());
        std::fs::remove_dir_all(dir).ok();
    }

    /// Normals go into the `.h5` beside the intensity and beside a `.npy` as `<stem>-normals.npy`,
    /// and read back as written.
    #[test]
    fn normals_are_written_beside_the_volume() {
        let dir = crate::testutil::tmpdir("vol-normals");
        let vol = Volume {
            x: Axis::new(0.0, 1.0, 2),
            y: Axis::new(0.0, 1.0, 1),
            z: Axis::new(1.0, 2.0, 3),
        };
        let intensity = [1.0f32, 0.0, 2.0, 3.0, 0.5, 0.0];
        let normals: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5, -1.0]).collect();
        let h5 = dir.join("v.h5");
        write_volume(&h5, &vol, &intensity, Some(&normals), &[]).unwrap();
        let back = read_volume_h5(&h5).unwrap();
        assert_eq!(back.normals.as_deref(), Some(&normals[..]));
        assert_eq!(normals_path(&h5), None);
        let npy = dir.join("v.npy");
        write_volume(&npy, &vol, &intensity, Some(&normals), &[]).unwrap();
        let beside = dir.join("v-normals.npy");
        assert_eq!(normals_path(&npy).as_deref(), Some(beside.as_path()));
        let (shape, flat) = crate::read_npy_f32(&beside).unwrap();
        assert_eq!(shape, [2, 1, 3, 3]);
        assert_eq!(flat, normals.as_flattened());
        assert!(write_volume(&npy, &vol, &intensity, Some(&normals[1..]), &[]).is_err());
        std::fs::remove_dir_all(dir).ok();
    }
}
