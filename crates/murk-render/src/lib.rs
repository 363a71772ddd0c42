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
//!
//! ```
//! use murk_render::{Overrides, Plan, RenderOptions, Scene};
//! use std::{path::Path, time::Duration};
//!
//! // A 0.5 m square 1 m behind a 1 m wall, scanned confocally on 4² points, no medium.
//! let text = r#"
//! [relay]
//! kind = "wall"
//! size = [1.0, 1.0]
//! [capture]
//! kind = "confocal"
//! grid = [4, 4]
//! bins = 400
//! bin_width = 0.01
//! start = 0.0
//! laser_position = [0.0, 0.0, 0.5]
//! spad_position = [0.0, 0.0, 0.5]
//! [[object]]
//! shape = "quad"
//! center = [0.0, 0.0, 1.0]
//! size = [0.5, 0.5]
//! "#;
//! let scene = Scene::from_str(text, Path::new("square.toml"), &Overrides::default())?;
//! let opt = RenderOptions {
//!     spp: 16,
//!     seed: 1,
//!     shard: None,
//!     checkpoint: None,
//!     checkpoint_every: Duration::ZERO,
//! };
//! let cap = Plan::new(&scene).render(&opt, &|_, _| {})?;
//! // The first point's light comes back between its shortest round trip to the square (to its
//! // nearest corner, 2 × 1.016 m) and its longest (to the far corner, 2 × 1.34 m).
//! let h = &cap.h[..cap.time.bins];
//! let path_m = |bin: usize| cap.time.start_m + (bin as f64 + 0.5) * cap.time.bin_width_m;
//! let lit: Vec<f64> = (0..h.len()).filter(|&b| h[b] > 0.0).map(path_m).collect();
//! assert!(!lit.is_empty() && lit.iter().all(|p| (2.02..2.69).contains(p)), "{lit:?}");
//! # Ok::<(), murk_core::Error>(())
//! ```

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
pub use medium::{
    density_fingerprint, Grid, Height, Homogeneous, Kind as MediumKind, Medium, Phase, Segment,
    MAX_HEIGHT_SCALE_M, MIN_HEIGHT_SCALE_M,
};
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
