//! Tables of unit phasors e^{iθ} and their powers, vectorised: the fast form builds one per plane
//! over tens of thousands of kernel offsets and voxels, where libm's scalar sin/cos dominated.

use murk_core::simd::wide;
use rustfft::num_complex::Complex32;

/// π/2 in three parts for Cody–Waite reduction (fdlibm's pio2_1, pio2_2, pio2_2t): n·P1 and n·P2
/// are exact for |n| < 2^20, so the reduced angle keeps full precision for |θ| up to about 1e6.
const P1: f64 = 1.570_796_326_734_125_6;
const P2: f64 = 6.077_100_506_303_966e-11;
const P3: f64 = 2.022_266_248_795_950_6e-21;

/// sin and cos of `x` without branches or table lookups, so that loops over it vectorise: reduction
/// by π/2, then fdlibm's minimax polynomials on [−π/4, π/4] and the quadrant's swap and signs.
/// Within 4e-16 of libm for |x| ≤ 1e5 (tested).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let n = (x * std::f64::consts::FRAC_2_PI).round();
    let r = ((x - n * P1) - n * P2) - n * P3;
    let z = r * r;
    let s = r + r
        * z
        * (-1.666_666_666_666_663_2e-1
            + z * (8.333_333_333_322_49e-3
                + z * (-1.984_126_982_985_795e-4
                    + z * (2.755_731_370_707_006_8e-6
                        + z * (-2.505_076_025_340_686_3e-8 + z * 1.589_690_995_211_55e-10)))));
    let c = 1.0 - 0.5 * z
        + z * z
            * (4.166_666_666_666_66e-2
                + z * (-1.388_888_888_887_411e-3
                    + z * (2.480_158_728_947_673e-5
                        + z * (-2.755_731_435_139_066_3e-7
                            + z * (2.087_572_321_298_175e-9 + z * -1.135_964_755_778_819_5e-11)))));
    // Quadrant q = n mod 4, in f64 so the selects stay in vector registers.
    let q = n - 4.0 * (n * 0.25).floor();
    let odd = q == 1.0 || q == 3.0;
    let (sn, cs) = if odd { (c, s) } else { (s, c) };
    let sin = if q >= 2.0 { -sn } else { sn };
    let cos = if q == 1.0 || q == 2.0 { -cs } else { cs };
    (sin, cos)
}

/// For each angle θ (rad) and amplitude a: `power[i] = a·e^{i·m·θ}` and `unit[i] = e^{iθ}`, rounded
/// to f32 (the start and step of a per-frequency recurrence from the m-th frequency).
pub fn phasors(
    theta: &[f64],
    amp: &[f64],
    m: f64,
    power: &mut [Complex32],
    unit: &mut [Complex32],
) {
    wide(
        #[inline(always)]
        || {
            for (((&t, &a), p), u) in theta
                .iter()
                .zip(amp)
                .zip(power.iter_mut())
                .zip(unit.iter_mut())
            {
                let (s, c) = sin_cos(t);
                *u = Complex32::new(c as f32, s as f32);
                let (s, c) = sin_cos(m * t);
                *p = Complex32::new((a * c) as f32, (a * s) as f32);
            }
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_matches_libm() {
        let mut worst: f64 = 0.0;
        // Angles over ±1e5 rad, dense near the quadrant boundaries' multiples of π/4.
        for i in -200_000..=200_000 {
            for x in [
                i as f64 * 0.5,
                i as f64 * std::f64::consts::FRAC_PI_4 + 1e-9 * i as f64,
            ] {
                let (s, c) = sin_cos(x);
                worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
            }
        }
        assert!(worst < 4e-16, "{worst}");
    }

    #[test]
    fn phasors_are_powers_of_their_unit() {
        let theta = [0.0, 0.3, -2.0, 123.456, 7e3];
        let amp = [1.0, 0.5, 2.0, 1.0, 3.0];
        let (mut p, mut u) = ([Complex32::default(); 5], [Complex32::default(); 5]);
        phasors(&theta, &amp, 37.0, &mut p, &mut u);
        for i in 0..5 {
            let want = rustfft::num_complex::Complex64::from_polar(amp[i], 37.0 * theta[i]);
            assert!((p[i].re as f64 - want.re).abs() < 1e-6 * amp[i]);
            assert!((p[i].im as f64 - want.im).abs() < 1e-6 * amp[i]);
            assert!((u[i].norm() - 1.0).abs() < 1e-6);
        }
    }
}
