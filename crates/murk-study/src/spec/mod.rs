//! The figures' cells as specs: each figure's rows and columns, the scene and medium each renders
//! and the wavelength it is reconstructed with, before the plan gives them their capture jobs.

use crate::plan::{Figure, MediumParams, SceneKind, ALBEDOS};

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
        let z = SceneKind::ZLetter;
        match self {
            // The Z letter without a medium.
            Figure::Fig3a => vec![cell("no medium".into(), String::new(), z, NO_MEDIUM, 1.0)],
            // μt by albedo, isotropic.
            Figure::Fig3b => [0.5, 1.0, 2.0]
                .into_iter()
                .flat_map(|mu_t| {
                    ALBEDOS.map(|a| {
                        let (r, c) = (format!("μt = {mu_t}"), format!("α = {a}"));
                        cell(r, c, z, fog(mu_t, a, 0.0), 1.0)
                    })
                })
                .collect(),
            // g by albedo at μt = 1.
            Figure::Fig3c => [0.7, 0.0, -0.7]
                .into_iter()
                .flat_map(|g| {
                    ALBEDOS.map(|a| {
                        let (r, c) = (format!("g = {g}"), format!("α = {a}"));
                        cell(r, c, z, fog(1.0, a, g), 1.0)
                    })
                })
                .collect(),
            // The wavelength at μt = 1, α = 0.83.
            Figure::Fig4 => [1.0, 2.0, 3.0]
                .into_iter()
                .map(|k| {
                    let c = if k == 1.0 {
                        "λ = λ0".to_string()
                    } else {
                        format!("λ = {k}λ0")
                    };
                    cell(String::new(), c, z, fog(1.0, 0.83, 0.0), k)
                })
                .collect(),
            // The shelf scene without a medium and at two μt.
            Figure::Fig5 => [0.0, 1.0, 1.5]
                .into_iter()
                .map(|mu_t| {
                    let c = if mu_t == 0.0 {
                        "no medium".to_string()
                    } else {
                        format!("μt = {mu_t}")
                    };
                    let m = MediumParams {
                        mu_t_per_m: mu_t,
                        ..NO_MEDIUM
                    };
                    cell(String::new(), c, SceneKind::Shelf, m, 1.0)
                })
                .collect(),
        }
    }
}
