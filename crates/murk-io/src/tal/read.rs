//! Reading a y-tal capture: its layouts checked against one another and the sizes it declares
//! checked before H is read.

use super::format::{dims, HFormat, GRID_FORMATS};
use super::{capture_crc32, read_limit_bytes, DENSITY_ATTR, DENSITY_SHAPE_ATTR};
use crate::h5;
use murk_core::{
    Capture, DVec3, DensityCells, Error, Pairing, PointLayout, PointSet, Result, TimeAxis,
};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Reads a y-tal HDF5 capture (see the module docs for the mapping), with the default size limit.
pub fn read_capture(path: &Path) -> Result<Capture> {
    read_capture_with_limit(path, read_limit_bytes())
}

/// As [`read_capture`], refusing any dataset whose declared size exceeds `max_bytes` before
/// allocating for it.
pub fn read_capture_with_limit(path: &Path, max_bytes: u64) -> Result<Capture> {
    let file = h5::open(path)?;
    let keys = h5::root_datasets(path, &file)?;
    if !keys.iter().any(|k| k == "H") || !keys.iter().any(|k| k == "H_format") {
        let mut shown = keys.clone();
        shown.truncate(10);
        return Err(Error::format(
            path,
            format!(
                "not a y-tal capture: no 'H'/'H_format' datasets (top-level datasets: {})",
                if shown.is_empty() {
                    "none".to_string()
                } else {
                    shown.join(", ")
                }
            ),
        ));
    }
    let has = |k: &str| keys.iter().any(|x| x == k);
    let ds = |k: &str| h5::dataset(path, &file, k);
    let bad = |msg: String| Error::format(path, msg);

    let h_format = h5::read_enum_name(path, &ds("H_format")?, "H_format")?;
    let Some(format) = HFormat::read(&h_format) else {
        return Err(
            if h_format.starts_with("F_") || h_format.parse::<i32>().is_ok() {
                Error::Unsupported(format!(
                "{}: H_format {h_format} (frequency-domain or unknown) is not supported; murk reads time-domain captures",
                path.display()
            ))
            } else {
                bad(format!("H_format is {h_format}, not a known layout"))
            },
        );
    };
    let h_format = format.name();

    let sensor = read_points(path, &file, "sensor", max_bytes)?;
    let illum = read_points(path, &file, "laser", max_bytes)?;

    let h_ds = ds("H")?;
    let h_shape = h5::shape(path, &h_ds, "H")?;
    let (ns, nl) = (sensor.len(), illum.len());
    let expect_dims =
        |dims: &[usize]| -> Result<()> {
            if h_shape.len() != dims.len() + 1 || h_shape[1..] != *dims {
                return Err(bad(format!(
                "H has shape {h_shape:?} but H_format {h_format} with these grids needs (T, {})",
                dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")
            )));
            }
            Ok(())
        };
    let pairing = match format {
        HFormat::SxSy | HFormat::Si => {
            if format == HFormat::SxSy && !matches!(sensor.layout, PointLayout::Grid { .. }) {
                return Err(bad(
                    "H_format T_Sx_Sy needs a sensor grid of shape (Sx, Sy, 3)".to_string(),
                ));
            }
            if format == HFormat::Si {
                expect_dims(&[ns])?;
            } else {
                expect_dims(&dims(&sensor))?;
            }
            if nl == 1 {
                Pairing::Product
            } else if nl == ns {
                Pairing::Paired
            } else {
                return Err(bad(format!(
                    "H_format {h_format} needs one laser point or one per sensor point ({ns}), the laser grid has {nl}"
                )));
            }
        }
        HFormat::LxLySxSy => {
            let (PointLayout::Grid { .. }, PointLayout::Grid { .. }) =
                (illum.layout, sensor.layout)
            else {
                return Err(bad(
                    "H_format T_Lx_Ly_Sx_Sy needs laser and sensor grids of shape (X, Y, 3)"
                        .to_string(),
                ));
            };
            expect_dims(&[dims(&illum), dims(&sensor)].concat())?;
            Pairing::Product
        }
        HFormat::LiSi => {
            expect_dims(&[nl, ns])?;
            Pairing::Product
        }
    };
    let bins = h_shape[0];
    if bins == 0 {
        return Err(bad("H has no time bins".to_string()));
    }

    let scalar = |k: &str| -> Result<f64> {
        if !has(k) {
            return Err(bad(format!("missing dataset '{k}'")));
        }
        let (_, v) = h5::read_real::<f64>(path, &ds(k)?, k, 64)?;
        match v.as_slice() {
            [x] => Ok(*x),
            _ => Err(bad(format!(
                "'{k}' should hold one number, holds {}",
                v.len()
            ))),
        }
    };
    let device = |k: &str| -> Result<Option<DVec3>> {
        if !has(k) {
            return Ok(None);
        }
        let (_, v) = h5::read_real::<f64>(path, &ds(k)?, k, 1024)?;
        match v.as_slice() {
            [] => Ok(None),
            [x, y, z] => Ok(Some(DVec3::new(*x, *y, *z))),
            _ => Err(bad(format!(
                "'{k}' should hold 3 coordinates, holds {}",
                v.len()
            ))),
        }
    };
    let t_accounts = if has("t_accounts_first_and_last_bounces") {
        let k = "t_accounts_first_and_last_bounces";
        match h5::read_enum_name(path, &ds(k)?, k)?.as_str() {
            "TRUE" | "1" => true,
            "FALSE" | "0" => false,
            other => return Err(bad(format!("'{k}' holds {other}, expected a bool"))),
        }
    } else {
        false
    };
    let scene_info = if has("scene_info") {
        let s_ds = ds("scene_info")?;
        // y-tal writes None as an empty (null-dataspace) float dataset.
        let null = h5::shape(path, &s_ds, "scene_info")?.is_empty()
            && matches!(
                s_ds.dtype(),
                Ok(hdf5_pure::DType::F64 | hdf5_pure::DType::F32)
            );
        if null {
            String::new()
        } else {
            h5::read_string(path, &s_ds, "scene_info", max_bytes)?
        }
    } else {
        String::new()
    };

    let mut cap = Capture {
        laser_xyz: device("laser_xyz")?,
        sensor_xyz: device("sensor_xyz")?,
        t_accounts_first_and_last_bounces: t_accounts,
        scene_info,
        ..Capture::new(
            illum,
            sensor,
            pairing,
            TimeAxis {
                start_m: scalar("t_start")?,
                bin_width_m: scalar("delta_t")?,
                bins,
            },
            Vec::new(),
        )
    };
    // Before H is read: a few bytes declaring an absurd time window must not cost gigabytes first.
    cap.validate_geometry().map_err(|e| bad(e.to_string()))?;
    let (_, tal_h) = h5::read_real::<f32>(path, &h_ds, "H", max_bytes)?;
    let n_hist = tal_h.len() / bins;
    let mut h = Vec::new();
    h.try_reserve_exact(tal_h.len()).map_err(|_| {
        Error::Limits(format!(
            "{}: cannot allocate {} MiB for H",
            path.display(),
            (tal_h.len() * 4) >> 20
        ))
    })?;
    h.resize(tal_h.len(), 0.0);
    // tal's [t][histogram] to murk's [histogram][t], blocked: an element-wise copy would stride
    // through memory once per value.
    transpose::transpose(&tal_h, &mut h, n_hist, bins);
    drop(tal_h);
    cap.h = h;
    cap.validate_data().map_err(|e| bad(e.to_string()))?;
    // Files murk wrote carry a checksum: a damaged one would otherwise read as a valid capture
    // (checked after the values, whose own faults, such as NaN written in place, say more).
    let attrs = file.root().attrs().unwrap_or_default();
    cap.medium_density = density_cells(&attrs).map_err(bad)?.map(Arc::new);
    h5::check_crc32(path, attrs.get(h5::CRC32_ATTR), || capture_crc32(&cap))?;
    Ok(cap)
}

/// The density cells murk stored in the root attributes (a capture rendered through a density grid),
/// if any; a shape without cells, or cells that no grid could hold, is an error's message.
pub(super) fn density_cells(
    attrs: &HashMap<String, hdf5_pure::AttrValue>,
) -> std::result::Result<Option<DensityCells>, String> {
    use hdf5_pure::AttrValue::{F32Array, U64Array};
    let what = |e: String| format!("{DENSITY_ATTR}: {e}");
    match (attrs.get(DENSITY_SHAPE_ATTR), attrs.get(DENSITY_ATTR)) {
        (None, None) => Ok(None),
        (Some(U64Array(shape)), Some(F32Array(values))) => {
            let shape: Vec<usize> = shape.iter().map(|&d| d as usize).collect();
            DensityCells::new(&shape, values.clone())
                .map(Some)
                .map_err(what)
        }
        _ => Err(what(format!(
            "the medium's density cells need both {DENSITY_ATTR} (f32) and {DENSITY_SHAPE_ATTR} (u64), this file has another pair"
        ))),
    }
}

/// Reads `<side>_grid_xyz` and `<side>_grid_normals`; a missing or empty normals dataset means +z.
fn read_points(
    path: &Path,
    file: &hdf5_pure::File,
    side: &str,
    max_bytes: u64,
) -> Result<PointSet> {
    let xyz_name = format!("{side}_grid_xyz");
    let nrm_name = format!("{side}_grid_normals");
    let bad = |msg: String| Error::format(path, msg);
    let ds = h5::dataset(path, file, &xyz_name)
        .map_err(|_| bad(format!("missing dataset '{xyz_name}'")))?;
    let (shape, xyz) = h5::read_real::<f64>(path, &ds, &xyz_name, max_bytes)?;
    let layout = match shape.as_slice() {
        [nx, ny, 3] => PointLayout::Grid { nx: *nx, ny: *ny },
        [_, 3] => PointLayout::List,
        _ => {
            return Err(bad(format!(
                "'{xyz_name}' has shape {shape:?}, expected (X, Y, 3) or (N, 3)"
            )))
        }
    };
    // The layout comes from the shape; a format y-tal could not even name marks a damaged or foreign file.
    let fmt_name = format!("{side}_grid_format");
    if let Ok(fds) = h5::dataset(path, file, &fmt_name) {
        let f = h5::read_enum_name(path, &fds, &fmt_name)?;
        if !GRID_FORMATS
            .iter()
            .any(|(n, v)| *n == f || v.to_string() == f)
        {
            return Err(bad(format!(
                "'{fmt_name}' is {f}, not a grid format (UNKNOWN = 0, N_3 = 1, X_Y_3 = 2)"
            )));
        }
    }
    let points: Vec<DVec3> = xyz
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0], p[1], p[2]))
        .collect();
    if points.is_empty() {
        return Err(bad(format!("'{xyz_name}' holds no points")));
    }
    let normals = match h5::dataset(path, file, &nrm_name) {
        Err(_) => vec![DVec3::Z; points.len()],
        Ok(nds) => {
            let (nshape, n) = h5::read_real::<f64>(path, &nds, &nrm_name, max_bytes)?;
            if n.is_empty() {
                vec![DVec3::Z; points.len()]
            } else if nshape != shape {
                return Err(bad(format!(
                    "'{nrm_name}' has shape {nshape:?} but '{xyz_name}' has {shape:?}"
                )));
            } else {
                n.chunks_exact(3)
                    .map(|p| DVec3::new(p[0], p[1], p[2]))
                    .collect()
            }
        }
    };
    Ok(PointSet {
        points,
        normals,
        layout,
    })
}
