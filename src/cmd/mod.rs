pub mod demo;
pub mod experiment;
pub mod figure;
pub mod import;
pub mod info;
pub mod medium;
pub mod progress;
pub mod reconstruct;
pub mod render;
pub mod synth;

use std::sync::atomic::AtomicBool;

/// Set by the first Ctrl-C while a render runs: no work unit starts after it, and the render's
/// checkpoint keeps every finished one, so the same command resumes without redoing them.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Whether a render that watches [`STOP`] runs now; otherwise Ctrl-C ends the process at once.
pub static RENDERING: AtomicBool = AtomicBool::new(false);

/// What Ctrl-C says as the process ends, set by a command that can be resumed (not with --quiet).
pub static ON_INTERRUPT: std::sync::OnceLock<Interrupted> = std::sync::OnceLock::new();

/// The notes of an interrupted command.
pub struct Interrupted {
    /// After a stop that let the render save its finished units (or with no render running).
    pub stopped: String,
    /// After a second signal, which ends the process before the render saves them.
    pub at_once: String,
}

/// The worker pool of `--threads` (default: one thread per core).
pub fn pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    use anyhow::Context;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")
}

/// A `--threads` count murk will start (0: one per core).
pub fn parse_threads(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a thread count"))?;
    murk_core::Limits::threads(n).map_err(|e| e.to_string())
}
