//! Which depth planes the fast form evaluates. Along z the field of a band frequency k oscillates
//! with the path's depth derivative: k·(legs·∂r/∂z + ∂d/∂z), bounded by the geometry (the wall's
//! and the volume's lateral extents, the point-side points) to a band [κ_lo, κ_hi] that is often
//! narrower than a finely sampled volume's Nyquist band. Then only every other plane is evaluated
//! (plus a few past each end), and the planes between are read by a least-squares band-limited
//! interpolator with the band's centre demodulated (docs/reconstruction.md, "Depth planes").

use crate::cmul;
use murk_core::{DVec3, Volume};
use rustfft::num_complex::{Complex32, Complex64};
use std::f64::consts::PI;

/// Taps of the interpolator: its least-squares error over |ω| ≤ 0.74π per evaluated plane is 1e-5
/// centred and 8e-4 shifted by SHIFT planes (docs/reconstruction.md, "Depth planes").
pub(super) const TAPS: usize = 28;
const _: () = assert!(TAPS.is_multiple_of(4), "the taps are summed in four lanes");

/// How far, in evaluated planes, the interpolator's taps may sit off-centre near the volume's ends,
/// where fewer planes past the ends are then evaluated.
const SHIFT: usize = 11;

/// The widest band (in units of π per evaluated-plane step) that is interpolated; wider bands
/// evaluate every plane.
pub(super) const MAX_BAND: f64 = 0.75;

/// The depth planes evaluated and how each volume plane is read from them.
#[derive(Clone, Debug)]
pub(super) struct Depths {
    /// Depths (m) evaluated, in the volume's order.
    pub(super) z: Vec<f64>,
    /// Index in `z` of volume plane 0 when planes are interpolated: volume plane i is evaluated
    /// plane `first + i/2` for even i.
    first: usize,
    /// Per shift s ∈ −SHIFT ..= SHIFT of the taps (index s + SHIFT), the interpolator's complex
    /// weights over TAPS evaluated planes, demodulation included; empty when every plane is
    /// evaluated.
    weights: Vec<[Complex32; TAPS]>,
}

/// The range of ∂(legs·r + d)/∂z over voxels at depths `z` (m) in the lateral box of `vol`, wall
/// points in the box `wall` (at depth `wall_z`) and point-side points `points` (none for confocal
/// captures, whose `legs` is 2).
pub(super) fn depth_rate(
    vol: &Volume,
    z: (f64, f64),
    wall: [(f64, f64); 2],
    wall_z: f64,
    points: &[DVec3],
    legs: f64,
) -> (f64, f64) {
    let span = |a: &murk_core::Axis| (a.start.min(a.end), a.start.max(a.end));
    let (vx, vy) = (span(&vol.x), span(&vol.y));
    // Lateral distance range between the volume's box and another box (or point).
    let rho = |bx: (f64, f64), by: (f64, f64)| {
        let gap = |a: (f64, f64), b: (f64, f64)| (b.0 - a.1).max(a.0 - b.1).max(0.0);
        let far = |a: (f64, f64), b: (f64, f64)| (a.1 - b.0).abs().max((b.1 - a.0).abs());
        (
            gap(vx, bx).hypot(gap(vy, by)),
            far(vx, bx).hypot(far(vy, by)),
        )
    };
    // h/√(ρ² + h²) is monotone in each of ρ and h, so its extremes over a box are at its corners.
    let corners = |(r0, r1): (f64, f64), (h0, h1): (f64, f64)| {
        let g = |r: f64, h: f64| if h == 0.0 { 0.0 } else { h / r.hypot(h) };
        let v = [g(r0, h0), g(r0, h1), g(r1, h0), g(r1, h1)];
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    };
    let (k0, k1) = corners(rho(wall[0], wall[1]), (z.0 - wall_z, z.1 - wall_z));
    let (mut p0, mut p1) = if points.is_empty() {
        (0.0, 0.0)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY)
    };
    for p in points {
        let (a, b) = corners(rho((p.x, p.x), (p.y, p.y)), (z.0 - p.z, z.1 - p.z));
        p0 = f64::min(p0, a);
        p1 = f64::max(p1, b);
    }
    (legs * k0 + p0, legs * k1 + p1)
}

impl Depths {
    /// Every plane of `vol`.
    pub(super) fn every(vol: &Volume) -> Depths {
        Depths {
            z: (0..vol.z.n).map(|i| vol.z.at(i)).collect(),
            first: 0,
            weights: Vec::new(),
        }
    }

    /// Every other plane of `vol` and a few past each end, or None when those would come closer to
    /// the wall (depth `wall_z`) than half the volume's shallower end, or there would be no fewer
    /// planes or fewer than the interpolator's taps.
    pub(super) fn halved(vol: &Volume, wall_z: f64) -> Option<Depths> {
        let n = vol.z.n;
        if n < 2 {
            return None;
        }
        let step = vol.z.step();
        // Odd plane i reads TAPS evaluated planes from e − (TAPS/2 − 1) (e: plane i − 1's), moved
        // inward by up to SHIFT at the ends.
        let first = TAPS / 2 - 1 - SHIFT;
        let last_odd = if n.is_multiple_of(2) { n - 1 } else { n - 2 };
        let e_last = first + (last_odd - 1) / 2;
        let evaluated = (first + n.div_ceil(2)).max(e_last + TAPS / 2 - SHIFT + 1);
        let z = |e: usize| vol.z.start + 2.0 * (e as f64 - first as f64) * step;
        // Either end may be the shallow one (a decreasing depth axis).
        let nearest = (vol.z.start.min(vol.z.end) - wall_z) * 0.5;
        if evaluated >= n || evaluated < TAPS || z(0).min(z(evaluated - 1)) - wall_z < nearest {
            return None;
        }
        Some(Depths {
            z: (0..evaluated).map(z).collect(),
            first,
            weights: Vec::new(),
        })
    }

    /// Whether planes between the evaluated ones are interpolated.
    pub(super) fn interpolates(&self) -> bool {
        !self.weights.is_empty()
    }

    /// Designs the interpolator for depth frequencies in `band` (rad/m, the path's depth rate times
    /// the band's wavenumbers); false (and nothing designed) when the band is wider than MAX_BAND.
    pub(super) fn design(&mut self, band: (f64, f64)) -> bool {
        // Signed: a decreasing depth axis turns the demodulation's phase around.
        let h = self.z[1] - self.z[0];
        let centre = 0.5 * (band.0 + band.1);
        let half = 0.5 * (band.1 - band.0) * h.abs() / PI;
        if half > MAX_BAND {
            return false;
        }
        // The odd plane sits half a step between evaluated planes: taps at t − TAPS/2 + ½ + s steps
        // from it for a shift s.
        self.weights = (-(SHIFT as i64)..=SHIFT as i64)
            .map(|s| {
                let offsets: Vec<f64> = (0..TAPS)
                    .map(|t| t as f64 - (TAPS / 2) as f64 + 0.5 + s as f64)
                    .collect();
                let taps = least_squares(&offsets, half.max(0.05) * PI);
                // Demodulated: the field's phase advances by κ·Δz, so the tap at offset o (in
                // steps) weighs its plane by e^{−iκ·o·h}.
                std::array::from_fn(|t| {
                    let c = Complex64::from_polar(taps[t], -centre * offsets[t] * h);
                    Complex32::new(c.re as f32, c.im as f32)
                })
            })
            .collect();
        true
    }

    /// A column of the volume (`out`, every plane) from its evaluated planes `col`.
    pub(super) fn read(&self, col: &[Complex32], out: &mut [Complex32]) {
        if !self.interpolates() {
            out.copy_from_slice(col);
            return;
        }
        let last = col.len() as i64 - TAPS as i64;
        for (i, o) in out.iter_mut().enumerate() {
            let e = self.first + i / 2;
            if i.is_multiple_of(2) {
                *o = col[e];
                continue;
            }
            // Evaluated planes e + 1 − TAPS/2 ..= e + TAPS/2 lie at offsets −(TAPS − 1)/2 ..=
            // (TAPS − 1)/2 steps from plane i, moved inward at the ends.
            let ideal = e as i64 + 1 - (TAPS / 2) as i64;
            let start = ideal.clamp(0, last);
            let w = &self.weights[(start - ideal + SHIFT as i64) as usize];
            *o = cmul::dot(&col[start as usize..start as usize + TAPS], w);
        }
    }
}

/// Weights w over samples at `offsets` (in sample steps from the point read) minimising
/// ∫_{−b}^{b} |Σ_t w_t e^{iω·o_t} − 1|² dω: the normal equations of the sinc Gram matrix, solved by
/// Cholesky in f64 with a ridge of 1e-12 for the near-singular high-order directions.
fn least_squares(offsets: &[f64], b: f64) -> Vec<f64> {
    let n = offsets.len();
    // ∫_{−b}^{b} e^{iωx} dω = 2 sin(bx)/x (2b at x = 0).
    let sinc = |x: f64| {
        if x.abs() < 1e-12 {
            2.0 * b
        } else {
            2.0 * (b * x).sin() / x
        }
    };
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] = sinc(offsets[i] - offsets[j]);
        }
        a[i * n + i] += 1e-12 * 2.0 * b;
    }
    let mut w: Vec<f64> = offsets.iter().map(|&o| sinc(o)).collect();
    // In-place Cholesky: a = L·Lᵀ, lower triangle.
    for j in 0..n {
        let d = (a[j * n + j] - (0..j).map(|k| a[j * n + k].powi(2)).sum::<f64>()).sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let s: f64 = (0..j).map(|k| a[i * n + k] * a[j * n + k]).sum();
            a[i * n + j] = (a[i * n + j] - s) / d;
        }
    }
    for i in 0..n {
        let s: f64 = (0..i).map(|k| a[i * n + k] * w[k]).sum();
        w[i] = (w[i] - s) / a[i * n + i];
    }
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[k * n + i] * w[k]).sum();
        w[i] = (w[i] - s) / a[i * n + i];
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The interpolator's worst error over its band with its taps shifted by `shift` planes, against
    /// a direct evaluation of the response.
    fn worst(b: f64, shift: f64) -> f64 {
        let offsets: Vec<f64> = (0..TAPS)
            .map(|t| t as f64 - (TAPS / 2) as f64 + 0.5 + shift)
            .collect();
        let w = least_squares(&offsets, b * PI);
        (0..=2000)
            .map(|i| {
                let om = b * PI * (i as f64 / 1000.0 - 1.0);
                let r: Complex64 = w
                    .iter()
                    .zip(&offsets)
                    .map(|(&w, &o)| Complex64::from_polar(w, om * o))
                    .sum();
                (r - 1.0).norm()
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_interpolator_reproduces_every_wave_of_its_band() {
        // A numpy least-squares design of 28 taps gives 1.7e-5 centred and 1.2e-3 shifted by 11 at
        // 0.75π, 7e-7 and 1.6e-5 at 0.6π.
        for (b, centred, shifted) in [(0.6, 2e-6, 3e-5), (MAX_BAND, 3e-5, 2e-3)] {
            let (c, s) = (worst(b, 0.0), worst(b, SHIFT as f64));
            assert!(c < centred && s < shifted, "{b}π: {c} centred, {s} shifted");
        }
    }
}
