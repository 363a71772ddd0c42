//! Exponential height fog: σt falls as exp(−(y − floor)/scale) above the floor of the medium's box
//! (y is up), so the optical depth along any segment has a closed form.

use super::Segment;
use murk_core::DVec3;

/// σt(p) = `sigma_t_floor_per_m` · exp(−(p.y − `floor_y_m`)/`scale_m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Height {
    pub sigma_t_floor_per_m: f64,
    pub floor_y_m: f64,
    pub scale_m: f64,
}

impl Height {
    pub fn sigma_t_at(&self, p: DVec3) -> f64 {
        self.sigma_t_floor_per_m * (-(p.y - self.floor_y_m) / self.scale_m).exp()
    }

    /// ∫σt along `seg`: σt(start)·len·(1 − e^{−x})/x with x = len·d.y/scale, the last factor from
    /// expm1 (and its series near x = 0, where the division would lose the digits).
    pub fn optical_depth(&self, seg: &Segment) -> f64 {
        let len = seg.len_m();
        let x = len * seg.d.y / self.scale_m;
        let shape = if x.abs() < 1e-8 {
            1.0 - 0.5 * x
        } else {
            -(-x).exp_m1() / x
        };
        self.sigma_t_at(seg.o + seg.d * seg.t0) * len * shape
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form against a 20 000-step midpoint sum, rising, falling and level.
    #[test]
    fn optical_depth_matches_quadrature() {
        let h = Height {
            sigma_t_floor_per_m: 2.0,
            floor_y_m: -0.5,
            scale_m: 0.3,
        };
        for d in [
            DVec3::new(0.2, 0.9, 0.1),
            DVec3::new(0.0, -0.6, 0.8),
            DVec3::X,
        ] {
            let d = d.normalize();
            let seg = Segment {
                o: DVec3::new(0.1, -0.2, 1.0),
                d,
                t0: 0.1,
                t1: 0.9,
            };
            let n = 20_000;
            let dt = seg.len_m() / n as f64;
            let sum: f64 = (0..n)
                .map(|i| h.sigma_t_at(seg.o + d * (seg.t0 + (i as f64 + 0.5) * dt)) * dt)
                .sum();
            let exact = h.optical_depth(&seg);
            assert!((exact - sum).abs() < 1e-8 * sum, "{d}: {exact} vs {sum}");
        }
    }
}
