//! What names a render: its key (everything that determines its numbers, compared by checkpoints and
//! the study), the key's short fingerprint, and the `scene_info` its captures carry.

use super::Plan;
use crate::scene::Scene;
use murk_core::Capture;

impl<'a> Plan<'a> {
    /// The `scene_info` of each capture this plan renders (one per albedo of a sweep): what a
    /// finished capture must hold to be this render's.
    pub fn scene_infos(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> Vec<String> {
        if self.albedos.is_empty() {
            return vec![scene_info(self.scene, spp, seed, shard)];
        }
        // The sweep's lines go before the shard line, which merging strips; the scene's own text (in
        // the info's head) may hold anything, so the head is rendered without a shard.
        let head = scene_info(self.scene, spp, seed, None);
        let shard = shard.map_or(String::new(), shard_line);
        self.albedos
            .iter()
            .map(|a| {
                format!(
                    "{head}{SWEEP_KEY}{:?}\n{ALBEDO_KEY}{a:?}\n{shard}",
                    self.albedos
                )
            })
            .collect()
    }

    /// One empty capture per albedo, each with its `scene_info`.
    pub(super) fn empty_captures(
        &self,
        spp: u64,
        seed: u64,
        shard: Option<(usize, usize)>,
    ) -> Vec<Capture> {
        self.scene_infos(spp, seed, shard)
            .into_iter()
            .map(|info| self.empty_capture(info))
            .collect()
    }

    /// The render key of this plan's renders: [`render_key`], with the albedos of a sweep.
    pub fn key(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
        let key = render_key(self.scene, spp, seed, shard);
        if self.albedos.is_empty() {
            key
        } else {
            format!("{key}\nrender.albedo_sweep = {:?}", self.albedos)
        }
    }
}

/// YAML for the capture's `scene_info`: the scene file, spp, seed, murk version, the overrides and the
/// resolved scene (and the shard of a part).
pub fn scene_info(scene: &Scene, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
    let mut s = format!(
        "generator: murk render\nmurk_version: {}\nscene_file: {:?}\nspp: {spp}\nseed: {seed}\n",
        env!("CARGO_PKG_VERSION"),
        scene.file_name
    );
    if !scene.overrides.is_empty() {
        s.push_str("overrides:\n");
        for o in &scene.overrides {
            s.push_str(&format!("- {o:?}\n"));
        }
    }
    s.push_str("scene: |\n");
    for line in scene.source.lines() {
        s.push_str("  ");
        s.push_str(line);
        s.push('\n');
    }
    if let Some(shard) = shard {
        s.push_str(&shard_line(shard));
    }
    s
}

pub(super) const SHARD_KEY: &str = "shard: ";

/// The last line of a shard's `scene_info`, which merging strips.
pub(super) fn shard_line((i, n): (usize, usize)) -> String {
    format!("{SHARD_KEY}{i}/{n}\n")
}

/// A sweep's albedos, and the one a capture of it has, in its `scene_info`.
const SWEEP_KEY: &str = "albedo_sweep: ";
const ALBEDO_KEY: &str = "albedo: ";

/// Everything that determines the rendered numbers, as `key = value` lines: the resolved scene, spp,
/// seed, shard and murk version. Two renders with the same key give the same bytes.
pub fn render_key(scene: &Scene, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
    let shard = shard.map_or_else(|| "none".to_string(), |(i, n)| format!("{i}/{n}"));
    format!(
        "{}\nrender.spp_used = {spp}\nrender.seed = {seed}\nrender.shard = {shard}\nrender.estimator = {ESTIMATOR_REVISION}\nmurk_version = {}",
        scene.resolved,
        env!("CARGO_PKG_VERSION")
    )
}

/// The estimator's revision, raised whenever a scene, spp and seed render other bytes than before (2:
/// anisotropic fog's shared-tail weights and target lobe), so that checkpoints and the study's finished
/// renders made before are refused or rendered again rather than mixed in. A change that moves only
/// some scenes' bytes names itself in those scenes' resolved key instead, so the others keep theirs
/// (the forward lobes' default shares: `render.target_lobe_default`, `render.surface_lobe_default`,
/// `render.medium_lobe_default`, set in `Scene::load`).
pub const ESTIMATOR_REVISION: u32 = 2;

/// FNV-1a, 64 bits: a short name for a render key.
pub fn fingerprint(key: &str) -> u64 {
    crate::hash::fnv1a(key.bytes())
}
