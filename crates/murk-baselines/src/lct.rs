//! Light-cone transform (O'Toole, Lindell, Wetzstein 2018), confocal captures only.
//!
//! With v = (path/R)², R = M·Δs, the confocal transient becomes a 3-D convolution of the albedo
//! (resampled in z²) with a light cone, inverted by a Wiener filter. Differences from the reference
//! code, both deliberate: the PSF grid is integer-centred (x_j = (j − N)/N, so the cone apex is a
//! sample and the result is not shifted half a voxel laterally) and its depth samples are k/M, the
//! same grid as the resampled data; cone samples beyond the padded depth are dropped instead of being
//! piled onto the last sample.

use crate::confocal::{ConfocalGeometry, TimeGrid};
use crate::fft3::{Fft3, Steps, C32};
use crate::Reconstruction;
use murk_core::{Capture, Error, NoProgress, Progress, Result};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reflectance {
    /// Diffuse hidden surfaces: intensity falls as 1/r⁴, scale by z⁴.
    Diffuse,
    /// Retro-reflective surfaces: 1/r², scale by z².
    Retroreflective,
}

impl murk_core::Named for Reflectance {
    const WHAT: &'static str = "weighting";
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("diffuse", Self::Diffuse),
        ("retroreflective", Self::Retroreflective),
    ];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LctParams {
    pub reflectance: Reflectance,
    /// Wiener signal-to-noise ratio: filter conj(F)/(|F|² + 1/snr). Lindell's code uses 0.1,
    /// y-tal 0.8.
    pub snr: f64,
    pub grid: TimeGrid,
}

impl Default for LctParams {
    fn default() -> Self {
        LctParams {
            reflectance: Reflectance::Diffuse,
            snr: 0.1,
            grid: TimeGrid::Native,
        }
    }
}

/// Everything that depends only on the geometry: FFT plans, the Wiener filter, the resampler.
pub struct LctPlan {
    geom: ConfocalGeometry,
    params: LctParams,
    /// Power-of-two number of depth samples (≥ the capture's), required by the resampler.
    m: usize,
    fft: Fft3,
    /// The Wiener filter, even in kx and ky: its quarter kx ≤ nx, ky ≤ ny, as
    /// [`Fft3::forward_even`] returns it.
    filter: Vec<C32>,
    resampler: Resampler,
}

impl murk_core::Reconstructor for LctPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.run(capture, progress)
    }
}

impl LctPlan {
    /// Plans for captures of `capture`'s geometry. The kernel's spectrum is a pass through a grid
    /// as large as a run's, so it reports to `progress` and stops when asked.
    pub fn new(capture: &Capture, params: LctParams, progress: &dyn Progress) -> Result<Self> {
        crate::lct::check_snr("LCT", params.snr)?;
        let geom = ConfocalGeometry::new(capture, params.grid)?;
        let m = geom.nt.next_power_of_two();
        let (nx, ny) = (geom.nx, geom.ny);
        let fft = Fft3::new([2 * nx, 2 * ny, 2 * m]);
        let (delay, norm) = light_cone(&geom, m);
        // A cone line is one sample, norm at k: its temporal spectrum is norm·e^(−2πi·kf/2m).
        let phase: Vec<C32> = (0..2 * m)
            .map(|q| {
                let z = Complex64::from_polar(norm as f64, -PI * q as f64 / m as f64);
                C32::new(z.re as f32, z.im as f32)
            })
            .collect();
        // The cone is even in x and y about its apex, so its spectrum and the filter are too.
        let steps = Steps::start(progress, Fft3::FORWARD_EVEN_PASSES);
        let spectrum = fft.forward_even(
            |f, plane| {
                for (v, d) in plane.iter_mut().zip(&delay) {
                    // kf mod 2m, m a power of two.
                    *v = d.map_or(C32::default(), |k| phase[(k * f) & (2 * m - 1)]);
                }
            },
            &steps,
        );
        steps.finish("light-cone transform")?;
        let filter = wiener(spectrum, params.snr);
        Ok(LctPlan {
            geom,
            params,
            m,
            fft,
            filter,
            resampler: Resampler::new(m),
        })
    }

    /// Reconstructs on the scan grid: [nx, ny, nt], depth k·Δs′/2.
    pub fn run(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.geom.check_same(capture, self.params.grid)?;
        let steps = Steps::start(progress, Fft3::CONVOLVE_PASSES);
        let (g, m) = (&self.geom, self.m);
        let tau = g.sample(capture);
        let power = match self.params.reflectance {
            Reflectance::Diffuse => 4,
            Reflectance::Retroreflective => 2,
        };
        let scale: Vec<f32> = (0..g.nt)
            .map(|k| (k as f32 / m as f32).powi(power))
            .collect();
        let mut data = vec![0.0f32; g.nx * g.ny * g.nt];
        self.fft.convolve_even(
            [g.nx, g.ny],
            |ix, iy, line| {
                let col = &tau[(ix * g.ny + iy) * g.nt..][..g.nt];
                self.resampler.t_to_v(col, &scale, &mut line[..m]);
            },
            &self.filter,
            &mut data,
            |v, out| {
                self.resampler.v_to_t(&v[..m], out);
                out.iter_mut().for_each(|o| *o = o.max(0.0));
            },
            &steps,
        );
        steps.finish("light-cone transform")?;
        Ok(
            g.reconstruction(g.nt, data, "light-cone transform (Wiener)")
                .row("snr", self.params.snr)
                .row(
                    "reflectance",
                    murk_core::Named::name(self.params.reflectance),
                ),
        )
    }
}

/// One-shot LCT (plans and runs).
pub fn lct(capture: &Capture, params: LctParams) -> Result<Reconstruction> {
    LctPlan::new(capture, params, &NoProgress)?.run(capture, &NoProgress)
}

/// The binary light cone on the padded [2nx][2ny][2m] grid, apex at index 0 (negative lateral
/// offsets wrap), even in x and y: on the lines [wx][wy], wx ≤ nx, wy ≤ ny, the depth sample of its
/// one non-zero value (none where the cone leaves the grid); and the value that normalises it to
/// unit L2 norm.
pub(crate) fn light_cone(g: &ConfocalGeometry, m: usize) -> (Vec<Option<usize>>, f32) {
    let [dx, dy] = g.spacing();
    // A scatterer at lateral distance r appears 4r²/R² later in v̂ = (path/R)², i.e. 4r²·M/R² samples.
    let r_total = m as f64 * g.ds;
    let mut delay = Vec::with_capacity((g.nx + 1) * (g.ny + 1));
    let mut count = 0;
    for wx in 0..=g.nx {
        for wy in 0..=g.ny {
            let (ox, oy) = (wx as f64 * dx, wy as f64 * dy);
            let k = (4.0 * (ox * ox + oy * oy) * m as f64 / (r_total * r_total)).round() as usize;
            let d = (k < 2 * m).then_some(k);
            if d.is_some() {
                // Lines strictly inside the quarter stand for their mirror images too.
                count += (1 + usize::from(wx % g.nx != 0)) * (1 + usize::from(wy % g.ny != 0));
            }
            delay.push(d);
        }
    }
    (delay, 1.0 / (count as f32).sqrt())
}

/// A Wiener signal-to-noise ratio that `method` can use: within 1e-12..=1e12, far beyond any useful
/// filter; past it 1/snr swamps, or vanishes against, every |F|² an f32 spectrum holds, so the
/// filter is all zeros or a bare inverse.
pub(crate) fn check_snr(method: &str, snr: f64) -> Result<()> {
    if (1e-12..=1e12).contains(&snr) {
        Ok(())
    } else {
        Err(Error::param(format!(
            "{method} snr must be within 1e-12 ..= 1e12, got {}",
            murk_core::short(snr)
        )))
    }
}

/// The Wiener filter conj(F)/(|F|² + 1/snr) of the PSF spectrum F. (Of a real PSF's spectrum it
/// stays Hermitian, so the real inverse transform applies.)
fn wiener(mut f: Vec<C32>, snr: f64) -> Vec<C32> {
    let inv_snr = (1.0 / snr) as f32;
    f.par_iter_mut()
        .for_each(|f| *f = f.conj() * (f.norm_sqr() + inv_snr).recip());
    f
}

/// O'Toole's t → v = t² resampling matrix as a sparse M×M operator (M a power of two): fine row
/// j = 1..M² takes 1/√j from t sample ⌈√j⌉ − 1, and M consecutive fine rows are averaged into one
/// row (what the reference's log2(M) pair-averagings amount to). v → t applies its transpose.
pub(crate) struct Resampler {
    rows: Vec<Vec<(usize, f32)>>,
}

impl Resampler {
    pub(crate) fn new(m: usize) -> Self {
        let rows = (0..m)
            .into_par_iter()
            .map(|i| {
                let mut row: Vec<(usize, f64)> = Vec::new();
                for j in i * m + 1..=(i + 1) * m {
                    let c = ((j as f64).sqrt().ceil() as usize).min(m) - 1;
                    let w = 1.0 / ((j as f64).sqrt() * m as f64);
                    match row.last_mut() {
                        Some((last, acc)) if *last == c => *acc += w,
                        _ => row.push((c, w)),
                    }
                }
                row.into_iter().map(|(c, w)| (c, w as f32)).collect()
            })
            .collect();
        Resampler { rows }
    }

    /// Resamples t·`scale` (elementwise), zero-padded to M samples.
    pub(crate) fn t_to_v(&self, t: &[f32], scale: &[f32], v: &mut [f32]) {
        for (row, out) in self.rows.iter().zip(v.iter_mut()) {
            *out = row
                .iter()
                .take_while(|&&(c, _)| c < t.len())
                .map(|&(c, w)| w * (t[c] * scale[c]))
                .sum();
        }
    }

    /// The transpose applied to `v`, the first `t.len()` samples of it.
    pub(crate) fn v_to_t(&self, v: &[f32], t: &mut [f32]) {
        t.fill(0.0);
        let n = t.len();
        for (row, x) in self.rows.iter().zip(v) {
            // A row's columns ascend.
            for &(c, w) in row.iter().take_while(|&&(c, _)| c < n) {
                t[c] += w * x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{add_plane, add_point, assert_plane_depth, axis, confocal};
    use murk_core::DVec3;

    #[test]
    fn point_at_half_a_metre_is_within_one_voxel_of_index_100() {
        // docs/reconstruction.md, LCT: z = 0.5 m, Δs = 1 cm, M = 256, N = 32; scan point (16, 16).
        let mut c = confocal(32, 0.64, axis(0.0, 0.01, 256));
        add_point(&mut c, DVec3::new(0.01, 0.01, 0.5));
        let r = lct(&c, LctParams::default()).unwrap();
        let [ix, iy, k] = r.argmax();
        // The integer-centred PSF keeps the lateral position exact.
        assert_eq!([ix, iy], [16, 16]);
        assert!(k.abs_diff(100) <= 1, "depth index {k}");
    }

    #[test]
    fn plane_comes_out_at_its_depth() {
        // 100 bins: not a power of two, so the plan pads to M = 128 and crops back.
        let mut c = confocal(16, 0.64, axis(0.0, 0.01, 100));
        add_plane(&mut c, 0.3, 0.48, 24);
        let r = lct(&c, LctParams::default()).unwrap();
        assert_eq!(r.volume.shape(), [16, 16, 100]);
        assert_plane_depth(&r, 60, 4);
    }

    #[test]
    fn quarter_filter_is_the_full_transform_of_the_cone() {
        // A non-square grid (8 × 6 columns) so that the x and y mirrors differ; 100 bins, M = 128.
        let mut c = confocal(8, 0.64, axis(0.0, 0.01, 100));
        let grid = murk_core::PointSet::wall_grid(DVec3::ZERO, 0.64, 0.48, 8, 6);
        (c.illum, c.sensor, c.h) = (grid.clone(), grid, vec![0.0; 8 * 6 * 100]);
        let plan = LctPlan::new(&c, LctParams::default(), &NoProgress).unwrap();
        let [nx, ny, _] = plan.fft.dims;
        let (hx, hy, nh) = (nx / 2 + 1, ny / 2 + 1, plan.fft.half());
        let (delay, norm) = light_cone(&plan.geom, plan.m);
        let psf_at = |wx: usize, wy: usize| delay[wx.min(nx - wx) * hy + wy.min(ny - wy)];
        let psf = |wx: usize, wy: usize, line: &mut [f32]| {
            if let Some(k) = psf_at(wx, wy) {
                line[k] = norm;
            }
        };
        // Unit L2 norm over the whole grid.
        let count = (0..nx * ny)
            .filter(|i| psf_at(i / ny, i % ny).is_some())
            .count();
        assert!((norm * (count as f32).sqrt() - 1.0).abs() < 1e-6);
        let full = wiener(
            plan.fft.forward([nx, ny], psf, &Steps::none()),
            plan.params.snr,
        );
        let peak = full.iter().map(|v| v.norm()).fold(0.0, f32::max);
        for (i, want) in full.iter().enumerate() {
            let (kx, ky, f) = (i / (ny * nh), i / nh % ny, i % nh);
            let (kx, ky) = (kx.min(nx - kx), ky.min(ny - ky));
            let got = plan.filter[(f * hy + ky) * hx + kx];
            // f32 rounding of two differently ordered transforms (about 3e-7 here), relative to the
            // largest value.
            assert!((got - want).norm() < 1e-5 * peak, "{got} vs {want}");
        }
    }

    #[test]
    fn resampler_rows_hold_the_weights_of_their_fine_rows() {
        let m = 8;
        let r = Resampler::new(m);
        // Row sums: (1/M) Σ_{j in block} 1/√j; every t sample is used.
        for (i, row) in r.rows.iter().enumerate() {
            let want: f64 = (i * m + 1..=(i + 1) * m)
                .map(|j| 1.0 / (j as f64).sqrt())
                .sum::<f64>()
                / m as f64;
            let got: f64 = row.iter().map(|&(_, w)| w as f64).sum();
            assert!((got - want).abs() < 1e-6, "row {i}: {got} vs {want}");
        }
        let mut used = vec![false; m];
        r.rows.iter().flatten().for_each(|&(c, _)| used[c] = true);
        assert!(used.iter().all(|&u| u));
    }
}
