//! Participating media: what the integrator asks of one (pbrt-v4's seam) — where it is, its
//! transmittance along segments, free-flight distances, σs and phase function at a point — answered
//! per kind of density, one file each.

mod grid;
mod height;
mod homogeneous;
mod phase;
mod tracking;

use crate::geometry::Aabb;
use murk_core::DVec3;

pub use grid::{density_fingerprint, Grid};
pub use height::{Height, MAX_HEIGHT_SCALE_M, MIN_HEIGHT_SCALE_M};
pub use homogeneous::Homogeneous;
pub use phase::Phase;

/// How a medium's extinction varies over its box. Free flights in the heterogeneous kinds are delta
/// tracked against one majorant for the whole medium (the largest σt in it); every kind's optical
/// depth is exact.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    Homogeneous(Homogeneous),
    Grid(Grid),
    Height(Height),
}

/// A medium filling `region`; boundaries are index-matched (no refraction), and `ior` only stretches
/// optical paths inside it. Albedo and phase function are the same at every point.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub kind: Kind,
    pub albedo: f64,
    pub phase: Phase,
    pub ior: f64,
    pub region: Aabb,
}

/// The piece `t0..t1` of the ray `o + t·d` (d unit), inside the medium's box.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    pub o: DVec3,
    pub d: DVec3,
    pub t0: f64,
    pub t1: f64,
}

impl Segment {
    pub fn len_m(&self) -> f64 {
        self.t1 - self.t0
    }
}

impl Medium {
    /// The part `(t0, t1)` of the ray `o + t·d`, t ∈ [0, t_max], inside the medium's box.
    pub fn clip(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64)> {
        self.region.clip(o, d, t_max)
    }

    /// Extinction σt (1/m) at `p`, a point of the medium.
    #[inline]
    pub fn sigma_t_at(&self, p: DVec3) -> f64 {
        match &self.kind {
            Kind::Homogeneous(h) => h.sigma_t_per_m,
            Kind::Grid(g) => g.sigma_t_at(p),
            Kind::Height(h) => h.sigma_t_at(p),
        }
    }

    /// The largest σt anywhere in the medium (1/m).
    pub fn majorant(&self) -> f64 {
        match &self.kind {
            Kind::Homogeneous(h) => h.sigma_t_per_m,
            Kind::Grid(g) => g.majorant_per_m,
            // Densest at the box's floor.
            Kind::Height(h) => h.sigma_t_floor_per_m,
        }
    }

    /// Scattering coefficient σs (1/m) at `p`, a point of the medium.
    pub fn sigma_s_at(&self, p: DVec3) -> f64 {
        self.sigma_t_at(p) * self.albedo
    }

    /// Whether it scatters light (not only absorbs it).
    pub fn scatters(&self) -> bool {
        self.majorant() * self.albedo > 0.0
    }

    /// The share of target-side draws in the phase function's lobe where a scene leaves
    /// `render.target_lobe` unset. In forward-scattering media a connection through a medium vertex
    /// peaks where the vertex lies on the line between its neighbours, so strongly forward media draw
    /// that lobe most of the time; at g 0.3 a large share raised the variance (the measurements are in
    /// docs/renderer-sampling.md).
    pub fn default_target_lobe(&self) -> f64 {
        match self.phase {
            _ if !self.scatters() => 0.0,
            Phase::HenyeyGreenstein { g } if g >= 0.6 => 0.9,
            Phase::HenyeyGreenstein { g } if g >= 0.3 => 0.5,
            _ => 0.0,
        }
    }

    /// The phase-angle distances where a scene leaves `render.phase_distances` and
    /// `render.target_phase_distances` unset: draws per segment and target, and the share of target-side
    /// distances drawn so. In strongly forward media a connection's phase value through the vertex
    /// varies by orders of magnitude along a segment, which equiangular distances ignore; below g 0.6 they were
    /// not measured (docs/renderer-sampling.md).
    pub fn default_phase_distances(&self) -> (u32, f64) {
        match self.phase {
            Phase::HenyeyGreenstein { g } if g >= 0.6 && self.scatters() => (2, 0.5),
            _ => (0, 0.0),
        }
    }

    /// The share of directions leaving the hidden geometry in the phase function's lobe toward the
    /// target where a scene leaves `render.surface_lobe` unset: in strongly forward media the light that
    /// reaches a wall point after the object left it heading for that point, which the cosine lobe finds
    /// rarely (docs/renderer-sampling.md).
    pub fn default_surface_lobe(&self) -> f64 {
        match self.phase {
            Phase::HenyeyGreenstein { g } if g >= 0.6 && self.scatters() => 0.5,
            _ => 0.0,
        }
    }

    /// Spindle draws per medium vertex and target (`Tracer::draw_spindle`) where a scene does not set
    /// them: in strongly forward media a fog path's connection through a vertex y between a medium
    /// vertex x and the target peaks where x, y and the target line up, and the path side's and the
    /// target side's densities there both vanish in proportion to y's distance from that line.
    pub fn default_spindle_draws(&self) -> u32 {
        match self.phase {
            Phase::HenyeyGreenstein { g } if g >= 0.6 && self.scatters() => 1,
            _ => 0,
        }
    }

    /// The share of directions leaving a medium vertex, on a path's way back from the hidden geometry, in
    /// the phase function's lobe toward the target where a scene leaves `render.medium_lobe` unset: in
    /// strongly forward media a deep connection's phase value is large only where the segment before it
    /// heads for the target, which the phase lobe around the arriving direction finds rarely
    /// (docs/renderer-sampling.md).
    pub fn default_medium_lobe(&self) -> f64 {
        match self.phase {
            Phase::HenyeyGreenstein { g } if g >= 0.6 && self.scatters() => 0.3,
            _ => 0.0,
        }
    }

    /// The optical depth ∫σt along all of `segs`, exactly.
    #[inline]
    fn optical_depth(&self, segs: &[Segment]) -> f64 {
        match &self.kind {
            // One product of the summed lengths: the renders before the seam rounded it so.
            Kind::Homogeneous(h) => h.sigma_t_per_m * segs.iter().map(Segment::len_m).sum::<f64>(),
            Kind::Grid(g) => segs.iter().map(|s| g.optical_depth(s)).sum(),
            Kind::Height(h) => segs.iter().map(|s| h.optical_depth(s)).sum(),
        }
    }

    /// Fraction of light that crosses all of `segs` unscattered, exactly (closed forms, or a walk
    /// over a grid's cells). The balance weights (the free-flight density, the shared tails' legs)
    /// need the exact value; ratio tracking on the connections alone saved 5 % of the time and would
    /// fall to 0 or 1 through a cell at the majorant (docs/media-heterogeneous.md).
    #[inline]
    pub fn transmittance(&self, segs: &[Segment]) -> f64 {
        (-self.optical_depth(segs)).exp()
    }

    /// The transmittance along `seg` and the density σt·T of a free flight from `seg.t0` scattering at
    /// its end, exactly: the weight that free flight takes in the balance heuristic against the
    /// integrator's other distance techniques.
    #[inline]
    pub fn flight(&self, seg: Segment) -> (f64, f64) {
        let tr = self.transmittance(&[seg]);
        (tr, self.sigma_t_at(seg.o + seg.d * seg.t1) * tr)
    }

    /// Where a free flight along `seg` from `seg.t0` scatters, drawn from the density of
    /// [`Medium::flight`]; a value ≥ `seg.t1` means it crosses the segment (with probability equal to
    /// the transmittance).
    pub fn sample_flight(&self, seg: Segment, rand: &mut impl FnMut() -> f64) -> f64 {
        match &self.kind {
            Kind::Homogeneous(h) => seg.t0 + h.sample_distance(rand()),
            Kind::Grid(_) | Kind::Height(_) => {
                tracking::delta(seg, self.majorant(), |p| self.sigma_t_at(p), rand)
            }
        }
    }

    /// Optical path that `len_m` of geometric path inside the medium adds beyond `len_m` itself.
    pub fn extra_path_m(&self, len_m: f64) -> f64 {
        (self.ior - 1.0) * len_m
    }
}
