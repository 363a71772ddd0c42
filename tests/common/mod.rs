//! Helpers shared by the integration tests: the real y-tal package, the murk binary.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The reason the tests that need y-tal are `#[ignore]`d; `.ci/run` creates `.venv` and runs them.
#[allow(dead_code)] // not every test crate that shares this module needs y-tal
pub const NEEDS_TAL: &str = "needs a Python with y-tal and h5py";

/// Python is `$MURK_PYTHON` or `<repo>/.venv/bin/python` (`.ci/run` creates it); it must import tal
/// and h5py. The tests that call this are ignored by default, so when one runs, a missing Python is
/// a failure that says why, not a skip.
#[allow(dead_code)] // not every test crate that shares this module needs y-tal
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

/// Runs the `murk` binary; returns (exit code, stdout, stderr).
#[allow(dead_code)] // not every test crate that shares this module runs murk
pub fn murk(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(args)
        .output()
        .expect("run murk");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}
