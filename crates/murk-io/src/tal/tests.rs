//! The y-tal format's tests: round trips of every kind, damaged, foreign and corrupted files.

use super::format::HFormat;
use super::*;
use crate::testutil::{all_kinds, assert_same, tmpdir};
use hdf5_pure::{EnumTypeBuilder, FileBuilder};
use murk_core::{Error, PointLayout};
use std::path::Path;

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

/// A capture rendered through a density grid keeps its cells: root attributes (y-tal's reader
/// refuses unknown datasets, and passes over attributes) that read back as written, under the
/// checksum; half of the pair is refused.
#[test]
fn density_cells_round_trip_as_attributes() {
    let dir = tmpdir("density");
    let p = dir.join("c.hdf5");
    let mut cap = all_kinds()[0].1.clone();
    let values: Vec<f32> = (0..24).map(|i| 0.25 * (i % 5) as f32).collect();
    let cells = murk_core::DensityCells::new(&[2, 3, 4], values).unwrap();
    cap.medium_density = Some(std::sync::Arc::new(cells));
    for level in [0, 4] {
        write_capture_compressed(&p, &cap, level).unwrap();
        assert_same(&read_capture(&p).unwrap(), &cap, "density");
    }
    let f = hdf5_pure::File::open(&p).unwrap();
    for k in f.root().datasets().unwrap() {
        assert!(TAL_FIELDS.contains(&k.as_str()), "{k}");
    }
    drop(f);
    // 256 kB of cells: past an object header's 64 kB, in HDF5's dense attribute storage.
    let mut big = cap.clone();
    let values: Vec<f32> = (0..64_000).map(|i| (i % 7) as f32).collect();
    big.medium_density = Some(std::sync::Arc::new(
        murk_core::DensityCells::new(&[40, 40, 40], values).unwrap(),
    ));
    let q = dir.join("big.hdf5");
    write_capture(&q, &big).unwrap();
    assert_same(&read_capture(&q).unwrap(), &big, "dense");
    // A cell changed in place is refused: small cells sit in the root's object header, which HDF5
    // checksums itself; murk's checksum covers them too, for the large ones HDF5 keeps elsewhere.
    let mut bytes = std::fs::read(&p).unwrap();
    let at = bytes
        .windows(8)
        .position(|w| w == [0.25f32.to_le_bytes(), 0.5f32.to_le_bytes()].concat())
        .unwrap();
    bytes[at] ^= 1;
    std::fs::write(&p, &bytes).unwrap();
    let e = err_of(&p);
    assert!(e.contains("c.hdf5") && e.contains("checksum"), "{e}");
    write_capture(&p, &all_kinds()[0].1).unwrap();
    assert_eq!(read_capture(&p).unwrap().medium_density, None);
    // Half of the pair, or cells that no grid could hold: named.
    use hdf5_pure::AttrValue::{F32Array, U64Array};
    let attrs = |pairs: Vec<(&str, hdf5_pure::AttrValue)>| {
        pairs
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect::<std::collections::HashMap<_, _>>()
    };
    let half = attrs(vec![(DENSITY_ATTR, F32Array(vec![1.0; 8]))]);
    let e = super::read::density_cells(&half).unwrap_err();
    assert!(e.contains("need both murk_medium_density (f32)"), "{e}");
    let short = attrs(vec![
        (DENSITY_SHAPE_ATTR, U64Array(vec![2, 2, 2])),
        (DENSITY_ATTR, F32Array(vec![1.0; 7])),
    ]);
    let e = super::read::density_cells(&short).unwrap_err();
    assert!(e.contains("holds 8 cells but 7 values"), "{e}");
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
    let ht = enum_type_for_test(&HFormat::members());
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

/// Each H layout is read by its member name and by its value, and y-tal's other members are not
/// layouts murk reads.
#[test]
fn h_formats_read_by_name_and_value() {
    for (name, code) in HFormat::members().into_iter().skip(1) {
        let f = HFormat::read(name).unwrap();
        assert_eq!((f.name(), f.code()), (name, code));
        assert_eq!(HFormat::read(&code.to_string()), Some(f));
    }
    for other in ["UNKNOWN", "0", "5", "F_Sx_Sy", "t_sx_sy"] {
        assert_eq!(HFormat::read(other), None, "{other}");
    }
}
