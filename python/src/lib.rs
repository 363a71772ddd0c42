//! `murk._murk`: thin glue from Python to murk's library crates. The Python package `murk` wraps
//! these functions (defaults, progress bars, Dask); every computation is the crates' own code.

mod capture;
mod medium;
mod ops;
mod recon;

use pyo3::prelude::*;
use pyo3::types::PyType;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The longest a progress callback waits between calls while the counts stand still.
const HEARTBEAT: Duration = Duration::from_millis(500);

/// The `murk.errors` class for a library error: the kind says whose fault it was, the message is the
/// library's one line.
fn to_py(e: murk_core::Error) -> PyErr {
    use murk_core::Error as E;
    let class = match &e {
        E::Io { .. } => "FileError",
        E::Format { .. } => "FormatError",
        E::Parameter(_) => "InputError",
        E::Limits(_) => "LimitError",
        E::Unsupported(_) => "UnsupportedError",
        _ => "Error",
    };
    error(class, e.to_string())
}

/// A `murk.errors.<class>(msg)`; falls back to RuntimeError if the Python package is broken.
fn error(class: &str, msg: String) -> PyErr {
    Python::attach(|py| {
        let cls = py
            .import("murk.errors")
            .and_then(|m| m.getattr(class))
            .and_then(|c| Ok(c.cast_into::<PyType>()?));
        match cls {
            Ok(cls) => PyErr::from_type(cls, msg),
            Err(e) => e,
        }
    })
}

/// Shared between a computation on its own thread and the Python thread waiting for it: progress
/// counts for the callback, and the flag that stops the computation after Ctrl-C.
#[derive(Default)]
pub(crate) struct Ticker {
    done: AtomicU64,
    total: AtomicU64,
    cancel: AtomicBool,
}

/// The panic payload that unwinds a cancelled computation (`resume_unwind` skips the panic hook, so
/// nothing is printed).
struct Cancelled;

impl Ticker {
    pub(crate) fn count(&self, done: u64, total: u64) {
        self.total.store(total, Relaxed);
        self.done.store(done, Relaxed);
    }
    pub(crate) fn set(&self, done: u64, total: u64) {
        self.count(done, total);
        self.check();
    }
    /// Set by Ctrl-C, for library calls that take a stop flag (the renderer's).
    pub(crate) fn stop(&self) -> &AtomicBool {
        &self.cancel
    }
    /// Where a library call takes no stop flag, its progress calls are the cancellation points:
    /// unwinding from one drops the computation's buffers. Parallel loops that ask
    /// `Progress::cancelled` skip their remaining pieces; elsewhere work that rayon already split
    /// runs to its end.
    pub(crate) fn check(&self) {
        if self.cancel.load(Relaxed) {
            std::panic::resume_unwind(Box::new(Cancelled));
        }
    }
}

impl murk_recon::Progress for Ticker {
    fn start(&self, total: u64) {
        self.set(0, total);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Relaxed);
        self.check();
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Relaxed)
    }
}

/// The worker threads `threads=n` asks for (0: one per core), refused if negative or beyond murk's
/// limit.
pub(crate) fn thread_count(n: i64) -> PyResult<usize> {
    usize::try_from(n)
        .map_err(|_| error("InputError", format!("threads must be ≥ 0, got {n}")))
        .and_then(|n| murk_core::Limits::threads(n).map_err(to_py))
}

/// Runs `work` on its own thread (on a pool of `threads` if given) with the GIL released, while this
/// thread reports progress to `progress(done, total)` and checks for Ctrl-C every 50 ms.
pub(crate) fn compute<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    threads: Option<i64>,
    work: impl FnOnce(&Ticker) -> murk_core::Result<T> + Send,
) -> PyResult<T> {
    murk_core::Limits::check_env().map_err(to_py)?;
    let ticker = Ticker::default();
    let pool = match threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(thread_count(n)?)
                .build()
                .map_err(|e| error("Error", format!("cannot start {n} worker threads: {e}")))?,
        ),
        None => None,
    };
    let (tx, rx) = mpsc::channel();
    // Only this thread receives; the mutex makes the receiver shareable with the detached closure.
    let rx = std::sync::Mutex::new(rx);
    std::thread::scope(|s| {
        let t = &ticker;
        let pool = pool.as_ref();
        // The main thread's stack size, which the CLI runs the same code on.
        std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn_scoped(s, move || {
                let run = || match pool {
                    Some(p) => p.install(|| work(t)),
                    None => work(t),
                };
                let _ = tx.send(catch_unwind(AssertUnwindSafe(run)));
            })
            .map_err(|e| error("Error", format!("cannot start a thread: {e}")))?;
        let mut stop: Option<PyErr> = None;
        let mut shown = (u64::MAX, u64::MAX);
        let mut shown_at = Instant::now();
        loop {
            let got = py.detach(|| {
                rx.lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .recv_timeout(Duration::from_millis(50))
            });
            if stop.is_none() {
                let now = (ticker.done.load(Relaxed), ticker.total.load(Relaxed));
                // Repeated while nothing changes too, so that a callback can stop a long unit's
                // successors (murk.dask's stop file) without waiting for the next count.
                let due = now != shown || shown_at.elapsed() >= HEARTBEAT;
                let report = match progress {
                    Some(cb) if due && now.1 > 0 => {
                        shown_at = Instant::now();
                        cb.call1(now).map(|_| ())
                    }
                    _ => Ok(()),
                };
                shown = now;
                if let Err(e) = report.and_then(|_| py.check_signals()) {
                    ticker.cancel.store(true, Relaxed);
                    stop = Some(e);
                }
            }
            match got {
                Ok(Ok(Ok(v))) => return stop.map_or(Ok(v), Err),
                Ok(Ok(Err(e))) => return Err(stop.unwrap_or_else(|| to_py(e))),
                Ok(Err(payload)) => {
                    return Err(match (stop, payload.downcast::<Cancelled>()) {
                        (Some(e), Ok(_)) => e,
                        (_, Err(p)) => {
                            let msg = p
                                .downcast_ref::<String>()
                                .cloned()
                                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                                .unwrap_or_default();
                            error("Error", format!("internal error in murk: {msg}"))
                        }
                        (None, Ok(_)) => error("Error", "cancelled".into()),
                    })
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(error("Error", "the computation's thread vanished".into()))
                }
            }
        }
    })
}

#[pymodule]
fn _murk(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The library's messages name options as this front end spells them: keywords.
    murk_core::spelling::set_front_end(murk_core::Spelling::Python);
    m.add_class::<capture::Capture>()?;
    m.add_function(wrap_pyfunction!(capture::read_capture, m)?)?;
    m.add_function(wrap_pyfunction!(capture::write_capture, m)?)?;
    m.add_function(wrap_pyfunction!(capture::import_capture, m)?)?;
    m.add_function(wrap_pyfunction!(capture::_capture_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(ops::synth, m)?)?;
    m.add_function(wrap_pyfunction!(ops::render, m)?)?;
    m.add_function(wrap_pyfunction!(ops::merge, m)?)?;
    m.add_function(wrap_pyfunction!(ops::render_part, m)?)?;
    m.add_function(wrap_pyfunction!(ops::check_render, m)?)?;
    m.add_function(wrap_pyfunction!(ops::check_threads, m)?)?;
    m.add_function(wrap_pyfunction!(ops::assemble, m)?)?;
    m.add_function(wrap_pyfunction!(ops::render_outputs, m)?)?;
    m.add_function(wrap_pyfunction!(ops::study_plan, m)?)?;
    m.add_function(wrap_pyfunction!(ops::run_study, m)?)?;
    m.add_function(wrap_pyfunction!(recon::reconstruct, m)?)?;
    m.add_function(wrap_pyfunction!(recon::methods, m)?)?;
    m.add_function(wrap_pyfunction!(medium::estimate_medium, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
