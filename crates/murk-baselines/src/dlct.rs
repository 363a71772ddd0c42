//! Directional light-cone transform (Young, Lindell, Girod, Taubman, Wetzstein, CVPR 2020),
//! confocal captures only: each voxel's albedo and the normal of the surface there.
//!
//! D-LCT replaces LCT's scalar albedo ρ by the vector a = ρ·n (n the unit normal, facing the wall)
//! and keeps one Lambertian cosine, ⟨n, p′ − p⟩/r, which makes the transient linear in a: at scan
//! point p′ and wall-relative path s = 2r, τ(p′, s) = ∫ ⟨a(p), p′ − p⟩ / r⁵ · δ(s − 2r) dp. Scaled
//! by r⁵ (the same r for every point a sample sees) and resampled as LCT does, it is a sum of three
//! convolutions: a_x and a_y with the light cone times the lateral offset (x′ − x)/L, (y′ − y)/L,
//! and b = −a_z·z/L with the light cone itself (L the depth of sample M). One measurement for three
//! unknowns: the regularised least squares (HᴴH + λ)⁻¹Hᴴy, H the row of the three kernels' spectra,
//! equals Hᴴy / (|H|² + λ) at each frequency (the paper's Cholesky–Wiener solve gives the same), so
//! each component is a filter conj(H_d)/(Σ|H_e|² + 1/snr) with a shared denominator.

use crate::confocal::{ConfocalGeometry, TimeGrid};
use crate::fft3::{Fft3, Steps, C32};
use crate::lct::{check_snr, light_cone, Resampler};
use crate::Reconstruction;
use murk_core::{Capture, Limits, NoProgress, Progress, Result};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DlctParams {
    /// Wiener signal-to-noise ratio, as LCT's: the cone kernel has unit L2 norm.
    pub snr: f64,
    pub grid: TimeGrid,
}

impl Default for DlctParams {
    fn default() -> Self {
        DlctParams {
            snr: 0.1,
            grid: TimeGrid::Native,
        }
    }
}

/// Everything that depends only on the geometry: FFT plans, the three filters, the resampler.
pub struct DlctPlan {
    geom: ConfocalGeometry,
    params: DlctParams,
    /// Power-of-two number of depth samples (≥ the capture's), required by the resampler.
    m: usize,
    fft: Fft3,
    /// Filters for a_x, a_y and b on the whole padded spectrum.
    filters: [Vec<C32>; 3],
    /// The L2 norms of the x and y kernels before scaling to unit norm.
    lateral_scale: [f32; 2],
    resampler: Resampler,
}

impl murk_core::Reconstructor for DlctPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.run(capture, progress)
    }
}

const NAME: &str = "directional light-cone transform";

impl DlctPlan {
    /// Plans for captures of `capture`'s geometry: three kernel spectra as large as a run's grid,
    /// reported to `progress`.
    pub fn new(capture: &Capture, params: DlctParams, progress: &dyn Progress) -> Result<Self> {
        check_snr("D-LCT", params.snr)?;
        let geom = ConfocalGeometry::new(capture, params.grid)?;
        let m = geom.nt.next_power_of_two();
        let (nx, ny) = (geom.nx, geom.ny);
        // The three filters, a run's spectrum and its product with one filter.
        Limits::get().elements(
            "D-LCT's five spectra",
            &[5, 2 * nx, 2 * ny, m + 1],
            std::mem::size_of::<C32>(),
        )?;
        let fft = Fft3::new([2 * nx, 2 * ny, 2 * m]);
        let (delay, norm) = light_cone(&geom, m);
        let l = 0.5 * m as f64 * geom.ds;
        // Signed lateral offset of padded index w over L (negative offsets wrap); index n stands
        // for +n and −n at once, so the odd kernels leave it out.
        let offset = |w: usize, n: usize, step_m: f64| -> f32 {
            match w.cmp(&n) {
                std::cmp::Ordering::Less => (w as f64 * step_m / l) as f32,
                std::cmp::Ordering::Greater => ((w as f64 - 2.0 * n as f64) * step_m / l) as f32,
                std::cmp::Ordering::Equal => 0.0,
            }
        };
        let (step_x, step_y) = (geom.x.step(), geom.y.step());
        // Each kernel scaled to unit L2 norm, as the cone is, so that one λ weighs the three
        // components alike (unscaled, the small lateral kernels lose most to the regulariser
        // and the normals lean towards the wall's); the run divides the scale out again.
        let lateral_norm = |n: usize, m_other: usize, step_m: f64, along_x: bool| -> f64 {
            let mut sum = 0.0;
            for w in 0..2 * n {
                for o in 0..2 * m_other {
                    let (wx, wy) = if along_x { (w, o) } else { (o, w) };
                    let quarter = wx.min(2 * nx - wx) * (ny + 1) + wy.min(2 * ny - wy);
                    if delay[quarter].is_some() {
                        sum += (norm * offset(w, n, step_m)).powi(2) as f64;
                    }
                }
            }
            sum.sqrt()
        };
        let scale = [
            lateral_norm(nx, ny, step_x, true),
            lateral_norm(ny, nx, step_y, false),
        ];
        let steps = Steps::start(progress, 3 * Fft3::FORWARD_PASSES);
        let spectra = [0, 1, 2].map(|d| {
            fft.forward(
                [2 * nx, 2 * ny],
                |wx, wy, line| {
                    let quarter = wx.min(2 * nx - wx) * (ny + 1) + wy.min(2 * ny - wy);
                    if let Some(k) = delay[quarter] {
                        line[k] = norm
                            * match d {
                                0 => offset(wx, nx, step_x) / scale[0] as f32,
                                1 => offset(wy, ny, step_y) / scale[1] as f32,
                                _ => 1.0,
                            };
                    }
                },
                &steps,
            )
        });
        steps.finish(NAME)?;
        Ok(DlctPlan {
            geom,
            params,
            m,
            fft,
            filters: filters(spectra, params.snr),
            lateral_scale: scale.map(|s| s as f32),
            resampler: Resampler::new(m),
        })
    }

    /// Albedo and normals on the scan grid: [nx, ny, nt], depth k·Δs′/2. The intensity is |a|·z/L
    /// per voxel (the factor keeps the division of b by z from amplifying the noise near the wall),
    /// zero where a surface would face away from the wall; the normals are a/|a| (n_z < 0: facing
    /// the wall), zero where the albedo is.
    pub fn run(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.geom.check_same(capture, self.params.grid)?;
        let steps = Steps::start(progress, Fft3::FORWARD_PASSES + 3 * Fft3::INVERSE_PASSES);
        let (g, m) = (&self.geom, self.m);
        let tau = g.sample(capture);
        // r⁵ in units of L: (k/M)⁵.
        let scale: Vec<f32> = (0..g.nt).map(|k| (k as f32 / m as f32).powi(5)).collect();
        let spectrum = self.fft.forward(
            [g.nx, g.ny],
            |ix, iy, line| {
                let col = &tau[(ix * g.ny + iy) * g.nt..][..g.nt];
                self.resampler.t_to_v(col, &scale, &mut line[..m]);
            },
            &steps,
        );
        let lines = g.nx * g.ny;
        let mut work = vec![C32::default(); spectrum.len()];
        let mut v = vec![0.0f32; lines * m];
        let components = self.filters.each_ref().map(|filter| {
            work.par_iter_mut()
                .zip(&spectrum)
                .zip(filter)
                .for_each(|((w, s), f)| *w = s * f);
            self.fft.inverse(&mut work, [g.nx, g.ny], &mut v, &steps);
            let mut c = vec![0.0f32; lines * g.nt];
            c.par_chunks_mut(g.nt)
                .zip(v.par_chunks(m))
                .for_each(|(t, v)| self.resampler.v_to_t(v, t));
            c
        });
        steps.finish(NAME)?;
        let [ax, ay, b] = &components;
        let (albedo, normals): (Vec<f32>, Vec<[f32; 3]>) = (0..lines * g.nt)
            .into_par_iter()
            .map(|i| {
                let k = i % g.nt;
                // b = −a_z·z/L, positive where the surface faces the wall.
                if b[i] <= 0.0 {
                    return (0.0, [0.0; 3]);
                }
                // a·z/L: the same direction as a, without dividing b by a z near zero.
                let z = k as f32 / m as f32;
                let [sx, sy] = self.lateral_scale;
                let a = [ax[i] / sx * z, ay[i] / sy * z, -b[i]];
                let len = a.iter().map(|c| c * c).sum::<f32>().sqrt();
                (len, a.map(|c| c / len))
            })
            .unzip();
        let mut out = g
            .reconstruction(g.nt, albedo, "directional light-cone transform (Wiener)")
            .row("snr", self.params.snr);
        out.normals = Some(normals);
        Ok(out)
    }
}

/// One-shot D-LCT (plans and runs).
pub fn dlct(capture: &Capture, params: DlctParams) -> Result<Reconstruction> {
    DlctPlan::new(capture, params, &NoProgress)?.run(capture, &NoProgress)
}

/// The filters conj(H_d)/(Σ_e |H_e|² + 1/snr) of the kernel spectra H_x, H_y, H_z. (Of real kernels'
/// spectra they stay Hermitian, so the real inverse transform applies.)
fn filters(mut h: [Vec<C32>; 3], snr: f64) -> [Vec<C32>; 3] {
    let inv_snr = (1.0 / snr) as f32;
    let [hx, hy, hz] = &mut h;
    hx.par_iter_mut()
        .zip(hy.par_iter_mut())
        .zip(hz.par_iter_mut())
        .for_each(|((x, y), z)| {
            let r = (x.norm_sqr() + y.norm_sqr() + z.norm_sqr() + inv_snr).recip();
            (*x, *y, *z) = (x.conj() * r, y.conj() * r, z.conj() * r);
        });
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::{DVec3, PointSet, TimeAxis};
    use murk_synth::{add_first_bounce, Scatterer, SynthOptions};

    /// A confocal scan of `n`² points over a 0.8 m wall, 1 cm bins, of `scatterers` under murk's
    /// Lambertian model (cosines at the wall and at the hidden surface).
    fn capture(n: usize, scatterers: &[Scatterer]) -> Capture {
        let time = TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.01,
            bins: 256,
        };
        let grid = PointSet::wall_grid(DVec3::ZERO, 0.8, 0.8, n, n);
        let mut c = Capture::confocal(grid, time, vec![0.0; n * n * 256], String::new());
        let opts = SynthOptions {
            cosines: true,
            ..Default::default()
        };
        add_first_bounce(&mut c, scatterers, &opts).unwrap();
        c
    }

    /// A square of `side` m centred on `centre` with unit normal `normal` (facing the wall),
    /// sampled every 5 mm.
    fn tilted_square(centre: DVec3, normal: DVec3, side: f64) -> Vec<Scatterer> {
        let u = normal.cross(DVec3::Y).normalize();
        let w = normal.cross(u);
        let n = (side / 0.005) as usize;
        let at = |i: usize| -0.5 * side + (i as f64 + 0.5) * side / n as f64;
        (0..n * n)
            .map(|i| Scatterer {
                pos: centre + at(i / n) * u + at(i % n) * w,
                weight: 0.005 * 0.005,
                normal: Some(normal),
            })
            .collect()
    }

    /// The albedo-weighted mean normal over the columns whose peak lies within `radius` m of the
    /// scan's centre axis, and the peak voxels' positions.
    fn mean_normal(r: &Reconstruction, radius: f64) -> (DVec3, Vec<DVec3>) {
        let normals = r.normals.as_ref().unwrap();
        let [nx, ny, nz] = r.volume.shape();
        let (mut sum, mut peaks) = (DVec3::ZERO, Vec::new());
        for ix in 0..nx {
            for iy in 0..ny {
                let i0 = r.volume.index(ix, iy, 0);
                let col = &r.intensity[i0..][..nz];
                let k = (0..nz).fold(0, |b, k| if col[k] > col[b] { k } else { b });
                let p = DVec3::new(r.volume.x.at(ix), r.volume.y.at(iy), r.volume.z.at(k));
                if col[k] > 0.0 && p.truncate().length() < radius {
                    sum += col[k] as f64 * DVec3::from_array(normals[i0 + k].map(f64::from));
                    peaks.push(p);
                }
            }
        }
        (sum.normalize(), peaks)
    }

    #[test]
    fn a_plane_facing_the_wall_comes_out_at_its_depth_facing_the_wall() {
        let n = -DVec3::Z;
        let c = capture(32, &tilted_square(DVec3::new(0.0, 0.0, 0.5), n, 0.3));
        let d = dlct(&c, DlctParams::default()).unwrap();
        let (mean, peaks) = mean_normal(&d, 0.1);
        assert!(peaks.len() >= 16, "{} columns", peaks.len());
        // One depth sample is 5 mm.
        for p in &peaks {
            assert!((p.z - 0.5).abs() <= 0.011, "{p}");
        }
        let angle = mean.angle_between(n).to_degrees();
        // 0.0° measured.
        assert!(angle < 1.0, "normal {mean} is {angle:.1}° off");
    }

    #[test]
    fn a_tilted_plane_gives_its_normal() {
        // Tilted 25° towards +x, and the same plane tilted towards −y: the lateral components
        // have the right signs and axes. (At 45°, beyond the 39° half-angle the wall subtends,
        // the normal comes back at about 32°: docs/reconstruction.md.)
        for (tilt, axis) in [(DVec3::X, "x"), (-DVec3::Y, "−y")] {
            let n = (-DVec3::Z * 25f64.to_radians().cos() + tilt * 25f64.to_radians().sin())
                .normalize();
            let c = capture(32, &tilted_square(DVec3::new(0.0, 0.0, 0.5), n, 0.3));
            let d = dlct(&c, DlctParams::default()).unwrap();
            let (mean, peaks) = mean_normal(&d, 0.1);
            for p in &peaks {
                // The plane's depth under the column, within two depth samples.
                let z = 0.5 - n.truncate().dot(p.truncate()) / n.z;
                assert!((p.z - z).abs() <= 0.011, "{axis}: {p} vs z = {z}");
            }
            let angle = mean.angle_between(n).to_degrees();
            // 0.5° measured; without the kernels' unit-norm scaling, 21.6°.
            assert!(angle < 2.0, "{axis}: normal {mean} is {angle:.1}° off {n}");
        }
    }

    #[test]
    fn a_point_is_found_where_it_is() {
        let p = DVec3::new(0.1, -0.125, 0.45);
        let point = Scatterer {
            pos: p,
            weight: 1.0,
            normal: None,
        };
        let d = dlct(&capture(32, &[point]), DlctParams::default()).unwrap();
        let (peak, _) = d.peak();
        // A lateral sample is 2.6 cm, a depth sample 5 mm.
        let e = DVec3::from_array(peak) - p;
        assert!(e.truncate().length() < 0.02 && e.z.abs() < 0.011, "{e}");
    }

    #[test]
    fn a_wrong_snr_and_another_geometry_are_refused() {
        let c = capture(8, &[]);
        let bad = DlctParams {
            snr: 0.0,
            ..Default::default()
        };
        let e = DlctPlan::new(&c, bad, &NoProgress).err().unwrap();
        assert!(e.to_string().contains("D-LCT snr"), "{e}");
        let plan = DlctPlan::new(&c, DlctParams::default(), &NoProgress).unwrap();
        assert!(plan.run(&capture(16, &[]), &NoProgress).is_err());
    }
}
