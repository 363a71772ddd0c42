//! NumPy `.npy` arrays (format versions 1–3): f32 writer, any-real-dtype reader.

use crate::atomic::write_atomic;
use crate::tal::read_limit_bytes;
use murk_core::{Error, Result};
use std::path::Path;

const MAGIC: &[u8] = b"\x93NUMPY";

/// Writes `data` as a little-endian f32 `.npy` array of `shape`, C order, atomically.
pub fn write_npy_f32(path: &Path, shape: &[usize], data: &[f32]) -> Result<()> {
    let n: usize = shape.iter().product();
    if n != data.len() {
        return Err(Error::param(format!(
            "{}: shape {shape:?} holds {n} values but {} were given",
            path.display(),
            data.len()
        )));
    }
    let dims = match shape {
        [d] => format!("({d},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {dims}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is padded to a multiple of 64.
    let unpadded = MAGIC.len() + 4 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let len = u16::try_from(header.len()).map_err(|_| {
        Error::param(format!(
            "{}: {}-dimensional shape too long for a .npy header",
            path.display(),
            shape.len()
        ))
    })?;
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        w.write_all(MAGIC).map_err(io)?;
        w.write_all(&[1, 0]).map_err(io)?;
        w.write_all(&len.to_le_bytes()).map_err(io)?;
        w.write_all(header.as_bytes()).map_err(io)?;
        let mut buf = Vec::with_capacity(data.len().min(1 << 16) * 4);
        for chunk in data.chunks(1 << 16) {
            buf.clear();
            buf.extend(chunk.iter().flat_map(|v| v.to_le_bytes()));
            w.write_all(&buf).map_err(io)?;
        }
        Ok(())
    })
}

/// Reads a `.npy` array of any real numeric dtype (f2/f4/f8, signed and unsigned integers, bool,
/// either byte order) as f32, returning its shape and values in C order (Fortran-order files are
/// transposed).
pub fn read_npy_f32(path: &Path) -> Result<(Vec<usize>, Vec<f32>)> {
    read_npy_f32_with_limit(path, read_limit_bytes())
}

/// As [`read_npy_f32`], refusing arrays whose f32 copy would exceed `max_bytes`.
pub fn read_npy_f32_with_limit(path: &Path, max_bytes: u64) -> Result<(Vec<usize>, Vec<f32>)> {
    let bad = |msg: String| Error::format(path, msg);
    let mut f = murk_core::open_input(path)?;
    let mut pre = [0u8; 12];
    let got = crate::h5::read_prefix(&mut f, &mut pre).map_err(|e| Error::io(path, e))?;
    if got < 10 || &pre[..6] != MAGIC {
        return Err(bad("not a .npy file (no \\x93NUMPY magic)".into()));
    }
    let (hlen, hstart) = match pre[6] {
        1 => (u16::from_le_bytes([pre[8], pre[9]]) as usize, 10),
        2 | 3 if got == 12 => (
            u32::from_le_bytes([pre[8], pre[9], pre[10], pre[11]]) as usize,
            12,
        ),
        v => return Err(bad(format!(".npy format version {v} is not supported"))),
    };
    let file_len = f.metadata().map_err(|e| Error::io(path, e))?.len();
    if (hstart + hlen) as u64 > file_len {
        return Err(bad("truncated .npy header".into()));
    }
    let bytes = murk_core::read_input(path)?;
    let header = std::str::from_utf8(&bytes[hstart..hstart + hlen])
        .map_err(|_| bad("the .npy header is not text".into()))?;
    let descr = dict_value(header, "descr")
        .and_then(|v| v.strip_prefix('\'').or_else(|| v.strip_prefix('"')))
        .and_then(|v| v.split(['\'', '"']).next())
        .ok_or_else(|| bad(format!("no dtype in the .npy header {header:?}")))?;
    let fortran = match dict_value(header, "fortran_order") {
        Some(v) if v.starts_with("True") => true,
        Some(v) if v.starts_with("False") => false,
        _ => return Err(bad("no fortran_order in the .npy header".into())),
    };
    let shape_text = dict_value(header, "shape")
        .and_then(|v| v.strip_prefix('('))
        .and_then(|v| v.split(')').next())
        .ok_or_else(|| bad("no shape in the .npy header".into()))?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<usize>())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| bad(format!("bad shape ({shape_text}) in the .npy header")))?;

    let (order, kind, size) = parse_descr(descr)
        .ok_or_else(|| bad(format!("dtype '{descr}' is not a real number type")))?;
    let n = shape
        .iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d as u64))
        .filter(|n| n.saturating_mul(4) <= max_bytes)
        .ok_or_else(|| {
            Error::Limits(format!(
                "{}: array of shape {shape:?} is over the {} MiB read limit",
                path.display(),
                max_bytes >> 20
            ))
        })? as usize;
    let body = &bytes[hstart + hlen..];
    if (body.len() as u64) < n as u64 * size as u64 {
        return Err(bad(format!(
            "truncated .npy data: shape {shape:?} of '{descr}' needs {} bytes, the file has {}",
            n * size,
            body.len()
        )));
    }
    // numpy never writes past the array: more bytes mean a header whose shape or dtype is wrong.
    if body.len() > n * size {
        return Err(bad(format!(
            "{} bytes after the array's data (shape {shape:?} of '{descr}' takes {}); the header does not describe this file",
            body.len() - n * size,
            n * size
        )));
    }
    let big = order == '>';
    let mut data: Vec<f32> = body[..n * size]
        .chunks_exact(size)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..size].copy_from_slice(c);
            if big {
                b[..size].reverse();
            }
            decode(kind, size, b)
        })
        .collect();
    if fortran && shape.len() > 1 {
        data = fortran_to_c(&shape, &data);
    }
    Ok((shape, data))
}

/// The text after `'key':` in a header dict.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let at = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = &header[at + key.len() + 2..];
    Some(rest.trim_start().strip_prefix(':')?.trim_start())
}

/// (byte order, kind, item size) of a real numeric dtype such as `<f4`, `|u1`, `>i8`, `|b1`.
fn parse_descr(d: &str) -> Option<(char, char, usize)> {
    let mut c = d.chars();
    let (order, kind) = match c.next()? {
        o @ ('<' | '>' | '|' | '=') => (o, c.next()?),
        k => ('=', k),
    };
    let size: usize = c.as_str().parse().ok()?;
    let ok = match kind {
        'f' => matches!(size, 2 | 4 | 8),
        'i' | 'u' => matches!(size, 1 | 2 | 4 | 8),
        'b' => size == 1,
        _ => false,
    };
    let order = if order == '=' { '<' } else { order };
    ok.then_some((order, kind, size))
}

fn decode(kind: char, size: usize, b: [u8; 8]) -> f32 {
    match (kind, size) {
        ('f', 2) => f16_to_f32(u16::from_le_bytes([b[0], b[1]])),
        ('f', 4) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        ('f', _) => f64::from_le_bytes(b) as f32,
        ('i', 1) => b[0] as i8 as f32,
        ('i', 2) => i16::from_le_bytes([b[0], b[1]]) as f32,
        ('i', 4) => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        ('i', _) => i64::from_le_bytes(b) as f32,
        ('u', 2) => u16::from_le_bytes([b[0], b[1]]) as f32,
        ('u', 4) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        ('u', 8) => u64::from_le_bytes(b) as f32,
        _ => b[0] as f32,
    }
}

fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let frac = (h & 0x3ff) as f32;
    sign * match exp {
        0 => frac * 2f32.powi(-24),
        31 if frac == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + frac / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Reorders column-major values of `shape` into row-major order.
pub(crate) fn fortran_to_c<T: Copy>(shape: &[usize], data: &[T]) -> Vec<T> {
    let mut out = Vec::with_capacity(data.len());
    let mut idx = vec![0usize; shape.len()];
    // Column-major strides: the first axis varies fastest.
    let mut strides = vec![1usize; shape.len()];
    for k in 1..shape.len() {
        strides[k] = strides[k - 1] * shape[k - 1];
    }
    for _ in 0..data.len() {
        out.push(data[idx.iter().zip(&strides).map(|(i, s)| i * s).sum::<usize>()]);
        // Advance the row-major multi-index (last axis fastest).
        for k in (0..shape.len()).rev() {
            idx[k] += 1;
            if idx[k] < shape[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let dir = crate::testutil::tmpdir("npy");
        let p = dir.join("v.npy");
        let data: Vec<f32> = (0..24).map(|i| i as f32 * 0.5 - 3.0).collect();
        write_npy_f32(&p, &[2, 3, 4], &data).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(bytes.len() % 16, 0, "header aligned");
        assert_eq!(read_npy_f32(&p).unwrap(), (vec![2, 3, 4], data.clone()));
        write_npy_f32(&p, &[24], &data).unwrap();
        assert_eq!(read_npy_f32(&p).unwrap().0, vec![24]);
        assert!(write_npy_f32(&p, &[5], &data).is_err());

        std::fs::write(&p, &bytes[..bytes.len() - 3]).unwrap();
        let e = read_npy_f32(&p).unwrap_err().to_string();
        assert!(e.contains("truncated") && e.contains("v.npy"), "{e}");
        std::fs::write(&p, b"PK\x03\x04").unwrap();
        assert!(read_npy_f32(&p)
            .unwrap_err()
            .to_string()
            .contains("not a .npy"));
        assert!(matches!(
            read_npy_f32(&dir.join("none.npy")),
            Err(Error::Io { .. })
        ));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn other_dtypes_and_fortran_order() {
        let dir = crate::testutil::tmpdir("npy2");
        let p = dir.join("u.npy");
        // numpy.save of np.asfortranarray(np.arange(6, dtype='>u2').reshape(2, 3)).
        let mut header = "{'descr': '>u2', 'fortran_order': True, 'shape': (2, 3), }".to_string();
        header.push_str(&" ".repeat(128 - 10 - header.len() - 1));
        header.push('\n');
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend((header.len() as u16).to_le_bytes());
        b.extend(header.as_bytes());
        for v in [0u16, 3, 1, 4, 2, 5] {
            b.extend(v.to_be_bytes());
        }
        std::fs::write(&p, &b).unwrap();
        let (s, v) = read_npy_f32(&p).unwrap();
        assert_eq!(s, vec![2, 3]);
        assert_eq!(v, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert!(read_npy_f32_with_limit(&p, 8).is_err());
        std::fs::remove_dir_all(dir).ok();
    }
}
