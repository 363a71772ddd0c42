//! The path tracer. A path starts at one wall point (the "origin": a laser or a SPAD point; the
//! estimator is symmetric, so either works by reciprocity) and every hidden vertex is connected
//! deterministically to each "target" wall point on the other side.
//!
//! Radiometry: the laser spot is a point emitter on the hidden side of the relay with unit power and a
//! Lambertian lobe, I(ω) = cos θ/π; the SPAD point is a point sensor with the same importance
//! W(ω) = cos θ/π. H(x_l → x_s, t) is the response per unit laser power, binned by optical path.
//! Relay reflectance at the two endpoints is not applied (it is one constant factor per capture).

use crate::geometry::{Hit, Shape, EPS};
use crate::medium::Medium;
use crate::scene::Scene;
use murk_core::DVec3;
use rand_core::Rng;
use rand_pcg::Pcg64;
use std::f64::consts::PI;

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
    #[inline]
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

    fn sample(&self, s: &mut Sampler) -> DVec3 {
        let x = s.next() * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.prims.len() - 1);
        self.prims[i].sample(s.next(), s.next())
    }

    /// Solid-angle density of directions from `o` produced by `sample`: every point along the ray counts,
    /// occluded or not, because sampling ignores visibility.
    fn pdf(&self, o: DVec3, d: DVec3) -> f64 {
        self.prims
            .iter()
            .filter_map(|p| {
                p.intersect(o, d, f64::INFINITY)
                    .map(|t| t * t / (self.total * p.normal().dot(d).abs().max(1e-12)))
            })
            .sum()
    }
}

/// Density of a distance along a ray segment, for one target point: equiangular (Kulla & Fajardo 2012)
/// when the target is off the ray's line, inverse-square when it lies on it.
enum Equiangular {
    Angular {
        tc: f64,
        d: f64,
        th_a: f64,
        th_b: f64,
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
            let (th_a, th_b) = (((a - tc) / d).atan(), ((b - tc) / d).atan());
            (th_b > th_a).then_some(Equiangular::Angular { tc, d, th_a, th_b })
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
            Equiangular::Angular { tc, d, th_a, th_b } => {
                let t = tc + d * (th_a + u * (th_b - th_a)).tan();
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
            Equiangular::Angular { tc, d, th_a, th_b } => {
                d / ((th_b - th_a) * (d * d + (t - tc).powi(2)))
            }
            Equiangular::InvSquare {
                tc, inv_a, inv_b, ..
            } => 1.0 / ((inv_a - inv_b).abs() * (t - tc).powi(2)),
        }
    }
}

/// Time-window-aware distance sampling for one target: the connected path length through the point at
/// distance t, L(t) = t + |o + t·ω − target|, is drawn uniformly over the part of the capture window the
/// segment can reach, so late bins (the object window behind fog) get as many medium vertices as early
/// ones. Needs ior = 1 (L is then this closed form).
struct TimeWindow {
    c: f64,
    v2: f64,
    l_lo: f64,
    l_hi: f64,
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
    ) -> Option<Self> {
        let v = o - target;
        let (c, v2) = (dir.dot(v), v.length_squared());
        let l = |t: f64| t + (t * t + 2.0 * t * c + v2).max(0.0).sqrt();
        let (l_lo, l_hi) = (l(a).max(window.0), l(b).min(window.1));
        (l_hi > l_lo + 1e-12).then_some(TimeWindow { c, v2, l_lo, l_hi })
    }

    fn sample(&self, u: f64) -> (f64, f64) {
        let l = self.l_lo + u * (self.l_hi - self.l_lo);
        let t = (l * l - self.v2) / (2.0 * (l + self.c));
        (t, self.pdf(t))
    }

    fn pdf(&self, t: f64) -> f64 {
        let r = (t * t + 2.0 * t * self.c + self.v2).max(0.0).sqrt();
        let l = t + r;
        if l < self.l_lo || l > self.l_hi || r <= 0.0 {
            return 0.0;
        }
        (1.0 + (t + self.c) / r) / (self.l_hi - self.l_lo)
    }
}

/// Per-segment distance samplers toward each target (reused buffers).
#[derive(Default)]
struct SegmentSamplers {
    equi: Vec<Option<Equiangular>>,
    time: Vec<Option<TimeWindow>>,
}

impl SegmentSamplers {
    /// Sum of the connection-technique densities for target k at distance t.
    fn pdf(&self, k: usize, t: f64) -> f64 {
        self.equi
            .get(k)
            .and_then(|e| e.as_ref())
            .map_or(0.0, |e| e.pdf(t))
            + self
                .time
                .get(k)
                .and_then(|e| e.as_ref())
                .map_or(0.0, |e| e.pdf(t))
    }
}

/// Per-scene precomputation shared by all work units.
pub struct Tracer<'a> {
    scene: &'a Scene,
    hidden: HiddenSampler,
    p_hidden: f64,
}

/// Where a connection starts: a surface vertex (normal facing the arriving path, albedo) or a medium vertex
/// (arriving propagation direction).
enum Vertex {
    Surface { n: DVec3, albedo: f64 },
    Medium { dir: DVec3 },
}

impl<'a> Tracer<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let hidden = HiddenSampler::new(scene);
        let p_hidden = if hidden.total > 0.0 {
            scene.settings.hidden_geometry_sampling
        } else {
            0.0
        };
        Tracer {
            scene,
            hidden,
            p_hidden,
        }
    }

    fn medium(&self) -> Option<&Medium> {
        self.scene.medium.as_ref()
    }

    /// Nearest surface along the ray: hidden geometry, or the relay seen from the hidden side.
    fn intersect(&self, o: DVec3, d: DVec3) -> Option<(Hit, bool)> {
        let mut best = self
            .scene
            .geometry
            .intersect(o, d, f64::INFINITY)
            .map(|h| (h, false));
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

    /// Adds `spp` paths from `origin` into `out` (`targets.len()` histograms of `bins`), unnormalised.
    pub fn trace(
        &self,
        origin: &Endpoint,
        targets: &[Endpoint],
        spp: u64,
        s: &mut Sampler,
        out: &mut [f64],
    ) {
        let mut seg = SegmentSamplers::default();
        for _ in 0..spp {
            self.path(origin, targets, s, out, &mut seg);
        }
    }

    fn splat(&self, out: &mut [f64], k: usize, opl: f64, value: f64, s: &mut Sampler) {
        let t = &self.scene.capture.time;
        let jitter = self.scene.settings.time_jitter;
        let opl = if jitter > 0.0 {
            opl + jitter * s.gauss()
        } else {
            opl
        };
        let x = (opl - t.start_m) / t.bin_width_m;
        if x >= 0.0 && x < t.bins as f64 {
            out[k * t.bins + x as usize] += value;
        }
    }

    /// Connects vertex `y` (reached with throughput `beta` at optical path `opl`) to every target.
    /// `mis(k)` weights the connection to target k.
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        y: DVec3,
        v: &Vertex,
        beta: f64,
        opl: f64,
        targets: &[Endpoint],
        mis: impl Fn(usize) -> f64,
        s: &mut Sampler,
        out: &mut [f64],
    ) {
        for (k, tgt) in targets.iter().enumerate() {
            let v_y = tgt.p - y;
            let r2 = v_y.length_squared();
            let r = r2.sqrt();
            let w = v_y / r;
            let cos_t = -tgt.n.dot(w);
            if cos_t <= 0.0 {
                continue;
            }
            let f = match *v {
                Vertex::Surface { n, albedo } => albedo / PI * n.dot(w).max(0.0),
                Vertex::Medium { dir } => self.medium().map_or(0.0, |m| m.phase.eval(dir.dot(w))),
            };
            if f <= 0.0 || self.scene.geometry.occluded(y, w, r) {
                continue;
            }
            let (tr, extra) = match self.medium() {
                Some(m) => {
                    let l = m.overlap(y, w, r);
                    ((-m.sigma_t * l).exp(), (m.ior - 1.0) * l)
                }
                None => (1.0, 0.0),
            };
            let value = beta * f * tr * cos_t / (PI * r2) * mis(k);
            self.splat(out, k, opl + r + extra + tgt.extra_m, value, s);
        }
    }

    fn path(
        &self,
        origin: &Endpoint,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut [f64],
        seg: &mut SegmentSamplers,
    ) {
        let set = &self.scene.settings;
        let bins = self.scene.capture.time.bins;
        let mut d = if s.next() < self.p_hidden {
            (self.hidden.sample(s) - origin.p).normalize()
        } else {
            cosine_hemisphere(origin.n, s.next(), s.next())
        };
        let cos0 = d.dot(origin.n);
        if cos0 <= 0.0 {
            return;
        }
        let pdf0 = self.p_hidden * self.hidden.pdf(origin.p, d) + (1.0 - self.p_hidden) * cos0 / PI;
        let mut beta = cos0 / PI / pdf0;
        let mut pos = origin.p;
        let mut opl = origin.extra_m;
        let mut depth = 0u32;
        loop {
            let hit = self.intersect(pos, d);
            let t_hit = hit.map_or(f64::INFINITY, |h| h.0.t);
            let mut medium_len = 0.0;
            let mut connected = false;
            if let Some(m) = self.medium() {
                if let Some((m0, m1)) = m.region.clip(pos, d, t_hit) {
                    medium_len = m1 - m0;
                    let sigma_s = m.sigma_s();
                    if sigma_s > 0.0 {
                        let pdf_ff = |t: f64| m.sigma_t * (-m.sigma_t * (t - m0)).exp();
                        // Connections from distances drawn toward each target (equiangular, and uniform in the
                        // capture's time window), MIS-combined (balance heuristic) with each other and with the
                        // free-flight vertex's connection below.
                        seg.equi.clear();
                        seg.time.clear();
                        if set.equiangular {
                            seg.equi.extend(
                                targets
                                    .iter()
                                    .map(|t| Equiangular::new(pos, d, t.p, m0, m1)),
                            );
                        }
                        if set.time_sampling && m.ior == 1.0 {
                            let tw = &self.scene.capture.time;
                            seg.time.extend(targets.iter().map(|t| {
                                let base = opl + t.extra_m;
                                TimeWindow::new(
                                    pos,
                                    d,
                                    t.p,
                                    m0,
                                    m1,
                                    (tw.start_m - base, tw.end_m() - base),
                                )
                            }));
                        }
                        for k in 0..targets.len() {
                            let draws = [
                                seg.equi
                                    .get(k)
                                    .and_then(|e| e.as_ref())
                                    .map(|e| e.sample(s.next())),
                                seg.time
                                    .get(k)
                                    .and_then(|e| e.as_ref())
                                    .map(|e| e.sample(s.next())),
                            ];
                            for (t, pdf) in draws.into_iter().flatten() {
                                if !(t >= m0 && t <= m1 && pdf > 0.0) {
                                    continue;
                                }
                                let b = beta * sigma_s * (-m.sigma_t * (t - m0)).exp() / pdf;
                                let w = pdf / (seg.pdf(k, t) + pdf_ff(t));
                                let o = opl + t + (m.ior - 1.0) * (t - m0);
                                let v = Vertex::Medium { dir: d };
                                self.connect(
                                    pos + d * t,
                                    &v,
                                    b,
                                    o,
                                    &targets[k..=k],
                                    |_| w,
                                    s,
                                    &mut out[k * bins..],
                                );
                            }
                        }
                        // The surface the segment reaches is connected now, weighted by the segment's
                        // transmittance (the expected value of free flight's pass/scatter choice), so every
                        // path toward the hidden object contributes its return; a pass below does not connect
                        // again.
                        if let Some((h, false)) = hit {
                            let tr = (-m.sigma_t * medium_len).exp();
                            let v = Vertex::Surface {
                                n: h.n,
                                albedo: h.albedo,
                            };
                            let o = opl + h.t + (m.ior - 1.0) * medium_len;
                            self.connect(pos + d * h.t, &v, beta * tr, o, targets, |_| 1.0, s, out);
                            connected = true;
                        }
                        // Free flight: scatter with density σt·exp(−σt·(t − m0)), else cross (weight T/P = 1).
                        let t = m0 - (1.0 - s.next()).ln() / m.sigma_t;
                        if t < m1 {
                            depth += 1;
                            pos += d * t;
                            opl += t + (m.ior - 1.0) * (t - m0);
                            beta *= m.albedo;
                            let pff = pdf_ff(t);
                            let mis = |k: usize| pff / (pff + seg.pdf(k, t));
                            self.connect(
                                pos,
                                &Vertex::Medium { dir: d },
                                beta,
                                opl,
                                targets,
                                mis,
                                s,
                                out,
                            );
                            if depth >= set.max_depth || !self.roulette(&mut beta, depth, s) {
                                return;
                            }
                            d = m.phase.sample(d, s.next(), s.next());
                            continue;
                        }
                    } else {
                        // Pure absorber: weight by the transmittance instead of sampling.
                        beta *= (-m.sigma_t * medium_len).exp();
                    }
                }
            }
            let Some((h, on_relay)) = hit else { return };
            depth += 1;
            pos += d * h.t;
            opl += h.t + self.medium().map_or(0.0, |m| (m.ior - 1.0) * medium_len);
            // A vertex on the relay is coplanar with every target: its connections vanish.
            if !on_relay && !connected {
                let v = Vertex::Surface {
                    n: h.n,
                    albedo: h.albedo,
                };
                self.connect(pos, &v, beta, opl, targets, |_| 1.0, s, out);
            }
            beta *= h.albedo;
            if beta <= 0.0 || depth >= set.max_depth || !self.roulette(&mut beta, depth, s) {
                return;
            }
            d = cosine_hemisphere(h.n, s.next(), s.next());
        }
    }

    fn roulette(&self, beta: &mut f64, depth: u32, s: &mut Sampler) -> bool {
        if depth < self.scene.settings.rr_depth {
            return true;
        }
        let q = beta.min(0.95);
        if s.next() >= q {
            return false;
        }
        *beta /= q;
        true
    }
}
