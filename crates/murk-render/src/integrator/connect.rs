//! Deterministic connections of hidden vertices to the target wall points, and the direct object
//! draws.

use super::*;

impl Tracer<'_> {
    /// The direct object return from the traced point `origin` by `object_draws` directions toward
    /// stratified uniform points of the hidden geometry: each connects the surface it first meets to the
    /// targets, through the segment's transmittance. Balance heuristic with the path's own first direction
    /// (`first_object_weight`).
    pub(super) fn draw_objects(
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
                scat: 0,
            };
            self.connect_hit(Ray { o: origin.p, d: w }, &h, carry, targets, s, out);
        }
    }

    /// Next-event estimation through the hidden geometry from the medium vertex `x` (arrived along
    /// `dir` with throughput `beta`): a direction toward a uniform point of the hidden geometry, its first
    /// hit connected to the targets. The object return after a scattering event otherwise needs the phase
    /// function's direction to meet the object, and those rare hits carry much of the object window's
    /// variance (docs/renderer-sampling.md). Balance heuristic against the path's direction, drawn with
    /// the phase function or its mixture with the lobe toward the target `lobe` (`object_weight`).
    pub(super) fn connect_object(
        &self,
        m: &Medium,
        (ray, lobe): (Ray, Option<DVec3>),
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
        let beta = carry.beta * ph / (self.medium_dir_pdf(m, dir, lobe, w) + p_h);
        if out.at_first {
            out.w = w;
        }
        let carry = Carry { beta, ..carry };
        self.connect_hit(Ray { o: x, d: w }, &h, carry, targets, s, out);
    }

    /// The transmittance along `o + t·d`, t ∈ [0, t_max], and the optical path the medium adds to it.
    pub(super) fn transmit(&self, o: DVec3, d: DVec3, t_max: f64) -> (f64, f64) {
        match self.medium().map(|m| (m, m.clip(o, d, t_max))) {
            Some((m, Some((t0, t1)))) => (
                m.transmittance(&[Segment { o, d, t0, t1 }]),
                m.extra_path_m(t1 - t0),
            ),
            _ => (1.0, 0.0),
        }
    }

    /// Connects the surface hit `h` of the ray `x + t·w` to every target, through the transmittance of
    /// the segment from `x` (reached with throughput `beta` at optical path `opl`).
    pub(super) fn connect_hit(
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
            ..carry
        };
        self.connect(at, carry, (0, targets), |_| 1.0, s, out);
    }

    /// Connects vertex `y` (reached with throughput `beta` at optical path `opl`) to every target of
    /// `(k0, targets)` (the first one is target k0). `mis(k)` weights the connection to `targets[k]`.
    /// `seen` is the start of the segment that reached y, which sees y: a target there (confocal: the
    /// origin at the first vertex) needs no occlusion test.
    pub(super) fn connect(
        &self,
        at: At,
        carry: Carry,
        (k0, targets): (usize, &[Endpoint]),
        mis: impl Fn(usize) -> f64,
        s: &mut Sampler,
        out: &mut Sink,
    ) {
        let (y, seen, v) = (at.y, at.seen, at.v);
        let Carry { beta, opl, scat } = carry;
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
            self.splat(out, k0 + k, opl + r + extra + tgt.extra_m, (value, scat), s);
        }
    }
}
