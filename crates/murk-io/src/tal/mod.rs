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

mod format;
mod read;
mod write;

pub use read::{read_capture, read_capture_with_limit};
pub use write::{write_capture, write_capture_compressed};

use murk_core::Capture;

/// Default ceiling on what one read may allocate for a single dataset (8 GiB).
pub const DEFAULT_READ_LIMIT_BYTES: u64 = 8 << 30;

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

/// CRC-32 of what a capture file stores, as stored: H histogram by histogram (murk's order, whatever
/// the file's layout), then the points, normals and devices, the time axis as f32, the flag and
/// `scene_info`, all little-endian.
/// The root attributes that hold a heterogeneous medium's density cells (f32, C order) and their
/// shape (nx, ny, nz): attributes, which y-tal's reader passes over, where a dataset would make it
/// refuse the file.
const DENSITY_ATTR: &str = "murk_medium_density";
const DENSITY_SHAPE_ATTR: &str = "murk_medium_density_shape";

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
    // Only where there are cells, so that every other capture keeps its checksum.
    if let Some(cells) = &cap.medium_density {
        for d in cells.dims() {
            crc.update(&(d as u64).to_le_bytes());
        }
        for block in cells.values().chunks(4096) {
            bytes.clear();
            bytes.extend(block.iter().flat_map(|v| v.to_le_bytes()));
            crc.update(&bytes);
        }
    }
    crc.finalize()
}

#[cfg(test)]
mod tests;
