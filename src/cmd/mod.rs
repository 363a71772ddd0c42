pub mod demo;
pub mod experiment;
pub mod figure;
pub mod import;
pub mod info;
pub mod progress;
pub mod reconstruct;
pub mod render;
pub mod synth;

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
