//! Writing a capture as y-tal does: H transposed to time-first in the layout [`WriteLayout::of`]
//! chooses, the point sets as f32, y-tal's enums, and murk's checksum attribute.

use super::format::{HFormat, WriteLayout, GRID_FORMATS};
use super::{capture_crc32, DENSITY_ATTR, DENSITY_SHAPE_ATTR};
use crate::atomic::write_atomic;
use crate::h5;
use hdf5_pure::{make_i8_type, EnumTypeBuilder, FileBuilder};
use murk_core::{Capture, DVec3, Error, PointLayout, PointSet, Result};
use std::path::Path;

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
    let layout = WriteLayout::of(cap);
    let bins = cap.time.bins;
    let n_hist = cap.n_hist();
    let mut tal_h = vec![0f32; cap.h.len()];
    transpose::transpose(&cap.h, &mut tal_h, bins, n_hist);
    let mut h_shape = vec![bins as u64];
    h_shape.extend(layout.h_dims.iter().map(|&d| d as u64));

    let enum_err = |e: hdf5_pure::FormatError| Error::param(format!("HDF5 enum type: {e}"));
    let enum_type = |members: &[(&str, i32)]| {
        members
            .iter()
            .fold(EnumTypeBuilder::i32_based(), |b, (n, v)| b.value(n, *v))
            .build()
            .map_err(enum_err)
    };
    let h_format_type = enum_type(&HFormat::members())?;
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
        .with_enum_i32_data(h_format_type, &[layout.h_format.code()]);
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
    grid(&mut fb, "sensor", &cap.sensor, layout.lists);
    if let Some(p) = cap.laser_xyz {
        fb.create_dataset("laser_xyz").with_f32_data(&xyz32(&[p]));
    }
    grid(&mut fb, "laser", &cap.illum, layout.lists);
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
    if let Some(cells) = &cap.medium_density {
        // Root attributes, not datasets: y-tal refuses a file with a top-level key it does not know.
        let dims = cells.dims().map(|d| d as u64).to_vec();
        fb.set_attr(DENSITY_SHAPE_ATTR, hdf5_pure::AttrValue::U64Array(dims));
        fb.set_attr(
            DENSITY_ATTR,
            hdf5_pure::AttrValue::F32Array(cells.values().to_vec()),
        );
    }

    write_atomic(path, |w| {
        fb.finish_to(w)
            .map_err(|e| Error::format(path, h5::one_line(format!("HDF5 write failed: {e}"))))
    })
}

fn xyz32(points: &[DVec3]) -> Vec<f32> {
    points
        .iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect()
}
