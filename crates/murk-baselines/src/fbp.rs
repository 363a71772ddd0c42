//! Filtered backprojection: backprojection followed by a high-pass filter on the volume, then
//! normalised to a maximum of 1 and clamped at 0.
//!
//! Sign: the Laplacian of a Gaussian ∇²G is negative at its centre, so ∇²G ⊛ BP has its *minimum* at
//! a point scatterer (and its maximum a few voxels away in depth). The filter is therefore −∇²G
//! (docs/reconstruction.md: the sign).

use crate::bp::{backproject_with, BpOptions};
use crate::Reconstruction;
use murk_core::simd::wide;
use murk_core::{Capture, NoProgress, Progress, Result, Volume};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FbpFilter {
    /// −∇²G, 5×5×5 voxels, σ = 1 voxel, zero-mean (O'Toole/Lindell `filterLaplacian`).
    #[default]
    LaplacianOfGaussian,
    /// −∂²/∂z² along depth only, [−1, 2, −1] (Velten et al. 2012).
    DepthSecondDerivative,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FbpOptions {
    pub bp: BpOptions,
    pub filter: FbpFilter,
}

/// Filtered backprojection on one volume: as [`crate::BpPlan`], its plan is the volume and the options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FbpPlan {
    pub volume: Volume,
    pub options: FbpOptions,
}

impl murk_core::Reconstructor for FbpPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        fbp_with(capture, &self.volume, self.options, progress)
    }
}

pub fn fbp(capture: &Capture, volume: &Volume, opts: FbpOptions) -> Result<Reconstruction> {
    fbp_with(capture, volume, opts, &NoProgress)
}

/// [`fbp`], reporting the backprojection to `progress` and stopping with an error once it is
/// cancelled.
pub fn fbp_with(
    capture: &Capture,
    volume: &Volume,
    opts: FbpOptions,
    progress: &dyn Progress,
) -> Result<Reconstruction> {
    let mut r = backproject_with(capture, volume, opts.bp, progress)?;
    let filtered = match opts.filter {
        FbpFilter::LaplacianOfGaussian => {
            let mut k = laplacian_of_gaussian_kernel();
            k.iter_mut().for_each(|v| *v = -*v);
            convolve_same(&r.intensity, volume.shape(), &k, [5, 5, 5])
        }
        FbpFilter::DepthSecondDerivative => {
            convolve_same(&r.intensity, volume.shape(), &[-1.0, 2.0, -1.0], [1, 1, 3])
        }
    };
    let max = filtered.iter().copied().fold(0.0f32, f32::max);
    let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
    r.intensity = filtered.into_iter().map(|v| (v * scale).max(0.0)).collect();
    let method = match opts.filter {
        FbpFilter::LaplacianOfGaussian => "filtered backprojection (−∇²G, 5³ voxels, σ = 1 voxel)",
        FbpFilter::DepthSecondDerivative => "filtered backprojection (−∂²/∂z², 3 voxels)",
    };
    r.rows = vec![("method".into(), method.into())];
    Ok(r)
}

/// ∇²G on a 5×5×5 grid (σ = 1 voxel): G (normalised to sum 1) times (r² − 3σ²)/σ⁴, minus its mean
/// so that it sums to zero (flat regions filter to 0). C order `[x][y][z]`.
pub fn laplacian_of_gaussian_kernel() -> [f32; 125] {
    let mut g = [0.0f64; 125];
    let mut r2 = [0.0f64; 125];
    for (i, (gv, rv)) in g.iter_mut().zip(r2.iter_mut()).enumerate() {
        let d = |c: usize| c as f64 - 2.0;
        *rv = d(i / 25).powi(2) + d(i / 5 % 5).powi(2) + d(i % 5).powi(2);
        *gv = (-*rv / 2.0).exp();
    }
    let gsum: f64 = g.iter().sum();
    let w: Vec<f64> = g
        .iter()
        .zip(&r2)
        .map(|(g, r2)| g / gsum * (r2 - 3.0))
        .collect();
    let mean = w.iter().sum::<f64>() / 125.0;
    std::array::from_fn(|i| (w[i] - mean) as f32)
}

/// "Same"-size 3-D correlation with a kernel of odd size `ks` centred on the output voxel, zeros
/// outside the volume. The kernels here are symmetric, so correlation equals convolution.
pub fn convolve_same(data: &[f32], shape: [usize; 3], kernel: &[f32], ks: [usize; 3]) -> Vec<f32> {
    let [nx, ny, nz] = shape;
    let h = ks.map(|k| (k / 2) as isize);
    let mut out = vec![0.0f32; data.len()];
    // Per output column: one multiply-add over the valid depth range per kernel tap, so the inner
    // loop is a contiguous, branch-free axpy.
    out.par_chunks_mut(nz).enumerate().for_each(|(col, dst)| {
        let (ix, iy) = ((col / ny) as isize, (col % ny) as isize);
        for a in 0..ks[0] {
            let x = ix + a as isize - h[0];
            for b in 0..ks[1] {
                let y = iy + b as isize - h[1];
                if x < 0 || x >= nx as isize || y < 0 || y >= ny as isize {
                    continue;
                }
                let src = &data[(x as usize * ny + y as usize) * nz..][..nz];
                for c in 0..ks[2] {
                    let k = kernel[(a * ks[1] + b) * ks[2] + c];
                    // dst[z] += k·src[z + c − h].
                    let shift = c as isize - h[2];
                    let (d0, s0) = if shift < 0 {
                        ((-shift) as usize, 0)
                    } else {
                        (0, shift as usize)
                    };
                    let n = nz.saturating_sub(d0.max(s0));
                    // A tap longer than the depth axis (few depth voxels) overlaps nothing.
                    if n == 0 {
                        continue;
                    }
                    wide(
                        #[inline(always)]
                        || {
                            for (d, s) in dst[d0..d0 + n].iter_mut().zip(&src[s0..s0 + n]) {
                                *d += k * s;
                            }
                        },
                    );
                }
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bp::backproject;
    use crate::testutil::{add_point, axis, confocal};
    use murk_core::{Axis, DVec3};

    fn point_bp() -> (Capture, Volume, [usize; 3]) {
        let mut c = confocal(16, 0.64, axis(0.0, 0.01, 128));
        // Scan point (8, 7) is at (0.02, −0.02); voxel (8, 7, 20) below it at z = 0.4.
        add_point(&mut c, DVec3::new(0.02, -0.02, 0.4));
        let vol = Volume {
            x: Axis::new(-0.3, 0.3, 16),
            y: Axis::new(-0.3, 0.3, 16),
            z: Axis::new(0.3, 0.5, 41),
        };
        (c, vol, [8, 7, 20])
    }

    #[test]
    fn kernel_is_zero_mean_and_negative_at_the_centre() {
        let k = laplacian_of_gaussian_kernel();
        assert!(k.iter().map(|&v| v as f64).sum::<f64>().abs() < 1e-6);
        let min = k.iter().copied().fold(f32::MAX, f32::min);
        assert_eq!(k[62], min);
        assert!(min < 0.0);
    }

    #[test]
    fn negative_laplacian_peaks_at_the_point_and_positive_one_has_its_minimum_there() {
        let (c, vol, truth) = point_bp();
        let r = fbp(&c, &vol, FbpOptions::default()).unwrap();
        assert_eq!(r.argmax(), truth);
        assert_eq!(r.intensity.iter().copied().fold(0.0, f32::max), 1.0);
        assert!(r.intensity.iter().all(|&v| v >= 0.0));

        // The wrong sign: +∇²G ⊛ BP has its minimum at the point and its maximum elsewhere.
        let bp = backproject(&c, &vol, BpOptions::default()).unwrap();
        let plus = convolve_same(
            &bp.intensity,
            vol.shape(),
            &laplacian_of_gaussian_kernel(),
            [5, 5, 5],
        );
        let argmin = plus
            .iter()
            .enumerate()
            .fold(0, |b, (i, &v)| if v < plus[b] { i } else { b });
        assert_eq!(argmin, vol.index(truth[0], truth[1], truth[2]));
        let wrong = Reconstruction::new(vol, plus, "+∇²G").argmax();
        assert!(
            wrong[2].abs_diff(truth[2]) >= 2,
            "+∇²G maximum at {wrong:?}"
        );
    }

    #[test]
    fn depth_second_derivative_peaks_at_the_point() {
        let (c, vol, truth) = point_bp();
        let opts = FbpOptions {
            filter: FbpFilter::DepthSecondDerivative,
            ..Default::default()
        };
        let got = fbp(&c, &vol, opts).unwrap().argmax();
        for a in 0..3 {
            assert!(got[a].abs_diff(truth[a]) <= 1, "{got:?} vs {truth:?}");
        }
    }

    /// The shifted-axpy correlation against the literal triple sum, with an asymmetric kernel and
    /// volumes thinner than the kernel along x, and along depth (one and two planes).
    #[test]
    fn convolution_matches_the_direct_sum() {
        let ks = [5, 3, 5];
        for shape in [[3, 6, 9], [3, 6, 1], [4, 2, 2]] {
            let [nx, ny, nz] = shape.map(|n| n as isize);
            let data: Vec<f32> = (0..shape.iter().product::<usize>())
                .map(|i| ((i * 37 % 17) as f32 - 8.0) / 3.0)
                .collect();
            let kernel: Vec<f32> = (0..ks.iter().product::<usize>())
                .map(|i| (i as f32 * 0.71).sin())
                .collect();
            let got = convolve_same(&data, shape, &kernel, ks);
            let at = |x: isize, y: isize, z: isize| {
                let ok = (0..nx).contains(&x) && (0..ny).contains(&y) && (0..nz).contains(&z);
                if ok {
                    data[((x * ny + y) * nz + z) as usize]
                } else {
                    0.0
                }
            };
            for (i, g) in got.iter().enumerate() {
                let i = i as isize;
                let (x, y, z) = (i / (ny * nz), i / nz % ny, i % nz);
                let mut want = 0.0f32;
                for (k, w) in kernel.iter().enumerate() {
                    let (a, b, c) = ((k / 15) as isize, (k / 5 % 3) as isize, (k % 5) as isize);
                    want += w * at(x + a - 2, y + b - 1, z + c - 2);
                }
                assert!(
                    (g - want).abs() < 1e-4,
                    "{shape:?}, voxel {i}: {g} vs {want}"
                );
            }
        }
    }
}
