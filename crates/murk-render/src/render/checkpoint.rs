//! The checkpoint: an append-only file of a render's finished units, which a stopped render resumes
//! from and a part render leaves as its result; where a render to a file keeps it and how often.

use super::provenance::fingerprint;
use crate::hash::Fnv1a;
use murk_core::{Error, Result};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

const MAX_SECONDS: f64 = murk_core::Limits::MAX_SECONDS;

/// The interval between checkpoint appends, from seconds (0: after every unit). Refuses negative,
/// non-finite and longer-than-a-year values.
pub fn checkpoint_interval(seconds: f64) -> Result<Duration> {
    match seconds {
        s if (0.0..=MAX_SECONDS).contains(&s) => Ok(Duration::from_secs_f64(s)),
        s => Err(Error::param(format!(
            "a checkpoint interval needs 0 ≤ seconds ≤ {MAX_SECONDS} (one year), got {}",
            murk_core::short(s)
        ))),
    }
}

/// The checkpoint a render to `out` keeps: `out` with `.ckpt` appended.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let mut p = out.as_os_str().to_owned();
    p.push(".ckpt");
    PathBuf::from(p)
}

/// An append-only file of finished units: a header (magic, fingerprint, unit length, key length, the
/// render key), then records of (unit index: u64, values: f32 × unit length, checksum: u64),
/// little-endian. The valid prefix ends at the first record cut short by a kill or whose checksum fails
/// (a crash can leave zeros where data was not yet written; a disk can flip bits): the units from there
/// on are rendered again, so a resumed capture is still exact. A key that differs is refused, naming
/// what differs.
pub(super) struct Checkpoint {
    file: std::fs::File,
    path: PathBuf,
    unit_len: usize,
}

const MAGIC: &[u8; 8] = b"MURKCKP3";

/// Bytes of one record: unit index, values and checksum.
fn record_len(unit_len: usize) -> usize {
    8 + 4 * unit_len + 8
}

/// A record's checksum over its index and values: FNV-1a over 8-byte words (a tail zero-padded), fast
/// enough to check a whole capture's checkpoint as it is read.
fn record_sum(bytes: &[u8]) -> u64 {
    let mut chunks = bytes.chunks_exact(8);
    let word = |c: &[u8]| {
        let mut w = [0u8; 8];
        w[..c.len()].copy_from_slice(c);
        u64::from_le_bytes(w)
    };
    let h = chunks.by_ref().fold(Fnv1a::new(), |h, c| h.word(word(c)));
    h.word(word(chunks.remainder())).finish()
}

/// A checkpoint's header: magic, fingerprint, unit length, key length and the render key.
fn header(key: &str, unit_len: usize) -> Vec<u8> {
    let mut header = Vec::with_capacity(32 + key.len());
    header.extend_from_slice(MAGIC);
    header.extend_from_slice(&fingerprint(key).to_le_bytes());
    header.extend_from_slice(&(unit_len as u64).to_le_bytes());
    header.extend_from_slice(&(key.len() as u64).to_le_bytes());
    header.extend_from_slice(key.as_bytes());
    header
}

/// Calls `unit(u, values)` for each whole record of the checkpoint at `path`, after checking that its
/// header is this render's; returns the length of the valid prefix, or `None` when there is no file.
/// A unit index beyond `units` in a record whose checksum holds is a format error.
pub(super) fn read_checkpoint(
    path: &Path,
    key: &str,
    unit_len: usize,
    units: usize,
    mut unit: impl FnMut(usize, &[f32]),
) -> Result<Option<u64>> {
    if matches!(std::fs::metadata(path), Err(e) if e.kind() == std::io::ErrorKind::NotFound) {
        return Ok(None);
    }
    // A regular file only (a FIFO would block, a device never end), and no larger than this
    // render's header and every unit once: checked before reading it into memory.
    let mut f = murk_core::open_input(path)?;
    let header = header(key, unit_len);
    let rec = record_len(unit_len);
    let most = (units as u64 + 1) * rec as u64 + header.len() as u64;
    let mut bytes = Vec::new();
    (&mut f)
        .take(most + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    // Empty, or cut inside this render's own header by a kill: nothing was recorded yet.
    if header.starts_with(&bytes) {
        return Ok(Some(0));
    }
    if !bytes.starts_with(&header) {
        return Err(Error::format(path, refusal(&bytes, key)));
    }
    if bytes.len() as u64 > most {
        return Err(Error::format(
            path,
            format!("more bytes than a checkpoint of this render's {units} units holds"),
        ));
    }
    let mut vals = vec![0f32; unit_len];
    let mut off = header.len();
    while off + rec <= bytes.len() {
        let (body, sum) = bytes[off..off + rec].split_at(rec - 8);
        if record_sum(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
            break;
        }
        let u = u64::from_le_bytes(body[..8].try_into().expect("8 bytes"));
        let u = usize::try_from(u)
            .ok()
            .filter(|&u| u < units)
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!("unit {u} recorded, but the render has {units}"),
                )
            })?;
        for (v, b) in vals.iter_mut().zip(body[8..].chunks_exact(4)) {
            *v = f32::from_le_bytes(b.try_into().expect("4 bytes"));
        }
        unit(u, &vals);
        off += rec;
    }
    Ok(Some(off as u64))
}

impl Checkpoint {
    /// Opens (or starts) the checkpoint at `path` for appending, passing each unit it holds to `unit`.
    pub(super) fn open(
        path: &Path,
        key: &str,
        unit_len: usize,
        units: usize,
        unit: impl FnMut(usize, &[f32]),
    ) -> Result<Self> {
        let io = |e| Error::io(path, e);
        let valid_len = read_checkpoint(path, key, unit_len, units, unit)?.unwrap_or(0);
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(io)?;
        if valid_len == 0 {
            file.set_len(0).map_err(io)?;
            file.write_all(&header(key, unit_len)).map_err(io)?;
        } else {
            // Drop a torn trailing record so appends stay aligned.
            file.set_len(valid_len).map_err(io)?;
        }
        Ok(Checkpoint {
            file,
            path: path.to_path_buf(),
            unit_len,
        })
    }

    pub(super) fn append(&mut self, recs: &[(usize, Vec<f32>)]) -> Result<()> {
        let mut buf = Vec::with_capacity(recs.len() * record_len(self.unit_len));
        for (u, vals) in recs {
            let start = buf.len();
            buf.extend_from_slice(&(*u as u64).to_le_bytes());
            vals.iter()
                .for_each(|v| buf.extend_from_slice(&v.to_le_bytes()));
            let sum = record_sum(&buf[start..]);
            buf.extend_from_slice(&sum.to_le_bytes());
        }
        let io = |e| Error::io(&self.path, e);
        let before = self.file.metadata().map_err(io)?.len();
        let written = self
            .file
            .write_all(&buf)
            .and_then(|_| self.file.sync_data());
        if written.is_err() {
            // A torn record would misalign every later append (a retry after a failed write
            // appends the same units again), so the file goes back to its last whole record.
            let _ = self.file.set_len(before);
        }
        written.map_err(io)
    }
}

/// A checkpoint and the finished units not yet appended to it.
pub(super) struct Unflushed {
    pub(super) ckpt: Checkpoint,
    pub(super) pending: Vec<(usize, Vec<f32>)>,
}

impl Unflushed {
    pub(super) fn append(mut self) -> Result<()> {
        self.ckpt.append(&self.pending)
    }
}

/// Why a checkpoint's header does not match this render, naming the keys that differ where it can.
fn refusal(bytes: &[u8], key: &str) -> String {
    let theirs = (bytes.len() >= 32 && bytes[..8] == MAGIC[..])
        .then(|| u64::from_le_bytes(bytes[24..32].try_into().expect("8 bytes")) as usize)
        .and_then(|n| bytes.get(32..32usize.checked_add(n)?))
        .and_then(|k| std::str::from_utf8(k).ok());
    let what = match theirs {
        Some(k) => {
            let diffs = crate::overrides::differences(k, key, 4);
            if diffs.is_empty() {
                "its layout differs".to_string()
            } else {
                diffs.join("; ")
            }
        }
        None if bytes.starts_with(MAGIC) => {
            return "damaged checkpoint (its header is cut short); delete it to start afresh".into()
        }
        None => "it is not a checkpoint of this murk version".to_string(),
    };
    format!("checkpoint of a different render ({what}); delete it to start afresh")
}

#[cfg(test)]
mod tests {
    use super::record_sum;

    /// The record checksum is stored in checkpoints, so it must stay FNV-1a over little-endian
    /// 8-byte words with the tail zero-padded (an empty tail still hashes one zero word): checked
    /// against that definition written out by hand, for whole and cut words.
    #[test]
    fn record_sum_is_fnv1a_over_padded_words() {
        let reference = |bytes: &[u8]| {
            let mut padded = bytes.to_vec();
            padded.resize(bytes.len() / 8 * 8 + 8, 0);
            padded.chunks(8).fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
                let w = u64::from_le_bytes(c.try_into().unwrap());
                (h ^ w).wrapping_mul(0x0100_0000_01b3)
            })
        };
        let bytes: Vec<u8> = (0..37u8).map(|b| b.wrapping_mul(97) ^ 0x5a).collect();
        for n in [0, 1, 8, 13, 16, 37] {
            assert_eq!(record_sum(&bytes[..n]), reference(&bytes[..n]), "{n} bytes");
        }
        assert_eq!(
            record_sum(&[]),
            (0xcbf2_9ce4_8422_2325u64).wrapping_mul(0x0100_0000_01b3)
        );
    }
}
