//! f-k (Stolt) migration (Lindell, Wetzstein, O'Toole 2019), confocal captures only.
//!
//! The confocal transient is an exploding-reflector wavefield at speed c/2: after a 3-D FFT on the
//! (2M × 2N × 2N) zero-padded data, the spectrum at temporal frequency k_z′ = √(a²(k_x² + k_y²) + k_z²)
//! is moved to k_z, with the Jacobian |k_z|/k_z′, for k_z > 0 only. With the normalised grids
//! k_z = m/M and k_x = j/N, a = Δs/(2Δx) (per axis, so Δx ≠ Δy is fine).
//! Memory: the non-negative temporal half of the padded spectrum ((2N)² × (M+1) complex f32) and the
//! output, no voxel × sensor tensors; 64² × 512 takes 67 MB of spectrum.

use crate::confocal::{ConfocalGeometry, TimeGrid};
use crate::fft3::{Fft3, Steps, C32};
use crate::Reconstruction;
use murk_core::{Capture, NoProgress, Progress, Result};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FkParams {
    pub grid: TimeGrid,
}

impl Default for FkParams {
    fn default() -> Self {
        FkParams {
            grid: TimeGrid::Native,
        }
    }
}

pub struct FkPlan {
    geom: ConfocalGeometry,
    params: FkParams,
    stolt: Stolt,
}

impl murk_core::Reconstructor for FkPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.run(capture, progress)
    }
}

impl FkPlan {
    pub fn new(capture: &Capture, params: FkParams) -> Result<Self> {
        let geom = ConfocalGeometry::new(capture, params.grid)?;
        Ok(FkPlan {
            stolt: Stolt::new(&geom),
            geom,
            params,
        })
    }

    /// Reconstructs on the scan grid: [nx, ny, nt], depth k·Δs′/2.
    pub fn run(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.geom.check_same(capture, self.params.grid)?;
        let g = &self.geom;
        let steps = Steps::start(progress, Fft3::FORWARD_PASSES + Stolt::MIGRATE_PASSES);
        // √(τ·ẑ²), ẑ = k/M: the amplitude of the wavefield, with the t² falloff undone.
        let m = g.nt as f32;
        let spec = self.stolt.transform(
            &g.sample(capture),
            |k, v| v.max(0.0).sqrt() * k as f32 / m,
            &steps,
        );
        let volume = self.stolt.migrate_and_crop(spec, &steps);
        steps.finish("f-k migration")?;
        Ok(g.reconstruction(g.nt, volume, "f-k migration"))
    }
}

/// One-shot f-k migration (plans and runs).
pub fn fk(capture: &Capture, params: FkParams) -> Result<Reconstruction> {
    FkPlan::new(capture, params)?.run(capture, &NoProgress)
}

/// The Stolt step on the spectrum of the padded [2nx][2ny][2m] grid, shared with CDT.
pub(crate) struct Stolt {
    pub fft: Fft3,
    nx: usize,
    ny: usize,
    m: usize,
    /// a² per lateral axis.
    a2: [f64; 2],
}

impl Stolt {
    pub fn new(g: &ConfocalGeometry) -> Self {
        let [dx, dy] = g.spacing();
        Stolt {
            fft: Fft3::new([2 * g.nx, 2 * g.ny, 2 * g.nt]),
            nx: g.nx,
            ny: g.ny,
            m: g.nt,
            a2: [(g.ds / (2.0 * dx)).powi(2), (g.ds / (2.0 * dy)).powi(2)],
        }
    }

    /// Spectrum of `tau` ([nx][ny][len], len ≤ 2m; usually m) zero-padded into the padded grid,
    /// sample k of each line mapped through `f(k, value)` first.
    pub fn transform(
        &self,
        tau: &[f32],
        f: impl Fn(usize, f32) -> f32 + Sync,
        steps: &Steps,
    ) -> Vec<C32> {
        let len = tau.len() / (self.nx * self.ny);
        debug_assert!(len <= 2 * self.m && len * self.nx * self.ny == tau.len());
        let fill = |ix: usize, iy: usize, line: &mut [f32]| {
            let src = &tau[(ix * self.ny + iy) * len..][..len];
            line.iter_mut()
                .zip(src)
                .enumerate()
                .for_each(|(k, (d, &s))| *d = f(k, s));
        };
        self.fft.forward([self.nx, self.ny], fill, steps)
    }

    /// Passes of [`Stolt::migrate_and_crop`]: the map, then the inverse transform.
    pub const MIGRATE_PASSES: usize = 1 + Fft3::INVERSE_PASSES;

    /// Stolt-maps the spectrum `spec`, inverse-transforms it and returns |·|² of the first octant.
    /// The map fills only positive temporal frequencies, so the migrated spectrum is not Hermitian:
    /// the inverse is complex, but the stored non-negative half is all there is.
    pub fn migrate_and_crop(&self, mut spec: Vec<C32>, steps: &Steps) -> Vec<f32> {
        let [nx2, ny2, _] = self.fft.dims;
        let (m, mf) = (self.m, self.m as f64);
        // Signed normalised frequency of FFT index j on an axis of 2n samples.
        let freq = |j: usize, n: usize| {
            (if j < n {
                j as f64
            } else {
                j as f64 - 2.0 * n as f64
            }) / n as f64
        };
        let half = self.fft.half();
        let pass = steps.pass(nx2);
        spec.par_chunks_mut(ny2 * half)
            .enumerate()
            .for_each(|(ix, slab)| {
                if !pass.piece() {
                    return;
                }
                let kx = freq(ix, nx2 / 2);
                for (iy, col) in slab.chunks_mut(half).enumerate() {
                    let ky = freq(iy, ny2 / 2);
                    let lateral = self.a2[0] * kx * kx + self.a2[1] * ky * ky;
                    // Source samples exist for k_z′ ≤ (M−1)/M; beyond, and for all larger k_z,
                    // it is zero.
                    let mut end = m;
                    // Output m reads the source at index ≥ m, so ascending order never reads a
                    // sample that was already overwritten: the mapping is done in place.
                    for mo in 1..m {
                        let kz = mo as f64 / mf;
                        // max() guards the in-place order against rounding when k_x = k_y = 0.
                        let u = ((lateral + kz * kz).sqrt() * mf).max(mo as f64);
                        if u > (m - 1) as f64 {
                            end = mo;
                            break;
                        }
                        // u ≥ 0, so the cast is the floor (f64::floor is a libm call without SSE4.1).
                        let n = u as usize;
                        let f = (u - n as f64) as f32;
                        let hi = if n + 1 < m {
                            col[n + 1]
                        } else {
                            C32::default()
                        };
                        col[mo] = (col[n] * (1.0 - f) + hi * f) * (mo as f64 / u) as f32;
                    }
                    // Only k_z > 0 survives: the wavefield travels towards the wall.
                    col[0] = C32::default();
                    col[end..].iter_mut().for_each(|v| *v = C32::default());
                }
            });
        let mut out = vec![0.0f32; self.nx * self.ny * m];
        self.fft
            .inverse_power_one_sided(&mut spec, [self.nx, self.ny], &mut out, steps);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{add_plane, add_point, assert_plane_depth, axis, confocal};
    use murk_core::DVec3;

    /// Scan point (16, 16) of a 32² grid over 0.64 m is at (0.01, 0.01).
    const ON_GRID: f64 = 0.01;

    #[test]
    fn point_at_half_a_metre_is_at_depth_index_100() {
        // docs/reconstruction.md, f-k: z = 0.5 m, Δs = 1 cm, M = 256, N = 32.
        let mut c = confocal(32, 0.64, axis(0.0, 0.01, 256));
        add_point(&mut c, DVec3::new(ON_GRID, ON_GRID, 0.5));
        let r = fk(&c, FkParams::default()).unwrap();
        assert_eq!(r.argmax(), [16, 16, 100]);
        assert!((r.volume.z.at(100) - 0.5).abs() < 1e-12);
        assert_eq!(r.volume.shape(), [32, 32, 256]);
    }

    #[test]
    fn time_offsets_and_wall_legs_are_removed() {
        // Same point, but the time axis starts at 2.2371 m and includes laser→wall and wall→SPAD.
        let mut c = confocal(32, 0.64, axis(2.2371, 0.01, 256));
        c.laser_xyz = Some(DVec3::new(0.5, -0.3, -1.2));
        c.sensor_xyz = Some(DVec3::new(-0.4, 0.2, -1.0));
        c.t_accounts_first_and_last_bounces = true;
        add_point(&mut c, DVec3::new(ON_GRID, ON_GRID, 0.5));
        let r = fk(&c, FkParams::default()).unwrap();
        assert_eq!(r.argmax(), [16, 16, 100]);
    }

    #[test]
    fn plane_comes_out_at_its_depth() {
        let mut c = confocal(16, 0.64, axis(0.0, 0.01, 128));
        add_plane(&mut c, 0.3, 0.48, 24);
        let r = fk(&c, FkParams::default()).unwrap();
        assert_plane_depth(&r, 60, 4);
    }

    #[test]
    fn plan_rejects_another_geometry() {
        let c = confocal(8, 0.64, axis(0.0, 0.01, 64));
        let plan = FkPlan::new(&c, FkParams::default()).unwrap();
        let e = plan
            .run(&confocal(8, 0.64, axis(0.0, 0.02, 64)), &NoProgress)
            .unwrap_err();
        assert!(e.to_string().contains("plan was built for"), "{e}");
        let mut single = confocal(8, 0.64, axis(0.0, 0.01, 64));
        single.pairing = murk_core::Pairing::Product;
        single.sensor = murk_core::PointSet::single(DVec3::ZERO);
        assert!(fk(&single, FkParams::default())
            .unwrap_err()
            .to_string()
            .contains("confocal"));
    }
}
