//! Distance sampling along a segment: equiangular toward a point, stratified over the time window,
//! and the target side's draws with their densities.

use super::*;

/// Density of a distance along a ray segment, for one target point: equiangular (Kulla & Fajardo 2012)
/// when the target is off the ray's line, inverse-square when it lies on it.
pub(super) enum Equiangular {
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
    pub(super) fn new(o: DVec3, dir: DVec3, target: DVec3, a: f64, b: f64) -> Option<Self> {
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

    pub(super) fn sample(&self, u: f64) -> (f64, f64) {
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

    pub(super) fn pdf(&self, t: f64) -> f64 {
        match *self {
            Equiangular::Angular { tc, d, span, .. } => d / (span * (d * d + (t - tc).powi(2))),
            Equiangular::InvSquare {
                tc, inv_a, inv_b, ..
            } => 1.0 / ((inv_a - inv_b).abs() * (t - tc).powi(2)),
        }
    }
}

/// Density of a distance along a ray segment toward one target point, in the scattering angle ψ that a
/// connection from the drawn point to the target turns through (cos ψ = ray · direction to the target):
/// the wrapped Cauchy density ∝ 1/(1 + ρ² − 2ρ cos ψ) in ψ. Equiangular distances are uniform in ψ
/// (ψ is the equiangular angle plus π/2), so the 1/r² of the connection cancels here as there, and
/// what is left of its integrand is the phase function p(cos ψ). Henyey–Greenstein's own integral over ψ
/// is elliptic; this one inverts in closed form, and with ρ from [`Phase::cauchy_rho`] its second
/// moment against HG stays near that of sampling HG exactly, where uniform ψ's grows with g (the
/// figures are in docs/renderer-sampling.md).
/// The target must lie off the ray's line.
pub(super) struct PhaseAngular {
    tc: f64,
    d: f64,
    rho: f64,
    k: f64,
    /// k·tan(ψa/2) = tan Φa, with Φ = atan(k·tan(ψ/2)) the variable that is uniform, and Φb − Φa.
    tan_a: f64,
    span: f64,
}

impl PhaseAngular {
    pub(super) fn new(
        o: DVec3,
        dir: DVec3,
        target: DVec3,
        (a, b): (f64, f64),
        rho: f64,
    ) -> Option<Self> {
        let v = target - o;
        let tc = v.dot(dir);
        let d = (v.length_squared() - tc * tc).max(0.0).sqrt();
        if d <= 1e-7 {
            return None;
        }
        let k = (1.0 + rho) / (1.0 - rho);
        // tan(ψ/2) at distance t, without cancellation on either side of the foot tc.
        let half = |t: f64| {
            let x = tc - t;
            let r = (d * d + x * x).sqrt();
            if x >= 0.0 {
                d / (r + x)
            } else {
                (r - x) / d
            }
        };
        let (ta, tb) = (k * half(a), k * half(b));
        // Φb − Φa from its tangent, as for equiangular: both lie in [0, π/2).
        let span = atan2_upper(tb - ta, 1.0 + ta * tb);
        (span > 0.0).then_some(PhaseAngular {
            tc,
            d,
            rho,
            k,
            tan_a: ta,
            span,
        })
    }

    pub(super) fn sample(&self, u: f64) -> (f64, f64) {
        let (sn, cs) = (u * self.span).sin_cos();
        // tan(Φa + φ) by the addition formula (Φa + φ < π/2: its denominator is positive), then
        // t = tc − d·cot ψ with cot ψ = (1 − τ²)/(2τ), τ = tan(ψ/2).
        let tau = (self.tan_a * cs + sn) / (cs - self.tan_a * sn) / self.k;
        let t = self.tc - self.d * (1.0 - tau * tau) / (2.0 * tau);
        (t, self.pdf(t))
    }

    pub(super) fn pdf(&self, t: f64) -> f64 {
        // dΦ/dψ = (1 − ρ²)/(2(1 + ρ² − 2ρ cos ψ)) and dψ/dt = d/r², cos ψ = (tc − t)/r.
        let x = self.tc - t;
        let r2 = self.d * self.d + x * x;
        let r = r2.sqrt();
        let rho = self.rho;
        (1.0 - rho * rho) * self.d / (2.0 * self.span * r * (r * (1.0 + rho * rho) - 2.0 * rho * x))
    }
}

/// Time-window-aware distance sampling for one target: the connected path length through the point at
/// distance t, L(t) = t + |o + t·ω − target|, is drawn uniformly over the part of the capture window the
/// segment can reach, so late bins (the object window behind fog) get as many medium vertices as early
/// ones; n draws, one per equal stratum of L, and `pdf` is their summed density. Needs ior = 1 (L is then
/// this closed form).
pub(super) struct TimeWindow {
    pub(super) c: f64,
    pub(super) v2: f64,
    pub(super) l_lo: f64,
    pub(super) l_hi: f64,
    pub(super) n: u32,
}

impl TimeWindow {
    /// `window` is the range of L (path still to go) that lands in the histogram.
    pub(super) fn new(
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
    pub(super) fn sample(&self, k: u32, u: f64) -> (f64, f64) {
        let l = self.l_lo + (k as f64 + u) / self.n as f64 * (self.l_hi - self.l_lo);
        let t = (l * l - self.v2) / (2.0 * (l + self.c));
        (t, self.pdf(t))
    }

    pub(super) fn pdf(&self, t: f64) -> f64 {
        let r = (t * t + 2.0 * t * self.c + self.v2).max(0.0).sqrt();
        let l = t + r;
        if l < self.l_lo || l > self.l_hi || r <= 0.0 {
            return 0.0;
        }
        self.n as f64 * (1.0 + (t + self.c) / r) / (self.l_hi - self.l_lo)
    }
}

/// A medium segment's distance samplers toward one target.
pub(super) struct Toward {
    pub(super) equi: Option<Equiangular>,
    pub(super) time: Option<TimeWindow>,
    /// The phase-angle distances ([`PhaseAngular`]) and how many of them.
    pub(super) phase: Option<(PhaseAngular, u32)>,
    /// Target-side draws from the segment's start toward this target (`target_draws`), for the
    /// target-side density of each vertex drawn on the segment.
    pub(super) target_draws: f64,
}

impl Toward {
    /// Sum of the connection-technique densities at distance t.
    pub(super) fn pdf(&self, t: f64) -> f64 {
        self.equi.as_ref().map_or(0.0, |e| e.pdf(t))
            + self.time.as_ref().map_or(0.0, |e| e.pdf(t))
            + self
                .phase
                .as_ref()
                .map_or(0.0, |(e, n)| *n as f64 * e.pdf(t))
    }
}

/// The distance of a target-side draw along its direction, toward the path vertex: equiangular, or a
/// mixture of it with the phase-angle distances (their share second).
pub(super) struct TargetDistance {
    equi: Equiangular,
    phase: Option<(PhaseAngular, f64)>,
}

impl TargetDistance {
    /// The distance for `u`; `choose` gives the number that picks the technique (drawn only where
    /// there is a mixture, so other scenes keep their random streams).
    pub(super) fn sample(&self, u: f64, choose: impl FnOnce() -> f64) -> (f64, f64) {
        let t = match &self.phase {
            Some((p, q)) if choose() < *q => p.sample(u).0,
            _ => self.equi.sample(u).0,
        };
        (t, self.pdf(t))
    }

    pub(super) fn pdf(&self, t: f64) -> f64 {
        match &self.phase {
            Some((p, q)) => (1.0 - q) * self.equi.pdf(t) + q * p.pdf(t),
            None => self.equi.pdf(t),
        }
    }
}

/// The spindle draws' radius as a share of the line's length: at g 0.7 the phase function falls to
/// half its peak 0.28 rad off forward, which at the line's middle is 0.07 of its length off the line.
const SPINDLE_WIDTH: f64 = 0.1;

impl Tracer<'_> {
    /// The path side's distance samplers toward `tgt` on the medium part `[m0, m1]` of the segment
    /// `x + t·d` that starts at optical path `opl`; `first`: the segment leaves the traced point.
    pub(super) fn toward(
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
            target_draws: self.target_draws(x, first, tgt) as f64,
            equi: set
                .equiangular
                .then(|| Equiangular::new(x, d, tgt.p, m01.0, m01.1))
                .flatten(),
            phase: (self.phase_distances > 0)
                .then(|| PhaseAngular::new(x, d, tgt.p, m01, m.phase.cauchy_rho()))
                .flatten()
                .map(|e| (e, self.phase_distances)),
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
    /// a direction from the target (`target_dir_pdf`), then an equiangular distance toward `x`.
    pub(super) fn target_pdf(&self, m: &Medium, tgt: &Endpoint, x: DVec3, y: DVec3) -> f64 {
        let v = y - tgt.p;
        let tl2 = v.length_squared();
        let tl = tl2.sqrt();
        let wl = v / tl;
        let p_dir = self.target_dir_pdf(m, tgt, self.lobe_axis(tgt, x), wl);
        if p_dir <= 0.0 {
            return 0.0;
        }
        match self.target_leg(m, tgt, wl) {
            Some((a, b)) if tl >= a && tl <= b => self
                .target_distance(m, (tgt.p, wl), x, (a, b))
                .map_or(0.0, |e| p_dir * e.pdf(tl) / tl2),
            _ => 0.0,
        }
    }

    /// The distance sampler of a target-side draw along `o + t·dir`, t ∈ `ab`, toward the path vertex
    /// `x`: equiangular, mixed with phase-angle distances (`target_phase_distances`) where they are on.
    fn target_distance(
        &self,
        m: &Medium,
        (o, dir): (DVec3, DVec3),
        x: DVec3,
        ab: (f64, f64),
    ) -> Option<TargetDistance> {
        let equi = Equiangular::new(o, dir, x, ab.0, ab.1)?;
        let q = self.target_phase_distances;
        let phase = (q > 0.0)
            .then(|| PhaseAngular::new(o, dir, x, ab, m.phase.cauchy_rho()))
            .flatten()
            .map(|e| (e, q));
        Some(TargetDistance { equi, phase })
    }

    /// The axis of the target-side phase lobe toward `x`, where that lobe is drawn at all.
    fn lobe_axis(&self, tgt: &Endpoint, x: DVec3) -> Option<DVec3> {
        let v = x - tgt.p;
        let len = v.length();
        (self.target_lobe > 0.0 && len > 1e-9).then(|| v / len)
    }

    /// Solid-angle density of a target-side direction `wl` from `tgt`: the target's cosine lobe, mixed
    /// (`target_lobe`) with the phase function around `axis`, the direction to the path vertex x
    /// (`lobe_axis`). A vertex y on
    /// that line joins x to the target through a forward scattering angle at y, the peak of
    /// p(w_xy·w_yt) that neither the cosine lobe nor the path side's phase draw around its arriving
    /// direction finds (docs/renderer-sampling.md). Directions behind the wall have density 0.
    fn target_dir_pdf(&self, m: &Medium, tgt: &Endpoint, axis: Option<DVec3>, wl: DVec3) -> f64 {
        let cos = tgt.n.dot(wl);
        if cos <= 0.0 {
            return 0.0;
        }
        match axis {
            Some(a) => {
                let q = self.target_lobe;
                (1.0 - q) * cos / PI + q * m.phase.eval(a.dot(wl))
            }
            None => cos / PI,
        }
    }

    /// Target-side sampling: for each target, a medium vertex y drawn from the target's side (direction by
    /// `target_dir_pdf`, distance equiangular toward the segment start `from.x`) and joined to `from.x`. Its
    /// volume density ∝ cos/|y − target|² cancels the 1/r² of the connection to the target, which the
    /// path side can only cancel along its own segment: there, the equiangular weight still grows as 1/d
    /// for segments passing at distance d from the target, the fireflies of multiply scattered fog near the
    /// laser spot. Balance heuristic against the path side's densities (free flight, equiangular, time
    /// window) for the same vertex. Segment starts (mostly relay vertices) a few cm from the target keep
    /// a spread growing as 1/distance, so they get `target_draws` draws. The measurements are in
    /// docs/renderer-sampling.md.
    pub(super) fn sample_from_target(
        &self,
        m: &Medium,
        from: &Start,
        targets: &[Endpoint],
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        for (k, tgt) in targets.iter().enumerate() {
            let n = self.target_draws(from.x, from.origin, tgt);
            for _ in 0..n {
                self.draw_from_target(m, from, (k, tgt), n, s, out);
            }
            if matches!(from.v, Vertex::Medium { .. }) {
                for _ in 0..self.spindle_draws {
                    self.draw_spindle(m, from, (k, tgt), n, s, out);
                }
            }
        }
    }

    /// Volume density of the spindle draws from the medium vertex `from` toward `tgt` at `y`: uniform
    /// along the line x → target, and ∝ 1/ρ in the distance ρ < `SPINDLE_WIDTH`·|x − target| from it.
    /// 0 where they do not run (other vertices, or no draws).
    pub(super) fn spindle_pdf(&self, from: &Start, tgt: &Endpoint, y: DVec3) -> f64 {
        if self.spindle_draws == 0 || !matches!(from.v, Vertex::Medium { .. }) {
            return 0.0;
        }
        let v = tgt.p - from.x;
        let len = v.length();
        let u = v / len;
        let q = y - from.x;
        let z = q.dot(u);
        let rho = (q - u * z).length();
        let width = SPINDLE_WIDTH * len;
        if !(z >= 0.0 && z <= len && rho > 0.0 && rho < width) {
            return 0.0;
        }
        self.spindle_draws as f64 / (len * 2.0 * PI * rho * width)
    }

    /// One spindle draw: a vertex y uniform along the line from the medium vertex `from` to the target
    /// and at a distance ρ from it with density ∝ 1/ρ (`spindle_pdf`), joined to both. Where the phase
    /// function peaks forward, the join's integrand stays near its peak close to that line, while the
    /// path side's density there (a phase direction, then distances toward the target) and the target
    /// side's (a direction, then distances toward `from`) both fall off ∝ ρ: their balance weight
    /// leaves values ∝ 1/ρ, the fog's fireflies after the object window (docs/renderer-sampling.md).
    /// `n`: the target-side draws from `from`.
    fn draw_spindle(
        &self,
        m: &Medium,
        from: &Start,
        (k, tgt): (usize, &Endpoint),
        n: u32,
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let v = tgt.p - from.x;
        let len = v.length();
        let u = v / len;
        let (z, rho, phi) = (
            len * s.next(),
            SPINDLE_WIDTH * len * s.next(),
            2.0 * PI * s.next(),
        );
        let (e1, e2) = u.any_orthonormal_pair();
        let y = from.x + u * z + (e1 * phi.cos() + e2 * phi.sin()) * rho;
        let lv = y - tgt.p;
        let tl = lv.length();
        if tl <= 0.0 {
            return;
        }
        let wl = lv / tl;
        if tgt.n.dot(wl) <= 0.0 {
            return;
        }
        let Some((a, b)) = self.target_leg(m, tgt, wl) else {
            return;
        };
        if !(tl >= a && tl <= b) {
            return;
        }
        let p_l = n as f64 * self.target_pdf(m, tgt, from.x, y);
        self.join_target(m, from, (k, tgt), (wl, tl, a, p_l), s, out);
    }

    /// How many target-side draws a segment starting at `x` (the traced point when `origin`) gets
    /// toward `tgt`: 1, or up to `target_split` when `x` lies within `target_split_radius` of the
    /// target (∝ radius/distance).
    pub(super) fn target_draws(&self, x: DVec3, origin: bool, tgt: &Endpoint) -> u32 {
        let set = &self.scene.settings;
        let r = set.target_split_radius_m;
        if origin || r <= 0.0 {
            return 1;
        }
        let d = (x - tgt.p).length();
        if d >= r {
            1
        } else {
            (r / d).ceil().min(set.target_split.max(1) as f64) as u32
        }
    }

    /// One of `n` target-side draws toward target `k`, `tgt`.
    pub(super) fn draw_from_target(
        &self,
        m: &Medium,
        from: &Start,
        (k, tgt): (usize, &Endpoint),
        n: u32,
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        // The phase lobe's share draws one more number, only where it is on (other scenes keep their
        // random streams).
        let axis = self.lobe_axis(tgt, from.x);
        let wl = match axis {
            Some(a) if s.next() < self.target_lobe => m.phase.sample(a, s.next(), s.next()),
            _ => cosine_hemisphere(tgt.n, s.next(), s.next()),
        };
        let p_dir = self.target_dir_pdf(m, tgt, axis, wl);
        if p_dir <= 0.0 {
            return;
        }
        let u = s.next();
        let Some((a, b)) = self.target_leg(m, tgt, wl) else {
            return;
        };
        let Some(dist) = self.target_distance(m, (tgt.p, wl), from.x, (a, b)) else {
            return;
        };
        let (tl, peq) = dist.sample(u, || s.next());
        if !(tl >= a && tl <= b && peq > 0.0) {
            return;
        }
        let p_l = n as f64 * (p_dir * peq / (tl * tl));
        self.join_target(m, from, (k, tgt), (wl, tl, a, p_l), s, out);
    }

    /// The stretch (a, b) of the ray from the target along `wl` that lies in the medium before the
    /// first surface: where a target-side vertex can be.
    fn target_leg(&self, m: &Medium, tgt: &Endpoint, wl: DVec3) -> Option<(f64, f64)> {
        let hit = self.intersect(tgt.p, wl).map_or(f64::INFINITY, |h| h.0.t);
        m.clip(tgt.p, wl, hit)
    }

    /// Joins the medium vertex y = target + `wl`·`tl` (its medium starting `a` along `wl`) to `from`
    /// and to target `k`, `tgt`, weighted by the balance heuristic over the target-side draws' density
    /// `p_l` at y, the spindle draws' and the path side's.
    fn join_target(
        &self,
        m: &Medium,
        from: &Start,
        (k, tgt): (usize, &Endpoint),
        (wl, tl, a, p_l): (DVec3, f64, f64, f64),
        s: &mut Sampler,
        out: &mut Sink,
    ) {
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
        let Some((m0, m1)) = m.clip(from.x, w, hit) else {
            return;
        };
        let leg = Segment {
            o: from.x,
            d: w,
            t0: m0,
            t1: t,
        };
        let pff = m.flight(leg).1;
        let p_path = self.dir_pdf(from, w)
            * (pff
                + self
                    .toward(m, (from.x, w), from.opl, (m0, m1), tgt, from.origin)
                    .pdf(t))
            / t2;
        let cos_l = tgt.n.dot(wl);
        // Integrand (volume measure) over the sum of densities: the balance-weighted estimate.
        let legs = [
            leg,
            Segment {
                o: tgt.p,
                d: wl,
                t0: a,
                t1: tl,
            },
        ];
        let value = from.beta * f * m.transmittance(&legs) / t2
            * m.sigma_s_at(y)
            * m.phase.eval(-w.dot(wl))
            * cos_l
            / (PI * tl * tl)
            / (p_l + p_path + self.spindle_pdf(from, tgt, y));
        let opl = from.opl + t + tl + m.extra_path_m((t - m0) + (tl - a)) + tgt.extra_m;
        // The target-side vertex scatters once more than the path that reached `from`.
        self.splat(out, k, opl, (value, from.scat + 1), s);
    }
}

#[cfg(test)]
mod tests {
    use super::PhaseAngular;
    use crate::medium::Phase;
    use murk_core::DVec3;

    /// The phase-angle distances invert their own density: for u on a grid, the density integrated
    /// (Simpson, 4 000 steps) from the segment's start to the drawn distance is u within 1e-6, on
    /// segments before, across and past the target's foot, for forward, isotropic and backward lobes.
    #[test]
    fn phase_angular_sample_inverts_its_density() {
        let (o, dir) = (DVec3::new(0.1, -0.2, 0.3), DVec3::new(1.0, 2.0, 2.0) / 3.0);
        let target = DVec3::new(0.9, 0.7, 1.9);
        for g in [0.9, 0.7, 0.0, -0.7] {
            let rho = Phase::new(g).cauchy_rho();
            for ab in [(0.0, 1.5), (0.0, 6.0), (2.2, 5.0), (0.01, 0.3)] {
                let e = PhaseAngular::new(o, dir, target, ab, rho).expect("target off the line");
                let cdf = |t: f64| {
                    let n = 4000;
                    let h = (t - ab.0) / n as f64;
                    (0..=n)
                        .map(|i| {
                            let w = if i == 0 || i == n {
                                1.0
                            } else {
                                2.0 + 2.0 * (i % 2) as f64
                            };
                            w * e.pdf(ab.0 + i as f64 * h)
                        })
                        .sum::<f64>()
                        * h
                        / 3.0
                };
                let mut last = ab.0;
                for i in 0..=20 {
                    let u = i as f64 / 20.0;
                    let (t, pdf) = e.sample(u);
                    assert!(
                        t >= last - 1e-12 && t <= ab.1 + 1e-9,
                        "g {g} {ab:?} u {u}: t {t}"
                    );
                    assert!((pdf - e.pdf(t)).abs() <= 1e-12 * pdf);
                    assert!(
                        (cdf(t) - u).abs() < 1e-6,
                        "g {g} {ab:?} u {u}: cdf {}",
                        cdf(t)
                    );
                    last = t;
                }
            }
        }
    }

    /// The fit of ρ keeps the wrapped Cauchy density close to Henyey–Greenstein's over ψ ∈ [0, π]: the
    /// second moment of p/q under q (1 for an exact fit) stays below 1.1 at |g| = 0.3–0.95, far below
    /// uniform ψ's (equiangular; docs/renderer-sampling.md).
    #[test]
    fn cauchy_fit_tracks_hg() {
        use std::f64::consts::PI;
        for g in [0.3, 0.7, 0.9, 0.95, -0.7] {
            let rho = Phase::new(g).cauchy_rho();
            let n = 200_000;
            let h = PI / n as f64;
            let psi = |i: usize| (i as f64 + 0.5) * h;
            let hg = |x: f64| Phase::new(g).eval(x.cos());
            let wc = |x: f64| 1.0 / (1.0 + rho * rho - 2.0 * rho * x.cos());
            let (zp, zq): (f64, f64) = (0..n).fold((0.0, 0.0), |s, i| {
                (s.0 + hg(psi(i)) * h, s.1 + wc(psi(i)) * h)
            });
            let m2: f64 = (0..n)
                .map(|i| (hg(psi(i)) / zp).powi(2) / (wc(psi(i)) / zq) * h)
                .sum();
            assert!(m2 < 1.1, "g {g}: second moment {m2}");
        }
    }
}
