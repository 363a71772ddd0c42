//! Numbers and text as the study's outputs show them: the CSV files' full digits, the report's
//! three significant digits, mean ± spread over seeds, HTML escapes.

use crate::metrics;
use crate::run::Scores;

/// Mean and spread over seeds.
pub(crate) fn stat(scores: &[Scores], get: fn(&Scores) -> f64) -> (f64, f64) {
    metrics::mean_std(&scores.iter().map(get).collect::<Vec<_>>())
}

/// A number as the CSV files hold it: every digit that round-trips (a share of 3.7e-5 kept whole,
/// where a fixed 5 decimals kept 0.00004), "nan" for none.
pub(crate) fn num(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v}")
    }
}

/// A number as the report shows it: three significant digits in plain decimals (0.0498 beside 0.999,
/// never 4.98e-2), integers from 1000 up, "—" where there is none (NaN), "∞" for an infinite value.
pub fn show(v: f64) -> String {
    if v.is_nan() {
        return "—".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "∞" } else { "−∞" }.into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let digits = 2 - v.abs().log10().floor() as i32;
    let t = if digits <= 0 {
        format!("{v:.0}")
    } else {
        format!("{v:.*}", digits as usize)
    };
    // A real minus sign, and none on a value that rounds to zero.
    match t.strip_prefix('-') {
        Some(rest) if rest.trim_matches(['0', '.']).is_empty() => rest.into(),
        Some(rest) => format!("−{rest}"),
        None => t,
    }
}

/// Mean ± spread over seeds, as the report shows them (the spread only where there is one).
pub(crate) fn show_stat((mean, sd): (f64, f64)) -> String {
    if sd.is_finite() && !mean.is_nan() {
        format!("{} ± {}", show(mean), show(sd))
    } else {
        show(mean)
    }
}

pub(crate) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
