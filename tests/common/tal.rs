//! The real y-tal package for the interoperability tests (`#[path]`-included where needed).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The reason the tests that need y-tal are `#[ignore]`d; `.ci/run` creates `.venv` and runs them.
const NEEDS_TAL: &str = "needs a Python with y-tal and h5py";

/// Python is `$MURK_PYTHON` or `<repo>/.venv/bin/python` (`.ci/run` creates it); it must import tal
/// and h5py. The tests that call this are ignored by default, so when one runs, a missing Python is
/// a failure that says why, not a skip.
pub fn python() -> PathBuf {
    usable_python().unwrap_or_else(|why| panic!("{NEEDS_TAL}: {why}"))
}

fn usable_python() -> Result<PathBuf, String> {
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
