//! Helpers shared by the integration tests that talk to the real y-tal package.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Python is `$MURK_PYTHON` or `<repo>/.venv/bin/python` (`.ci/run` creates it); it must import tal
/// and h5py, else the caller prints "skipped: <why>".
pub fn python() -> Result<PathBuf, String> {
    let py = std::env::var_os("MURK_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python"));
    let out = Command::new(&py)
        .args(["-c", "import tal, h5py"])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", py.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} cannot import tal and h5py: {}",
            py.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(py)
}
