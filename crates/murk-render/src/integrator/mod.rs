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
//! medium, time-window distances, target-side draws, object draws and connections, shared tails, the
//! phase lobe out of the hidden geometry, spindle draws between a medium vertex and a target) and the
//! measurements that chose their defaults are in `docs/renderer-sampling.md`.

use crate::geometry::{Geometry, Hit, Shape, EPS};
use crate::medium::{Medium, Segment};
use crate::scene::Scene;
use murk_core::DVec3;
use rand_core::Rng;
use rand_pcg::Pcg64;
use std::f64::consts::PI;
use std::sync::Mutex;

mod connect;
mod distance;
mod sampling;
mod share;

use distance::*;
pub use sampling::Sampler;
use sampling::*;
use share::*;

/// A wall point with its normal (into the hidden side) and the optical path of its device leg.
#[derive(Clone, Copy, Debug)]
pub struct Endpoint {
    pub p: DVec3,
    pub n: DVec3,
    pub extra_m: f64,
}

/// Per-scene precomputation shared by all work units.
/// A ray o + t·d (d unit).
#[derive(Clone, Copy)]
struct Ray {
    o: DVec3,
    d: DVec3,
}

/// A path's throughput, the optical path it has travelled, and how many medium scattering events its
/// throughput holds (the power of the albedo in it, which an albedo sweep rescales).
#[derive(Clone, Copy)]
struct Carry {
    beta: f64,
    opl: f64,
    scat: i32,
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
    /// Share of target-side directions drawn in the phase function's lobe (`target_dir_pdf`).
    target_lobe: f64,
    /// Phase-angle distances per segment and target (`PhaseAngular`), and the share of target-side
    /// distances drawn so.
    phase_distances: u32,
    target_phase_distances: f64,
    /// Share of directions leaving a hidden-geometry vertex in the phase lobe toward the one target.
    surface_lobe: f64,
    /// Vertices drawn around the line from each medium vertex to each target (`draw_spindle`).
    spindle_draws: u32,
    /// Share of directions leaving a medium vertex (on the way back from the hidden geometry, past a
    /// tile's shared first vertex) in the phase lobe toward the one target instead of around the arriving
    /// direction.
    medium_lobe: f64,
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
    scat: i32,
    origin: bool,
    /// The axis of the phase lobe toward the target that shares this vertex's directions with its
    /// cosine lobe (`surface_lobe`) or, at a medium vertex, its phase lobe around the arriving
    /// direction (`medium_lobe`).
    lobe: Option<DVec3>,
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
        let target_lobe = set.target_lobe.unwrap_or_else(|| {
            scene
                .medium
                .as_ref()
                .map_or(0.0, Medium::default_target_lobe)
        });
        let phase_default = scene
            .medium
            .as_ref()
            .map_or((0, 0.0), Medium::default_phase_distances);
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
            target_lobe,
            phase_distances: set.phase_distances.unwrap_or(phase_default.0),
            target_phase_distances: set.target_phase_distances.unwrap_or(phase_default.1),
            surface_lobe: set.surface_lobe.unwrap_or_else(|| {
                scene
                    .medium
                    .as_ref()
                    .map_or(0.0, Medium::default_surface_lobe)
            }),
            spindle_draws: set.spindle_draws.unwrap_or_else(|| {
                scene
                    .medium
                    .as_ref()
                    .map_or(0, Medium::default_spindle_draws)
            }),
            medium_lobe: set.medium_lobe.unwrap_or_else(|| {
                scene
                    .medium
                    .as_ref()
                    .map_or(0.0, Medium::default_medium_lobe)
            }),
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
    /// hidden vertex is shared by all of them (`share_tail`). Each bin holds one value per entry of
    /// `ratios`, the albedos of a sweep over the medium's own, side by side: a contribution whose path
    /// scattered k times in the medium adds `ratios[j]^k` times itself to value j (a plain render has
    /// the one ratio 1).
    pub fn trace(
        &self,
        origins: &[Endpoint],
        targets: &[Endpoint],
        (spp, ratios): (u64, &[f64]),
        s: &mut Sampler,
        out: &mut [f32],
    ) {
        let mut seg = Vec::new();
        let mut sink = Sink {
            out,
            ratios,
            unit: targets.len() * self.scene.capture.time.bins,
            origin: 0,
            share: origins.len() > 1,
            recording: false,
            at_first: false,
            w: DVec3::ZERO,
            first: None,
            tail: Vec::new(),
        };
        let mut scratch = TileScratch::default();
        let g = {
            // Every unit of a render has the same spp: search once.
            let mut last = self.lattice.lock().unwrap_or_else(|e| e.into_inner());
            if last.0 != spp {
                *last = (spp, lattice_generator(spp));
            }
            last.1
        };
        let reach = self.window_reach(origins);
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
                self.path(origin, (targets, reach), u, s, &mut sink, &mut seg);
                if !sink.tail.is_empty() {
                    self.share_tail(origins, i, &mut sink, &mut scratch);
                }
                jg += g;
                if jg >= spp {
                    jg -= spp;
                }
            }
        }
    }

    /// Adds `value` (whose throughput holds `scat` medium scattering events) at optical path `opl` to
    /// target `k`'s histogram of the traced point, once per albedo of the sweep.
    fn splat(
        &self,
        out: &mut Sink,
        k: usize,
        opl: f64,
        (value, scat): (f64, i32),
        s: &mut Sampler,
    ) {
        let t = &self.scene.capture.time;
        let jitter = self.scene.settings.time_jitter_m;
        let opl = if jitter > 0.0 {
            opl + jitter * s.gauss()
        } else {
            opl
        };
        if out.recording {
            out.tail.push(Tail {
                hist0: k * t.bins,
                bin: (opl - t.start_m) / t.bin_width_m,
                value,
                scat,
                w: out.w,
            });
            return;
        }
        let x = (opl - t.start_m) / t.bin_width_m;
        if x >= 0.0 && x < t.bins as f64 {
            let n = out.ratios.len();
            let i = (out.origin * out.unit + k * t.bins + x as usize) * n;
            for (o, r) in out.out[i..i + n].iter_mut().zip(out.ratios) {
                *o += (value * r.powi(scat)) as f32;
            }
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
            Vertex::Medium { dir } => self
                .medium()
                .map_or(0.0, |m| self.medium_dir_pdf(m, dir, from.lobe, w)),
            Vertex::Surface { n, .. } => {
                let c = n.dot(w);
                if c <= 0.0 {
                    0.0
                } else if from.origin {
                    self.origin_pdf(from.x, n, w).0
                } else {
                    match (from.lobe, self.medium()) {
                        (Some(a), Some(m)) => {
                            let q = self.surface_lobe;
                            (1.0 - q) * c / PI + q * m.phase.eval(a.dot(w))
                        }
                        _ => c / PI,
                    }
                }
            }
        }
    }

    /// Solid-angle density of a direction `w` leaving a medium vertex reached along `dir`: the phase
    /// function around `dir`, mixed (`medium_lobe`) with the phase function around `lobe`, the direction
    /// to the target, where that lobe is on.
    fn medium_dir_pdf(&self, m: &Medium, dir: DVec3, lobe: Option<DVec3>, w: DVec3) -> f64 {
        let p = m.phase.eval(dir.dot(w));
        match lobe {
            Some(a) => {
                let q = self.medium_lobe;
                (1.0 - q) * p + q * m.phase.eval(a.dot(w))
            }
            None => p,
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

    /// The balance weight of a path's own surface connection along direction `d` from `from` against
    /// `connect_object` (only from medium vertices), or `first` from the traced point (against
    /// `draw_objects`).
    fn object_weight(&self, from: &Start, d: DVec3, first: f64) -> f64 {
        match (from.v, self.medium()) {
            _ if from.origin => first,
            (Vertex::Medium { dir }, Some(m)) if self.medium_objects => {
                let ph = self.medium_dir_pdf(m, dir, from.lobe, d);
                let (p_h, _) = self.hidden.pdf(&self.scene.geometry, from.x, d);
                ph / (ph + p_h)
            }
            _ => 1.0,
        }
    }

    /// The latest optical path (m) at which a path traced from any of `origins` can still add to the
    /// capture: the window's end, plus what a shared tail's replay can take off (the origins' spread in
    /// position and device leg bounds it by the triangle inequality where the medium's ior is 1). None
    /// with timing jitter, which can move any contribution into the window.
    fn window_reach(&self, origins: &[Endpoint]) -> Option<f64> {
        if self.scene.settings.time_jitter_m > 0.0 {
            return None;
        }
        let end_m = self.scene.capture.time.end_m();
        if origins.len() < 2 {
            return Some(end_m);
        }
        if self.medium().is_some_and(|m| m.ior != 1.0) {
            return None;
        }
        let bounds = origins
            .iter()
            .fold(crate::geometry::Aabb::empty(), |b, o| b.grow(o.p));
        let (lo, hi) = origins
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), o| {
                (lo.min(o.extra_m), hi.max(o.extra_m))
            });
        Some(end_m + (bounds.max - bounds.min).length() + (hi - lo))
    }

    /// Whether everything a path at `pos`, having travelled `opl`, can still add lands past `reach`:
    /// each of its connections travels at least the straight line to a target and that target's device
    /// leg (a medium's ior ≥ 1 only lengthens paths).
    fn past_window(&self, pos: DVec3, opl: f64, targets: &[Endpoint], reach: Option<f64>) -> bool {
        let Some(reach) = reach else { return false };
        let nearest = targets
            .iter()
            .map(|t| (pos - t.p).length() + t.extra_m)
            .fold(f64::INFINITY, f64::min);
        opl + nearest > reach * (1.0 + 1e-12) + 1e-9
    }

    fn path(
        &self,
        origin: &Endpoint,
        (targets, reach): (&[Endpoint], Option<f64>),
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
            scat: 0,
            origin: true,
            lobe: None,
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
        let mut scat = 0;
        // Whether the path has left the hidden geometry: only then does it head back for the target
        // (`medium_lobe`); before, the object is what it heads for.
        let mut returning = false;
        loop {
            // Fog paths wander on long after the window has closed for them: in a 1/m medium each
            // vertex adds about a metre of path.
            if depth > 0 && self.past_window(pos, opl, targets, reach) {
                return;
            }
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
            // Target-side and spindle density of a path-side vertex y at distance t, per unit length
            // along d.
            let pd = if scattering.is_some() {
                self.dir_pdf(&from, d)
            } else {
                0.0
            };
            let target_pdf = |m: &Medium, seg: &Toward, k: usize, y: DVec3, t: f64| {
                if scattering.is_some() && pd > 0.0 {
                    (seg.target_draws * self.target_pdf(m, &targets[k], from.x, y)
                        + self.spindle_pdf(&from, &targets[k], y))
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
                if let Some((m0, m1)) = m.clip(pos, d, t_hit) {
                    medium_len = m1 - m0;
                    if m.scatters() {
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
                            let n_phase = seg[k].phase.as_ref().map_or(0, |e| e.1);
                            // Draw 0 is equiangular, draws 1..=n_time the time window's strata, the
                            // rest phase-angle distances.
                            for j in 0..=n_time + n_phase {
                                let draw = if j == 0 {
                                    seg[k].equi.as_ref().map(|e| e.sample(s.next()))
                                } else if j <= n_time {
                                    seg[k].time.as_ref().map(|e| e.sample(j - 1, s.next()))
                                } else {
                                    seg[k].phase.as_ref().map(|e| e.0.sample(s.next()))
                                };
                                let Some((t, pdf)) = draw else { continue };
                                if !(t >= m0 && t <= m1 && pdf > 0.0) {
                                    continue;
                                }
                                let y = pos + d * t;
                                let (tr, pff) = m.flight(Segment {
                                    o: pos,
                                    d,
                                    t0: m0,
                                    t1: t,
                                });
                                let b = beta * m.sigma_s_at(y) * tr / pdf;
                                let w =
                                    pdf / (seg[k].pdf(t) + pff + target_pdf(m, &seg[k], k, y, t));
                                let o = opl + t + m.extra_path_m(t - m0);
                                let v = Vertex::Medium { dir: d };
                                let at = At {
                                    y,
                                    seen: from.x,
                                    v: &v,
                                };
                                let carry = Carry {
                                    beta: b,
                                    opl: o,
                                    scat: scat + 1,
                                };
                                self.connect(at, carry, (k, &targets[k..=k]), |_| w, s, out);
                            }
                        }
                        // The surface the segment reaches is connected now, weighted by the segment's
                        // transmittance (the expected value of free flight's pass/scatter choice), so every
                        // path toward the hidden object contributes its return; a pass below does not connect
                        // again.
                        if let Some((h, false)) = hit {
                            let b = beta * self.object_weight(&from, d, first_object_weight);
                            let carry = Carry { beta: b, opl, scat };
                            self.connect_hit(Ray { o: pos, d }, &h, carry, targets, s, out);
                            connected = true;
                        }
                        // Free flight: scatter with density σt(y)·T(m0 → t), else cross (weight T/P = 1).
                        let flight = Segment {
                            o: pos,
                            d,
                            t0: m0,
                            t1: m1,
                        };
                        let t = m.sample_flight(flight, &mut || s.next());
                        if t < m1 {
                            depth += 1;
                            // What leaves this vertex keeps the first vertex's outgoing direction.
                            out.at_first = false;
                            let y = pos + d * t;
                            let pff = m.flight(Segment { t1: t, ..flight }).1;
                            let mis = |k: usize| {
                                pff / (pff + seg[k].pdf(t) + target_pdf(m, &seg[k], k, y, t))
                            };
                            pos = y;
                            opl += t + m.extra_path_m(t - m0);
                            beta *= m.albedo;
                            scat += 1;
                            let at = At {
                                y: pos,
                                seen: from.x,
                                v: &Vertex::Medium { dir: d },
                            };
                            let carry = Carry { beta, opl, scat };
                            self.connect(at, carry, (0, targets), mis, s, out);
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
                            // Only on the way back from the hidden geometry; the first vertex of a shared
                            // tail keeps the phase lobe alone (the tile's weights there are each point's
                            // own phase density, `share_tail`).
                            let lobe = if !returning || (out.share && depth == 1) {
                                None
                            } else {
                                self.lobe_axis_to_target(pos, self.medium_lobe, targets)
                            };
                            let ray = Ray { o: pos, d };
                            self.connect_object(m, (ray, lobe), carry, targets, s, out);
                            if !self.roulette(&mut beta, depth, s) {
                                return;
                            }
                            from = Start {
                                x: pos,
                                v: Vertex::Medium { dir: d },
                                beta,
                                opl,
                                scat,
                                origin: false,
                                lobe,
                            };
                            d = match lobe {
                                Some(a) => {
                                    // As for the surface lobe: one more number where the lobe is on;
                                    // weight: the phase function over the mixture's density.
                                    let w = if s.next() < self.medium_lobe {
                                        m.phase.sample(a, s.next(), s.next())
                                    } else {
                                        m.phase.sample(d, s.next(), s.next())
                                    };
                                    beta *= m.phase.eval(d.dot(w)) / self.dir_pdf(&from, w);
                                    w
                                }
                                None => m.phase.sample(d, s.next(), s.next()),
                            };
                            continue;
                        }
                    } else {
                        // Pure absorber: weight by the transmittance instead of sampling.
                        let seg = Segment {
                            o: pos,
                            d,
                            t0: m0,
                            t1: m1,
                        };
                        beta *= m.transmittance(&[seg]);
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
            returning |= !on_relay;
            if !on_relay && !connected {
                let b = beta * self.object_weight(&from, d, first_object_weight);
                let at = At {
                    y: pos,
                    seen: from.x,
                    v: &v,
                };
                let carry = Carry { beta: b, opl, scat };
                self.connect(at, carry, (0, targets), |_| 1.0, s, out);
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
                scat,
                origin: false,
                lobe: if on_relay {
                    None
                } else {
                    self.lobe_axis_to_target(pos, self.surface_lobe, targets)
                },
            };
            d = match (from.lobe, self.medium()) {
                (Some(a), Some(m)) => {
                    // One more number for the choice, only where the lobe is on (other scenes keep
                    // their random streams); weight: the cosine lobe over the mixture's density.
                    let w = if s.next() < self.surface_lobe {
                        m.phase.sample(a, s.next(), s.next())
                    } else {
                        cosine_hemisphere(h.n, s.next(), s.next())
                    };
                    let c = h.n.dot(w);
                    if c <= 0.0 {
                        return;
                    }
                    beta *= c / PI / self.dir_pdf(&from, w);
                    w
                }
                _ => cosine_hemisphere(h.n, s.next(), s.next()),
            };
        }
    }

    /// The axis of a vertex's phase lobe at `x` (`surface_lobe`, `medium_lobe`): the direction to the
    /// one target. None with several targets or where the lobe's `share` is 0 (the relay, coplanar with
    /// the targets, never gets one).
    fn lobe_axis_to_target(&self, x: DVec3, share: f64, targets: &[Endpoint]) -> Option<DVec3> {
        match targets {
            [t] if share > 0.0 => (t.p - x).try_normalize(),
            _ => None,
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
