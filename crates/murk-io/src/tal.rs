//! y-tal's HDF5 capture format (`tal.io.read_capture` / `write_capture`), murk's native format.
//!
//! A file holds one top-level dataset per field and nothing else (y-tal refuses unknown keys):
//!
//! | field | stored as |
//! |---|---|
//! | `H` | f32, time axis first: `T_Sx_Sy` (T,Sx,Sy), `T_Lx_Ly_Sx_Sy` (T,Lx,Ly,Sx,Sy), `T_Si` (T,N), `T_Li_Si` (T,Nl,Ns) |
//! | `H_format`, `sensor_grid_format`, `laser_grid_format` | one-element i32 enum with y-tal's member names |
//! | `sensor_grid_xyz`, `sensor_grid_normals`, `laser_grid_xyz`, `laser_grid_normals` | f32 (X,Y,3) for `X_Y_3` grids, (N,3) for `N_3` lists |
//! | `sensor_xyz`, `laser_xyz` | f32 (3,), left out when unknown (y-tal reads that as `None`) |
//! | `delta_t`, `t_start` | f32 scalars, metres of optical path |
//! | `t_accounts_first_and_last_bounces` | h5py bool (i8 enum FALSE/TRUE) scalar |
//! | `scene_info` | UTF-8 variable-length string scalar holding YAML |
//! | `volume_format` | deprecated; left out on write, ignored on read |
//!
//! murk also writes one root attribute, `murk_crc32`: the CRC-32 of H, the points, normals, devices,
//! time axis and `scene_info` as stored, which a read checks where it is present (y-tal ignores
//! attributes, and writes none).
//!
//! Mapping to [`Capture`]: tal's histogram index over the non-time axes in C order equals murk's
//! (laser grids `[ix, iy]` are murk's x-major `Grid`, product index = l·n_sensor + s), so H is a
//! (T, n_hist) ↔ (n_hist, T) transpose. Which layout murk writes:
//!
//! * paired captures whose two point sets are grids of one shape → `T_Sx_Sy` with a laser grid of
//!   the sensor grid's shape (y-tal's confocal/paired); other paired captures → `T_Si`, both sets
//!   written as `N_3` lists (a grid layout is not kept then);
//! * product captures with one laser point → `T_Sx_Sy` (sensor grid) or `T_Si` (sensor list);
//! * other product captures → `T_Lx_Ly_Sx_Sy` when both sets are grids (the paper's "laser grid +
//!   one SPAD point" is Sx = Sy = 1), else `T_Li_Si`.
//!
//! Round trip murk → tal → murk keeps every field bit-exactly, with two stated exceptions:
//! coordinates, normals, `delta_t` and `t_start` are stored as f32 (as y-tal does), so only values
//! representable in f32 survive unchanged; and a paired capture of a single point reads back as a
//! product capture of one laser and one sensor point (the file cannot tell them apart, and they
//! mean the same measurement).

use crate::atomic::write_atomic;
use crate::h5;
use hdf5_pure::{make_i8_type, EnumTypeBuilder, FileBuilder};
use murk_core::{Capture, DVec3, Error, Pairing, PointLayout, PointSet, Result, TimeAxis};
use std::path::Path;

/// Default ceiling on what one read may allocate for a single dataset (8 GiB).
pub const DEFAULT_READ_LIMIT_BYTES: u64 = 8 << 30;

const H_FORMATS: [(&str, i32); 5] = [
    ("UNKNOWN", 0),
    ("T_Sx_Sy", 1),
    ("T_Lx_Ly_Sx_Sy", 2),
    ("T_Si", 3),
    ("T_Li_Si", 4),
];
const GRID_FORMATS: [(&str, i32); 3] = [("UNKNOWN", 0), ("N_3", 1), ("X_Y_3", 2)];

/// The fields y-tal's `NLOSCaptureData` accepts, in its `as_dict()` order.
pub const TAL_FIELDS: [&str; 15] = [
    "H",
    "H_format",
    "sensor_xyz",
    "sensor_grid_xyz",
    "sensor_grid_normals",
    "sensor_grid_format",
    "laser_xyz",
    "laser_grid_xyz",
    "laser_grid_normals",
    "laser_grid_format",
    "volume_format",
    "delta_t",
    "t_start",
    "t_accounts_first_and_last_bounces",
    "scene_info",
];

/// The largest array murk reads from a file: the file readers' limit or the memory budget
/// (`MURK_MAX_BYTES`, else physical memory), whichever is smaller.
pub(crate) fn read_limit_bytes() -> u64 {
    DEFAULT_READ_LIMIT_BYTES.min(murk_core::Limits::get().max_bytes)
}

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
    let h_format = match h_format.as_str() {
        "1" => "T_Sx_Sy",
        "2" => "T_Lx_Ly_Sx_Sy",
        "3" => "T_Si",
        "4" => "T_Li_Si",
        s => s,
    }
    .to_string();
    if !H_FORMATS[1..].iter().any(|(n, _)| *n == h_format) {
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
    }

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
    let grid_dims = |p: &PointSet| -> Vec<usize> {
        match p.layout {
            PointLayout::Grid { nx, ny } => vec![nx, ny],
            PointLayout::List => vec![p.len()],
        }
    };
    let pairing = match h_format.as_str() {
        "T_Sx_Sy" | "T_Si" => {
            if h_format == "T_Sx_Sy" && !matches!(sensor.layout, PointLayout::Grid { .. }) {
                return Err(bad(
                    "H_format T_Sx_Sy needs a sensor grid of shape (Sx, Sy, 3)".to_string(),
                ));
            }
            if h_format == "T_Si" {
                expect_dims(&[ns])?;
            } else {
                expect_dims(&grid_dims(&sensor))?;
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
        "T_Lx_Ly_Sx_Sy" => {
            let (PointLayout::Grid { .. }, PointLayout::Grid { .. }) =
                (illum.layout, sensor.layout)
            else {
                return Err(bad(
                    "H_format T_Lx_Ly_Sx_Sy needs laser and sensor grids of shape (X, Y, 3)"
                        .to_string(),
                ));
            };
            expect_dims(&[grid_dims(&illum), grid_dims(&sensor)].concat())?;
            Pairing::Product
        }
        _ => {
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
        illum,
        sensor,
        laser_xyz: device("laser_xyz")?,
        sensor_xyz: device("sensor_xyz")?,
        time: TimeAxis {
            start_m: scalar("t_start")?,
            bin_width_m: scalar("delta_t")?,
            bins,
        },
        t_accounts_first_and_last_bounces: t_accounts,
        pairing,
        h: Vec::new(),
        scene_info,
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
    h5::check_crc32(path, attrs.get(h5::CRC32_ATTR), || capture_crc32(&cap))?;
    Ok(cap)
}

/// CRC-32 of what a capture file stores, as stored: H histogram by histogram (murk's order, whatever
/// the file's layout), then the points, normals and devices, the time axis as f32, the flag and
/// `scene_info`, all little-endian.
fn capture_crc32(cap: &Capture) -> u32 {
    let mut crc = crc32fast::Hasher::new();
    let mut bytes = Vec::with_capacity(4 * 4096);
    for block in cap.h.chunks(4096) {
        bytes.clear();
        bytes.extend(block.iter().flat_map(|v| v.to_le_bytes()));
        crc.update(&bytes);
    }
    let f32s = |crc: &mut crc32fast::Hasher, vs: &mut dyn Iterator<Item = f64>| {
        for v in vs {
            crc.update(&(v as f32).to_le_bytes());
        }
    };
    for set in [&cap.illum, &cap.sensor] {
        f32s(
            &mut crc,
            &mut set
                .points
                .iter()
                .chain(&set.normals)
                .flat_map(|p| p.to_array()),
        );
    }
    for device in [cap.laser_xyz, cap.sensor_xyz] {
        crc.update(&[device.is_some() as u8]);
        f32s(&mut crc, &mut device.into_iter().flat_map(|p| p.to_array()));
    }
    f32s(
        &mut crc,
        &mut [cap.time.start_m, cap.time.bin_width_m].into_iter(),
    );
    crc.update(&[cap.t_accounts_first_and_last_bounces as u8]);
    crc.update(cap.scene_info.as_bytes());
    crc.finalize()
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

/// Writes `cap` as a y-tal HDF5 capture (uncompressed), atomically.
pub fn write_capture(path: &Path, cap: &Capture) -> Result<()> {
    write_capture_compressed(path, cap, 0)
}

/// As [`write_capture`], gzip-compressing H at `level` 1..=9 (0 = none), as y-tal's
/// `compression_level` does.
pub fn write_capture_compressed(path: &Path, cap: &Capture, level: u32) -> Result<()> {
    crate::check_h5_name(path)?;
    if level > 9 {
        return Err(Error::param(format!(
            "compression level must be 0..=9, got {level}"
        )));
    }
    cap.validate()?;
    let plan = plan_layout(cap);
    let bins = cap.time.bins;
    let n_hist = cap.n_hist();
    let mut tal_h = vec![0f32; cap.h.len()];
    transpose::transpose(&cap.h, &mut tal_h, bins, n_hist);
    let mut h_shape = vec![bins as u64];
    h_shape.extend(plan.h_dims.iter().map(|&d| d as u64));

    let enum_err = |e: hdf5_pure::FormatError| Error::param(format!("HDF5 enum type: {e}"));
    let enum_type = |members: &[(&str, i32)]| {
        members
            .iter()
            .fold(EnumTypeBuilder::i32_based(), |b, (n, v)| b.value(n, *v))
            .build()
            .map_err(enum_err)
    };
    let h_format_type = enum_type(&H_FORMATS)?;
    let grid_type = enum_type(&GRID_FORMATS)?;
    let bool_type = EnumTypeBuilder::with_base(make_i8_type())
        .value("FALSE", 0)
        .value("TRUE", 1)
        .build()
        .map_err(enum_err)?;
    let code = |table: &[(&str, i32)], name: &str| {
        table
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .unwrap_or(0)
    };

    let mut fb = FileBuilder::new();
    fb.set_attr(
        h5::CRC32_ATTR,
        hdf5_pure::AttrValue::U32(capture_crc32(cap)),
    );
    let h = fb.create_dataset("H");
    h.with_shape(&h_shape).with_f32_data(&tal_h);
    if level > 0 {
        h.with_deflate(level);
    }
    drop(tal_h);
    fb.create_dataset("H_format")
        .with_enum_i32_data(h_format_type, &[code(&H_FORMATS, plan.h_format)]);
    if let Some(p) = cap.sensor_xyz {
        fb.create_dataset("sensor_xyz").with_f32_data(&xyz32(&[p]));
    }
    let grid = |fb: &mut FileBuilder, side: &str, set: &PointSet, as_list: bool| {
        let shape: Vec<u64> = match (set.layout, as_list) {
            (PointLayout::Grid { nx, ny }, false) => vec![nx as u64, ny as u64, 3],
            _ => vec![set.len() as u64, 3],
        };
        fb.create_dataset(&format!("{side}_grid_xyz"))
            .with_shape(&shape)
            .with_f32_data(&xyz32(&set.points));
        fb.create_dataset(&format!("{side}_grid_normals"))
            .with_shape(&shape)
            .with_f32_data(&xyz32(&set.normals));
        let fmt = if shape.len() == 3 { "X_Y_3" } else { "N_3" };
        fb.create_dataset(&format!("{side}_grid_format"))
            .with_enum_i32_data(grid_type.clone(), &[code(&GRID_FORMATS, fmt)]);
    };
    grid(&mut fb, "sensor", &cap.sensor, plan.lists);
    if let Some(p) = cap.laser_xyz {
        fb.create_dataset("laser_xyz").with_f32_data(&xyz32(&[p]));
    }
    grid(&mut fb, "laser", &cap.illum, plan.lists);
    fb.create_dataset("delta_t")
        .with_shape(&[])
        .with_f32_data(&[cap.time.bin_width_m as f32]);
    fb.create_dataset("t_start")
        .with_shape(&[])
        .with_f32_data(&[cap.time.start_m as f32]);
    fb.create_dataset("t_accounts_first_and_last_bounces")
        .with_shape(&[])
        .with_enum_u8_data(bool_type, &[cap.t_accounts_first_and_last_bounces as u8]);
    fb.create_dataset("scene_info")
        .with_shape(&[])
        .with_vlen_strings(&[cap.scene_info.as_str()]);

    write_atomic(path, |w| {
        fb.finish_to(w)
            .map_err(|e| Error::format(path, h5::one_line(format!("HDF5 write failed: {e}"))))
    })
}

struct Plan {
    h_format: &'static str,
    /// H's non-time dimensions.
    h_dims: Vec<usize>,
    /// Write both point sets as `N_3` lists regardless of their layout.
    lists: bool,
}

fn plan_layout(cap: &Capture) -> Plan {
    let dims = |p: &PointSet| match p.layout {
        PointLayout::Grid { nx, ny } => vec![nx, ny],
        PointLayout::List => vec![p.len()],
    };
    let (il, sl) = (cap.illum.layout, cap.sensor.layout);
    let sensor_grid = matches!(sl, PointLayout::Grid { .. });
    match cap.pairing {
        Pairing::Paired if sensor_grid && il == sl => Plan {
            h_format: "T_Sx_Sy",
            h_dims: dims(&cap.sensor),
            lists: false,
        },
        Pairing::Paired => Plan {
            h_format: "T_Si",
            h_dims: vec![cap.sensor.len()],
            lists: true,
        },
        Pairing::Product if cap.illum.len() == 1 => Plan {
            h_format: if sensor_grid { "T_Sx_Sy" } else { "T_Si" },
            h_dims: dims(&cap.sensor),
            lists: false,
        },
        Pairing::Product if sensor_grid && matches!(il, PointLayout::Grid { .. }) => Plan {
            h_format: "T_Lx_Ly_Sx_Sy",
            h_dims: [dims(&cap.illum), dims(&cap.sensor)].concat(),
            lists: false,
        },
        Pairing::Product => Plan {
            h_format: "T_Li_Si",
            h_dims: vec![cap.illum.len(), cap.sensor.len()],
            lists: false,
        },
    }
}

fn xyz32(points: &[DVec3]) -> Vec<f32> {
    points
        .iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Coordinates on a 1/64 m lattice so that their f32 copies are exact.
    fn grid(nx: usize, ny: usize, z: f64) -> PointSet {
        let mut points = Vec::new();
        for ix in 0..nx {
            for iy in 0..ny {
                points.push(DVec3::new(ix as f64 * 0.125 - 0.25, iy as f64 * 0.0625, z));
            }
        }
        PointSet {
            normals: (0..points.len())
                .map(|i| DVec3::new(0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 }))
                .collect(),
            points,
            layout: PointLayout::Grid { nx, ny },
        }
    }

    fn list(n: usize) -> PointSet {
        PointSet {
            points: (0..n)
                .map(|i| DVec3::new(i as f64 * 0.125, -0.0625 * i as f64, 0.5))
                .collect(),
            normals: vec![DVec3::Z; n],
            layout: PointLayout::List,
        }
    }

    pub(crate) fn capture(illum: PointSet, sensor: PointSet, pairing: Pairing) -> Capture {
        let bins = 7;
        let mut c = Capture {
            illum,
            sensor,
            laser_xyz: Some(DVec3::new(-1.5, 0.25, 2.0)),
            sensor_xyz: None,
            time: TimeAxis {
                start_m: 0.75,
                bin_width_m: 0.0078125,
                bins,
            },
            t_accounts_first_and_last_bounces: false,
            pairing,
            h: Vec::new(),
            scene_info: "name: test\nvalues:\n- 1\n- 2\n".into(),
        };
        c.h = (0..c.n_hist() * bins)
            .map(|i| (i as f32 * 0.37).sin())
            .collect();
        c
    }

    /// One capture of every kind murk distinguishes, with every layout the writer chooses.
    pub(crate) fn all_kinds() -> Vec<(&'static str, Capture)> {
        let mut confocal = capture(grid(3, 4, 0.0), grid(3, 4, 0.0), Pairing::Paired);
        confocal.t_accounts_first_and_last_bounces = true;
        confocal.sensor_xyz = Some(DVec3::new(1.0, 2.0, 3.0));
        vec![
            ("confocal", confocal),
            (
                "paired",
                capture(grid(2, 3, 0.0), grid(2, 3, 0.125), Pairing::Paired),
            ),
            ("paired_list", capture(list(5), list(5), Pairing::Paired)),
            (
                "single",
                capture(
                    PointSet::single(DVec3::new(0.5, 0.5, 0.0)),
                    grid(4, 2, 0.0),
                    Pairing::Product,
                ),
            ),
            (
                "single_list",
                capture(PointSet::single(DVec3::ZERO), list(6), Pairing::Product),
            ),
            (
                "laser_grid_one_spad",
                capture(
                    grid(3, 2, 0.0),
                    PointSet::single(DVec3::new(0.0, 0.25, 0.0)),
                    Pairing::Product,
                ),
            ),
            (
                "exhaustive",
                capture(grid(2, 3, 0.0), grid(3, 2, 0.0), Pairing::Product),
            ),
            (
                "exhaustive_list",
                capture(list(3), list(4), Pairing::Product),
            ),
            (
                "exhaustive_mixed",
                capture(grid(2, 2, 0.0), list(3), Pairing::Product),
            ),
        ]
    }

    pub(crate) fn tmpdir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("murk-io-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    pub(crate) fn assert_same(a: &Capture, b: &Capture, what: &str) {
        assert_eq!(a.illum, b.illum, "{what}: illum");
        assert_eq!(a.sensor, b.sensor, "{what}: sensor");
        assert_eq!(a.laser_xyz, b.laser_xyz, "{what}: laser_xyz");
        assert_eq!(a.sensor_xyz, b.sensor_xyz, "{what}: sensor_xyz");
        assert_eq!(a.time, b.time, "{what}: time");
        assert_eq!(
            a.t_accounts_first_and_last_bounces, b.t_accounts_first_and_last_bounces,
            "{what}: t_accounts"
        );
        assert_eq!(a.pairing, b.pairing, "{what}: pairing");
        assert_eq!(
            a.h.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            b.h.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            "{what}: H"
        );
        assert_eq!(a.scene_info, b.scene_info, "{what}: scene_info");
    }

    #[test]
    fn round_trip_every_kind() {
        let dir = tmpdir("rt");
        for (name, cap) in all_kinds() {
            for level in [0, 4] {
                let p = dir.join(format!("{name}-{level}.hdf5"));
                write_capture_compressed(&p, &cap, level).unwrap();
                let back = read_capture(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_eq!(back.kind(), cap.kind(), "{name}");
                let mut want = cap.clone();
                if name == "paired_list" {
                    // Documented: paired captures without a common grid shape are written as lists.
                    want.illum.layout = PointLayout::List;
                }
                assert_same(&back, &want, name);
            }
        }
        std::fs::remove_dir_all(dir).ok();
    }

    /// One bit flipped in H, in a point's coordinate or in the time axis is refused, naming the file
    /// and the checksum; the unchanged file reads.
    #[test]
    fn a_damaged_capture_is_refused() {
        let dir = tmpdir("crc");
        let p = dir.join("c.hdf5");
        let cap = all_kinds()[0].1.clone();
        let laser_x = cap.laser_xyz.unwrap().x as f32;
        for (what, value) in [
            ("H", cap.h[5].to_le_bytes()),
            ("laser_xyz", laser_x.to_le_bytes()),
            ("delta_t", (cap.time.bin_width_m as f32).to_le_bytes()),
        ] {
            write_capture(&p, &cap).unwrap();
            assert!(read_capture(&p).is_ok());
            let mut bytes = std::fs::read(&p).unwrap();
            let at = bytes.windows(4).position(|w| w == value).unwrap();
            bytes[at] ^= 1;
            std::fs::write(&p, &bytes).unwrap();
            let e = err_of(&p);
            assert!(
                e.contains("c.hdf5")
                    && e.contains("its data do not match the checksum murk wrote with them"),
                "{what}: {e}"
            );
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn writes_only_tal_fields() {
        let dir = tmpdir("fields");
        let p = dir.join("c.hdf5");
        write_capture(&p, &all_kinds()[0].1).unwrap();
        let f = hdf5_pure::File::open(&p).unwrap();
        for k in f.root().datasets().unwrap() {
            assert!(TAL_FIELDS.contains(&k.as_str()), "{k}");
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn invalid_capture_is_not_written() {
        let dir = tmpdir("invalid");
        let p = dir.join("c.hdf5");
        let mut c = all_kinds()[0].1.clone();
        c.h.pop();
        assert!(matches!(write_capture(&p, &c), Err(Error::Parameter(_))));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(dir).ok();
    }

    fn err_of(p: &Path) -> String {
        let e = read_capture(p).unwrap_err().to_string();
        assert!(!e.contains('\n'), "multi-line error: {e}");
        e
    }

    #[test]
    fn bad_input_gives_one_line_errors() {
        let dir = tmpdir("bad");
        let missing = dir.join("missing.hdf5");
        assert!(matches!(read_capture(&missing), Err(Error::Io { .. })));
        assert!(err_of(&missing).contains("missing.hdf5"));

        let text = dir.join("text.hdf5");
        std::fs::write(&text, "hello").unwrap();
        assert!(err_of(&text).contains("not an HDF5 file"));

        let empty = dir.join("empty.hdf5");
        std::fs::write(&empty, "").unwrap();
        assert!(err_of(&empty).contains("not an HDF5 file"));

        let other = dir.join("other.hdf5");
        let mut fb = FileBuilder::new();
        fb.create_dataset("data").with_f32_data(&[1.0, 2.0]);
        fb.write(&other).unwrap();
        let e = err_of(&other);
        assert!(
            e.contains("not a y-tal capture") && e.contains("data"),
            "{e}"
        );

        let good = dir.join("good.hdf5");
        let cap = all_kinds()[6].1.clone();
        write_capture(&good, &cap).unwrap();
        let e = read_capture_with_limit(&good, 64).unwrap_err();
        assert!(matches!(e, Error::Limits(_)), "{e}");
        assert!(e.to_string().contains("good.hdf5"), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    /// A capture whose H does not match its grids, written field by field.
    #[test]
    fn inconsistent_shapes_are_reported() {
        let dir = tmpdir("shape");
        let p = dir.join("bad.hdf5");
        let fb = field_by_field(
            (&[4, 2, 3], &[0.0; 24]),
            (&[3, 3, 3], &[0.0; 27]),
            (&[1, 1, 3], &[0.0; 3]),
            0.01,
        );
        fb.write(&p).unwrap();
        let e = err_of(&p);
        assert!(
            e.contains("H has shape [4, 2, 3]") && e.contains("bad.hdf5"),
            "{e}"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    /// An absurd time window is refused before H is read: with a read limit below H's size, the
    /// window is still what is named.
    #[test]
    fn an_absurd_window_is_refused_before_h_is_read() {
        let dir = tmpdir("window");
        let p = dir.join("far.hdf5");
        field_by_field(
            (&[64, 2, 2], &[1.0; 256]),
            (&[2, 2, 3], &UNIT_SQUARE),
            (&[1, 3], &[0.5, 0.5, 0.0]),
            1e5,
        )
        .write(&p)
        .unwrap();
        let e = read_capture_with_limit(&p, 512).unwrap_err().to_string();
        assert!(
            e.contains("far.hdf5") && e.contains("the time window's end"),
            "{e}"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    /// A grid format outside y-tal's enum, stored as a plain integer, is named; a known one passes.
    #[test]
    fn unknown_grid_formats_are_reported() {
        let dir = tmpdir("gridfmt");
        let p = dir.join("fmt.hdf5");
        for (code, ok) in [(2, true), (9, false)] {
            let mut fb = field_by_field(
                (&[4, 2, 2], &[1.0; 16]),
                (&[2, 2, 3], &UNIT_SQUARE),
                (&[1, 3], &[0.5, 0.5, 0.0]),
                0.01,
            );
            fb.create_dataset("sensor_grid_format")
                .with_shape(&[1])
                .with_i32_data(&[code]);
            fb.write(&p).unwrap();
            match read_capture(&p) {
                Ok(_) => assert!(ok, "format {code} was accepted"),
                Err(e) => {
                    let e = e.to_string();
                    assert!(!ok, "format {code}: {e}");
                    assert!(
                        e.contains("'sensor_grid_format' is 9, not a grid format")
                            && e.contains("fmt.hdf5"),
                        "{e}"
                    );
                }
            }
        }
        std::fs::remove_dir_all(dir).ok();
    }

    /// The corners of a unit square at z = 0, as a 2 × 2 grid of wall points.
    const UNIT_SQUARE: [f32; 12] = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0];

    /// A time-domain capture (H_format T_Sx_Sy, bins of `delta_t` m from 0) written dataset by
    /// dataset from (shape, values) of H and of the sensor and laser grids, as a foreign writer might.
    fn field_by_field(
        h: (&[u64], &[f32]),
        sensor: (&[u64], &[f32]),
        laser: (&[u64], &[f32]),
        delta_t: f32,
    ) -> FileBuilder {
        let mut fb = FileBuilder::new();
        fb.create_dataset("H").with_shape(h.0).with_f32_data(h.1);
        let ht = enum_type_for_test(&H_FORMATS);
        fb.create_dataset("H_format").with_enum_i32_data(ht, &[1]);
        fb.create_dataset("sensor_grid_xyz")
            .with_shape(sensor.0)
            .with_f32_data(sensor.1);
        fb.create_dataset("laser_grid_xyz")
            .with_shape(laser.0)
            .with_f32_data(laser.1);
        fb.create_dataset("delta_t")
            .with_shape(&[])
            .with_f32_data(&[delta_t]);
        fb.create_dataset("t_start")
            .with_shape(&[])
            .with_f32_data(&[0.0]);
        fb
    }

    fn enum_type_for_test(m: &[(&str, i32)]) -> hdf5_pure::Datatype {
        m.iter()
            .fold(EnumTypeBuilder::i32_based(), |b, (n, v)| b.value(n, *v))
            .build()
            .unwrap()
    }

    /// Truncated and bit-flipped copies must give errors (or, for harmless flips, a capture), never a panic.
    #[test]
    fn corrupted_files_never_panic() {
        let dir = tmpdir("fuzz");
        let good = dir.join("good.hdf5");
        write_capture(&good, &all_kinds()[0].1).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        let p = dir.join("bad.hdf5");
        let mut cuts: Vec<usize> = (0..bytes.len()).step_by(97).collect();
        cuts.extend([8, 48, bytes.len() - 1]);
        for cut in cuts {
            std::fs::write(&p, &bytes[..cut]).unwrap();
            if let Err(e) = read_capture(&p) {
                assert!(!e.to_string().contains('\n'));
            }
        }
        // Deterministic pseudo-random byte flips (xorshift).
        let mut s = 0x9e3779b97f4a7c15u64;
        for _ in 0..300 {
            let mut b = bytes.clone();
            for _ in 0..4 {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let i = (s % b.len() as u64) as usize;
                b[i] ^= (s >> 32) as u8 | 1;
            }
            std::fs::write(&p, &b).unwrap();
            let _ = read_capture_with_limit(&p, 1 << 20);
        }
        std::fs::remove_dir_all(dir).ok();
    }
}
