//! The scene file's TOML schema: every field a scene file may hold, with its defaults. Validation
//! and resolution happen in the parent module.

use serde::Deserialize;
use std::path::PathBuf;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub relay: RelayDef,
    pub capture: CaptureDef,
    #[serde(default)]
    pub render: RenderDef,
    pub medium: Option<MediumDef>,
    #[serde(default, rename = "object")]
    pub objects: Vec<ObjectDef>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RelayKind {
    /// A reflective relay wall: laser and SPAD on the hidden side.
    Wall,
    /// A transmissive diffuser: laser and SPAD outside (z < 0), light crosses it both ways.
    Diffuser,
}

/// The relay surface: a `size[0] × size[1]` rectangle centred at the origin in the plane z = 0; the
/// hidden scene is at z > 0.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RelayDef {
    pub kind: RelayKind,
    #[serde(rename = "size")]
    pub size_m: [f64; 2],
    /// Lambertian albedo that hidden light meets when it returns to the relay (default: wall 1, diffuser 0,
    /// i.e. light reaching a diffuser leaves the scene).
    pub albedo: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CaptureKindDef {
    /// Laser grid + one SPAD point (the paper's synthetic data).
    LaserGrid,
    Confocal,
    /// One laser point + a sensor grid (y-tal's "single").
    Single,
    /// Every grid point as laser × every grid point as sensor.
    Exhaustive,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureDef {
    pub kind: CaptureKindDef,
    /// Points along x and y.
    pub grid: [usize; 2],
    /// Grid extent (m); default: the whole relay. Points are pixel centres, as `tal render` places them.
    #[serde(rename = "extent")]
    pub extent_m: Option<[f64; 2]>,
    #[serde(default)]
    #[serde(rename = "center")]
    pub center_m: [f64; 2],
    /// The one laser point of a `single` capture (default: the relay centre).
    #[serde(rename = "laser_point")]
    pub laser_point_m: Option<[f64; 2]>,
    /// The one SPAD point of a `laser-grid` capture (default: the relay centre).
    #[serde(rename = "spad_point")]
    pub spad_point_m: Option<[f64; 2]>,
    pub bins: usize,
    /// Bin width in metres of optical path.
    #[serde(rename = "bin_width")]
    pub bin_width_m: f64,
    /// Optical path at the start of bin 0 (m).
    #[serde(default)]
    #[serde(rename = "start")]
    pub start_m: f64,
    /// Whether times include laser device → laser point and SPAD point → SPAD device.
    #[serde(default)]
    pub account_first_and_last_bounces: bool,
    #[serde(rename = "laser_position")]
    pub laser_position_m: Option<[f64; 3]>,
    #[serde(rename = "spad_position")]
    pub spad_position_m: Option<[f64; 3]>,
    /// Apply the visible side's radiometry: the projector's cos/d² irradiance at each laser point
    /// and the SPAD aperture's cos/d² collection from each sensor point (needs both positions).
    /// Off: H between wall points, murk's and y-tal's convention.
    #[serde(default)]
    pub device_radiometry: bool,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum TraceFrom {
    /// From whichever side has more points, connecting every vertex to the other side (reciprocity).
    #[default]
    Auto,
    Laser,
    Sensor,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDef {
    /// Paths per traced point (per laser point for a laser grid); `--spp` overrides it.
    pub spp: u64,
    /// Most hidden vertices (surface or medium) on a path; 1 = third-bounce NLOS only.
    pub max_depth: u32,
    /// Russian roulette from this many hidden vertices on. Default: 5 where no medium scatters, else none
    /// (see the integrator).
    pub rr_depth: Option<u32>,
    /// Standard deviation (m of path) of a Gaussian SPAD timing jitter added before binning; 0 = box.
    #[serde(rename = "time_jitter")]
    pub time_jitter_m: f64,
    /// Probability of sampling the first direction toward the hidden geometry (mixed with cosine sampling).
    /// Default: 1 where no medium scatters (every first direction that contributes then meets the hidden
    /// geometry), else 0.8; below 1 where a medium scatters (first vertices lie in every direction).
    pub hidden_geometry_sampling: Option<f64>,
    /// Probability that a path goes on past its first hidden vertex (weighted by its inverse). Default: 0.1
    /// where no medium scatters (the direct return needs only the first vertex; see the integrator), else 1.
    pub first_vertex_survival: Option<f64>,
    /// Medium vertices also connect to the other side through a uniform point of the hidden geometry
    /// (next-event estimation of the object return after scattering), MIS-combined with the phase direction.
    pub object_connections: bool,
    /// Extra directions per path from the traced point toward uniform points of the hidden geometry, each
    /// only connected where it first meets a surface (the direct object return), MIS-combined with the
    /// path's own first direction. 0: off.
    pub object_draws: u32,
    /// Equiangular sampling of medium points toward the wall points, MIS-combined with free flight. Off by
    /// default: with target-side sampling and without Russian roulette it cost more than it removed
    /// (see the integrator).
    pub equiangular: bool,
    /// Medium distances per segment and target drawn so the connected path lands uniformly in the capture's
    /// time window, stratified (MIS-combined with equiangular and free flight); used where the medium's ior
    /// is 1. 0: off.
    pub time_samples: u32,
    /// `time_samples` for the segment leaving the traced point (default: `time_samples`): its medium
    /// vertices are the single scattering of each traced point, which no tile shares.
    pub first_time_samples: Option<u32>,
    /// Medium vertices also drawn from the wall points' side (cosine lobe, or `target_lobe`; equiangular
    /// toward the path vertex), MIS-combined with the path side: removes the fireflies of fog paths passing
    /// near a wall point.
    pub target_sampling: bool,
    /// Segments starting within `target_split_radius` (m) of a target get up to this many target-side
    /// draws toward it (∝ radius/distance; counted as n·pdf in the balance weights). 0 or 1: off.
    pub target_split: u32,
    /// Distance (m) from a target within which `target_split` applies; 0: off.
    #[serde(rename = "target_split_radius")]
    pub target_split_radius_m: f64,
    /// Probability that a target-side draw leaves the target in the phase function's lobe around the
    /// direction to the path vertex instead of the target's cosine lobe: in forward-scattering fog the
    /// connections through a vertex peak where the vertex lies between the target and the path.
    /// Default: 0.5 where the phase function is Henyey–Greenstein with g ≥ 0.3, else 0.
    pub target_lobe: Option<f64>,
    /// Medium distances per segment and target drawn in the scattering angle that the connection to the
    /// target turns through, after the phase function (MIS-combined with the other distances). Default:
    /// 2 where the phase function is Henyey–Greenstein with g ≥ 0.6, else 0.
    pub phase_distances: Option<u32>,
    /// Share of the target-side draws' distances drawn so toward the path vertex, instead of
    /// equiangular, in [0, 1]. Default: 0.5 where g ≥ 0.6, else 0.
    pub target_phase_distances: Option<f64>,
    /// Probability that a path leaves a hidden-geometry vertex in the phase function's lobe around the
    /// direction to the target instead of the surface's cosine lobe (one target only): in forward fog
    /// the light that returns to a wall point leaves the object heading for it. Default: 0.5 where g ≥
    /// 0.6, else 0.
    pub surface_lobe: Option<f64>,
    /// Medium vertices per medium vertex and target drawn around the line between them (the forward
    /// "spindle" where both connections' phase values peak), MIS-combined with the path side and the
    /// target side. Default: 1 where g ≥ 0.6, else 0.
    pub spindle_draws: Option<u32>,
    /// Probability that a path on its way back from the hidden geometry leaves a medium vertex in the
    /// phase function's lobe around the direction to the target instead of around its arriving direction
    /// (one target only; not at a tile's shared first vertex): in forward fog a connection's phase value
    /// is large only where the segment heads for the target. Default: 0.3 where g ≥ 0.6, else 0.
    pub medium_lobe: Option<f64>,
    /// Side (in grid points) of the tiles of traced points that share their paths past the first hidden
    /// vertex, where a medium scatters and every traced point has the same targets (see the integrator);
    /// at most 16. 0 or 1: off.
    pub share_tile: u32,
    pub trace_from: TraceFrom,
}

impl Default for RenderDef {
    fn default() -> Self {
        RenderDef {
            spp: 256,
            max_depth: 8,
            rr_depth: None,
            time_jitter_m: 0.0,
            hidden_geometry_sampling: None,
            first_vertex_survival: None,
            object_connections: true,
            object_draws: 0,
            equiangular: false,
            time_samples: 0,
            first_time_samples: None,
            target_sampling: true,
            target_split: 64,
            target_split_radius_m: 0.5,
            target_lobe: None,
            phase_distances: None,
            target_phase_distances: None,
            surface_lobe: None,
            spindle_draws: None,
            medium_lobe: None,
            share_tile: 4,
            trace_from: TraceFrom::Auto,
        }
    }
}

/// A participating medium filling the box `min`..`max` (e.g. the half-space behind the diffuser clipped
/// to a box, or the inside of a room): homogeneous, or with its extinction scaled by a density that
/// varies over the box (docs/media-heterogeneous.md).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumDef {
    /// How the extinction varies over the box (default: homogeneous).
    #[serde(default)]
    pub kind: MediumKindDef,
    /// Extinction coefficient μt (1/m); where a density varies, σt(x) = density(x) × μt.
    #[serde(rename = "mu_t")]
    pub mu_t_per_m: f64,
    /// Single-scattering albedo α = μs/μt, the same at every point.
    pub albedo: f64,
    /// Henyey–Greenstein anisotropy, |g| ≤ 0.9999.
    #[serde(default)]
    pub g: f64,
    /// Refractive index: optical path = ior × geometric path inside the medium (no refraction at its boundary).
    #[serde(default = "one")]
    pub ior: f64,
    #[serde(rename = "min")]
    pub min_m: [f64; 3],
    #[serde(rename = "max")]
    pub max_m: [f64; 3],
    /// kind = "grid": a `.npy` of densities, shape (nx, ny, nz), relative to the scene file; its cells
    /// split the box evenly, cell [0, 0, 0] at `min`.
    pub density: Option<PathBuf>,
    /// kind = "height": the height (m) over which the density falls by e, from 1 at the box's floor
    /// (y = min.y; y is up).
    #[serde(rename = "height_scale")]
    pub height_scale_m: Option<f64>,
}

/// How a medium's extinction varies over its box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MediumKindDef {
    /// μt everywhere.
    #[default]
    Homogeneous,
    /// μt × the density grid of `density`.
    Grid,
    /// μt × exp(−(y − min.y)/height_scale): fog settling toward the floor.
    Height,
}

fn one() -> f64 {
    1.0
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "shape", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ObjectDef {
    /// A rectangle `size` centred at `center` with normal `normal` (default: facing the relay) and `up`.
    Quad {
        #[serde(rename = "center")]
        center_m: [f64; 3],
        #[serde(rename = "size")]
        size_m: [f64; 2],
        #[serde(default = "toward_relay")]
        normal: [f64; 3],
        #[serde(default = "y_up")]
        up: [f64; 3],
        #[serde(default = "one")]
        albedo: f64,
        /// A label for ground truth and reports (default: `object[i] (shape)`).
        name: Option<String>,
    },
    /// An axis-aligned box; `omit` drops faces ("-x", "+x", "-y", "+y", "-z", "+z"), e.g. a room's relay side.
    Box {
        #[serde(rename = "min")]
        min_m: [f64; 3],
        #[serde(rename = "max")]
        max_m: [f64; 3],
        #[serde(default)]
        omit: Vec<String>,
        #[serde(default = "one")]
        albedo: f64,
        /// A label for ground truth and reports (default: `object[i] (shape)`).
        name: Option<String>,
    },
    /// y-tal's planar Z letter (0.8 m × 0.8 m at `scale` 1) in the plane z = center.z.
    ZLetter {
        #[serde(rename = "center")]
        center_m: [f64; 3],
        #[serde(default = "one")]
        scale: f64,
        #[serde(default = "one")]
        albedo: f64,
        /// A label for ground truth and reports (default: `object[i] (shape)`).
        name: Option<String>,
    },
    /// A Wavefront OBJ mesh (path relative to the scene file), scaled then translated.
    Mesh {
        file: PathBuf,
        #[serde(default = "one")]
        scale: f64,
        #[serde(default)]
        #[serde(rename = "translate")]
        translate_m: [f64; 3],
        #[serde(default = "one")]
        albedo: f64,
        /// A label for ground truth and reports (default: `object[i] (shape)`).
        name: Option<String>,
    },
}

fn toward_relay() -> [f64; 3] {
    [0.0, 0.0, -1.0]
}
fn y_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}
