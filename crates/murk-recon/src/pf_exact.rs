//! Exact Phasor Fields for any geometry and voxel set (docs/reconstruction.md): each histogram is filtered
//! into its complex band-limited signal once, then every voxel sums the signals read (linear
//! interpolation) at its exact round-trip path. Cost O(voxels × histograms).

use crate::spectrum::Part;
use crate::{Falloff, Progress};
use murk_core::{Capture, Volume};
use rayon::prelude::*;
use rustfft::num_complex::Complex32;
use rustfft::FftPlanner;

pub fn run(
    cap: &Capture,
    vol: &Volume,
    spectra: &Part,
    falloff: Falloff,
    progress: &dyn Progress,
) -> Vec<Complex32> {
    let band = &spectra.band;
    let nf = band.nf;
    let ifft = FftPlanner::<f32>::new().plan_fft_inverse(nf);
    // Filtered signal of each histogram at residual path n·Δs (offsets already folded into the spectra).
    // Zero outside the band; allocated zeroed (a gigabyte at the paper's format).
    let mut signals: Vec<Complex32> = murk_core::buffer::zeroed(cap.n_hist() * nf);
    signals.par_chunks_mut(nf).enumerate().for_each_init(
        || vec![Complex32::default(); ifft.get_inplace_scratch_len()],
        |scratch, (i, sig)| {
            sig[band.m_lo..band.m_lo + band.len()].copy_from_slice(spectra.hist(i));
            ifft.process_with_scratch(sig, scratch);
        },
    );
    let (nx, ny, nz) = (vol.x.n, vol.y.n, vol.z.n);
    let inv_dt = 1.0 / band.bin_width_m;
    let pairs: Vec<(usize, usize)> = (0..cap.n_hist()).map(|i| cap.hist_pair(i)).collect();
    progress.start(nx as u64);
    let mut field = vec![Complex32::default(); nx * ny * nz];
    field.par_chunks_mut(ny * nz).enumerate().for_each_init(
        || {
            (
                vec![0.0f64; cap.illum.len()],
                vec![0.0f64; cap.sensor.len()],
            )
        },
        |(dl, ds), (ix, out)| {
            for iy in 0..ny {
                for iz in 0..nz {
                    let v = vol.centre(ix, iy, iz);
                    for (d, p) in dl.iter_mut().zip(&cap.illum.points) {
                        *d = (v - *p).length();
                    }
                    for (d, p) in ds.iter_mut().zip(&cap.sensor.points) {
                        *d = (v - *p).length();
                    }
                    let mut acc = (0.0f64, 0.0f64);
                    for (h, &(l, s)) in pairs.iter().enumerate() {
                        let u = ((dl[l] + ds[s]) * inv_dt).rem_euclid(nf as f64);
                        let i0 = u as usize % nf;
                        let frac = (u - u.floor()) as f32;
                        let sig = &signals[h * nf..(h + 1) * nf];
                        let val = sig[i0] * (1.0 - frac) + sig[(i0 + 1) % nf] * frac;
                        let a = match falloff {
                            Falloff::None => 1.0,
                            Falloff::InvR => 1.0 / (dl[l] * ds[s]).max(1e-18),
                        };
                        acc.0 += val.re as f64 * a;
                        acc.1 += val.im as f64 * a;
                    }
                    out[iy * nz + iz] = Complex32::new(acc.0 as f32, acc.1 as f32);
                }
            }
            progress.advance(1);
        },
    );
    field
}
