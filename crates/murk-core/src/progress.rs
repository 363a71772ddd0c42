//! Progress reports and cancellation for long computations.

/// Reports work done, for progress bars, and says whether the caller has asked to stop. Called from
/// worker threads.
pub trait Progress: Sync {
    fn start(&self, _total: u64) {}
    fn advance(&self, _n: u64) {}
    /// Whether to stop: parallel loops check it before each piece of work and skip the rest, and the
    /// computation then returns an error instead of a partial result.
    fn cancelled(&self) -> bool {
        false
    }
}

/// A progress sink that ignores everything and never stops.
pub struct NoProgress;
impl Progress for NoProgress {}
