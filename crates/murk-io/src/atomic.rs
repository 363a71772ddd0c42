//! Atomic file replacement: write a sibling temporary file, flush it, rename it over the target.

use murk_core::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Writes `path` through `fill` (buffered), so that readers see either the old file or the complete new one,
/// and a failed write leaves nothing behind.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    refuse_special(path)?;
    let tmp = temp_sibling(path)?;
    let _live = Live::register(&tmp);
    // Errors name `path`, the file the user asked for, not the temporary that is gone afterwards.
    let result = (|| {
        let file = std::fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        let file = w
            .into_inner()
            .map_err(|e| Error::io(path, e.into_error()))?;
        file.sync_all().map_err(|e| Error::io(path, e))?;
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        // Best effort: the temporary may not exist if creating it failed.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Temporaries being written now, so that an interrupted process can remove them.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Registration of one temporary in [`LIVE`] for the duration of its write.
struct Live(PathBuf);

impl Live {
    fn register(tmp: &Path) -> Live {
        lock_live().push(tmp.to_path_buf());
        Live(tmp.to_path_buf())
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        lock_live().retain(|p| p != &self.0);
    }
}

fn lock_live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes every temporary that a write in progress has made, for a signal handler about to end the
/// process: the targets keep their previous content (or stay absent). Returns the guard so that the
/// caller can exit while holding it, before a write could start another temporary.
pub fn remove_temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    let live = lock_live();
    for p in live.iter() {
        let _ = std::fs::remove_file(p);
    }
    live
}

/// This machine's name, which temporaries carry: a folder shared between machines (a cluster's
/// file system) holds other machines' temporaries, whose processes this one cannot see. Linux's;
/// elsewhere `None`, and no temporary is taken for stale.
fn host() -> Option<&'static str> {
    static HOST: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        std::fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .map(|h| h.trim().to_string())
            .filter(|h| !h.is_empty() && !h.contains(['/', '@']))
    })
    .as_deref()
}

/// Removes from `dir` the temporaries that this machine's writes left when their process was killed
/// (SIGKILL gives it no time to clean up), and returns how many. Processes are looked up in `/proc`,
/// so only temporaries named with this machine's name are considered; on other systems, none.
pub fn remove_stale_temporaries(dir: &Path) -> Result<usize> {
    let Some(host) = host() else {
        return Ok(0);
    };
    let mut removed = 0;
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        // `.{target}.{pid}-{n}@{host}.tmp`, as temp_sibling names them.
        let pid = name
            .strip_prefix('.')
            .and_then(|n| n.strip_suffix(".tmp"))
            .and_then(|n| n.rsplit_once('@'))
            .filter(|(_, h)| *h == host)
            .and_then(|(n, _)| n.rsplit_once('.'))
            .and_then(|(_, tail)| tail.split_once('-'))
            .and_then(|(pid, n)| n.parse::<u64>().ok().and(pid.parse::<u32>().ok()));
        if let Some(pid) = pid {
            if !Path::new(&format!("/proc/{pid}")).exists() {
                std::fs::remove_file(entry.path()).map_err(|e| Error::io(entry.path(), e))?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// A unique name in the target's directory (same file system, so the rename is atomic).
fn temp_sibling(path: &Path) -> Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"),
        )
    })?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let host = host().map_or(String::new(), |h| format!("@{h}"));
    let tmp_name = format!(
        ".{}.{}-{n}{host}.tmp",
        name.to_string_lossy(),
        std::process::id()
    );
    Ok(path.with_file_name(tmp_name))
}

/// Refuses to replace anything but a regular file: the rename would turn a folder's path, a device
/// (`/dev/null`) or a FIFO into a plain file.
fn refuse_special(out: &Path) -> Result<()> {
    match std::fs::metadata(out) {
        Ok(m) if m.is_dir() => Err(Error::param(format!(
            "{}: is a folder; the output must be a file path",
            out.display()
        ))),
        Ok(m) if !m.is_file() => Err(Error::param(format!(
            "{}: is not a regular file (a device, FIFO or socket); murk writes only regular files",
            out.display()
        ))),
        _ => Ok(()),
    }
}

/// Refuses an output that is one of the inputs (the same file, whatever path names it): the
/// atomic rename would replace the input with the result.
fn refuse_overwrite(out: &Path, inputs: &[&Path]) -> Result<()> {
    let Ok(out_id) = file_id(out) else {
        return Ok(()); // no file there yet, so it is no input
    };
    for input in inputs {
        if file_id(input).is_ok_and(|id| id == out_id) {
            return Err(Error::param(format!(
                "{}: the output would replace the input {}; choose another output path",
                out.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// Refuses, before any work is done, an output path that cannot be written (an existing folder, or a
/// file in a folder that does not exist: otherwise a long render fails only when it writes) or that
/// names one of `inputs`.
pub fn check_output(out: &Path, inputs: &[&Path]) -> Result<()> {
    refuse_special(out)?;
    // Checked here, not when the rename fails after all the work.
    if let Some(n) = out.file_name().filter(|n| n.len() > 255) {
        return Err(Error::param(format!(
            "{}: its file name is {} bytes long; file systems allow 255",
            out.display(),
            n.len()
        )));
    }
    let parent = folder_of(out);
    if !parent.is_dir() {
        let (what, why) = match parent.exists() {
            true => ("", "is not a folder"),
            false => ("the folder ", "does not exist"),
        };
        return Err(Error::param(format!(
            "{}: {what}{} {why}",
            out.display(),
            parent.display()
        )));
    }
    refuse_overwrite(out, inputs)
}

/// Creates the output folder `dir` (and its parents) unless it exists; a file, device or FIFO at its
/// path is refused as such ("File exists" named no reason).
pub fn create_output_dir(dir: &Path) -> Result<()> {
    if std::fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        return Err(Error::param(format!(
            "{}: exists and is not a folder; the output here is a folder",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

/// [`check_output`] for an HDF5 file (a capture or a ground truth), which must also be named so.
pub fn check_h5_output(out: &Path, inputs: &[&Path]) -> Result<()> {
    check_output(out, inputs)?;
    check_h5_name(out)
}

/// Captures and ground truths are always y-tal-style HDF5: a `.mat` or `.npy` name would put HDF5
/// bytes under the wrong name, which other tools then misread.
pub fn check_h5_name(path: &Path) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext.to_ascii_lowercase().as_str() {
        "h5" | "hdf5" => Ok(()),
        _ => Err(Error::param(format!(
            "{}: murk writes HDF5 here; name the file .h5 or .hdf5",
            path.display()
        ))),
    }
}

/// Whether `a` and `b` name the same file, whether or not it exists yet (`./x`, `d/../x` and `x`
/// are one file): each path's folder is resolved, then the file names compared.
pub fn same_target(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| {
        let folder = std::fs::canonicalize(folder_of(p)).unwrap_or_else(|_| folder_of(p));
        p.file_name().map(|name| folder.join(name))
    };
    file_id(a).is_ok_and(|id| file_id(b).is_ok_and(|other| other == id))
        || matches!((resolved(a), resolved(b)), (Some(x), Some(y)) if x == y)
}

/// The folder a file path lies in (`.` for a bare name).
fn folder_of(p: &Path) -> std::path::PathBuf {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    }
}

fn file_id(p: &Path) -> std::io::Result<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(p)?;
        Ok((m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let c = std::fs::canonicalize(p)?;
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::hash::Hash::hash(&c, &mut h);
        Ok((0, std::hash::Hasher::finish(&h)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file name longer than file systems allow is refused before any work (a render of
    /// `--albedos 1e-300` failed only at its rename, with "File name too long").
    #[test]
    fn long_file_names_are_refused_up_front() {
        let long = std::env::temp_dir().join(format!("{}.h5", "x".repeat(300)));
        let e = check_output(&long, &[]).unwrap_err().to_string();
        assert!(
            e.contains("its file name is 303 bytes long; file systems allow 255"),
            "{e}"
        );
        let fine = std::env::temp_dir().join(format!("{}.h5", "x".repeat(252)));
        assert!(check_output(&fine, &[]).is_ok());
    }

    /// A dead process's temporary is removed; a live one's (this process's), another machine's,
    /// other hidden files and finished outputs stay.
    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = std::env::temp_dir().join(format!("murk-stale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Linux's pid_max is at most 2^22: this pid cannot be running.
        let host = host().unwrap();
        let dead = dir.join(format!(".c.h5.4294967295-0@{host}.tmp"));
        let live = temp_sibling(&dir.join("c.h5")).unwrap();
        let keep = [
            dir.join("c.h5"),
            dir.join(".hidden"),
            dir.join(".c.h5.x-0.tmp"),
            // Another machine's, whose processes /proc does not show.
            dir.join(".c.h5.4294967295-0@elsewhere.tmp"),
        ];
        for p in keep.iter().chain([&dead, &live]) {
            std::fs::write(p, "x").unwrap();
        }
        assert_eq!(remove_stale_temporaries(&dir).unwrap(), 1);
        assert!(!dead.exists() && live.exists());
        assert!(keep.iter().all(|p| p.exists()));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
