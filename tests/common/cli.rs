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

/// Runs `murk` and asserts it succeeded; returns its stdout.
#[allow(dead_code)]
pub fn ok(args: &[&str]) -> String {
    let (code, out, err) = murk(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    out
}

/// A path as the `&str` an argument list takes.
#[allow(dead_code)]
pub fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// A fresh, empty temporary folder `murk-{tag}-{pid}`.
#[allow(dead_code)]
pub fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("murk-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
