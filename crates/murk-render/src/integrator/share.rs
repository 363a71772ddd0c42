//! Sharing a path's tail among a tile of traced points: what a path records past its first vertex,
//! and its replay for every point of the tile.

use super::*;

/// What a path adds past its first hidden vertex, kept to be shared by the traced points of a tile: where
/// its target's histogram starts in a traced point's histograms, optical path (jitter included) in bins
/// from the capture's start (a replay then shifts it without a division per entry), value, and the
/// direction that left the first vertex on the way to it (for the phase function's ratio there), and
/// the medium scattering events its value holds.
pub(super) struct Tail {
    pub(super) hist0: usize,
    pub(super) bin: f64,
    pub(super) value: f64,
    pub(super) scat: i32,
    pub(super) w: DVec3,
}

/// The bin that entry `tl`, shifted by `shift` bins, lands in, if inside the `end` bins.
#[inline(always)]
fn shifted_bin(tl: &Tail, shift: f64, end: f64) -> Option<usize> {
    let x = tl.bin + shift;
    // SAFETY: 0 ≤ x < bins ≤ u32::MAX (NaN fails the test; scene resolution bounds bins), so truncation
    // to u32 is exact. To usize the conversion needs a fix-up for values past i64::MAX, on the
    // renderer's hottest loop (docs/renderer-sampling.md).
    if x >= 0.0 && x < end {
        Some(unsafe { x.to_int_unchecked::<u32>() } as usize)
    } else {
        None
    }
}

/// Adds `tail` to one traced point's histograms `hists` (of `bins` each), scaled, shifted by `shift`
/// bins, entry e times `weight(e)`. Every entry of every path is replayed once per point of its tile,
/// which makes this the renderer's innermost loop: one conversion and one bounds check per entry.
pub(super) fn replay(
    bins: usize,
    hists: &mut [f32],
    tail: &[Tail],
    scale: f64,
    shift: f64,
    weight: impl Fn(usize) -> f64,
) {
    let end = bins as f64;
    for (e, tl) in tail.iter().enumerate() {
        if let Some(bin) = shifted_bin(tl, shift, end) {
            hists[tl.hist0 + bin] += (tl.value * scale * weight(e)) as f32;
        }
    }
}

/// [`replay`] for an albedo sweep: each bin of `hists` holds one value per albedo, side by side, and
/// entry e adds `factors[e · albedos + j]` times its value to albedo j (one cache line per entry, as in
/// a plain render, rather than one per albedo).
pub(super) fn replay_sweep(
    bins: usize,
    hists: &mut [f32],
    tail: &[Tail],
    (scale, shift): (f64, f64),
    factors: &[f64],
    weight: impl Fn(usize) -> f64,
) {
    let n = factors.len() / tail.len();
    let end = bins as f64;
    for (e, tl) in tail.iter().enumerate() {
        if let Some(bin) = shifted_bin(tl, shift, end) {
            let v = tl.value * scale * weight(e);
            let at = (tl.hist0 + bin) * n;
            let f = &factors[e * n..(e + 1) * n];
            for (o, f) in hists[at..at + n].iter_mut().zip(f) {
                *o += (v * f) as f32;
            }
        }
    }
}

/// The leg from a traced point to a path's first vertex, in the measure of that vertex (volume or area):
/// its integrand `f`, the optical path `opl` to it and the direction `d`.
#[derive(Clone, Copy)]
pub(super) struct Leg {
    pub(super) f: f64,
    pub(super) opl: f64,
    pub(super) d: DVec3,
}

/// A path's first hidden vertex: a medium vertex (`normal` None) or a surface one (its normal facing the
/// arriving path).
#[derive(Clone, Copy)]
pub(super) struct First {
    pub(super) y: DVec3,
    pub(super) normal: Option<DVec3>,
}

/// Where a path's contributions go: the traced point's histograms (`unit` values at `origin · unit`
/// in the work unit's buffer), or, while `recording`, the tail list shared with the rest of the tile.
pub(super) struct Sink<'o> {
    pub(super) out: &'o mut [f32],
    /// Each albedo of a sweep over the medium's own (one value per bin each, side by side).
    pub(super) ratios: &'o [f64],
    /// Length of one traced point's histograms, and the point now traced.
    pub(super) unit: usize,
    pub(super) origin: usize,
    /// Whether the unit is a tile of more than one traced point.
    pub(super) share: bool,
    pub(super) recording: bool,
    /// Whether the techniques now running leave from the first vertex (each sets `w`).
    pub(super) at_first: bool,
    pub(super) w: DVec3,
    pub(super) first: Option<First>,
    pub(super) tail: Vec<Tail>,
}

/// `share_tail`'s buffers, reused from path to path: each origin's leg to the first vertex and, with an
/// anisotropic phase function, one row of the origins' shares per distinct direction leaving that vertex,
/// with each tail entry's row; in an albedo sweep, each entry's factor per albedo.
#[derive(Default)]
pub(super) struct TileScratch {
    legs: Vec<Option<Leg>>,
    shares: Vec<f64>,
    row: Vec<usize>,
    factors: Vec<f64>,
}

impl Tracer<'_> {
    /// The first leg from origin `o` to the first vertex `f`; None where `o` cannot reach it (behind,
    /// occluded, outside the medium along the leg).
    pub(super) fn leg(&self, o: &Endpoint, f: &First) -> Option<Leg> {
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
                let (m0, m1) = m.clip(o.p, w, t_hit)?;
                if t < m0 || t > m1 {
                    return None;
                }
                let seg = Segment {
                    o: o.p,
                    d: w,
                    t0: m0,
                    t1: t,
                };
                let tr = m.transmittance(&[seg]);
                let opl = o.extra_m + t + m.extra_path_m(t - m0);
                Some(Leg {
                    f: g * tr * m.sigma_s_at(f.y),
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
    ///
    /// With an anisotropic phase function the weights also cover the direction w that leaves the first
    /// vertex: each origin k draws it with (or, for a connection, evaluates) its own p(d_k·w), so origin i
    /// takes f_i·p(d_i·w) / Σ_k f_k·p(d_k·w) of each entry. Swapping the source's phase for origin i's
    /// instead would multiply entries by p(d_i·w)/p(d_src·w), up to 180× at g = 0.7.
    pub(super) fn share_tail(
        &self,
        origins: &[Endpoint],
        src: usize,
        sink: &mut Sink,
        scratch: &mut TileScratch,
    ) {
        let Some(first) = sink.first else { return };
        let TileScratch {
            legs,
            shares,
            row,
            factors,
        } = scratch;
        legs.clear();
        legs.extend(origins.iter().map(|o| self.leg(o, &first)));
        let sum_f: f64 = legs.iter().flatten().map(|l| l.f).sum();
        let (t, unit) = (&self.scene.capture.time, sink.unit);
        // A sweep's albedo j scales an entry by ratios[j]^(its scattering events); a plain render keeps
        // the loops below free of it. A sweep of one albedo is not plain: its ratio is not 1.
        let nr = sink.ratios.len();
        let plain = sink.ratios == [1.0];
        if !plain {
            factors.clear();
            for tl in &sink.tail {
                factors.extend(sink.ratios.iter().map(|r| r.powi(tl.scat)));
            }
        }
        let Some(own) = legs[src].filter(|l| l.f > 0.0) else {
            // Rounding kept the source from re-joining its own vertex (a grazing or boundary leg): the
            // tail stays the source's own, unshared.
            let hist = &mut sink.out[src * unit * nr..(src + 1) * unit * nr];
            return if plain {
                replay(t.bins, hist, &sink.tail, 1.0, 0.0, |_| 1.0)
            } else {
                replay_sweep(t.bins, hist, &sink.tail, (1.0, 0.0), factors, |_| 1.0)
            };
        };
        let phase = self
            .medium()
            .map(|m| m.phase)
            .filter(|p| first.normal.is_none() && !matches!(p, crate::medium::Phase::Isotropic));
        let n = legs.len();
        if let Some(p) = phase {
            // Entries after the first one a path adds past its first vertex leave it in the same
            // direction: they share one row.
            shares.clear();
            row.clear();
            let mut last = None;
            for tl in &sink.tail {
                if last != Some(tl.w) {
                    last = Some(tl.w);
                    let start = shares.len();
                    shares.extend(
                        legs.iter()
                            .map(|l| l.map_or(0.0, |l| l.f * p.eval(l.d.dot(tl.w)))),
                    );
                    let tile: f64 = shares[start..].iter().sum();
                    shares[start..].iter_mut().for_each(|v| *v /= tile);
                }
                row.push(shares.len() / n - 1);
            }
        }
        for (i, leg) in legs.iter().enumerate() {
            let Some(leg) = leg else { continue };
            let shift = (leg.opl - own.opl) / t.bin_width_m;
            let hist = &mut sink.out[i * unit * nr..(i + 1) * unit * nr];
            let (tail, scale) = (&sink.tail, leg.f / sum_f);
            let share = |e: usize| shares[row[e] * n + i];
            match (phase, plain) {
                (Some(_), true) => replay(t.bins, hist, tail, 1.0, shift, share),
                (Some(_), false) => replay_sweep(t.bins, hist, tail, (1.0, shift), factors, share),
                (None, true) => replay(t.bins, hist, tail, scale, shift, |_| 1.0),
                (None, false) => replay_sweep(t.bins, hist, tail, (scale, shift), factors, |_| 1.0),
            }
        }
    }
}
