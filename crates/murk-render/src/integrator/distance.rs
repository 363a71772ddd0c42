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
    /// Target-side draws from the segment's start toward this target (`target_draws`), for the
    /// target-side density of each vertex drawn on the segment.
    pub(super) target_draws: f64,
}

impl Toward {
    /// Sum of the connection-technique densities at distance t.
    pub(super) fn pdf(&self, t: f64) -> f64 {
        self.equi.as_ref().map_or(0.0, |e| e.pdf(t)) + self.time.as_ref().map_or(0.0, |e| e.pdf(t))
    }
}

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
        let hit = self.intersect(tgt.p, wl).map_or(f64::INFINITY, |h| h.0.t);
        match m.clip(tgt.p, wl, hit) {
            Some((a, b)) if tl >= a && tl <= b => {
                Equiangular::new(tgt.p, wl, x, a, b).map_or(0.0, |e| p_dir * e.pdf(tl) / tl2)
            }
            _ => 0.0,
        }
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
        }
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
        let hit_l = self.intersect(tgt.p, wl).map_or(f64::INFINITY, |h| h.0.t);
        let Some((a, b)) = m.clip(tgt.p, wl, hit_l) else {
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
        let p_l = p_dir * peq / (tl * tl);
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
            / (n as f64 * p_l + p_path);
        let opl = from.opl + t + tl + m.extra_path_m((t - m0) + (tl - a)) + tgt.extra_m;
        // The target-side vertex scatters once more than the path that reached `from`.
        self.splat(out, k, opl, (value, from.scat + 1), s);
    }
}
