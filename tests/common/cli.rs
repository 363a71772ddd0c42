//! Runs the real `murk` binary for the integration tests (`#[path]`-included where needed).

use std::process::Command;

/// Runs the `murk` binary; returns (exit code, stdout, stderr).
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
