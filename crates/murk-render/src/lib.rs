//! murk's transient renderer: time-resolved volumetric path tracing of hidden scenes behind a relay wall
//! or a diffuser, optionally inside a scattering medium: homogeneous, a density grid or height fog
//! (`docs/media-heterogeneous.md`).
//!
//! Sampling (see `integrator`): deterministic connections from every hidden vertex to the wall points
//! of the other side (the laser spot is a point emitter, the SPAD point a point sensor),
//! hidden-geometry sampling of the first direction mixed with cosine sampling (one-sample MIS with the
//! exact mixture pdf), free-flight (delta tracking in heterogeneous media) and Henyey–Greenstein
//! sampling, target-side sampling of medium vertices from the wall points, phase-angle distances in
//! strongly forward media (the connection's scattering angle drawn after the phase function), and
//! (opt-in) equiangular and stratified time-window distances toward the wall points on every medium
//! segment, all combined with free flight by the balance heuristic; Russian roulette (surfaces only) and a depth cap.
//! For many laser points and one SPAD point paths start at the laser points (reciprocity), so every
//! vertex makes one connection instead of one per laser point.

pub mod bench;
mod geometry;
pub mod hash;
mod integrator;
mod medium;
mod overrides;
mod render;
mod scene;
mod truth;

pub use geometry::{Aabb, Geometry, Object, Shape};
pub use integrator::{Endpoint, Sampler, Tracer};
pub use medium::{Grid, Height, Homogeneous, Kind as MediumKind, Medium, Phase, Segment};
pub use overrides::{Overrides, Spelling};
pub use render::{
    check_shard, checkpoint_interval, checkpoint_path, fingerprint, merge, render_key,
    render_outputs, scene_info, sweep_output, time_budget, Outputs, Plan, RenderOptions,
    StoredRender,
};
pub use scene::{
    CaptureDef, CaptureKindDef, CaptureSpec, MediumDef, MediumKindDef, ObjectDef, Relay, RelayDef,
    RelayKind, RenderDef, Scene, SceneFile, TraceFrom,
};
