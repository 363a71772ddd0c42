//! Random numbers and first-direction sampling: the per-unit stream, the rank-1 lattice, cosine
//! and hidden-geometry directions.

use super::*;

/// Uniform numbers in [0, 1) from one PCG stream.
pub struct Sampler(Pcg64);

impl Sampler {
    /// The stream for work unit `unit` of a render seeded with `seed`: independent of thread count.
    pub fn new(seed: u64, unit: u64) -> Self {
        // Spread the seed over the 128-bit state; the unit index selects the PCG stream.
        let state = (seed as u128).wrapping_mul(0x2360_ED05_1FC6_5DA4_4385_DF64_9FCC_F645)
            ^ 0x5851_F42D_4C95_7F2D;
        Sampler(Pcg64::new(state, unit as u128))
    }
    /// The next uniform number (not an iterator: the stream never ends).
    #[inline]
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    pub(super) fn gauss(&mut self) -> f64 {
        let (u1, u2) = (1.0 - self.next(), self.next());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

pub(super) fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (a, b) = n.any_orthonormal_pair();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// Squared length of the shortest vector of the n-point rank-1 lattice {(j/n, j·g/n mod 1)}, by
/// Lagrange–Gauss reduction of its basis (1/n, g/n), (0, 1).
pub(super) fn lattice_shortest2(n: u64, g: u64) -> f64 {
    let len = |v: (f64, f64)| v.0 * v.0 + v.1 * v.1;
    let (mut a, mut b) = ((1.0 / n as f64, g as f64 / n as f64), (0.0, 1.0));
    if len(a) > len(b) {
        std::mem::swap(&mut a, &mut b);
    }
    loop {
        let m = ((a.0 * b.0 + a.1 * b.1) / len(a)).round();
        let c = (b.0 - m * a.0, b.1 - m * a.1);
        if len(c) >= len(a) {
            return len(a);
        }
        b = a;
        a = c;
    }
}

/// The generator of the n-point rank-1 lattice whose shortest vector is longest.
pub(super) fn lattice_generator(n: u64) -> u64 {
    (1..n.max(2))
        .max_by(|&x, &y| lattice_shortest2(n, x).total_cmp(&lattice_shortest2(n, y)))
        .unwrap_or(1)
}

/// Area-proportional sampling of points on the hidden geometry (the relay excluded).
pub(super) struct HiddenSampler {
    pub(super) prims: Vec<Shape>,
    pub(super) cdf: Vec<f64>,
    pub(super) total: f64,
}

impl HiddenSampler {
    pub(super) fn new(scene: &Scene) -> Self {
        let prims: Vec<Shape> = scene
            .geometry
            .objects
            .iter()
            .filter(|o| o.albedo > 0.0)
            .flat_map(|o| o.prims.iter().cloned())
            .collect();
        let mut acc = 0.0;
        let cdf = prims
            .iter()
            .map(|p| {
                acc += p.area();
                acc
            })
            .collect();
        HiddenSampler {
            prims,
            cdf,
            total: acc,
        }
    }

    /// The point for `(u, v)` uniform in [0, 1)²: u picks the primitive by area and, rescaled, its first
    /// coordinate, so stratified (u, v) stay stratified on the geometry.
    pub(super) fn sample(&self, u: f64, v: f64) -> DVec3 {
        let x = u * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.prims.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let u1 = ((x - lo) / (self.cdf[i] - lo)).clamp(0.0, 1.0);
        self.prims[i].sample(u1, v)
    }

    /// Solid-angle density of directions from `o` produced by `sample`, and the nearest hit along them,
    /// from one walk: every point along the ray counts, occluded or not, because sampling ignores
    /// visibility.
    pub(super) fn pdf(&self, g: &Geometry, o: DVec3, d: DVec3) -> (f64, Option<Hit>) {
        let mut sum = 0.0;
        let hit = g.all_hits(o, d, |p, obj, t| {
            if obj.albedo > 0.0 {
                sum += t * t / (self.total * p.normal().dot(d).abs().max(1e-12));
            }
        });
        (sum, hit)
    }
}

/// atan2(y, x) for y ≥ 0 (not both zero) within 3e-11: libm's atan2 was a sixth of the CPU time in fog,
/// where every segment builds an equiangular sampler per target and every MIS weight another. The
/// sampler and its density share this angle, so the estimate stays consistent.
#[inline]
pub(super) fn atan2_upper(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
    let ax = x.abs();
    let swap = y > ax;
    let z = if swap { ax / y } else { y / ax };
    // atan z = π/4 + atan((z − 1)/(z + 1)) brings z ∈ [0, 1] to |u| ≤ tan(π/8).
    let (u, base) = if z > 0.414_213_562_373_095_1 {
        ((z - 1.0) / (z + 1.0), FRAC_PI_4)
    } else {
        (z, 0.0)
    };
    // Chebyshev fit of atan(u)/u in u² on [0, tan²(π/8)].
    const C: [f64; 7] = [
        9.999_999_999_851_087e-1,
        -3.333_333_241_211_982e-1,
        1.999_990_740_220_291_5e-1,
        -1.428_222_617_091_132_5e-1,
        1.104_821_831_404_844_8e-1,
        -8.499_072_690_991_342e-2,
        4.796_012_611_713_859_6e-2,
    ];
    let w = u * u;
    let poly = C.iter().rev().fold(0.0, |acc, c| acc * w + c);
    let mut a = base + u * poly;
    if swap {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    a
}
