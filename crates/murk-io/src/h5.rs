//! Thin, defensive helpers over hdf5-pure: every failure becomes a one-line `murk_core::Error`
//! naming the file, and sizes declared by the file are checked before anything is allocated.

use hdf5_pure::{Dataset, Datatype, File};
use murk_core::{Error, Result};
use std::path::Path;

/// One line, whatever the library put in its message.
pub(crate) fn one_line(msg: impl std::fmt::Display) -> String {
    msg.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

pub(crate) fn fmt_err(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::format(path, one_line(msg))
}

/// Runs a read with the HDF5 parser, turning a panic inside it (malformed input the library did
/// not anticipate) into a format error instead of aborting the caller.
pub(crate) fn guarded<T>(path: &Path, f: impl FnOnce() -> Result<T>) -> Result<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let why = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown reason".into());
            Err(fmt_err(
                path,
                format!("corrupt HDF5 data (the reader gave up: {why})"),
            ))
        }
    }
}

/// The root attribute in which murk stores the CRC-32 of what a file holds (captures, ground truths).
pub(crate) const CRC32_ATTR: &str = "murk_crc32";

/// Refuses a file whose stored checksum (`stored`, the [`CRC32_ATTR`] attribute, if the file has
/// one) differs from `got` of the data as read; files without it (another tool's) pass.
pub(crate) fn check_crc32(
    path: &Path,
    stored: Option<&hdf5_pure::AttrValue>,
    got: impl FnOnce() -> u32,
) -> Result<()> {
    let Some(&hdf5_pure::AttrValue::U32(want)) = stored else {
        return Ok(());
    };
    match got() {
        got if got == want => Ok(()),
        got => Err(Error::format(
            path,
            format!("its data do not match the checksum murk wrote with them ({CRC32_ATTR} {want:08x}, now {got:08x}): the file is damaged, or was changed in place by another tool, whose change murk reads once the attribute is deleted"),
        )),
    }
}

/// Opens an HDF5 file lazily (metadata and data are fetched on demand, so a large capture is not
/// buffered twice). Distinguishes "cannot open" (Io) from "not HDF5" (Format).
pub(crate) fn open(path: &Path) -> Result<File> {
    let mut f = murk_core::open_input(path)?;
    let mut head = [0u8; 128];
    let n = read_prefix(&mut f, &mut head).map_err(|e| Error::io(path, e))?;
    if !hdf5_pure::is_hdf5(path).map_err(|e| Error::io(path, e))? {
        if head[..n].starts_with(b"MATLAB 5.0 MAT-file") {
            return Err(Error::format(
                path,
                "this is a MATLAB v5 .mat file, not an HDF5 capture; `murk import` converts it",
            ));
        }
        return Err(Error::format(
            path,
            "not an HDF5 file (no HDF5 signature found)",
        ));
    }
    guarded(path, || {
        File::open_streaming(path).map_err(|e| fmt_err(path, format!("unreadable HDF5: {e}")))
    })
}

pub(crate) fn read_prefix(f: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    use std::io::Read;
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Names of the root group's datasets.
pub(crate) fn root_datasets(path: &Path, file: &File) -> Result<Vec<String>> {
    guarded(path, || {
        file.root()
            .datasets()
            .map_err(|e| fmt_err(path, format!("cannot list datasets: {e}")))
    })
}

pub(crate) fn dataset(path: &Path, file: &File, name: &str) -> Result<Dataset> {
    guarded(path, || {
        file.dataset(name)
            .map_err(|e| fmt_err(path, format!("dataset '{name}': {e}")))
    })
}

pub(crate) fn shape(path: &Path, ds: &Dataset, name: &str) -> Result<Vec<usize>> {
    let s = guarded(path, || {
        ds.shape()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': bad dataspace: {e}")))
    })?;
    s.iter()
        .map(|&d| {
            usize::try_from(d).map_err(|_| {
                Error::Limits(format!(
                    "{}: dataset '{name}' declares a dimension of {d}",
                    path.display()
                ))
            })
        })
        .collect()
}

/// Element count of `shape`, refusing anything whose copy of `elem_bytes`-sized values would
/// exceed `max_bytes`.
pub(crate) fn checked_len(
    path: &Path,
    name: &str,
    shape: &[usize],
    elem_bytes: u64,
    max_bytes: u64,
) -> Result<usize> {
    let n = shape
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(d as u64));
    match n {
        Some(n) if n.saturating_mul(elem_bytes) <= max_bytes => Ok(n as usize),
        _ => Err(Error::Limits(format!(
            "{}: dataset '{name}' declares shape {shape:?}, over the {} MiB read limit",
            path.display(),
            max_bytes >> 20
        ))),
    }
}

/// Element types [`read_real`] can produce.
pub(crate) trait Real: Sized {
    const BYTES: u64;
    fn read(ds: &Dataset) -> std::result::Result<Vec<Self>, hdf5_pure::Error>;
}
impl Real for f32 {
    const BYTES: u64 = 4;
    fn read(ds: &Dataset) -> std::result::Result<Vec<Self>, hdf5_pure::Error> {
        ds.read_f32()
    }
}
impl Real for f64 {
    const BYTES: u64 = 8;
    fn read(ds: &Dataset) -> std::result::Result<Vec<Self>, hdf5_pure::Error> {
        ds.read_f64()
    }
}

/// Reads a real numeric dataset (any integer or float storage) after checking its declared size
/// against `max_bytes`. A null dataspace (h5py's `Empty`, y-tal's `None`) reads as no values.
pub(crate) fn read_real<T: Real>(
    path: &Path,
    ds: &Dataset,
    name: &str,
    max_bytes: u64,
) -> Result<(Vec<usize>, Vec<T>)> {
    let shape = shape(path, ds, name)?;
    let n = checked_len(path, name, &shape, T::BYTES, max_bytes)?;
    let dtype = guarded(path, || {
        ds.datatype()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': bad datatype: {e}")))
    })?;
    if !matches!(
        dtype,
        Datatype::FloatingPoint { .. } | Datatype::FixedPoint { .. }
    ) {
        return Err(Error::format(
            path,
            format!(
                "dataset '{name}' holds {} values, expected real numbers",
                describe(ds)
            ),
        ));
    }
    let data = guarded(path, || {
        T::read(ds).map_err(|e| fmt_err(path, format!("dataset '{name}': {e}")))
    })?;
    if data.len() != n && !(shape.is_empty() && data.is_empty()) {
        return Err(Error::format(
            path,
            format!(
                "dataset '{name}' declares {n} values but holds {}",
                data.len()
            ),
        ));
    }
    Ok((shape, data))
}

/// The member name of a one-element enum dataset (or, for a plain integer dataset, its value as text).
pub(crate) fn read_enum_name(path: &Path, ds: &Dataset, name: &str) -> Result<String> {
    let dtype = guarded(path, || {
        ds.datatype()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': bad datatype: {e}")))
    })?;
    let shape = shape(path, ds, name)?;
    if shape.iter().product::<usize>() != 1 {
        return Err(Error::format(
            path,
            format!("dataset '{name}' should hold one value, has shape {shape:?}"),
        ));
    }
    let raw = guarded(path, || {
        ds.read_raw()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': {e}")))
    })?;
    match dtype {
        Datatype::Enumeration { members, .. } => members
            .iter()
            .find(|m| m.value == raw)
            .map(|m| m.name.clone())
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!("dataset '{name}' holds an undeclared enum value"),
                )
            }),
        Datatype::FixedPoint { .. } => {
            let v = guarded(path, || {
                ds.read_i64()
                    .map_err(|e| fmt_err(path, format!("dataset '{name}': {e}")))
            })?;
            Ok(v[0].to_string())
        }
        _ => Err(Error::format(
            path,
            format!(
                "dataset '{name}' holds {} values, expected an enum",
                describe(ds)
            ),
        )),
    }
}

fn describe(ds: &Dataset) -> String {
    ds.dtype()
        .map(|d| d.to_string())
        .unwrap_or_else(|_| "unreadable".into())
}

/// A scalar string dataset (variable-length or fixed-size).
pub(crate) fn read_string(path: &Path, ds: &Dataset, name: &str, max_bytes: u64) -> Result<String> {
    let shape = shape(path, ds, name)?;
    if shape.iter().product::<usize>() != 1 {
        return Err(Error::format(
            path,
            format!("dataset '{name}' should hold one string, has shape {shape:?}"),
        ));
    }
    let size = guarded(path, || {
        ds.vlen_string_payload_size()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': {e}")))
    })
    .unwrap_or(0);
    if size > max_bytes {
        return Err(Error::Limits(format!(
            "{}: string '{name}' declares {size} bytes, over the read limit",
            path.display()
        )));
    }
    let mut v = guarded(path, || {
        ds.read_string()
            .map_err(|e| fmt_err(path, format!("dataset '{name}': not a string: {e}")))
    })?;
    Ok(v.pop().unwrap_or_default())
}
