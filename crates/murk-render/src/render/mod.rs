//! Work units, parallel rendering, checkpoints, shards, merging and assembling checkpoint parts.
//!
//! A work unit is a tile of traced wall points (laser points when tracing from lasers; one point unless
//! they share path tails, `share_tile`) with its own PCG stream (seed, unit index), rendered by one
//! thread into histograms nobody else writes. So the result does not depend on the thread count, on how
//! units are sharded, or on an interruption and `--resume`.
//!
//! One job per module: `job` maps units to wall points and histograms, `run` renders them in
//! parallel, `checkpoint` keeps finished units on disk, `shard` splits and merges a render,
//! `provenance` names a render (its key and `scene_info`) and `store` is the one render that writes
//! its captures, as `murk render`, `murk.render` and the study run it.

mod checkpoint;
mod job;
mod provenance;
mod run;
mod shard;
mod store;

pub use checkpoint::{checkpoint_interval, checkpoint_path};
pub use job::Plan;
pub use provenance::{fingerprint, render_key, scene_info};
pub use run::{time_budget, RenderOptions};
pub use shard::{check_shard, merge};
pub use store::{render_outputs, sweep_output, Outputs, StoredRender};
