//! The homogeneous medium: one extinction coefficient throughout, so transmittance and free-flight
//! distances have closed forms.

/// Extinction σt (1/m), the same at every point of the medium's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_t_per_m: f64,
}

impl Homogeneous {
    /// A free-flight distance drawn with the uniform number `u` (inverse CDF of σt·e^{−σt·len}).
    pub fn sample_distance(&self, u: f64) -> f64 {
        -(1.0 - u).ln() / self.sigma_t_per_m
    }
}
