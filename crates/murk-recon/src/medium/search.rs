//! The depth range chosen from where the signal focuses.
//!
//! In a medium the brightest voxels of a reconstruction over the whole reach are near the wall: the
//! medium's response and its noise are strongest there, and intensity falls steeply with depth. What
//! marks a hidden surface is not brightness but focus: on its plane a few voxels stand far above the
//! plane's own spread, while a plane lit by the medium is bright everywhere. So each depth plane is
//! scored by how far its brightest voxel stands above the plane's median, in units of the plane's
//! median absolute deviation, and the volume is cut around the best plane.

use murk_core::{Axis, Reconstruction, Volume};

/// Half the depth range kept around the best plane (m): the study's volumes span 1 m around the Z.
pub const HALF_RANGE_M: f64 = 0.5;
/// The search reconstructs at most this many planes over the whole reach: its cost is in its planes,
/// and a surface's focus spans more than a plane at that spacing (docs/benchmarks.md).
pub const SEARCH_PLANES: usize = 128;
/// The best plane must score this many times the median plane's score; otherwise no plane stands
/// out and the default volume stays.
const MIN_CONTRAST: f64 = 3.0;

/// What [`choose`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// Depth of the best plane (m).
    pub z_m: f64,
    /// Its score and the median plane's.
    pub score: f64,
    pub median_score: f64,
    /// The volume to reconstruct: `None` when no plane stands out.
    pub volume: Option<Volume>,
}

impl Found {
    /// One line for a summary.
    pub fn describe(&self, searched: &Volume) -> String {
        let over = format!(
            "over z {}:{} m, the signal focuses best at z = {} m (its peak stands {:.0} deviations above the plane, the median plane's {:.0})",
            murk_core::short(searched.z.start),
            murk_core::short(searched.z.end),
            murk_core::short(self.z_m),
            self.score,
            self.median_score
        );
        match &self.volume {
            Some(v) => format!(
                "{over}; depth range z {}:{} m kept ({} or {} to choose)",
                murk_core::short(v.z.start),
                murk_core::short(v.z.end),
                murk_core::Opt::Volume,
                murk_core::Opt::DepthSearch.set("off")
            ),
            None => format!("{over}: no plane stands out, the default volume kept"),
        }
    }
}

/// Scores the planes of `rec` for which `usable(z)` holds and chooses the depth range around the best
/// one, with planes `step_m` apart.
pub fn choose(rec: &Reconstruction, usable: &dyn Fn(f64) -> bool, step_m: f64) -> Option<Found> {
    let v = &rec.volume;
    let scores: Vec<Option<f64>> = (0..v.z.n)
        .map(|k| plane_score(rec, k).filter(|_| usable(v.z.at(k))))
        .collect();
    let (best, score) = scores
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.map(|s| (k, s)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let mut valid: Vec<f64> = scores.iter().flatten().copied().collect();
    valid.sort_by(f64::total_cmp);
    let median_score = valid[valid.len() / 2];
    let z_m = v.z.at(best);
    let volume = (score >= MIN_CONTRAST * median_score).then(|| around(v, z_m, step_m));
    Some(Found {
        z_m,
        score,
        median_score,
        volume,
    })
}

/// `v` cut to `z_m ± HALF_RANGE_M` (within its own depths), with planes `step_m` apart.
fn around(v: &Volume, z_m: f64, step_m: f64) -> Volume {
    let (lo, hi) = (v.z.start.min(v.z.end), v.z.start.max(v.z.end));
    let z0 = (z_m - HALF_RANGE_M).max(lo);
    let z1 = (z_m + HALF_RANGE_M).min(hi);
    let nz = (((z1 - z0) / step_m).round() as usize + 1).max(2);
    Volume {
        x: v.x,
        y: v.y,
        z: Axis::new(z0, z1, nz),
    }
}

/// (max − median) / MAD of plane `k`'s magnitudes; `None` for a plane without spread (cleared by the
/// window-end handling, or constant), which says nothing about focus.
fn plane_score(rec: &Reconstruction, k: usize) -> Option<f64> {
    let v = &rec.volume;
    let mut values: Vec<f32> = Vec::with_capacity(v.x.n * v.y.n);
    for ix in 0..v.x.n {
        for iy in 0..v.y.n {
            values.push(rec.intensity[v.index(ix, iy, k)].abs());
        }
    }
    let max = values.iter().copied().fold(0f32, f32::max) as f64;
    let median = median_of(&mut values) as f64;
    let mut dev: Vec<f32> = values
        .iter()
        .map(|&x| (x as f64 - median).abs() as f32)
        .collect();
    let mad = median_of(&mut dev) as f64;
    (mad > 0.0 && max.is_finite()).then(|| (max - median) / mad)
}

fn median_of(values: &mut [f32]) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f32::total_cmp);
    *m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn volume(nz: usize) -> Volume {
        Volume {
            x: Axis::new(-1.0, 1.0, 16),
            y: Axis::new(-1.0, 1.0, 16),
            z: Axis::new(0.1, 3.0, nz),
        }
    }

    /// A bright near plane lit everywhere loses to a dim plane with one focused spot.
    #[test]
    fn the_focused_plane_wins_over_the_bright_one() {
        let v = volume(30);
        let mut i = vec![0f32; v.x.n * v.y.n * v.z.n];
        let mut seed = 1u64;
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for ix in 0..16 {
            for iy in 0..16 {
                for iz in 0..30 {
                    let near = 100.0 * (-(iz as f32) / 3.0).exp();
                    i[v.index(ix, iy, iz)] = near * (1.0 + 0.3 * noise()) + 0.01 * noise();
                }
            }
        }
        i[v.index(8, 8, 20)] += 1.0;
        let rec = Reconstruction::new(v, i, "test");
        let step_m = 0.05;
        let found = choose(&rec, &|_| true, step_m).unwrap();
        assert_eq!(found.z_m, v.z.at(20));
        let kept = found.volume.unwrap();
        assert!((kept.z.start - (v.z.at(20) - HALF_RANGE_M)).abs() < 1e-12);
        assert!(kept.z.end <= 3.0 + 1e-12);
        assert_eq!(kept.z.n, 21, "1 m at the given 5 cm spacing");
        // Without the spot no plane stands out.
        let mut flat = rec.clone();
        flat.intensity[v.index(8, 8, 20)] -= 1.0;
        assert_eq!(choose(&flat, &|_| true, step_m).unwrap().volume, None);
        // Planes ruled out are not chosen.
        let near = choose(&rec, &|z| z < 2.0, step_m).unwrap();
        assert!(near.z_m < 2.0);
    }
}
