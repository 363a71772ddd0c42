//! Medium compensation applied to the intensity (docs/reconstruction.md).

use murk_core::{DVec3, Error, Result};

/// How much of a medium a straight path crosses: ∫ density ds from `from` to `to`, in metres of
/// density 1, so that μt times it is the optical depth. A heterogeneous medium's compensation reads
/// it along each leg (docs/media-heterogeneous.md); without one every metre counts as density 1.
pub trait PathDensity: Send + Sync {
    fn density_length_m(&self, from: DVec3, to: DVec3) -> f64;
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Compensation {
    None,
    /// The paper's eq. K(x_v) = (1 − α·e^{−α·d}) / e^{−μt·d}, with d = |x_v − x_c| in metres, verbatim
    /// (α·d mixes units: the formula is reproduced as printed). For confocal data d is the depth.
    Paper {
        mu_t_per_m: f64,
        albedo: f64,
    },
    /// Undoes ballistic round-trip attenuation of the focused signal: |U|² ∝ e^{−2μt(d_ill + d_cam)},
    /// so K = e^{2μt(d_ill + d_cam)} with d_cam to the wall centroid; confocal: e^{4μt·depth}.
    Ballistic {
        mu_t_per_m: f64,
    },
}

impl Compensation {
    /// Gains above this are clamped: exp(μt·d) overflows quickly and only amplifies noise beyond it.
    pub const MAX_GAIN: f64 = 1e6;

    /// Every compensation's name ("none" is no compensation).
    pub const NAMES: [&'static str; 3] = ["none", "paper", "ballistic"];

    /// The compensation called `name`, for a medium of `mu_t_per_m` and `albedo` (0 if not given).
    /// An albedo is refused where the compensation does not read it, so it cannot look applied.
    pub fn named(name: &str, mu_t_per_m: f64, albedo: Option<f64>) -> Result<Compensation> {
        match (name, albedo) {
            ("none", None) => Ok(Compensation::None),
            ("paper", _) => Ok(Compensation::Paper {
                mu_t_per_m,
                albedo: albedo.unwrap_or(0.0),
            }),
            ("ballistic", None) => Ok(Compensation::Ballistic { mu_t_per_m }),
            ("none" | "ballistic", Some(_)) => Err(Error::param(format!(
                "compensate '{name}' does not read an albedo; only 'paper' does"
            ))),
            _ => Err(Error::param(format!(
                "compensate '{name}': expected {}",
                Self::NAMES.join(", ")
            ))),
        }
    }

    pub fn validate(&self) -> Result<()> {
        let (mu, alb) = match *self {
            Compensation::None => return Ok(()),
            Compensation::Paper { mu_t_per_m, albedo } => (mu_t_per_m, albedo),
            Compensation::Ballistic { mu_t_per_m } => (mu_t_per_m, 0.0),
        };
        murk_core::Limits::extinction(mu).map_err(|e| Error::param(format!("μt {e}")))?;
        if !(0.0..=1.0).contains(&alb) {
            return Err(Error::param(format!("albedo must be in [0, 1], got {alb}")));
        }
        Ok(())
    }

    /// Gain for voxel `v`; `point` is the paper's x_c, `aperture` the centroid of the gridded side.
    /// For confocal data distances are depths (v.z).
    pub fn gain(&self, v: DVec3, point: DVec3, aperture: DVec3, confocal: bool) -> f64 {
        self.gain_along(v, point, aperture, confocal, None)
    }

    /// As [`Compensation::gain`], with the attenuation integrated along each leg through `density`
    /// (μt × [`PathDensity::density_length_m`]) where one is given; the paper's α·d term stays
    /// geometric. Confocal legs run from the wall point (v.x, v.y, 0) to `v`.
    pub fn gain_along(
        &self,
        v: DVec3,
        point: DVec3,
        aperture: DVec3,
        confocal: bool,
        density: Option<&dyn PathDensity>,
    ) -> f64 {
        let from = if confocal {
            DVec3::new(v.x, v.y, 0.0)
        } else {
            point
        };
        let d = if confocal {
            v.z.max(0.0)
        } else {
            (v - point).length()
        };
        // Metres of density 1 along the leg from `a` to `v` (its length d_a without a density).
        let leg = |a: DVec3, d_a: f64| density.map_or(d_a, |g| g.density_length_m(a, v));
        let k = match *self {
            Compensation::None => return 1.0,
            Compensation::Paper { mu_t_per_m, albedo } => {
                // α is undefined without a medium; K ≡ 1 then.
                let alpha = if mu_t_per_m == 0.0 { 0.0 } else { albedo };
                (1.0 - alpha * (-d * alpha).exp()) * (leg(from, d) * mu_t_per_m).exp()
            }
            Compensation::Ballistic { mu_t_per_m } => {
                let legs = if confocal {
                    2.0 * leg(from, d)
                } else {
                    leg(from, d) + leg(aperture, (v - aperture).length())
                };
                (2.0 * mu_t_per_m * legs).exp()
            }
        };
        k.min(Self::MAX_GAIN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_table() {
        // docs/reconstruction.md, d = 0, 0.5, 1, 2 m.
        let table = [
            ((0.5, 0.15), [0.85, 1.10534, 1.43586, 2.41622]),
            ((1.0, 0.83), [0.17, 0.745086, 1.73448, 6.22295]),
            ((2.0, 0.5), [0.5, 1.65978, 5.14821, 44.5554]),
        ];
        for ((mu, a), want) in table {
            let k = Compensation::Paper {
                mu_t_per_m: mu,
                albedo: a,
            };
            for (d, w) in [0.0, 0.5, 1.0, 2.0].iter().zip(want) {
                let got = k.gain(DVec3::new(0.0, 0.0, *d), DVec3::ZERO, DVec3::ZERO, false);
                assert!(
                    (got - w).abs() <= 1e-5 * w,
                    "μt {mu} α {a} d {d}: {got} vs {w}"
                );
            }
        }
        let none = Compensation::Paper {
            mu_t_per_m: 0.0,
            albedo: 0.7,
        };
        assert_eq!(
            none.gain(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::ZERO, false),
            1.0
        );
        // The CDT slab would overflow: the gain is clamped, finite.
        let slab = Compensation::Paper {
            mu_t_per_m: 262.52,
            albedo: 0.99,
        };
        assert_eq!(
            slab.gain(DVec3::new(0.0, 0.0, 2.0), DVec3::ZERO, DVec3::ZERO, false),
            Compensation::MAX_GAIN
        );
    }
}
