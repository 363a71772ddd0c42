//! The report's findings: each figure's own (see [`crate::spec`]), then the medium-aware column's.

use super::scored;
use crate::format::stat;
use crate::plan::Figure;
use crate::run::{CellResult, Scores};

/// What this run shows against each claim of the paper it can test, figure by figure (see
/// [`Figure::findings`]), then how murk's medium-aware column fared.
pub fn findings(results: &[CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    for fig in Figure::ALL {
        let cells: Vec<&CellResult> = results.iter().filter(|r| r.cell.figure == fig).collect();
        out.extend(fig.findings(&cells));
    }
    out.extend(aware_finding(results));
    out
}

/// How the medium-aware column compares with the paper's PF + K over the cells with a medium, and how
/// close its estimates came to the truth.
fn aware_finding(results: &[CellResult]) -> Option<String> {
    let score = |r: &CellResult, name: &str, get: fn(&Scores) -> f64| {
        scored(r, name).map_or(f64::NAN, |(_, s, _)| stat(s, get).0)
    };
    let fogged: Vec<&CellResult> = results
        .iter()
        .filter(|r| r.cell.medium.mu_t_per_m > 0.0 && scored(r, crate::run::AWARE).is_some())
        .collect();
    if fogged.is_empty() {
        return None;
    }
    let at_least = |get: fn(&Scores) -> f64| {
        fogged
            .iter()
            .filter(|r| score(r, crate::run::AWARE, get) >= score(r, "paper", get) - 1e-9)
            .count()
    };
    let close = fogged
        .iter()
        .filter(|r| {
            let m = r.cell.medium;
            let est: Vec<&[f64; 3]> = r.estimated.iter().flatten().collect();
            !est.is_empty()
                && est.iter().all(|e| {
                    (e[0] / m.mu_t_per_m - 1.0).abs() <= 0.1 && (e[1] / m.albedo - 1.0).abs() <= 0.1
                })
        })
        .count();
    let failed: usize = fogged.iter().map(|r| r.aware_notes.len()).sum();
    Some(format!(
        "Medium-aware (murk's own addition, not the paper's): reconstructed without being told the medium, it scores an IoU at least that of the paper's PF + K (which is told μt and α) in {} of {} cells with a medium, and an SSIM at least as high in {}; its estimate of μt and α (g free) is within 10 % of the truth in {} of them{}. Per cell: metrics.csv, the rows whose compensation is aware, columns est_mu_t, est_albedo, est_g.",
        at_least(|s| s.iou.best),
        fogged.len(),
        at_least(|s| s.ssim),
        close,
        if failed > 0 {
            format!("; the estimate failed on {failed} captures, reconstructed without K")
        } else {
            String::new()
        }
    ))
}
