//! Progress bars on stderr for long steps; silent with --quiet or when stderr is not a terminal.

use indicatif::{ProgressBar, ProgressState, ProgressStyle};
use std::io::IsTerminal;

pub struct Bar(ProgressBar);

/// The ETA as `{eta}` prints it, or "…" while it would be a guess: before the first unit, in the first
/// two seconds and the first 5 % (a bar that starts with a slow unit would promise minutes).
pub fn eta(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    if eta_is_a_guess(state.pos(), state.elapsed().as_secs_f64(), state.fraction()) {
        let _ = w.write_str("…");
    } else {
        let _ = write!(w, "{:#}", indicatif::HumanDuration(state.eta()));
    }
}

fn eta_is_a_guess(pos: u64, elapsed_s: f64, fraction: f32) -> bool {
    pos == 0 || elapsed_s < 2.0 || fraction < 0.05
}

impl Bar {
    pub fn new(label: &str, quiet: bool) -> Bar {
        let pb = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(0)
        };
        // No bar until a stage says how long it is: an empty one would draw full, "0/0".
        pb.set_style(
            ProgressStyle::with_template("{msg:>12} {spinner} {elapsed} elapsed")
                .expect("valid template"),
        );
        pb.set_message(label.to_string());
        Bar(pb)
    }
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl murk_recon::Progress for Bar {
    /// A new bar: a method whose plan reports progress starts a second one for its run. The
    /// position goes back first so that no frame shows the old position against the new length,
    /// and the rate of the last stage does not feed the new ETA.
    fn start(&self, total: u64) {
        self.0.set_position(0);
        self.0.set_length(total);
        self.0.reset_eta();
        self.0.set_style(
            ProgressStyle::with_template(
                "{msg:>12} [{bar:40}] {pos}/{len} ({elapsed} elapsed, ETA {eta})",
            )
            .expect("valid template")
            .with_key("eta", eta)
            .progress_chars("=> "),
        );
    }
    fn advance(&self, n: u64) {
        self.0.inc(n);
    }
}

/// Prints a line unless quiet.
pub fn say(quiet: bool, line: impl AsRef<str>) {
    if !quiet {
        println!("{}", line.as_ref());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3-second job whose first unit is slow once read "ETA 3m": no ETA before the first unit,
    /// in the first two seconds or the first 5 %.
    #[test]
    fn eta_waits_for_evidence() {
        assert!(eta_is_a_guess(0, 10.0, 0.0));
        assert!(eta_is_a_guess(1, 1.9, 0.5));
        assert!(eta_is_a_guess(1, 30.0, 0.01));
        assert!(!eta_is_a_guess(5, 2.0, 0.05));
    }
}
