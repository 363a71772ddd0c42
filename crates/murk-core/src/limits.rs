//! What murk accepts, checked before anything is allocated or iterated: lengths far beyond any NLOS
//! set-up (so no derived size can overflow or loop for ever) and a memory budget per buffer.

use crate::{Error, Result};

/// Bounds on declared magnitudes and sizes. [`Limits::get`] gives the ones in force.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Largest |coordinate|, time offset or path end (m). Long-range NLOS reaches about 1.5 km.
    pub max_length_m: f64,
    /// Smallest time bin (m of path), and smallest span of a grid of wall points; 1e-7 m is 0.3 fs,
    /// finer than any streak camera.
    pub min_bin_width_m: f64,
    /// Largest single buffer (bytes): the memory this process may use (physical memory, lowered by
    /// a cgroup limit or an address-space rlimit), or `MURK_MAX_BYTES` when set.
    pub max_bytes: u64,
}

/// `MURK_MAX_BYTES`: `None` when unset, its text when it is not a positive number of bytes (text
/// that is not UTF-8 included).
fn env_max_bytes() -> Option<std::result::Result<u64, String>> {
    let raw = std::env::var_os("MURK_MAX_BYTES")?;
    let text = raw.to_string_lossy();
    Some(
        text.trim()
            .parse::<u64>()
            .ok()
            .filter(|&b| b > 0)
            .ok_or_else(|| text.into_owned()),
    )
}

impl Limits {
    /// Most worker threads murk starts: far above any machine's cores, far below what the OS can run.
    pub const MAX_THREADS: usize = 1024;

    /// Most paths per traced point one render takes: 2^40 ≈ 1.1·10¹², far beyond any converged
    /// render; more is a typo that would run for ever.
    pub const MAX_SPP: u64 = 1 << 40;

    /// Longest interval or time budget in seconds: one year (a `Duration` cannot hold every float,
    /// and anything longer is a typo).
    pub const MAX_SECONDS: f64 = 365.0 * 86_400.0;

    /// Largest extinction coefficient: a mean free path of 1 µm, about the wavelength of light,
    /// below which radiative transfer (what the renderer and the compensations model) does not hold.
    pub const MAX_MU_T_PER_M: f64 = 1e6;

    /// `mu` (an extinction coefficient in 1/m) is finite, ≥ 0 and at most [`Self::MAX_MU_T_PER_M`];
    /// the error is the text to follow the caller's name for it.
    pub fn extinction(mu: f64) -> std::result::Result<(), String> {
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(format!("must be ≥ 0 (1/m), got {}", short(mu)));
        }
        if mu > Self::MAX_MU_T_PER_M {
            return Err(format!(
                "is {} /m, a mean free path below the 1 µm where radiative transfer holds; murk accepts up to {} /m",
                short(mu),
                short(Self::MAX_MU_T_PER_M)
            ));
        }
        Ok(())
    }

    /// A worker thread count `n` (0: one per core) that murk will start.
    pub fn threads(n: usize) -> Result<usize> {
        if n > Self::MAX_THREADS {
            return Err(Error::Limits(format!(
                "{n} worker threads; murk starts at most {}",
                Self::MAX_THREADS
            )));
        }
        Ok(n)
    }

    /// Refuses a `MURK_MAX_BYTES` that is set but not a positive number of bytes ([`Limits::get`]
    /// would ignore it and use the machine's memory, which is not what its setter meant).
    pub fn check_env() -> Result<()> {
        match env_max_bytes() {
            Some(Err(v)) => Err(Error::param(format!(
                "MURK_MAX_BYTES is '{v}'; it must be a positive number of bytes"
            ))),
            _ => Ok(()),
        }
    }

    pub fn get() -> Limits {
        let max_bytes = env_max_bytes()
            .and_then(|b| b.ok())
            .unwrap_or_else(memory_budget_bytes);
        Limits {
            max_length_m: 1e5,
            min_bin_width_m: 1e-7,
            max_bytes,
        }
    }

    /// `v` (a length in metres, named `what`) is finite and within ±`max_length_m`.
    pub fn length(&self, what: &str, v: f64) -> Result<()> {
        if !v.is_finite() {
            return Err(Error::param(format!("{what} is {v}; it must be finite")));
        }
        if v.abs() > self.max_length_m {
            return Err(Error::Limits(format!(
                "{what} is {} m; murk accepts magnitudes up to {} m",
                short(v),
                short(self.max_length_m)
            )));
        }
        Ok(())
    }

    /// The values of a capture's H of `hists` histograms × `bins` bins, if H and the transposed copy
    /// that writing it to a file makes fit the budget.
    pub fn capture_h(&self, hists: usize, bins: usize) -> Result<usize> {
        self.elements(
            "H (and the copy a file write makes)",
            &[hists, bins],
            2 * std::mem::size_of::<f32>(),
        )
    }

    /// The element count of `dims` if a buffer of that many `elem_bytes`-sized values fits the
    /// budget (overflow-safe); `what` names the buffer in the error.
    pub fn elements(&self, what: &str, dims: &[usize], elem_bytes: usize) -> Result<usize> {
        let n = dims
            .iter()
            .try_fold(1u128, |acc, &d| acc.checked_mul(d as u128))
            .unwrap_or(u128::MAX);
        let bytes = n.saturating_mul(elem_bytes as u128);
        if bytes > self.max_bytes as u128 || n > usize::MAX as u128 {
            let shape: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
            return Err(Error::Limits(format!(
                "{what} of {} values would take {}, more than the {} this process may use",
                shape.join(" × "),
                human_bytes(bytes),
                human_bytes(self.max_bytes as u128)
            )));
        }
        Ok(n as usize)
    }
}

/// The memory this process may use: physical memory, lowered by a container's cgroup limit or an
/// address-space rlimit (a cluster's workers often run under one, and an allocation beyond it
/// aborts instead of failing). Read once.
fn memory_budget_bytes() -> u64 {
    static BUDGET: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *BUDGET.get_or_init(|| {
        #[allow(unused_mut)]
        let mut budget = physical_memory_bytes();
        #[cfg(target_os = "linux")]
        {
            // cgroup v2, then v1; "max" (no limit) does not parse and is skipped.
            for f in [
                "/sys/fs/cgroup/memory.max",
                "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            ] {
                if let Some(v) = std::fs::read_to_string(f)
                    .ok()
                    .and_then(|t| t.trim().parse::<u64>().ok())
                {
                    budget = budget.min(v);
                }
            }
            let mut r = libc::rlimit {
                rlim_cur: 0,
                rlim_max: 0,
            };
            // SAFETY: getrlimit only writes the struct it is given.
            if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0
                && r.rlim_cur != libc::RLIM_INFINITY
            {
                #[allow(clippy::unnecessary_cast)] // rlim_t is 32-bit on some Linux targets
                let limit = r.rlim_cur as u64;
                budget = budget.min(limit);
            }
        }
        budget
    })
}

/// Physical memory from the OS; 16 GiB where it cannot be read.
fn physical_memory_bytes() -> u64 {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: sysconf has no preconditions; it returns -1 for an unknown name.
        let (pages, size) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        if pages > 0 && size > 0 {
            return pages as u64 * size as u64;
        }
    }
    16 << 30
}

fn human_bytes(b: u128) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A number for a message: at most 6 significant digits, no trailing zeros, and no digits that an
/// f32 round trip added (0.003 read from an f32 dataset prints as "0.003", not
/// "0.003000000026077032"); scientific notation outside 1e-4..1e6.
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-4..1e6).contains(&a) {
        let s = format!("{v:.5e}");
        let (m, e) = s.split_once('e').expect("{:e} has an exponent");
        return format!("{}e{e}", trim_zeros(m));
    }
    let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
    trim_zeros(&format!("{v:.decimals$}")).to_string()
}

/// What a non-finite f32 read from a file may have been: data are held as 32-bit floats, so a finite
/// f64 beyond their range arrives as inf.
pub fn non_finite(v: f32) -> String {
    if v.is_nan() {
        "NaN".into()
    } else {
        format!("{v}: infinite, or beyond the ±3.4e38 that 32-bit floats hold")
    }
}

fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers_read_as_typed() {
        assert_eq!(short(0.003f32 as f64), "0.003");
        assert_eq!(short(1.5), "1.5");
        assert_eq!(short(-2.0), "-2");
        assert_eq!(short(123456.7), "123457");
        assert_eq!(short(1e30f32 as f64), "1e30");
        assert_eq!(short(1.25e-7), "1.25e-7");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn lengths_and_sizes_are_bounded_before_use() {
        let l = Limits {
            max_length_m: 1e5,
            min_bin_width_m: 1e-7,
            max_bytes: 1 << 20,
        };
        assert!(l.length("t_start", 3.5).is_ok());
        let e = l.length("t_start", 1e20).unwrap_err().to_string();
        assert_eq!(
            e,
            "t_start is 1e20 m; murk accepts magnitudes up to 100000 m"
        );
        assert!(l.length("x", f64::NAN).is_err());
        assert_eq!(l.elements("H", &[256, 256], 4).unwrap(), 65536);
        let e = l.elements("H", &[257, 256], 16).unwrap_err().to_string();
        assert!(e.contains("257 × 256") && e.contains("1.0 MiB"), "{e}");
        // A product that overflows u128 is refused, not wrapped.
        assert!(l
            .elements("H", &[usize::MAX, usize::MAX, usize::MAX], 4)
            .is_err());
    }
}
