//! The paper's figures as specs, one module per figure: its cells (rows and columns, the scene and
//! medium each renders and the wavelength it is reconstructed with, before the plan gives them their
//! capture jobs) and its findings (the paper's claims those cells test, each with its numbers and a
//! verdict computed from them).

mod fig3a;
mod fig3b;
mod fig3c;
mod fig4;
mod fig5;

use crate::format::{show, stat};
use crate::plan::{Figure, MediumParams, SceneKind};
use crate::run::{CellResult, Scores};

/// One cell of a figure, as the paper lays it out.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CellSpec {
    pub figure: Figure,
    pub row: String,
    pub col: String,
    pub scene: SceneKind,
    pub medium: MediumParams,
    /// λ as a multiple of the paper's λ0 = 4Δc ([`crate::plan::Cell::wall_factor`] gives it in Δc).
    pub lambda_factor: f64,
}

/// No medium (μt = 0; the albedo and g are not read).
pub const NO_MEDIUM: MediumParams = MediumParams {
    mu_t_per_m: 0.0,
    albedo: 0.5,
    g: 0.0,
};

fn fog(mu_t_per_m: f64, albedo: f64, g: f64) -> MediumParams {
    MediumParams {
        mu_t_per_m,
        albedo,
        g,
    }
}

/// A best-threshold IoU from which the Z counts as found (the reduced study's test uses the same).
pub const FOUND_IOU: f64 = 0.2;

/// What a figure's module makes its cells with: row, column, scene, medium and λ factor.
type Cell<'a> = dyn Fn(String, String, SceneKind, MediumParams, f64) -> CellSpec + 'a;

impl Figure {
    /// The figure's cells, row by row.
    pub fn cells(self) -> Vec<CellSpec> {
        let cell = |row: String, col: String, scene, medium, lambda_factor| CellSpec {
            figure: self,
            row,
            col,
            scene,
            medium,
            lambda_factor,
        };
        match self {
            Figure::Fig3a => fig3a::cells(&cell),
            Figure::Fig3b => fig3b::cells(&cell),
            Figure::Fig3c => fig3c::cells(&cell),
            Figure::Fig4 => fig4::cells(&cell),
            Figure::Fig5 => fig5::cells(&cell),
        }
    }

    /// What this run shows against each claim of the paper that the figure's `cells` (this run's
    /// results of its cells, in the plan's order) can test, one sentence each with its numbers (the
    /// paper's K, mean over seeds) and a verdict computed from them: a claim that does not reproduce
    /// is stated as plainly as one that does. Claims whose cells did not run are left out.
    pub fn findings(self, cells: &[&CellResult]) -> Vec<String> {
        match self {
            Figure::Fig3a => fig3a::findings(cells),
            Figure::Fig3b => fig3b::findings(cells),
            Figure::Fig3c => fig3c::findings(cells),
            Figure::Fig4 => fig4::findings(cells),
            Figure::Fig5 => fig5::findings(cells),
        }
    }
}

/// A cell's score under the paper's K, mean over seeds (NaN where it was not scored so).
fn paper(r: &CellResult, get: fn(&Scores) -> f64) -> f64 {
    r.by_compensation
        .iter()
        .find(|(name, ..)| *name == "paper")
        .map_or(f64::NAN, |(_, scores, _)| stat(scores, get).0)
}

fn iou(r: &CellResult) -> f64 {
    paper(r, |s| s.iou.best)
}

fn hf(r: &CellResult) -> f64 {
    paper(r, |s| s.hf_share)
}

fn ssim(r: &CellResult) -> f64 {
    paper(r, |s| s.ssim)
}

fn verdict(holds: bool) -> &'static str {
    if holds {
        "holds"
    } else {
        "does not hold"
    }
}

/// `value (key)` of each cell, comma-separated. Three significant digits, so that close values
/// (high-frequency shares of 1e-5 to 0.1) show which is larger.
fn list(
    rs: &[&CellResult],
    value: &dyn Fn(&CellResult) -> f64,
    key: &dyn Fn(&CellResult) -> String,
) -> String {
    rs.iter()
        .map(|r| format!("{} ({})", show(value(r)), key(r)))
        .collect::<Vec<_>>()
        .join(", ")
}
