//! murk-bench's bad arguments: one line naming the problem, a non-zero exit, nothing benchmarked.

use std::process::Command;

fn fails(args: &[&str], says: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_murk-bench"))
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with("murk-bench: error: ") && err.contains(says),
        "{args:?}: {err}"
    );
}

#[test]
fn bad_arguments_are_one_line() {
    // clap's own text was three or four lines without the prefix.
    fails(&["--runs", "-1"], "unexpected argument '-1'");
    fails(&["--paper-only", "frob"], "invalid value 'frob'");
    // The OS error was printed twice.
    fails(
        &["--real", "/nonexistent"],
        "/nonexistent/letter_s.mat: No such file or directory (os error 2)",
    );
    let twice = "No such file or directory (os error 2): No such file";
    let out = Command::new(env!("CARGO_BIN_EXE_murk-bench"))
        .args(["--real", "/nonexistent", "--quiet"])
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&out.stderr).contains(twice));
    // These benchmarked nothing, or skipped y-tal, and exited 0.
    fails(
        &["--render", "--scenes", "/nonexistent", "--only", "nomatch"],
        "--only nomatch: matches none of the cases",
    );
    fails(
        &["--tal-python", "/nonexistent", "--confocal-vs-tal"],
        "/nonexistent: no such file",
    );
    // Run from the crate's folder, which has no .venv: --skip-z would leave nothing to measure.
    assert!(!std::path::Path::new(".venv/bin/python").exists());
    fails(
        &["--skip-z"],
        "--skip-z leaves only the side-by-side cases with y-tal",
    );
}
