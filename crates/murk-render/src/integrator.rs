//! The path tracer. A path starts at one wall point (the "origin": a laser or a SPAD point; the
//! estimator is symmetric, so either works by reciprocity) and every hidden vertex is connected
//! deterministically to each "target" wall point on the other side. In a scattering medium, medium vertices
//! also come from the targets' side (`sample_from_target`), MIS-combined with the path side.
//!
//! Radiometry: the laser spot is a point emitter on the hidden side of the relay with unit power and a
//! Lambertian lobe, I(ω) = cos θ/π; the SPAD point is a point sensor with the same importance
//! W(ω) = cos θ/π. H(x_l → x_s, t) is the response per unit laser power, binned by optical path.
//! Relay reflectance at the two endpoints is not applied (it is one constant factor per capture).
//!
//! The sampling techniques (first directions, survival past the first vertex, no roulette in a
//! medium, time-window distances, target-side draws, object draws and connections, shared tails) and the
//! measurements that chose their defaults are in `docs/renderer-sampling.md`.

use crate::geometry::{Geometry, Hit, Shape, EPS};
use crate::medium::Medium;
use crate::scene::Scene;
use murk_core::DVec3;
use rand_core::Rng;
use rand_pcg::Pcg64;
use std::f64::consts::PI;
use std::sync::Mutex;

/// A wall point with its normal (into the hidden side) and the optical path of its device leg.
#[derive(Clone, Copy, Debug)]
pub struct Endpoint {
    pub p: DVec3,
    pub n: DVec3,
    pub extra_m: f64,
}

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
    fn gauss(&mut self) -> f64 {
        let (u1, u2) = (1.0 - self.next(), self.next());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (a, b) = n.any_orthonormal_pair();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// Squared length of the shortest vector of the n-point rank-1 lattice {(j/n, j·g/n mod 1)}, by
/// Lagrange–Gauss reduction of its basis (1/n, g/n), (0, 1).
fn lattice_shortest2(n: u64, g: u64) -> f64 {
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
fn lattice_generator(n: u64) -> u64 {
    (1..n.max(2))
        .max_by(|&x, &y| lattice_shortest2(n, x).total_cmp(&lattice_shortest2(n, y)))
        .unwrap_or(1)
}

/// Area-proportional sampling of points on the hidden geometry (the relay excluded).
struct HiddenSampler {
    prims: Vec<Shape>,
    cdf: Vec<f64>,
    total: f64,
}

impl HiddenSampler {
    fn new(scene: &Scene) -> Self {
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
    fn sample(&self, u: f64, v: f64) -> DVec3 {
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
    fn pdf(&self, g: &Geometry, o: DVec3, d: DVec3) -> (f64, Option<Hit>) {
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
fn atan2_upper(y: f64, x: f64) -> f64 {
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

/// Density of a distance along a ray segment, for one target point: equiangular (Kulla & Fajardo 2012)
/// when the target is off the ray's line, inverse-square when it lies on it.
enum Equiangular {
    Angular {
        tc: f64,
        d: f64,
        /// tan θa = (a − tc)/d and the angle θb − θa subtended by the segment (one atan2, no atan pair).
        tan_a: f64,
        span: f64,
    },
    InvSquare {
        tc: f64,
        inv_a: f64,
        inv_b: f64,
        sign: f64,
    },
}

impl Equiangular {
    fn new(o: DVec3, dir: DVec3, target: DVec3, a: f64, b: f64) -> Option<Self> {
        let v = target - o;
        let tc = v.dot(dir);
        let d = (v.length_squared() - tc * tc).max(0.0).sqrt();
        if d > 1e-7 {
            let (ta, tb) = ((a - tc) / d, (b - tc) / d);
            // θb − θa from tan(θb − θa) = (tb − ta)/(1 + ta·tb); its sine is positive, so atan2 is exact.
            let span = atan2_upper(tb - ta, 1.0 + ta * tb);
            (span > 0.0).then_some(Equiangular::Angular {
                tc,
                d,
                tan_a: ta,
                span,
            })
        } else if a - tc > 1e-9 {
            Some(Equiangular::InvSquare {
                tc,
                inv_a: 1.0 / (a - tc),
                inv_b: 1.0 / (b - tc),
                sign: 1.0,
            })
        } else if tc - b > 1e-9 {
            Some(Equiangular::InvSquare {
                tc,
                inv_a: 1.0 / (tc - a),
                inv_b: 1.0 / (tc - b),
                sign: -1.0,
            })
        } else {
            None
        }
    }

    fn sample(&self, u: f64) -> (f64, f64) {
        match *self {
            Equiangular::Angular { tc, d, tan_a, span } => {
                // tan(θa + φ) by the addition formula; its denominator cos(θa + φ)/cos θa is positive.
                let (sn, cs) = (u * span).sin_cos();
                let t = tc + d * (tan_a * cs + sn) / (cs - tan_a * sn);
                (t, self.pdf(t))
            }
            Equiangular::InvSquare {
                tc,
                inv_a,
                inv_b,
                sign,
            } => {
                let x = 1.0 / (inv_a + u * (inv_b - inv_a));
                let t = tc + sign * x;
                (t, self.pdf(t))
            }
        }
    }

    fn pdf(&self, t: f64) -> f64 {
        match *self {
            Equiangular::Angular { tc, d, span, .. } => d / (span * (d * d + (t - tc).powi(2))),
            Equiangular::InvSquare {
                tc, inv_a, inv_b, ..
            } => 1.0 / ((inv_a - inv_b).abs() * (t - tc).powi(2)),
        }
    }
}

/// Time-window-aware distance sampling for one target: the connected path length through the point at
/// distance t, L(t) = t + |o + t·ω − target|, is drawn uniformly over the part of the capture window the
/// segment can reach, so late bins (the object window behind fog) get as many medium vertices as early
/// ones; n draws, one per equal stratum of L, and `pdf` is their summed density. Needs ior = 1 (L is then
/// this closed form).
struct TimeWindow {
    c: f64,
    v2: f64,
    l_lo: f64,
    l_hi: f64,
    n: u32,
}

impl TimeWindow {
    /// `window` is the range of L (path still to go) that lands in the histogram.
    fn new(
        o: DVec3,
        dir: DVec3,
        target: DVec3,
        a: f64,
        b: f64,
        window: (f64, f64),
        n: u32,
    ) -> Option<Self> {
        let v = o - target;
        let (c, v2) = (dir.dot(v), v.length_squared());
        let l = |t: f64| t + (t * t + 2.0 * t * c + v2).max(0.0).sqrt();
        let (l_lo, l_hi) = (l(a).max(window.0), l(b).min(window.1));
        (l_hi > l_lo + 1e-12).then_some(TimeWindow {
            c,
            v2,
            l_lo,
            l_hi,
            n,
        })
    }

    /// The k-th of the n stratified draws (stratum k, offset u within it).
    fn sample(&self, k: u32, u: f64) -> (f64, f64) {
        let l = self.l_lo + (k as f64 + u) / self.n as f64 * (self.l_hi - self.l_lo);
        let t = (l * l - self.v2) / (2.0 * (l + self.c));
        (t, self.pdf(t))
    }

    fn pdf(&self, t: f64) -> f64 {
        let r = (t * t + 2.0 * t * self.c + self.v2).max(0.0).sqrt();
        let l = t + r;
        if l < self.l_lo || l > self.l_hi || r <= 0.0 {
            return 0.0;
        }
        self.n as f64 * (1.0 + (t + self.c) / r) / (self.l_hi - self.l_lo)
    }
}

/// A medium segment's distance samplers toward one target.
struct Toward {
    equi: Option<Equiangular>,
    time: Option<TimeWindow>,
}

impl Toward {
    /// Sum of the connection-technique densities at distance t.
    fn pdf(&self, t: f64) -> f64 {
        self.equi.as_ref().map_or(0.0, |e| e.pdf(t)) + self.time.as_ref().map_or(0.0, |e| e.pdf(t))
    }
}

/// What a path adds past its first hidden vertex, kept to be shared by the traced points of a tile: target
/// index, optical path (jitter included) in bins from the capture's start (a replay then shifts it
/// without a division per entry), value, and the direction that left the first vertex on the way to it
/// (for the phase function's ratio there).
struct Tail {
    k: usize,
    bin: f64,
    value: f64,
    w: DVec3,
}

/// Adds `tail` to one traced point's histograms `hist`, scaled, shifted by `shift` bins, each entry times
/// `ratio` of its direction at the first vertex.
fn replay(
    bins: usize,
    hist: &mut [f64],
    tail: &[Tail],
    scale: f64,
    shift: f64,
    ratio: impl Fn(DVec3) -> f64,
) {
    for tl in tail {
        let x = tl.bin + shift;
        if x >= 0.0 && x < bins as f64 {
            hist[tl.k * bins + x as usize] += tl.value * scale * ratio(tl.w);
        }
    }
}

/// The leg from a traced point to a path's first vertex, in the measure of that vertex (volume or area):
/// its integrand `f`, the optical path `opl` to it and the direction `d`.
#[derive(Clone, Copy)]
struct Leg {
    f: f64,
    opl: f64,
    d: DVec3,
}

/// A path's first hidden vertex: a medium vertex (`normal` None) or a surface one (its normal facing the
/// arriving path).
#[derive(Clone, Copy)]
struct First {
    y: DVec3,
    normal: Option<DVec3>,
}

/// Where a path's contributions go: the traced point's histograms (`unit` values at `origin · unit`
/// in the work unit's buffer), or, while `recording`, the tail list shared with the rest of the tile.
struct Sink<'o> {
    out: &'o mut [f64],
    /// Length of one traced point's histograms, and the point now traced.
    unit: usize,
    origin: usize,
    /// Whether the unit is a tile of more than one traced point.
    share: bool,
    recording: bool,
    /// Whether the techniques now running leave from the first vertex (each sets `w`).
    at_first: bool,
    w: DVec3,
    first: Option<First>,
    tail: Vec<Tail>,
}

/// Per-scene precomputation shared by all work units.
/// A ray o + t·d (d unit).
#[derive(Clone, Copy)]
struct Ray {
    o: DVec3,
    d: DVec3,
}

/// A path's throughput and the optical path it has travelled.
#[derive(Clone, Copy)]
struct Carry {
    beta: f64,
    opl: f64,
}

/// A vertex to connect: where it is, what scatters there, and the start of the segment that reached
/// it (which sees it, so a target there needs no occlusion test).
struct At<'v> {
    y: DVec3,
    seen: DVec3,
    v: &'v Vertex,
}

pub struct Tracer<'a> {
    scene: &'a Scene,
    hidden: HiddenSampler,
    p_hidden: f64,
    /// Whether medium vertices also connect through the hidden geometry (`connect_object`).
    medium_objects: bool,
    rr_depth: u32,
    /// Survival probability past the first hidden vertex.
    q_first: f64,
    /// Direct object-return draws per path from the traced point (`draw_objects`).
    object_draws: u32,
    /// The hidden geometry's bounds, grown by a margin: a leg outside them meets nothing.
    hidden_bounds: crate::geometry::Aabb,
    /// The last (spp, lattice generator) pair `trace` used.
    lattice: Mutex<(u64, u64)>,
}

/// Where a connection starts: a surface vertex (normal facing the arriving path, albedo) or a medium vertex
/// (arriving propagation direction).
#[derive(Clone, Copy)]
enum Vertex {
    Surface { n: DVec3, albedo: f64 },
    Medium { dir: DVec3 },
}

/// The vertex a segment leaves from: its scattering function, the throughput that reached it (after
/// Russian roulette, before its scattering function) and its optical path. The origin is a `Surface` of
/// albedo 1 (its lobe cos θ/π) whose directions come from the hidden-geometry/cosine mixture.
#[derive(Clone, Copy)]
struct Start {
    x: DVec3,
    v: Vertex,
    beta: f64,
    opl: f64,
    origin: bool,
}

impl<'a> Tracer<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let hidden = HiddenSampler::new(scene);
        let set = &scene.settings;
        let scatters = scene.scatters();
        let p_hidden = if hidden.total > 0.0 {
            set.hidden_geometry_sampling
                .unwrap_or(if scatters { 0.8 } else { 1.0 })
        } else {
            0.0
        };
        let q_first = set
            .first_vertex_survival
            .unwrap_or(if scatters { 1.0 } else { 0.1 });
        let rr_depth = set.rr_depth.unwrap_or(if scatters { u32::MAX } else { 5 });
        let medium_objects = set.object_connections && scatters && hidden.total > 0.0;
        let object_draws = if hidden.total > 0.0 {
            set.object_draws
        } else {
            0
        };
        Tracer {
            scene,
            hidden,
            p_hidden,
            medium_objects,
            q_first,
            rr_depth,
            object_draws,
            hidden_bounds: {
                let b = scene.geometry.bounds();
                // Rounding of the leg's end points; none to cover when there is no geometry (empty box).
                let scale = if b.min.cmple(b.max).all() {
                    b.min.abs().max(b.max.abs()).max_element()
                } else {
                    0.0
                };
                let m = DVec3::splat(1e-6 * (1.0 + scale));
                crate::geometry::Aabb {
                    min: b.min - m,
                    max: b.max + m,
                }
            },
            lattice: Mutex::new((0, 0)),
        }
    }

    fn medium(&self) -> Option<&Medium> {
        self.scene.medium.as_ref()
    }

    /// Nearest surface along the ray: hidden geometry, or the relay seen from the hidden side.
    fn intersect(&self, o: DVec3, d: DVec3) -> Option<(Hit, bool)> {
        self.or_relay(o, d, self.scene.geometry.intersect(o, d, f64::INFINITY))
    }

    /// The relay's hit when it is nearer than `hit`, the nearest hidden-geometry hit along the ray.
    fn or_relay(&self, o: DVec3, d: DVec3, hit: Option<Hit>) -> Option<(Hit, bool)> {
        let mut best = hit.map(|h| (h, false));
        if d.z < 0.0 {
            let t = -o.z / d.z;
            let p = o + d * t;
            let r = &self.scene.relay;
            if t > EPS
                && t < best.map_or(f64::INFINITY, |b| b.0.t)
                && p.x.abs() <= r.half[0]
                && p.y.abs() <= r.half[1]
            {
                best = Some((
                    Hit {
                        t,
                        n: DVec3::Z,
                        albedo: r.albedo,
                    },
                    true,
                ));
            }
        }
        best
    }

    /// Adds `spp` paths from each of `origins` into `out` (per origin, `targets.len()` histograms of
    /// `bins`), unnormalised. With more than one origin (a tile), what each path adds past its first
    /// hidden vertex is shared by all of them (`share_tail`).
    pub fn trace(
        &self,
        origins: &[Endpoint],
        targets: &[Endpoint],
        spp: u64,
        s: &mut Sampler,
        out: &mut [f64],
    ) {
        let mut seg = Vec::new();
        let mut sink = Sink {
            out,
            unit: targets.len() * self.scene.capture.time.bins,
            origin: 0,
            share: origins.len() > 1,
            recording: false,
            at_first: false,
            w: DVec3::ZERO,
            first: None,
            tail: Vec::new(),
        };
        let mut legs = Vec::new();
        let g = {
            // Every unit of a render has the same spp: search once.
            let mut last = self.lattice.lock().unwrap_or_else(|e| e.into_inner());
            if last.0 != spp {
                *last = (spp, lattice_generator(spp));
            }
            last.1
        };
        let n = spp as f64;
        for (i, origin) in origins.iter().enumerate() {
            sink.origin = i;
            let (s1, s2) = (s.next(), s.next());
            // j·g mod spp, kept incrementally (no division per path).
            let mut jg = 0;
            for j in 0..spp {
                let u = ((s1 + j as f64 / n).fract(), (s2 + jg as f64 / n).fract());
                // A path starts at its traced point: nothing of it is shared yet.
                sink.first = None;
                sink.recording = false;
                sink.tail.clear();
                self.path(origin, targets, u, s, &mut sink, &mut seg);
                if !sink.tail.is_empty() {
                    self.share_tail(origins, i, &mut sink, &mut legs);
                }
                jg += g;
                if jg >= spp {
                    jg -= spp;
                }
            }
        }
    }

    /// The first leg from origin `o` to the first vertex `f`; None where `o` cannot reach it (behind,
    /// occluded, outside the medium along the leg).
    fn leg(&self, o: &Endpoint, f: &First) -> Option<Leg> {
        let v = f.y - o.p;
        let t = v.length();
        let w = v / t;
        let cos = o.n.dot(w);
        if cos.is_nan() || cos <= 0.0 {
            return None;
        }
        let reach = t * (1.0 + 1e-6) + 1e-6;
        // Most legs stay clear of the hidden geometry's box: no walk for them.
        let clear = !crate::geometry::Aabb::empty()
            .grow(o.p)
            .grow(o.p + w * reach)
            .overlaps(&self.hidden_bounds);
        let t_hit = if clear {
            f64::INFINITY
        } else {
            self.scene
                .geometry
                .intersect(o.p, w, reach)
                .map_or(f64::INFINITY, |h| h.t)
        };
        let g = cos / PI / (t * t);
        match f.normal {
            None => {
                let m = self.medium()?;
                if t_hit < t - EPS {
                    return None;
                }
                let (m0, m1) = m.region.clip(o.p, w, t_hit)?;
                if t < m0 || t > m1 {
                    return None;
                }
                let tr = m.transmittance(t - m0);
                let opl = o.extra_m + t + m.extra_path_m(t - m0);
                Some(Leg {
                    f: g * tr * m.sigma_s(),
                    opl,
                    d: w,
                })
            }
            Some(n) => {
                // The same surface point, seen from its front (the side the shared path left from).
                let cos_y = -n.dot(w);
                if (t_hit - t).abs() > 1e-6 * t.max(1.0) || cos_y <= 0.0 {
                    return None;
                }
                let (tr, extra) = self.transmit(o.p, w, t);
                Some(Leg {
                    f: g * tr * cos_y,
                    opl: o.extra_m + t + extra,
                    d: w,
                })
            }
        }
    }

    /// Adds the tail of a path traced from `origins[src]` to every origin of the tile: the first vertex is
    /// re-joined to each origin, and origin i takes the share f_i/Σf of the tail divided by the source's
    /// own f (every origin traces the same spp). That is the balance heuristic over the densities of the
    /// cosine part of the origins' first directions (each is its f times one constant for the whole tile),
    /// which is nonzero wherever an origin can place the vertex because every first direction has a cosine
    /// share where a medium scatters (scene validation): each origin's estimate stays unbiased and gets the
    /// tails of the whole tile. Weighting by the full mixture density instead would walk the hidden
    /// geometry along every leg's whole ray; this needs only the nearest hit up to the vertex.
    fn share_tail(
        &self,
        origins: &[Endpoint],
        src: usize,
        sink: &mut Sink,
        legs: &mut Vec<Option<Leg>>,
    ) {
        let Some(first) = sink.first else { return };
        legs.clear();
        legs.extend(origins.iter().map(|o| self.leg(o, &first)));
        let sum_f: f64 = legs.iter().flatten().map(|l| l.f).sum();
        let (t, unit) = (&self.scene.capture.time, sink.unit);
        let Some(own) = legs[src].filter(|l| l.f > 0.0) else {
            // Rounding kept the source from re-joining its own vertex (a grazing or boundary leg): the
            // tail stays the source's own, unshared.
            let hist = &mut sink.out[src * unit..(src + 1) * unit];
            return replay(t.bins, hist, &sink.tail, 1.0, 0.0, |_| 1.0);
        };
        let phase = self
            .medium()
            .map(|m| m.phase)
            .filter(|p| first.normal.is_none() && !matches!(p, crate::medium::Phase::Isotropic));
        if let Some(p) = phase {
            // The source's phase at the first vertex, divided out once; each origin multiplies its own.
            for tl in &mut sink.tail {
                tl.value /= p.eval(own.d.dot(tl.w));
            }
        }
        for (i, leg) in legs.iter().enumerate() {
            let Some(leg) = leg else { continue };
            let scale = leg.f / sum_f;
            let shift = (leg.opl - own.opl) / t.bin_width_m;
            let hist = &mut sink.out[i * unit..(i + 1) * unit];
            replay(t.bins, hist, &sink.tail, scale, shift, |w| {
                phase.map_or(1.0, |p| p.eval(leg.d.dot(w)))
            });
        }
    }

    fn splat(&self, out: &mut Sink, k: usize, opl: f64, value: f64, s: &mut Sampler) {
        let t = &self.scene.capture.time;
        let jitter = self.scene.settings.time_jitter;
        let opl = if jitter > 0.0 {
            opl + jitter * s.gauss()
        } else {
            opl
        };
        if out.recording {
            out.tail.push(Tail {
                k,
                bin: (opl - t.start_m) / t.bin_width_m,
                value,
                w: out.w,
            });
            return;
        }
        let x = (opl - t.start_m) / t.bin_width_m;
        if x >= 0.0 && x < t.bins as f64 {
            out.out[out.origin * out.unit + k * t.bins + x as usize] += value;
        }
    }

    /// The scattering function of `v` toward the propagation direction `w`.
    fn eval(&self, v: &Vertex, w: DVec3) -> f64 {
        match *v {
            Vertex::Surface { n, albedo } => albedo / PI * n.dot(w).max(0.0),
            Vertex::Medium { dir } => self.medium().map_or(0.0, |m| m.phase.eval(dir.dot(w))),
        }
    }

    /// Solid-angle density with which the path leaves `from` in direction `w`.
    fn dir_pdf(&self, from: &Start, w: DVec3) -> f64 {
        match from.v {
            Vertex::Medium { dir } => self.medium().map_or(0.0, |m| m.phase.eval(dir.dot(w))),
            Vertex::Surface { n, .. } => {
                let c = n.dot(w);
                if c <= 0.0 {
                    0.0
                } else if from.origin {
                    self.origin_pdf(from.x, n, w).0
                } else {
                    c / PI
                }
            }
        }
    }

    /// The density of the origin's first direction `w` (the hidden-geometry/cosine mixture), with the
    /// nearest hidden-geometry hit along it.
    fn origin_pdf(&self, o: DVec3, n: DVec3, w: DVec3) -> (f64, Option<Hit>) {
        let (p, _, hit) = self.origin_pdfs(o, n, w);
        (p, hit)
    }

    /// `origin_pdf`, with the hidden-geometry density of `w` on its own.
    fn origin_pdfs(&self, o: DVec3, n: DVec3, w: DVec3) -> (f64, f64, Option<Hit>) {
        let (p, hit) = self.hidden.pdf(&self.scene.geometry, o, w);
        let c = n.dot(w).max(0.0);
        (self.p_hidden * p + (1.0 - self.p_hidden) * c / PI, p, hit)
    }

    /// The direct object return from the traced point `origin` by `object_draws` directions toward
    /// stratified uniform points of the hidden geometry: each connects the surface it first meets to the
    /// targets, through the segment's transmittance. Balance heuristic with the path's own first direction
    /// (`first_object_weight`).
    fn draw_objects(
        &self,
        origin: &Endpoint,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let n = self.object_draws;
        for j in 0..n {
            let u = (j as f64 + s.next()) / n as f64;
            let y = self.hidden.sample(u, s.next());
            let w = (y - origin.p).normalize();
            let cos = origin.n.dot(w);
            if cos.is_nan() || cos <= 0.0 {
                continue;
            }
            let (p_mix, p_h, hit) = self.origin_pdfs(origin.p, origin.n, w);
            let Some(h) = hit else { continue };
            let b = cos / PI / (p_mix + n as f64 * p_h);
            let carry = Carry {
                beta: b,
                opl: origin.extra_m,
            };
            self.connect_hit(Ray { o: origin.p, d: w }, &h, carry, targets, s, out);
        }
    }

    /// The path side's distance samplers toward `tgt` on the medium part `[m0, m1]` of the segment
    /// `x + t·d` that starts at optical path `opl`; `first`: the segment leaves the traced point.
    fn toward(
        &self,
        m: &Medium,
        (x, d): (DVec3, DVec3),
        opl: f64,
        m01: (f64, f64),
        tgt: &Endpoint,
        first: bool,
    ) -> Toward {
        let set = &self.scene.settings;
        let n_time = match set.first_time_samples {
            Some(n) if first => n,
            _ => set.time_samples,
        };
        let tw = &self.scene.capture.time;
        let base = opl + tgt.extra_m;
        Toward {
            equi: set
                .equiangular
                .then(|| Equiangular::new(x, d, tgt.p, m01.0, m01.1))
                .flatten(),
            time: (n_time > 0 && m.ior == 1.0)
                .then(|| {
                    TimeWindow::new(
                        x,
                        d,
                        tgt.p,
                        m01.0,
                        m01.1,
                        (tw.start_m - base, tw.end_m() - base),
                        n_time,
                    )
                })
                .flatten(),
        }
    }

    /// Volume density with which target-side sampling from `tgt` aiming at `x` places a vertex at `y`:
    /// a cosine-lobe direction from the target, then an equiangular distance toward `x`.
    fn target_pdf(&self, m: &Medium, tgt: &Endpoint, x: DVec3, y: DVec3) -> f64 {
        let v = y - tgt.p;
        let tl2 = v.length_squared();
        let tl = tl2.sqrt();
        let wl = v / tl;
        let cos = tgt.n.dot(wl);
        if cos <= 0.0 {
            return 0.0;
        }
        let hit = self.intersect(tgt.p, wl).map_or(f64::INFINITY, |h| h.0.t);
        match m.region.clip(tgt.p, wl, hit) {
            Some((a, b)) if tl >= a && tl <= b => {
                Equiangular::new(tgt.p, wl, x, a, b).map_or(0.0, |e| cos / PI * e.pdf(tl) / tl2)
            }
            _ => 0.0,
        }
    }

    /// Target-side sampling: for each target, a medium vertex y drawn from the target's side (direction in
    /// its cosine lobe, distance equiangular toward the segment start `from.x`) and joined to `from.x`. Its
    /// volume density ∝ cos/|y − target|² cancels the 1/r² of the connection to the target, which the
    /// path side can only cancel along its own segment: there, the equiangular weight still grows as 1/d
    /// for segments passing at distance d from the target, the fireflies of multiply scattered fog near the
    /// laser spot (measured: the largest object-window samples had d = 1–15 cm). Balance heuristic against
    /// the path side's densities (free flight, equiangular, time window) for the same vertex. Measured on
    /// t-wall-medium (64 spp, variance over 16 seeds): object-window relL2 9.7 → 4.6 at 2.3× the CPU time
    /// (1.9× the efficiency); the largest in-window samples drop from ~700× to ~200× the mean one. What
    /// was left is segment starts (mostly relay vertices) a few cm from the target, whose one draw has a
    /// spread growing as 1/distance: those get `target_draws` draws.
    fn sample_from_target(
        &self,
        m: &Medium,
        from: &Start,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        for (k, tgt) in targets.iter().enumerate() {
            let n = self.target_draws(from, tgt);
            for _ in 0..n {
                self.draw_from_target(m, from, (k, tgt), n, s, out);
            }
        }
    }

    /// How many target-side draws a segment starting at `from` gets toward `tgt`: 1, or up to
    /// `target_split` when `from` lies within `target_split_radius` of the target (∝ radius/distance).
    fn target_draws(&self, from: &Start, tgt: &Endpoint) -> u32 {
        let set = &self.scene.settings;
        let r = set.target_split_radius;
        if from.origin || r <= 0.0 {
            return 1;
        }
        let d = (from.x - tgt.p).length();
        if d >= r {
            1
        } else {
            (r / d).ceil().min(set.target_split.max(1) as f64) as u32
        }
    }

    /// One of `n` target-side draws toward target `k`, `tgt`.
    fn draw_from_target(
        &self,
        m: &Medium,
        from: &Start,
        (k, tgt): (usize, &Endpoint),
        n: u32,
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let wl = cosine_hemisphere(tgt.n, s.next(), s.next());
        let u = s.next();
        let hit_l = self.intersect(tgt.p, wl).map_or(f64::INFINITY, |h| h.0.t);
        let Some((a, b)) = m.region.clip(tgt.p, wl, hit_l) else {
            return;
        };
        let Some(eq) = Equiangular::new(tgt.p, wl, from.x, a, b) else {
            return;
        };
        let (tl, peq) = eq.sample(u);
        if !(tl >= a && tl <= b && peq > 0.0) {
            return;
        }
        let y = tgt.p + wl * tl;
        let v = y - from.x;
        let t2 = v.length_squared();
        let t = t2.sqrt();
        let w = v / t;
        let f = self.eval(&from.v, w);
        if f <= 0.0 {
            return;
        }
        if out.at_first {
            out.w = w;
        }
        let hit = self.intersect(from.x, w).map_or(f64::INFINITY, |h| h.0.t);
        if hit < t - EPS {
            return;
        }
        let Some((m0, m1)) = m.region.clip(from.x, w, hit) else {
            return;
        };
        let pff = m.free_flight_pdf(t - m0);
        let p_path = self.dir_pdf(from, w)
            * (pff
                + self
                    .toward(m, (from.x, w), from.opl, (m0, m1), tgt, from.origin)
                    .pdf(t))
            / t2;
        let cos_l = tgt.n.dot(wl);
        let p_l = cos_l / PI * peq / (tl * tl);
        // Integrand (volume measure) over the sum of densities: the balance-weighted estimate.
        let value = from.beta * f * m.transmittance((t - m0) + (tl - a)) / t2
            * m.sigma_s()
            * m.phase.eval(-w.dot(wl))
            * cos_l
            / (PI * tl * tl)
            / (n as f64 * p_l + p_path);
        let opl = from.opl + t + tl + m.extra_path_m((t - m0) + (tl - a)) + tgt.extra_m;
        self.splat(out, k, opl, value, s);
    }

    /// The balance weight of a path's own surface connection along direction `d` from `from` against
    /// `connect_object` (only from medium vertices), or `first` from the traced point (against
    /// `draw_objects`).
    fn object_weight(&self, from: &Start, d: DVec3, first: f64) -> f64 {
        match (from.v, self.medium()) {
            _ if from.origin => first,
            (Vertex::Medium { dir }, Some(m)) if self.medium_objects => {
                let ph = m.phase.eval(dir.dot(d));
                let (p_h, _) = self.hidden.pdf(&self.scene.geometry, from.x, d);
                ph / (ph + p_h)
            }
            _ => 1.0,
        }
    }

    /// Next-event estimation through the hidden geometry from the medium vertex `x` (arrived along
    /// `dir` with throughput `beta`): a direction toward a uniform point of the hidden geometry, its first
    /// hit connected to the targets. The object return after a scattering event otherwise needs the phase
    /// function's direction to meet the object: on z-letter those rare hits carried 18 % of the object
    /// window's second moment from 0.1 % of its samples. Balance heuristic against the phase direction
    /// (`object_weight`).
    fn connect_object(
        &self,
        m: &Medium,
        ray: Ray,
        carry: Carry,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let (x, dir) = (ray.o, ray.d);
        if !self.medium_objects {
            return;
        }
        let (u, v) = (s.next(), s.next());
        let to = self.hidden.sample(u, v) - x;
        let len = to.length();
        if len <= 0.0 {
            return;
        }
        let w = to / len;
        let (p_h, hit) = self.hidden.pdf(&self.scene.geometry, x, w);
        let ph = m.phase.eval(dir.dot(w));
        let Some((h, false)) = self.or_relay(x, w, hit) else {
            return;
        };
        if p_h <= 0.0 || ph <= 0.0 {
            return;
        }
        let beta = carry.beta * ph / (ph + p_h);
        if out.at_first {
            out.w = w;
        }
        let carry = Carry { beta, ..carry };
        self.connect_hit(Ray { o: x, d: w }, &h, carry, targets, s, out);
    }

    /// Transmittance along `o + t·d`, t ∈ [0, t_max], and the optical path the medium adds to it.
    fn transmit(&self, o: DVec3, d: DVec3, t_max: f64) -> (f64, f64) {
        self.medium().map_or((1.0, 0.0), |m| {
            let l = m.overlap(o, d, t_max);
            (m.transmittance(l), m.extra_path_m(l))
        })
    }

    /// Connects the surface hit `h` of the ray `x + t·w` to every target, through the transmittance of
    /// the segment from `x` (reached with throughput `beta` at optical path `opl`).
    fn connect_hit(
        &self,
        ray: Ray,
        h: &Hit,
        carry: Carry,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let (x, w) = (ray.o, ray.d);
        let (tr, extra) = self.transmit(x, w, h.t);
        let v = Vertex::Surface {
            n: h.n,
            albedo: h.albedo,
        };
        let at = At {
            y: x + w * h.t,
            seen: x,
            v: &v,
        };
        let carry = Carry {
            beta: carry.beta * tr,
            opl: carry.opl + h.t + extra,
        };
        self.connect(at, carry, (0, targets), |_| 1.0, s, out);
    }

    /// Connects vertex `y` (reached with throughput `beta` at optical path `opl`) to every target of
    /// `(k0, targets)` (the first one is target k0). `mis(k)` weights the connection to `targets[k]`.
    /// `seen` is the start of the segment that reached y, which sees y: a target there (confocal: the
    /// origin at the first vertex) needs no occlusion test.
    fn connect(
        &self,
        at: At,
        carry: Carry,
        (k0, targets): (usize, &[Endpoint]),
        mis: impl Fn(usize) -> f64,
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let (y, seen, v) = (at.y, at.seen, at.v);
        let (beta, opl) = (carry.beta, carry.opl);
        for (k, tgt) in targets.iter().enumerate() {
            let v_y = tgt.p - y;
            let r2 = v_y.length_squared();
            let r = r2.sqrt();
            let w = v_y / r;
            let cos_t = -tgt.n.dot(w);
            if cos_t <= 0.0 {
                continue;
            }
            let f = self.eval(v, w);
            if f <= 0.0 || (tgt.p != seen && self.scene.geometry.occluded(y, w, r)) {
                continue;
            }
            let (tr, extra) = self.transmit(y, w, r);
            let value = beta * f * tr * cos_t / (PI * r2) * mis(k);
            self.splat(out, k0 + k, opl + r + extra + tgt.extra_m, value, s);
        }
    }

    fn path(
        &self,
        origin: &Endpoint,
        targets: &[Endpoint],
        (u, v): (f64, f64),
        s: &mut Sampler,
        out: &mut Sink,
        seg: &mut Vec<Toward>,
    ) {
        let set = &self.scene.settings;
        // (u, v) picks the technique (hidden geometry with probability p_hidden) and, rescaled, its sample.
        let mut d = if u < self.p_hidden {
            (self.hidden.sample(u / self.p_hidden, v) - origin.p).normalize()
        } else {
            cosine_hemisphere(origin.n, (u - self.p_hidden) / (1.0 - self.p_hidden), v)
        };
        let mut from = Start {
            x: origin.p,
            v: Vertex::Surface {
                n: origin.n,
                albedo: 1.0,
            },
            beta: 1.0,
            opl: origin.extra_m,
            origin: true,
        };
        if d.dot(origin.n) <= 0.0 {
            return;
        }
        // The density's walk also finds the first segment's hit.
        let (pdf0, p_h0, hit0) = self.origin_pdfs(origin.p, origin.n, d);
        let mut first_hit = Some(hit0);
        if pdf0 <= 0.0 {
            return;
        }
        let mut beta = d.dot(origin.n) / PI / pdf0;
        if self.object_draws > 0 {
            self.draw_objects(origin, targets, s, out);
        }
        // The balance weight of the first segment's own object return against `draw_objects`.
        let first_object_weight = pdf0 / (pdf0 + self.object_draws as f64 * p_h0);
        let mut pos = origin.p;
        let mut opl = origin.extra_m;
        let mut depth = 0u32;
        loop {
            // Past the first vertex, everything goes to the tail the tile shares.
            out.recording = out.share && !from.origin;
            out.at_first = out.recording && depth == 1;
            // The medium that scatters, when target-side sampling runs in it.
            let scattering = self
                .medium()
                .filter(|m| m.scatters() && set.target_sampling);
            if let Some(m) = scattering {
                self.sample_from_target(m, &from, targets, s, out);
            }
            if out.at_first {
                out.w = d;
            }
            // Target-side density of a path-side vertex y at distance t, per unit length along d.
            let pd = if scattering.is_some() {
                self.dir_pdf(&from, d)
            } else {
                0.0
            };
            let target_pdf = |m: &Medium, k: usize, y: DVec3, t: f64| {
                if scattering.is_some() && pd > 0.0 {
                    let tgt = &targets[k];
                    self.target_draws(&from, tgt) as f64
                        * self.target_pdf(m, tgt, from.x, y)
                        * t
                        * t
                        / pd
                } else {
                    0.0
                }
            };
            let hit = match first_hit.take() {
                Some(h) => self.or_relay(pos, d, h),
                None => self.intersect(pos, d),
            };
            let t_hit = hit.map_or(f64::INFINITY, |h| h.0.t);
            let mut medium_len = 0.0;
            let mut connected = false;
            if let Some(m) = self.medium() {
                if let Some((m0, m1)) = m.region.clip(pos, d, t_hit) {
                    medium_len = m1 - m0;
                    let sigma_s = m.sigma_s();
                    if sigma_s > 0.0 {
                        let pdf_ff = |t: f64| m.free_flight_pdf(t - m0);
                        // Connections from distances drawn toward each target (equiangular, and uniform in the
                        // capture's time window), MIS-combined (balance heuristic) with each other, with the
                        // free-flight vertex's connection below and with target-side sampling.
                        seg.clear();
                        seg.extend(
                            targets
                                .iter()
                                .map(|t| self.toward(m, (pos, d), opl, (m0, m1), t, from.origin)),
                        );
                        for k in 0..targets.len() {
                            let n_time = seg[k].time.as_ref().map_or(0, |e| e.n);
                            // Draw 0 is equiangular, draws 1..=n_time the time window's strata.
                            for j in 0..=n_time {
                                let draw = if j == 0 {
                                    seg[k].equi.as_ref().map(|e| e.sample(s.next()))
                                } else {
                                    seg[k].time.as_ref().map(|e| e.sample(j - 1, s.next()))
                                };
                                let Some((t, pdf)) = draw else { continue };
                                if !(t >= m0 && t <= m1 && pdf > 0.0) {
                                    continue;
                                }
                                let y = pos + d * t;
                                let b = beta * sigma_s * m.transmittance(t - m0) / pdf;
                                let w = pdf / (seg[k].pdf(t) + pdf_ff(t) + target_pdf(m, k, y, t));
                                let o = opl + t + m.extra_path_m(t - m0);
                                let v = Vertex::Medium { dir: d };
                                let at = At {
                                    y,
                                    seen: from.x,
                                    v: &v,
                                };
                                let carry = Carry { beta: b, opl: o };
                                self.connect(at, carry, (k, &targets[k..=k]), |_| w, s, out);
                            }
                        }
                        // The surface the segment reaches is connected now, weighted by the segment's
                        // transmittance (the expected value of free flight's pass/scatter choice), so every
                        // path toward the hidden object contributes its return; a pass below does not connect
                        // again.
                        if let Some((h, false)) = hit {
                            let b = beta * self.object_weight(&from, d, first_object_weight);
                            let carry = Carry { beta: b, opl };
                            self.connect_hit(Ray { o: pos, d }, &h, carry, targets, s, out);
                            connected = true;
                        }
                        // Free flight: scatter with density σt·exp(−σt·(t − m0)), else cross (weight T/P = 1).
                        let t = m0 + m.sample_distance(s.next());
                        if t < m1 {
                            depth += 1;
                            // What leaves this vertex keeps the first vertex's outgoing direction.
                            out.at_first = false;
                            let y = pos + d * t;
                            let pff = pdf_ff(t);
                            let mis =
                                |k: usize| pff / (pff + seg[k].pdf(t) + target_pdf(m, k, y, t));
                            pos = y;
                            opl += t + m.extra_path_m(t - m0);
                            beta *= m.albedo;
                            let at = At {
                                y: pos,
                                seen: from.x,
                                v: &Vertex::Medium { dir: d },
                            };
                            self.connect(at, Carry { beta, opl }, (0, targets), mis, s, out);
                            if depth >= set.max_depth {
                                return;
                            }
                            if depth == 1 {
                                // The first vertex: what leaves it is shared.
                                out.first = Some(First {
                                    y: pos,
                                    normal: None,
                                });
                                out.recording = out.share;
                                out.at_first = out.share;
                            }
                            let ray = Ray { o: pos, d };
                            self.connect_object(m, ray, Carry { beta, opl }, targets, s, out);
                            if !self.roulette(&mut beta, depth, s) {
                                return;
                            }
                            from = Start {
                                x: pos,
                                v: Vertex::Medium { dir: d },
                                beta,
                                opl,
                                origin: false,
                            };
                            d = m.phase.sample(d, s.next(), s.next());
                            continue;
                        }
                    } else {
                        // Pure absorber: weight by the transmittance instead of sampling.
                        beta *= m.transmittance(medium_len);
                    }
                }
            }
            let Some((h, on_relay)) = hit else { return };
            depth += 1;
            pos += d * h.t;
            opl += h.t + self.medium().map_or(0.0, |m| m.extra_path_m(medium_len));
            // A vertex on the relay is coplanar with every target: its connections vanish.
            let v = Vertex::Surface {
                n: h.n,
                albedo: h.albedo,
            };
            if !on_relay && !connected {
                let b = beta * self.object_weight(&from, d, first_object_weight);
                let at = At {
                    y: pos,
                    seen: from.x,
                    v: &v,
                };
                self.connect(at, Carry { beta: b, opl }, (0, targets), |_| 1.0, s, out);
            }
            beta *= h.albedo;
            if beta <= 0.0 || depth >= set.max_depth || !self.roulette(&mut beta, depth, s) {
                return;
            }
            if depth == 1 {
                out.first = Some(First {
                    y: pos,
                    normal: Some(h.n),
                });
            }
            from = Start {
                x: pos,
                v,
                beta: beta / h.albedo,
                opl,
                origin: false,
            };
            d = cosine_hemisphere(h.n, s.next(), s.next());
        }
    }

    fn roulette(&self, beta: &mut f64, depth: u32, s: &mut Sampler) -> bool {
        let mut q = if depth < self.rr_depth {
            1.0
        } else {
            beta.min(0.95)
        };
        if depth == 1 {
            q *= self.q_first;
        }
        if q >= 1.0 {
            return true;
        }
        if s.next() >= q {
            return false;
        }
        *beta /= q;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::{atan2_upper, lattice_generator, lattice_shortest2};

    /// The polynomial atan2 agrees with libm over the upper half-plane, axes and extreme ratios
    /// included.
    #[test]
    fn atan2_upper_matches_libm() {
        let mut worst = 0.0f64;
        for i in 0..=2000 {
            let phi = std::f64::consts::PI * i as f64 / 2000.0;
            for r in [1e-9, 1e-3, 1.0, 7.0, 1e6] {
                let (y, x) = (r * phi.sin().max(0.0), r * phi.cos());
                worst = worst.max((atan2_upper(y, x) - y.atan2(x)).abs());
            }
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (1e-300, 1.0),
            (1.0, 1e-300),
        ] {
            worst = worst.max((atan2_upper(y, x) - f64::atan2(y, x)).abs());
        }
        assert!(worst < 3e-11, "{worst}");
    }

    /// The chosen lattice spreads its points at least as well as the Fibonacci lattice and close to the
    /// densest packing (hexagonal: shortest vector² = 2/(√3·n)).
    #[test]
    fn lattice_generator_spreads_points() {
        let n = 987;
        let d2 = lattice_shortest2(n, lattice_generator(n));
        assert!(d2 >= lattice_shortest2(n, 610));
        assert!(d2 > 0.9 * 2.0 / (3f64.sqrt() * n as f64), "{d2}");
        assert_eq!(lattice_generator(1), 1);
    }
}
