//! What ran, where, when and for how long: the top of every murk page.

use crate::format::show;
use crate::plan::StudyPlan;
use crate::run::CellResult;
use std::fmt::Write as _;

/// What every murk page states first: murk's version, the command, when and on which machine.
pub(crate) fn run_provenance() -> Vec<(&'static str, String)> {
    let command = std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || "'\"$\\".contains(c)) {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ");
    vec![
        ("murk version", env!("CARGO_PKG_VERSION").to_string()),
        ("command", command),
        ("written", utc_now()),
        ("machine", machine()),
    ]
}

/// The run's provenance, for the top of the report: what ran, where, when and for how long.
pub(super) fn provenance(plan: &StudyPlan, results: &[CellResult]) -> Vec<(&'static str, String)> {
    // Cells that share their captures (Fig. 3c's g = 0 row is Fig. 3b's μt = 1 row, Fig. 4's three
    // λ one capture) count them once.
    let mut seen = std::collections::HashSet::new();
    let distinct: Vec<&CellResult> = results
        .iter()
        .filter(|r| seen.insert(r.cell.captures.clone()))
        .collect();
    let counted = |timed: bool| -> usize {
        distinct
            .iter()
            .filter(|r| r.cpu_s.is_some() == timed)
            .map(|r| r.cell.captures.len())
            .sum()
    };
    let cpu_s: f64 = distinct.iter().filter_map(|r| r.cpu_s).sum();
    // Every cell is reconstructed and scored on its own, shared captures or not.
    let scoring_s: f64 = results.iter().filter_map(|r| r.scoring_cpu_s).sum();
    let (ours, external) = (counted(true), counted(false));
    let hours = |s: f64| format!("{} CPU-hours ({} s)", show(s / 3600.0), show(s));
    let mut cpu_text = format!(
        "rendering {} for {} {}",
        hours(cpu_s),
        ours,
        plural(ours, "capture")
    );
    if external > 0 {
        let _ = write!(
            cpu_text,
            " ({external} {} rendered by an external executor, not counted)",
            plural(external, "capture")
        );
    }
    let _ = write!(
        cpu_text,
        " + reconstruction and scoring {} for {} {}",
        hours(scoring_s),
        results.len(),
        plural(results.len(), "cell")
    );
    let mut rows = run_provenance();
    rows.insert(
        2,
        (
            "scale",
            format!(
                "{} ({} {})",
                plan.scale.name(),
                plan.seeds,
                plural(plan.seeds as usize, "seed")
            ),
        ),
    );
    rows.insert(4, ("CPU time", cpu_text));
    rows
}

/// The current time as "YYYY-MM-DD HH:MM UTC" (days to civil date after Howard Hinnant's algorithm).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rest) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rest / 3600,
        rest % 3600 / 60
    )
}

/// Host name, CPU model and the cores this process may use.
fn machine() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "unknown host".into());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{host}: {cpu}, {cores} cores available")
}

/// `word`, with an s unless there is one.
fn plural(n: usize, word: &str) -> String {
    if n == 1 {
        word.to_string()
    } else {
        format!("{word}s")
    }
}
