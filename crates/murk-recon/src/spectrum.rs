//! The temporal side of Phasor Fields: which part of each histogram matters for a volume, the band of
//! frequencies of the virtual pulse, and each histogram's band-limited spectrum with its fixed path
//! offsets already applied as exact phases.

use murk_core::{Capture, DVec3, Error, Result, Volume};
use rayon::prelude::*;
use rustfft::num_complex::{Complex32, Complex64};
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

/// Gaussian envelope truncation used for time windows and padding, in units of σ.
const ENVELOPE_SIGMAS: f64 = 4.0;

/// Frequencies of the virtual pulse P0(s) = exp(i2πs/λ)·exp(−s²/2σ²) on the DFT grid of the padded window.
#[derive(Clone, Debug)]
pub struct Band {
    /// DFT length of the padded window.
    pub nf: usize,
    pub bin_width_m: f64,
    /// First DFT index kept; the band is `m_lo .. m_lo + weights.len()`.
    pub m_lo: usize,
    /// Gaussian weights W_m = exp(−2π²σ²(f_m − 1/λ)²), so W(1/λ) = 1.
    pub weights: Vec<f64>,
}

impl Band {
    /// tal pf_dev's band: f ∈ [1/λ − 1/(2σ), 1/λ + 1/(2σ)] (≈ ±3.1 spectral std), positive frequencies only.
    pub fn new(nf: usize, bin_width_m: f64, wavelength_m: f64, sigma_m: f64) -> Band {
        let span = nf as f64 * bin_width_m;
        let mu = span / wavelength_m;
        let half = span / (2.0 * sigma_m);
        let m_lo = ((mu - half).floor().max(1.0)) as usize;
        let m_hi = ((mu + half).ceil() as usize).min(nf / 2);
        let weights = (m_lo..=m_hi.max(m_lo))
            .map(|m| {
                let df = m as f64 / span - 1.0 / wavelength_m;
                (-2.0 * PI * PI * sigma_m * sigma_m * df * df).exp()
            })
            .collect();
        Band {
            nf,
            bin_width_m,
            m_lo,
            weights,
        }
    }
    pub fn len(&self) -> usize {
        self.weights.len()
    }
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }
    /// Angular wavenumber k_m = 2π f_m of the j-th band entry (rad per metre of path).
    pub fn k(&self, j: usize) -> f64 {
        2.0 * PI * (self.m_lo + j) as f64 / (self.nf as f64 * self.bin_width_m)
    }
    /// Spacing between consecutive k_m.
    pub fn dk(&self) -> f64 {
        2.0 * PI / (self.nf as f64 * self.bin_width_m)
    }
    /// Shortest wavelength in the band (what the spatial Nyquist limit applies to).
    pub fn min_wavelength_m(&self) -> f64 {
        2.0 * PI / self.k(self.len() - 1)
    }
}

/// Band-limited spectra of every histogram for several [`Window`]s, computed in one pass over the
/// data (reading the histograms dominates, not the transforms).
pub struct Spectra<'w> {
    windows: &'w [Window],
    /// `[hist][window][j]`: W_j·Ĥ_j·exp(ik_j(e_l + e_s − s_pad0)) / nf, so that a voxel's value is
    /// Σ_j spec[j]·exp(ik_j(d_l + d_s)) summed over histograms.
    spec: Vec<Complex32>,
    /// Offset of each window's band within a histogram's row, and the row length.
    offsets: Vec<usize>,
    stride: usize,
}

impl Spectra<'_> {
    /// The spectra of window `w`.
    pub fn part(&self, w: usize) -> Part<'_> {
        Part {
            band: &self.windows[w].band,
            spec: &self.spec,
            offset: self.offsets[w],
            stride: self.stride,
        }
    }
}

/// One window's spectra within [`Spectra`].
pub struct Part<'a> {
    pub band: &'a Band,
    spec: &'a [Complex32],
    offset: usize,
    stride: usize,
}

impl Part<'_> {
    pub fn hist(&self, i: usize) -> &[Complex32] {
        &self.spec[i * self.stride + self.offset..][..self.band.len()]
    }
}

/// Smallest and largest distance from `p` to the axis-aligned box of the volume.
pub fn box_distance_range(p: DVec3, vol: &Volume) -> (f64, f64) {
    let lo = DVec3::new(
        vol.x.start.min(vol.x.end),
        vol.y.start.min(vol.y.end),
        vol.z.start.min(vol.z.end),
    );
    let hi = DVec3::new(
        vol.x.start.max(vol.x.end),
        vol.y.start.max(vol.y.end),
        vol.z.start.max(vol.z.end),
    );
    let near = p.clamp(lo, hi);
    let far = DVec3::new(
        if (p.x - lo.x).abs() > (p.x - hi.x).abs() {
            lo.x
        } else {
            hi.x
        },
        if (p.y - lo.y).abs() > (p.y - hi.y).abs() {
            lo.y
        } else {
            hi.y
        },
        if (p.z - lo.z).abs() > (p.z - hi.z).abs() {
            lo.z
        } else {
            hi.z
        },
    );
    ((p - near).length(), (p - far).length())
}

/// Range of total path (device to device) over all measured pairs and all voxels of `vol`.
pub fn path_range(cap: &Capture, vol: &Volume) -> (f64, f64) {
    let side = |pts: &[DVec3], off: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
        pts.iter()
            .enumerate()
            .map(|(i, &p)| {
                let (a, b) = box_distance_range(p, vol);
                (a + off(i), b + off(i))
            })
            .collect()
    };
    let il = side(&cap.illum.points, &|l| cap.first_bounce_m(l));
    let se = side(&cap.sensor.points, &|s| cap.last_bounce_m(s));
    match cap.pairing {
        murk_core::Pairing::Product => {
            let min = |v: &[(f64, f64)]| v.iter().map(|r| r.0).fold(f64::MAX, f64::min);
            let max = |v: &[(f64, f64)]| v.iter().map(|r| r.1).fold(f64::MIN, f64::max);
            (min(&il) + min(&se), max(&il) + max(&se))
        }
        murk_core::Pairing::Paired => il
            .iter()
            .zip(&se)
            .fold((f64::MAX, f64::MIN), |(lo, hi), (a, b)| {
                (lo.min(a.0 + b.0), hi.max(a.1 + b.1))
            }),
    }
}

/// Smallest length ≥ n whose only prime factors are 2, 3 and 5: rustfft's fastest kernels (a factor
/// 7 costs more per point; docs/benchmarks.md).
pub fn next_fast_len(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

/// The bins of every histogram that paths in a range need (± the pulse envelope), zero-padded (never
/// wrapped) to a fast DFT length, and the pulse's band on that DFT's grid.
pub struct Window {
    pub band: Band,
    /// Bins `i_lo..i_hi` of the data are used; they start at `lead` in the padded window.
    i_lo: usize,
    i_hi: usize,
    lead: usize,
    /// Path at the centre of the padded window's first sample.
    s_pad0_m: f64,
    /// True when the data's time window misses part of the paths (zeros are used there).
    pub truncated: bool,
    /// True when no data bin falls within the paths at all.
    pub empty: bool,
}

impl Window {
    /// The window for total paths (device to device) in `paths_m`.
    pub fn new(
        cap: &Capture,
        paths_m: (f64, f64),
        sigma_m: f64,
        wavelength_m: f64,
    ) -> Result<Window> {
        let t = cap.time;
        let dt = t.bin_width_m;
        let (pmin, pmax) = paths_m;
        let margin = ENVELOPE_SIGMAS * sigma_m;
        // Bin n represents path start + (n + ½)Δs.
        let want_lo = ((pmin - margin - t.start_m) / dt - 0.5).floor() as i64;
        let want_hi = ((pmax + margin - t.start_m) / dt - 0.5).ceil() as i64 + 1;
        let i_lo = want_lo.clamp(0, t.bins as i64) as usize;
        let i_hi = want_hi.clamp(0, t.bins as i64) as usize;
        // The window the paths need, not the data we have, sets the period. A read lies at least one
        // margin inside the window, so the nearest wrapped image of any data bin is at least a margin
        // away: it weighs no more than the data the crop already drops. Lengths are even: the real DFT
        // is a complex one of half the length (see [`HalfLength`]).
        let pad = 1;
        // Checked before rounding up to a fast length, whose search is linear in the length.
        let span_bins = want_hi.saturating_sub(want_lo).max(1);
        if span_bins > 1 << 24 {
            return Err(Error::Limits(format!(
                "the volume needs {span_bins} time samples of {} m; use a smaller volume or coarser bins",
                murk_core::short(dt)
            )));
        }
        let nf = 2 * next_fast_len((span_bins as usize + 2 * pad).div_ceil(2));
        let band = Band::new(nf, dt, wavelength_m, sigma_m);
        if band.is_empty() {
            return Err(Error::param(format!(
                "no frequency of the virtual pulse (λ = {} m) fits the {} m bins",
                murk_core::short(wavelength_m),
                murk_core::short(dt)
            )));
        }
        let first_bin = want_lo - pad as i64;
        Ok(Window {
            band,
            i_lo,
            i_hi,
            lead: (i_lo as i64 - first_bin) as usize,
            s_pad0_m: t.start_m + (first_bin as f64 + 0.5) * dt,
            truncated: want_lo < 0 || want_hi > t.bins as i64,
            empty: i_lo >= i_hi,
        })
    }
}

/// A real DFT of even length N restricted to a band's bins: the samples, read as N/2 complex values
/// (even ones real, odd ones imaginary), take one complex FFT of N/2, and only the band's bins are
/// separated into the real signal's spectrum, not all N/2 + 1.
struct HalfLength {
    fft: Arc<dyn Fft<f32>>,
    /// e^{−2πi·m/N} at the band's bins m.
    twiddles: Vec<Complex32>,
    m_lo: usize,
}

impl HalfLength {
    fn new(band: &Band, planner: &mut FftPlanner<f32>) -> HalfLength {
        let twiddles = (0..band.len())
            .map(|j| {
                let turn = -2.0 * PI * (band.m_lo + j) as f64 / band.nf as f64;
                let c = Complex64::from_polar(1.0, turn);
                Complex32::new(c.re as f32, c.im as f32)
            })
            .collect();
        HalfLength {
            fft: planner.plan_fft_forward(band.nf / 2),
            twiddles,
            m_lo: band.m_lo,
        }
    }

    /// The real signal's DFT at the band's j-th bin m from the half-length transform `z`: the
    /// even samples' spectrum plus e^{−2πi·m/N} times the odd samples'.
    fn bin(&self, z: &[Complex32], j: usize) -> Complex32 {
        let half = z.len();
        let m = (self.m_lo + j) % half;
        let (a, b) = (z[m], z[(half - m) % half].conj());
        let even = (a + b) * 0.5;
        let odd = (a - b) * Complex32::new(0.0, -0.5);
        even + self.twiddles[j] * odd
    }
}

/// Transforms every histogram over each window and keeps the windows' bands, path offsets applied as
/// exact phases.
pub fn spectra<'w>(cap: &Capture, windows: &'w [Window]) -> Spectra<'w> {
    let mut offsets = Vec::with_capacity(windows.len());
    let mut stride = 0;
    for w in windows {
        offsets.push(stride);
        stride += w.band.len();
    }
    // Zero pages from the OS, first touched by the threads that write the rows (a window with no
    // data leaves its part zero).
    let mut spec: Vec<Complex32> = murk_core::buffer::zeroed(cap.n_hist() * stride);
    let halves: Vec<HalfLength> = {
        let mut planner = FftPlanner::<f32>::new();
        windows
            .iter()
            .map(|w| HalfLength::new(&w.band, &mut planner))
            .collect()
    };
    spec.par_chunks_mut(stride.max(1))
        .enumerate()
        .for_each_init(
            || {
                halves
                    .iter()
                    .map(|f| {
                        let n = f.fft.len();
                        (
                            vec![Complex32::default(); n],
                            vec![Complex32::default(); f.fft.get_inplace_scratch_len()],
                        )
                    })
                    .collect::<Vec<_>>()
            },
            |bufs, (i, row)| {
                let h = cap.histogram(i);
                let (l, s) = cap.hist_pair(i);
                let bounces_m = cap.first_bounce_m(l) + cap.last_bounce_m(s);
                for (((w, half), (z, scratch)), &o) in windows
                    .iter()
                    .zip(&halves)
                    .zip(bufs.iter_mut())
                    .zip(&offsets)
                {
                    if w.empty {
                        continue;
                    }
                    let band = &w.band;
                    let (lead, n) = (w.lead, w.i_hi - w.i_lo);
                    let input = crate::cmul::floats_mut(z);
                    input[..lead].iter_mut().for_each(|v| *v = 0.0);
                    input[lead + n..].iter_mut().for_each(|v| *v = 0.0);
                    input[lead..lead + n].copy_from_slice(&h[w.i_lo..w.i_hi]);
                    half.fft.process_with_scratch(z, scratch);
                    let shift = bounces_m - w.s_pad0_m;
                    // exp(ik_j·shift) by recurrence from k_0 (f64: no drift over a band), times the
                    // pulse weight and the 1/nf scale.
                    let mut ph = Complex64::from_polar(1.0 / band.nf as f64, band.k(0) * shift);
                    let step = Complex64::from_polar(1.0, band.dk() * shift);
                    for (j, (r, wj)) in row[o..o + band.len()]
                        .iter_mut()
                        .zip(&band.weights)
                        .enumerate()
                    {
                        let p = ph * *wj;
                        *r = half.bin(z, j) * Complex32::new(p.re as f32, p.im as f32);
                        ph *= step;
                    }
                }
            },
        );
    Spectra {
        windows,
        spec,
        offsets,
        stride,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_matches_tal_table() {
        // docs/reconstruction.md: 2 m wall / 128 points, λ = 4Δc, cycles 4, Nf = 5104, 1 mm bins → [20, 142].
        let dc = 2.0 / 127.0;
        let lambda = 4.0 * dc;
        let b = Band::new(5104, 0.001, lambda, 4.0 * lambda / 6.0);
        assert_eq!((b.m_lo, b.m_lo + b.len() - 1), (20, 142));
        let jc = (5104.0 * 0.001 / lambda).round() as usize - b.m_lo;
        // W(f_c) = 1 up to the off-grid distance of the nearest bin.
        assert!((b.weights[jc] - 1.0).abs() < 1e-3, "{}", b.weights[jc]);
    }

    /// The half-length transform's band bins against a direct f64 DFT, over every bin 0..=N/2.
    #[test]
    fn half_length_bins_match_a_direct_dft() {
        for nf in [50, 2000] {
            let band = Band {
                nf,
                bin_width_m: 0.001,
                m_lo: 0,
                weights: vec![1.0; nf / 2 + 1],
            };
            let half = HalfLength::new(&band, &mut FftPlanner::new());
            let x: Vec<f32> = (0..nf)
                .map(|n| ((n * 7919) % 101) as f32 / 50.0 - 1.0)
                .collect();
            let mut z: Vec<Complex32> = x
                .chunks_exact(2)
                .map(|p| Complex32::new(p[0], p[1]))
                .collect();
            half.fft.process(&mut z);
            let scale: f64 = x.iter().map(|v| v.abs() as f64).sum();
            for m in 0..=nf / 2 {
                let want: Complex64 = x
                    .iter()
                    .enumerate()
                    .map(|(n, &v)| {
                        Complex64::from_polar(v as f64, -2.0 * PI * (m * n) as f64 / nf as f64)
                    })
                    .sum();
                let got = half.bin(&z, m);
                let err = (Complex64::new(got.re as f64, got.im as f64) - want).norm();
                assert!(err <= 1e-6 * scale, "N = {nf}, bin {m}: {err}");
            }
        }
    }

    #[test]
    fn fast_lengths() {
        assert_eq!(next_fast_len(5101), 5120);
        assert_eq!(next_fast_len(63), 64);
        assert_eq!(next_fast_len(263), 270);
        assert_eq!(next_fast_len(256), 256);
    }

    #[test]
    fn box_distances() {
        let v = Volume::parse("-1:1:3,-1:1:3,1:2:2").unwrap();
        let (a, b) = box_distance_range(DVec3::ZERO, &v);
        assert!((a - 1.0).abs() < 1e-12 && (b - 6f64.sqrt()).abs() < 1e-12);
    }
}
