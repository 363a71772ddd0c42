//! MATLAB v5 (v6/v7, non-HDF5) `.mat` files: numeric, logical and char arrays, structs and cell
//! arrays, compressed or not, either byte order. Every declared size is checked against the bytes
//! that hold it before anything is allocated, and decompression stops at the memory budget, so a
//! corrupt file fails fast with one line.

use murk_core::{Error, Limits, Result};
use std::io::Read;
use std::path::Path;

/// A decoded MATLAB value. Dimensions are MATLAB's (column-major order of the values).
#[derive(Clone, Debug)]
pub enum MatValue {
    /// Numeric or logical array, converted to f64.
    Numeric {
        dims: Vec<usize>,
        values: Vec<f64>,
    },
    Char(String),
    /// A struct array: `fields[f][e]` is field `f` of element `e` (column-major over `dims`).
    Struct {
        dims: Vec<usize>,
        names: Vec<String>,
        fields: Vec<Vec<MatValue>>,
    },
    Cell {
        dims: Vec<usize>,
        items: Vec<MatValue>,
    },
    /// A class murk does not decode (sparse, objects, function handles), by name.
    Other(&'static str),
}

impl MatValue {
    /// A short description for messages: "double 64×64×512", "struct 1×1 (transient, l, s)".
    pub fn describe(&self) -> String {
        let dims = |d: &[usize]| {
            d.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join("×")
        };
        match self {
            MatValue::Numeric { dims: d, .. } => format!("numeric {}", dims(d)),
            MatValue::Char(s) => format!("char '{s}'"),
            MatValue::Struct { dims: d, names, .. } => {
                format!("struct {} ({})", dims(d), names.join(", "))
            }
            MatValue::Cell { dims: d, .. } => format!("cell {}", dims(d)),
            MatValue::Other(c) => c.to_string(),
        }
    }
}

/// The top-level variables of a v5 file, in file order.
pub fn read_mat_v5(path: &Path) -> Result<Vec<(String, MatValue)>> {
    let bytes = murk_core::read_input(path)?;
    parse(&bytes).map_err(|msg| Error::format(path, format!("MATLAB v5 file: {msg}")))
}

type Parse<T> = std::result::Result<T, String>;

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;
const MI_UTF16: u32 = 17;

/// Deepest nesting of structs and cells accepted (a corrupt file could otherwise recurse for ever).
const MAX_DEPTH: usize = 32;

fn parse(bytes: &[u8]) -> Parse<Vec<(String, MatValue)>> {
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB 5.0 MAT-file") {
        return Err("no 'MATLAB 5.0 MAT-file' header".into());
    }
    let big = match &bytes[126..128] {
        b"IM" => false,
        b"MI" => true,
        _ => return Err("the header's byte-order mark is neither 'IM' nor 'MI'".into()),
    };
    let limits = Limits::get();
    let mut r = Reader {
        b: bytes,
        pos: 128,
        big,
    };
    let mut vars = Vec::new();
    while r.pos < bytes.len() {
        if bytes.len() - r.pos < 8 {
            break; // trailing padding
        }
        let (ty, data) = r.element()?;
        let value = match ty {
            MI_MATRIX => matrix(data, big, &limits, 0)?,
            MI_COMPRESSED => {
                let inner = inflate(data, &limits)?;
                let mut ir = Reader {
                    b: &inner,
                    pos: 0,
                    big,
                };
                let (ty, data) = ir.element()?;
                if ty != MI_MATRIX {
                    continue; // not a variable (MATLAB writes nothing else here)
                }
                matrix(data, big, &limits, 0)?
            }
            _ => continue,
        };
        vars.push(value);
    }
    Ok(vars)
}

fn inflate(data: &[u8], limits: &Limits) -> Parse<Vec<u8>> {
    let mut out = Vec::new();
    let cap = limits.max_bytes;
    flate2::read::ZlibDecoder::new(data)
        .take(cap + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("a compressed variable does not decompress ({e})"))?;
    if out.len() as u64 > cap {
        return Err(format!(
            "a compressed variable expands beyond the memory budget ({} MiB)",
            cap >> 20
        ));
    }
    Ok(out)
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
    big: bool,
}

impl<'a> Reader<'a> {
    fn u32_at(&self, at: usize) -> Parse<u32> {
        let s: [u8; 4] = self
            .b
            .get(at..at + 4)
            .ok_or("cut short inside a tag")?
            .try_into()
            .expect("4 bytes");
        Ok(if self.big {
            u32::from_be_bytes(s)
        } else {
            u32::from_le_bytes(s)
        })
    }

    /// The next data element: its type and payload. Small elements pack both into 8 bytes;
    /// uncompressed payloads are padded to 8 bytes, compressed ones are not.
    fn element(&mut self) -> Parse<(u32, &'a [u8])> {
        let first = self.u32_at(self.pos)?;
        if first >> 16 != 0 {
            let (ty, n) = (first & 0xffff, (first >> 16) as usize);
            if n > 4 {
                return Err(format!("a small element claims {n} bytes (at most 4)"));
            }
            let data = self
                .b
                .get(self.pos + 4..self.pos + 4 + n)
                .ok_or("cut short inside a small element")?;
            self.pos += 8;
            return Ok((ty, data));
        }
        let n = self.u32_at(self.pos + 4)? as usize;
        let start = self.pos + 8;
        let end = start
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| {
                format!(
                    "an element declares {n} bytes but {} remain (truncated or corrupt)",
                    self.b.len().saturating_sub(start)
                )
            })?;
        self.pos = if first == MI_COMPRESSED {
            end
        } else {
            (end.next_multiple_of(8)).min(self.b.len())
        };
        Ok((first, &self.b[start..end]))
    }

    fn expect(&mut self, what: &str) -> Parse<(u32, &'a [u8])> {
        if self.pos >= self.b.len() {
            return Err(format!("a variable ends before its {what}"));
        }
        self.element()
    }
}

/// MATLAB array classes (mxClassID).
fn class_name(c: u8) -> &'static str {
    match c {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        16 => "function handle",
        17 => "opaque",
        _ => "unknown class",
    }
}

/// Decodes a miMATRIX payload into (name, value).
fn matrix(data: &[u8], big: bool, limits: &Limits, depth: usize) -> Parse<(String, MatValue)> {
    if depth > MAX_DEPTH {
        return Err(format!("structs or cells nested deeper than {MAX_DEPTH}"));
    }
    if data.is_empty() {
        return Ok((
            String::new(),
            MatValue::Numeric {
                dims: vec![0, 0],
                values: vec![],
            },
        ));
    }
    let mut r = Reader {
        b: data,
        pos: 0,
        big,
    };
    let (ty, flags) = r.expect("array flags")?;
    if ty != MI_UINT32 || flags.len() < 8 {
        return Err("a variable's array flags are malformed".into());
    }
    let flag_word = Reader {
        b: flags,
        pos: 0,
        big,
    }
    .u32_at(0)?;
    let class = (flag_word & 0xff) as u8;
    let complex = flag_word & 0x0800 != 0;
    let (ty, d) = r.expect("dimensions")?;
    if ty != MI_INT32 || d.len() % 4 != 0 || d.is_empty() {
        return Err("a variable's dimensions are malformed".into());
    }
    let dr = Reader { b: d, pos: 0, big };
    let dims = (0..d.len() / 4)
        .map(|i| {
            let v = dr.u32_at(4 * i)? as i32;
            usize::try_from(v).map_err(|_| format!("a negative dimension ({v})"))
        })
        .collect::<Parse<Vec<usize>>>()?;
    let count = dims
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or("dimensions whose product overflows")?;
    let (_, name) = r.expect("name")?;
    let name = String::from_utf8_lossy(name).into_owned();
    let value = match class {
        1 => {
            // Each item needs at least an 8-byte tag: more items than that is corruption.
            if count > data.len() / 8 {
                return Err(format!(
                    "cell '{name}' declares {count} items in {} bytes",
                    data.len()
                ));
            }
            let mut items = Vec::with_capacity(count);
            for _ in 0..count {
                let (ty, payload) = r.expect("cell items")?;
                if ty != MI_MATRIX {
                    return Err(format!("cell '{name}' holds an element of type {ty}"));
                }
                items.push(matrix(payload, big, limits, depth + 1)?.1);
            }
            MatValue::Cell { dims, items }
        }
        2 | 3 => {
            if class == 3 {
                r.expect("class name")?;
            }
            let (_, len) = r.expect("field name length")?;
            let len = Reader {
                b: len,
                pos: 0,
                big,
            }
            .u32_at(0)? as usize;
            let (_, names_raw) = r.expect("field names")?;
            if len == 0 || names_raw.len() % len != 0 {
                return Err(format!("struct '{name}' has malformed field names"));
            }
            let names: Vec<String> = names_raw
                .chunks(len)
                .map(|c| {
                    let end = c.iter().position(|&b| b == 0).unwrap_or(c.len());
                    String::from_utf8_lossy(&c[..end]).into_owned()
                })
                .collect();
            let total = count
                .checked_mul(names.len())
                .filter(|&t| t <= data.len() / 8)
                .ok_or_else(|| {
                    format!("struct '{name}' declares more fields than its bytes hold")
                })?;
            let mut fields: Vec<Vec<MatValue>> = vec![Vec::with_capacity(count); names.len()];
            for i in 0..total {
                let (ty, payload) = r.expect("struct fields")?;
                if ty != MI_MATRIX {
                    return Err(format!("struct '{name}' holds an element of type {ty}"));
                }
                fields[i % names.len()].push(matrix(payload, big, limits, depth + 1)?.1);
            }
            MatValue::Struct {
                dims,
                names,
                fields,
            }
        }
        4 => {
            let (ty, raw) = r.expect("characters")?;
            let text = match ty {
                MI_UINT16 | MI_UTF16 => {
                    let rr = Reader {
                        b: raw,
                        pos: 0,
                        big,
                    };
                    let units: Vec<u16> = (0..raw.len() / 2)
                        .map(|i| {
                            let s = [rr.b[2 * i], rr.b[2 * i + 1]];
                            if big {
                                u16::from_be_bytes(s)
                            } else {
                                u16::from_le_bytes(s)
                            }
                        })
                        .collect();
                    String::from_utf16_lossy(&units)
                }
                _ => String::from_utf8_lossy(raw).into_owned(),
            };
            MatValue::Char(text)
        }
        6..=15 => {
            if complex {
                return Err(format!(
                    "variable '{name}' is complex; murk reads real arrays"
                ));
            }
            let (ty, raw) = r.expect("real part")?;
            let values = numbers(ty, raw, big, count, limits)
                .map_err(|m| format!("variable '{name}': {m}"))?;
            MatValue::Numeric { dims, values }
        }
        c => MatValue::Other(class_name(c)),
    };
    Ok((name, value))
}

/// The `count` values of a numeric payload of element type `ty`, as f64.
fn numbers(ty: u32, raw: &[u8], big: bool, count: usize, limits: &Limits) -> Parse<Vec<f64>> {
    let size = match ty {
        MI_INT8 | MI_UINT8 => 1,
        MI_INT16 | MI_UINT16 => 2,
        MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
        MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
        MI_UTF8 => 1,
        _ => return Err(format!("values of unknown element type {ty}")),
    };
    if raw.len() / size != count {
        return Err(format!(
            "declares {count} values but holds {} (truncated or corrupt)",
            raw.len() / size
        ));
    }
    limits
        .elements("the array", &[count], 8)
        .map_err(|e| e.to_string())?;
    macro_rules! conv {
        ($t:ty) => {
            raw.chunks_exact(size)
                .map(|c| {
                    let a: [u8; std::mem::size_of::<$t>()] = c.try_into().expect("size");
                    (if big {
                        <$t>::from_be_bytes(a)
                    } else {
                        <$t>::from_le_bytes(a)
                    }) as f64
                })
                .collect()
        };
    }
    Ok(match ty {
        MI_INT8 => conv!(i8),
        MI_UINT8 | MI_UTF8 => conv!(u8),
        MI_INT16 => conv!(i16),
        MI_UINT16 => conv!(u16),
        MI_INT32 => conv!(i32),
        MI_UINT32 => conv!(u32),
        MI_SINGLE => conv!(f32),
        MI_DOUBLE => conv!(f64),
        MI_INT64 => conv!(i64),
        _ => conv!(u64),
    })
}

/// How a variable's values are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatClass {
    Double,
    UInt16,
}

/// A numeric variable for [`write_mat_v5`]: MATLAB dimensions and the values in MATLAB's
/// column-major order.
pub struct MatArray<'a> {
    pub name: &'a str,
    pub dims: &'a [usize],
    pub values: &'a [f64],
    pub class: MatClass,
}

/// Writes numeric variables as a little-endian MATLAB v5 file, as MATLAB's `save -v6` does, or with
/// each variable zlib-compressed as `save -v7` does.
pub fn write_mat_v5(path: &Path, vars: &[MatArray], compress: bool) -> Result<()> {
    let mut matrices = Vec::with_capacity(vars.len());
    for v in vars {
        if v.dims.iter().product::<usize>() != v.values.len() {
            return Err(Error::param(format!(
                "{}: variable '{}' has dimensions {:?} but {} values",
                path.display(),
                v.name,
                v.dims,
                v.values.len()
            )));
        }
        let (class, data) = match v.class {
            MatClass::Double => (
                6,
                encode_values(MI_DOUBLE, v.values, |x| x.to_le_bytes().to_vec()),
            ),
            MatClass::UInt16 => (
                11,
                encode_values(MI_UINT16, v.values, |x| (x as u16).to_le_bytes().to_vec()),
            ),
        };
        matrices.push(encode_matrix(class, v.dims, v.name, &data));
    }
    let bytes = encode_file(&matrices, compress);
    crate::write_atomic(path, |w| {
        w.write_all(&bytes).map_err(|e| Error::io(path, e))
    })
}

fn encode_values(ty: u32, values: &[f64], bytes: impl Fn(f64) -> Vec<u8>) -> Vec<u8> {
    encode_element(
        ty,
        &values.iter().flat_map(|&x| bytes(x)).collect::<Vec<_>>(),
    )
}

/// The 128-byte header and the variables (miMATRIX elements), each zlib-compressed if asked.
pub(crate) fn encode_file(matrices: &[Vec<u8>], compress: bool) -> Vec<u8> {
    let mut f = format!("{:<116}", "MATLAB 5.0 MAT-file, written by murk").into_bytes();
    f.extend([0u8; 8]);
    f.extend(0x0100u16.to_le_bytes());
    f.extend(b"IM");
    for m in matrices {
        if compress {
            use std::io::Write;
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(m).expect("writing to memory");
            let c = z.finish().expect("writing to memory");
            f.extend(MI_COMPRESSED.to_le_bytes());
            f.extend((c.len() as u32).to_le_bytes());
            f.extend(c);
        } else {
            f.extend(m);
        }
    }
    f
}

/// A tagged data element, padded to 8 bytes.
pub(crate) fn encode_element(ty: u32, data: &[u8]) -> Vec<u8> {
    let mut v = ty.to_le_bytes().to_vec();
    v.extend((data.len() as u32).to_le_bytes());
    v.extend(data);
    v.resize(v.len().next_multiple_of(8), 0);
    v
}

/// A miMATRIX element: array flags of `class`, dimensions, name, then `body` (encoded elements).
pub(crate) fn encode_matrix(class: u8, dims: &[usize], name: &str, body: &[u8]) -> Vec<u8> {
    let mut m = encode_element(MI_UINT32, &[class, 0, 0, 0, 0, 0, 0, 0]);
    let d: Vec<u8> = dims
        .iter()
        .flat_map(|&v| (v as i32).to_le_bytes())
        .collect();
    m.extend(encode_element(MI_INT32, &d));
    m.extend(encode_element(MI_INT8, name.as_bytes()));
    m.extend(body);
    encode_element(MI_MATRIX, &m)
}

/// Looks up `a.b.c` through 1×1 structs among `vars`.
pub fn lookup<'v>(vars: &'v [(String, MatValue)], path: &str) -> Option<&'v MatValue> {
    let mut parts = path.split('.');
    let first = parts.next()?;
    let mut v = &vars.iter().find(|(n, _)| n == first)?.1;
    for p in parts {
        let MatValue::Struct { names, fields, .. } = v else {
            return None;
        };
        let f = names.iter().position(|n| n == p)?;
        v = fields[f].first()?;
    }
    Some(v)
}

/// A test-only v5 encoder (little-endian; variables uncompressed or zlib-compressed).
#[cfg(test)]
pub(crate) mod write {
    use super::*;

    pub(crate) use super::{
        encode_element as element, encode_file as file, encode_matrix as matrix_bytes,
    };

    /// A double array; `v` in MATLAB's column-major order.
    pub(crate) fn doubles(name: &str, dims: &[usize], v: &[f64]) -> Vec<u8> {
        let raw: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        matrix_bytes(6, dims, name, &element(MI_DOUBLE, &raw))
    }

    /// A uint8 (`wide` false) or uint16 array, as MATLAB stores captures of counts.
    pub(crate) fn counts(name: &str, dims: &[usize], v: &[f64], wide: bool) -> Vec<u8> {
        if wide {
            let raw: Vec<u8> = v.iter().flat_map(|&x| (x as u16).to_le_bytes()).collect();
            matrix_bytes(11, dims, name, &element(MI_UINT16, &raw))
        } else {
            let raw: Vec<u8> = v.iter().map(|&x| x as u8).collect();
            matrix_bytes(9, dims, name, &element(MI_UINT8, &raw))
        }
    }

    /// A 1×1 struct of `fields` (each written with an empty name, as MATLAB does).
    pub(crate) fn structure(name: &str, fields: &[(&str, Vec<u8>)]) -> Vec<u8> {
        const LEN: usize = 32;
        let mut names = Vec::new();
        for (n, _) in fields {
            let mut b = n.as_bytes().to_vec();
            b.resize(LEN, 0);
            names.extend(b);
        }
        // The field-name length is a small element in MATLAB's files.
        let mut body = (MI_INT32 | (4 << 16)).to_le_bytes().to_vec();
        body.extend((LEN as i32).to_le_bytes());
        body.extend(element(MI_INT8, &names));
        for (_, v) in fields {
            body.extend(v);
        }
        matrix_bytes(2, &[1, 1], name, &body)
    }
}

#[cfg(test)]
mod tests {
    use super::write::*;
    use super::*;

    /// A 1×1 struct with a 2×3 numeric field and a char field (the shape of Ahn 2019's `NLOSDATA`),
    /// next to a cell array, compressed and not.
    #[test]
    fn structs_cells_and_numbers() {
        let chars: Vec<u8> = "hi".encode_utf16().flat_map(|u| u.to_le_bytes()).collect();
        let st = structure(
            "NLOSDATA",
            &[
                (
                    "transient",
                    doubles("", &[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
                ),
                (
                    "note",
                    matrix_bytes(4, &[1, 2], "", &element(MI_UINT16, &chars)),
                ),
            ],
        );
        let cell = matrix_bytes(1, &[1, 1], "c", &doubles("", &[1, 1], &[7.5]));
        for compress in [false, true] {
            let bytes = encode_file(&[st.clone(), cell.clone()], compress);
            let vars = parse(&bytes).unwrap();
            let Some(MatValue::Numeric { dims, values }) = lookup(&vars, "NLOSDATA.transient")
            else {
                panic!("{:?}", vars)
            };
            assert_eq!(
                (dims.as_slice(), values.as_slice()),
                (&[2, 3][..], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0][..])
            );
            assert!(matches!(lookup(&vars, "NLOSDATA.note"), Some(MatValue::Char(s)) if s == "hi"));
            let Some(MatValue::Cell { items, .. }) = lookup(&vars, "c") else {
                panic!()
            };
            assert!(matches!(&items[0], MatValue::Numeric { values, .. } if values == &[7.5]));
            assert!(lookup(&vars, "NLOSDATA.nope").is_none());
        }
    }

    #[test]
    fn written_files_read_back() {
        let dir = std::env::temp_dir().join(format!("murk-mat5-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("w.mat");
        let counts: Vec<f64> = (0..24).map(|i| (i % 7) as f64).collect();
        for compress in [false, true] {
            let vars = [
                MatArray {
                    name: "rect_data",
                    dims: &[2, 3, 4],
                    values: &counts,
                    class: MatClass::UInt16,
                },
                MatArray {
                    name: "width",
                    dims: &[1, 1],
                    values: &[0.4],
                    class: MatClass::Double,
                },
            ];
            write_mat_v5(&p, &vars, compress).unwrap();
            let back = read_mat_v5(&p).unwrap();
            assert!(matches!(lookup(&back, "rect_data"),
                Some(MatValue::Numeric { dims, values }) if dims == &[2, 3, 4] && values == &counts));
            assert!(matches!(lookup(&back, "width"),
                Some(MatValue::Numeric { values, .. }) if values == &[0.4]));
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Declared sizes larger than the bytes present fail at once, without allocating them.
    #[test]
    fn corrupt_sizes_fail_fast() {
        let v = doubles("x", &[2, 2], &[1.0, 2.0, 3.0, 4.0]);
        // Dimensions claiming 2^30 × 2^30 values over 32 bytes of data.
        let mut huge = v.clone();
        let at = huge
            .windows(8)
            .position(|w| w == [2, 0, 0, 0, 2, 0, 0, 0])
            .unwrap();
        huge[at..at + 8].copy_from_slice(&[0, 0, 0, 64, 0, 0, 0, 64]);
        let t = std::time::Instant::now();
        let e = parse(&encode_file(&[huge], true)).unwrap_err();
        assert!(e.contains("values but holds 4"), "{e}");
        // A tag claiming 4 GB in a short file.
        let mut long = v.clone();
        long[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(&encode_file(&[long], false)).unwrap_err();
        assert!(e.contains("truncated or corrupt"), "{e}");
        // Cut inside the compressed stream.
        let whole = encode_file(&[v], true);
        let e = parse(&whole[..whole.len() - 6]).unwrap_err();
        assert!(e.contains("declares") || e.contains("decompress"), "{e}");
        assert!(t.elapsed().as_secs_f64() < 1.0);
    }
}
