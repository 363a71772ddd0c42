//! Fig. 3c: the Z letter in fog at μt = 1, anisotropy g (rows) by albedo (columns).

use super::{fog, iou, verdict, Cell, CellSpec};
use crate::plan::SceneKind;
use crate::plan::ALBEDOS;
use crate::run::CellResult;

/// g by albedo at μt = 1.
pub(super) fn cells(cell: &Cell) -> Vec<CellSpec> {
    [0.7, 0.0, -0.7]
        .into_iter()
        .flat_map(|g| {
            ALBEDOS.map(|a| {
                let (r, c) = (format!("g = {g}"), format!("α = {a}"));
                cell(r, c, SceneKind::ZLetter, fog(1.0, a, g), 1.0)
            })
        })
        .collect()
}

/// The claims the cells test, in the report's words.
pub(super) fn findings(cells: &[&CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    // Fig. 3c: rows are g, columns α.
    let fig3c = cells;
    let at_g = |g: f64, a: f64| {
        fig3c
            .iter()
            .find(|r| r.cell.medium.g == g && r.cell.medium.albedo == a)
    };
    for (g, claim, better) in [
        (
            0.7,
            "forward scattering lets the phasor penetrate deeper",
            true,
        ),
        (-0.7, "backward scattering gives poorer visibility", false),
    ] {
        let pairs: Vec<(f64, f64, f64)> = crate::plan::ALBEDOS
            .iter()
            .filter_map(|&a| Some((a, iou(at_g(g, a)?), iou(at_g(0.0, a)?))))
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let agree = pairs
            .iter()
            .filter(|(_, x, z)| if better { x >= z } else { x < z })
            .count();
        out.push(format!(
            "Fig. 3c, g = {g} against g = 0: the paper says {claim}; IoU is {} g = 0's at {agree} of {} albedos: {}. IoU {}.",
            if better { "at or above" } else { "below" },
            pairs.len(),
            verdict(agree == pairs.len()),
            pairs
                .iter()
                .map(|(a, x, z)| format!("α {a}: {x:.3} against {z:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    out
}
