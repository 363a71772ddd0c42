//! Image-quality metrics for comparing reconstructions with the renderer's ground truth.
//!
//! Images are row-major `width × height` slices (pixel `(x, y)` at `y * width + x`) and masks are
//! `bool` slices of the same layout. Image metrics first pass through [`normalised`], so
//! non-finite pixels count as 0 and the reconstruction's arbitrary intensity scale drops out;
//! degenerate inputs (empty, mismatched lengths) give NaN rather than a panic.

use std::f64::consts::PI;

/// Half-width of the SSIM Gaussian window (11 × 11), as in Wang et al. 2004.
const SSIM_RADIUS: usize = 5;
const SSIM_SIGMA: f64 = 1.5;
/// SSIM stabilisers (K1 L)² and (K2 L)² for K1 = 0.01, K2 = 0.03 and dynamic range L = 1.
const SSIM_C1: f64 = 0.01 * 0.01;
const SSIM_C2: f64 = 0.03 * 0.03;
/// Radial frequency (cycles/pixel) above which spectral energy counts as high: half of Nyquist.
const HIGH_FREQUENCY: f64 = 0.25;

/// Scales an image so its maximum is 1, making metrics independent of a reconstruction's intensity
/// scale. Non-finite pixels become 0; an image whose maximum is not positive (all zero, all
/// negative, empty) is returned unscaled.
pub fn normalised(img: &[f32]) -> Vec<f32> {
    let mut out: Vec<f32> = img
        .iter()
        .map(|&v| if v.is_finite() { v } else { 0.0 })
        .collect();
    let max = out.iter().copied().fold(0.0, f32::max);
    if max > 0.0 {
        out.iter_mut().for_each(|v| *v /= max);
    }
    out
}

/// Intersection over union of two masks. NaN when both masks are empty (the overlap is undefined)
/// or their lengths differ.
pub fn iou(a: &[bool], b: &[bool]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    iou_of(a.iter().copied().zip(b.iter().copied()))
}

/// IoU of paired mask values, counted without building the masks; 0/0 gives NaN for empty unions.
fn iou_of(pairs: impl Iterator<Item = (bool, bool)>) -> f64 {
    let (mut intersection, mut union) = (0usize, 0usize);
    for (a, b) in pairs {
        intersection += usize::from(a && b);
        union += usize::from(a || b);
    }
    intersection as f64 / union as f64
}

/// Otsu's threshold of the finite values, from a 256-bin histogram between their min and max, in
/// the image's units; pixels at or above it are the object. Equally good adjacent splits (empty
/// bins between two modes) resolve to the middle of the gap, so a two-valued image splits halfway.
/// NaN without two distinct finite values, since no split exists.
pub fn otsu_threshold(img: &[f32]) -> f32 {
    const BINS: usize = 256;
    let finite = || img.iter().copied().filter(|v| v.is_finite()).map(f64::from);
    let (min, max) = finite().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if min >= max {
        return f32::NAN;
    }
    let mut hist = [0.0f64; BINS];
    for v in finite() {
        let bin = ((v - min) / (max - min) * BINS as f64) as usize;
        hist[bin.min(BINS - 1)] += 1.0;
    }
    let total: f64 = hist.iter().sum();
    let total_sum: f64 = hist.iter().enumerate().map(|(k, &c)| k as f64 * c).sum();
    // The min lands in bin 0 and the max in the last bin, so both classes are non-empty at every
    // split.
    let (mut below, mut below_sum) = (0.0, 0.0);
    let (mut best, mut first, mut last) = (f64::NEG_INFINITY, 0, 0);
    for (k, &count) in hist.iter().enumerate().take(BINS - 1) {
        below += count;
        below_sum += k as f64 * count;
        let above = total - below;
        let gap = below_sum / below - (total_sum - below_sum) / above;
        let between_variance = below * above * gap * gap;
        if between_variance > best {
            (best, first, last) = (between_variance, k, k);
        } else if between_variance == best && last + 1 == k {
            last = k;
        }
    }
    // Average of the upper edges of the first and last best bins.
    let edge = (first + last) as f64 / 2.0 + 1.0;
    (min + edge * (max - min) / BINS as f64) as f32
}

/// IoU of a thresholded image against the true object mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IouScores {
    /// Best IoU over the relative thresholds 0.01, 0.02, …, 0.99 (NaN if every one is undefined).
    pub best: f64,
    /// The lowest relative threshold reaching `best`.
    pub best_threshold: f32,
    /// IoU at Otsu's threshold; an image without contrast has an empty Otsu mask.
    pub otsu: f64,
    /// Otsu's threshold of the normalised image, relative to its max (NaN without contrast).
    pub otsu_threshold: f32,
}

/// IoU of the normalised image thresholded (pixels at or above the threshold) against `truth`: the
/// best over relative thresholds 0.01..=0.99 in steps of 0.01, which rewards a reconstruction for
/// its shape whatever its contrast, and at Otsu's threshold, which needs no knowledge of the truth.
/// All scores are NaN when the lengths differ.
pub fn iou_scores(img: &[f32], truth: &[bool]) -> IouScores {
    let norm = normalised(img);
    let score = |threshold: f32| {
        if norm.len() != truth.len() {
            return f64::NAN;
        }
        iou_of(norm.iter().zip(truth).map(|(&v, &t)| (v >= threshold, t)))
    };
    let (mut best, mut best_threshold) = (f64::NAN, f32::NAN);
    for threshold in (1..=99).map(|k| k as f32 / 100.0) {
        let s = score(threshold);
        if s > best || (best.is_nan() && !s.is_nan()) {
            (best, best_threshold) = (s, threshold);
        }
    }
    let otsu_threshold = otsu_threshold(&norm);
    IouScores {
        best,
        best_threshold,
        otsu: score(otsu_threshold),
        otsu_threshold,
    }
}

/// Peak signal-to-noise ratio in dB of `test` against `reference`, both normalised to max 1 (the
/// peak). Identical images give `f64::INFINITY`; empty or mismatched images give NaN.
pub fn psnr(test: &[f32], reference: &[f32]) -> f64 {
    if test.len() != reference.len() {
        return f64::NAN;
    }
    let (test, reference) = (normalised(test), normalised(reference));
    let squared_error: f64 = test
        .iter()
        .zip(&reference)
        .map(|(&t, &r)| (f64::from(t) - f64::from(r)).powi(2))
        .sum();
    -10.0 * (squared_error / test.len() as f64).log10()
}

/// Mean structural similarity (Wang et al. 2004) with an 11 × 11 Gaussian window of σ = 1.5,
/// K1 = 0.01, K2 = 0.03 and L = 1, on both images normalised to max 1. At the borders the window is
/// truncated and its weights renormalised, so every pixel counts and tiny images work; scikit-image
/// instead reflects the image and averages only pixels at least 5 from the border, so the two agree
/// on that interior but not on the overall mean. NaN for empty or mismatched images.
pub fn ssim(a: &[f32], b: &[f32], width: usize, height: usize) -> f64 {
    ssim_map(a, b, width, height).map_or(f64::NAN, |map| map.iter().sum::<f64>() / map.len() as f64)
}

/// Per-pixel SSIM, or `None` when the images are empty or do not match `width × height`.
fn ssim_map(a: &[f32], b: &[f32], width: usize, height: usize) -> Option<Vec<f64>> {
    let n = width.checked_mul(height)?;
    if n == 0 || a.len() != n || b.len() != n {
        return None;
    }
    let widen = |img: &[f32]| {
        normalised(img)
            .into_iter()
            .map(f64::from)
            .collect::<Vec<_>>()
    };
    let (a, b) = (widen(a), widen(b));
    let product = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).collect::<Vec<_>>();
    let kernel: Vec<f64> = (0..=2 * SSIM_RADIUS)
        .map(|i| {
            let d = i as f64 - SSIM_RADIUS as f64;
            (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp()
        })
        .collect();
    // The 2-D Gaussian and its truncation to the image rectangle both factor into rows and columns,
    // so the renormalised 2-D window mean is the renormalised 1-D mean applied twice.
    let local_mean = |img: &[f64]| separable(img, width, height, |line| window_mean(line, &kernel));
    let (mean_a, mean_b) = (local_mean(&a), local_mean(&b));
    let (mean_aa, mean_bb, mean_ab) = (
        local_mean(&product(&a, &a)),
        local_mean(&product(&b, &b)),
        local_mean(&product(&a, &b)),
    );
    Some(
        (0..n)
            .map(|i| {
                let (ma, mb) = (mean_a[i], mean_b[i]);
                let var_a = mean_aa[i] - ma * ma;
                let var_b = mean_bb[i] - mb * mb;
                let cov = mean_ab[i] - ma * mb;
                (2.0 * ma * mb + SSIM_C1) * (2.0 * cov + SSIM_C2)
                    / ((ma * ma + mb * mb + SSIM_C1) * (var_a + var_b + SSIM_C2))
            })
            .collect(),
    )
}

/// Weighted mean of each sample's neighbourhood under a centred kernel, with the kernel cut off at
/// the ends of the line and its remaining weights renormalised.
fn window_mean(line: &[f64], kernel: &[f64]) -> Vec<f64> {
    let radius = kernel.len() / 2;
    (0..line.len())
        .map(|i| {
            let lo = i.saturating_sub(radius);
            let hi = (i + radius).min(line.len() - 1);
            let (sum, weight) = (lo..=hi).fold((0.0, 0.0), |(sum, weight), j| {
                let w = kernel[j + radius - i];
                (sum + w * line[j], weight + w)
            });
            sum / weight
        })
        .collect()
}

/// Applies a length-preserving 1-D transform to every row, then to every column, of a row-major
/// image.
fn separable<T: Copy>(
    img: &[T],
    width: usize,
    height: usize,
    transform: impl Fn(&[T]) -> Vec<T>,
) -> Vec<T> {
    let mut out: Vec<T> = img.chunks_exact(width).flat_map(&transform).collect();
    let mut column = Vec::with_capacity(height);
    for x in 0..width {
        column.clear();
        column.extend((0..height).map(|y| out[y * width + x]));
        for (y, v) in transform(&column).into_iter().enumerate() {
            out[y * width + x] = v;
        }
    }
    out
}

/// Contrast-to-noise ratio of the object mask against the rest, |μ_in − μ_out| / √(σ²_in + σ²_out)
/// with population variances on the normalised image. NaN if either side is empty or the lengths
/// differ; infinite when both sides are noise-free but differ.
pub fn cnr(img: &[f32], mask: &[bool]) -> f64 {
    if img.len() != mask.len() {
        return f64::NAN;
    }
    let norm = normalised(img);
    let side = |inside: bool| {
        moments(
            norm.iter()
                .zip(mask)
                .filter(|&(_, &m)| m == inside)
                .map(|(&v, _)| f64::from(v)),
        )
    };
    let (object, rest) = (side(true), side(false));
    if object.n == 0 || rest.n == 0 {
        return f64::NAN;
    }
    let noise = object.m2 / object.n as f64 + rest.m2 / rest.n as f64;
    (object.mean - rest.mean).abs() / noise.sqrt()
}

/// Share of the spectral energy of the normalised image, minus its mean, at radial frequencies
/// above half of Nyquist (|f| > 0.25 cycles/pixel): a blur-free measure of fine detail and noise,
/// lower for smoother images. 0 for a constant image, NaN for an empty or mismatched one. The 2-D
/// DFT is direct but separable, O(wh(w + h)), ample for images of a few hundred pixels a side.
pub fn high_frequency_share(img: &[f32], width: usize, height: usize) -> f64 {
    if width
        .checked_mul(height)
        .is_none_or(|n| n == 0 || n != img.len())
    {
        return f64::NAN;
    }
    let norm = normalised(img);
    let mean = norm.iter().map(|&v| f64::from(v)).sum::<f64>() / norm.len() as f64;
    let centred: Vec<(f64, f64)> = norm.iter().map(|&v| (f64::from(v) - mean, 0.0)).collect();
    let spectrum = separable(&centred, width, height, dft);
    // Signed frequency in cycles/pixel of DFT bin k of a length-`len` axis.
    let frequency = |k: usize, len: usize| {
        let signed = if 2 * k > len {
            k as f64 - len as f64
        } else {
            k as f64
        };
        signed / len as f64
    };
    let (mut high, mut total) = (0.0, 0.0);
    for (i, &(re, im)) in spectrum.iter().enumerate() {
        let power = re * re + im * im;
        total += power;
        if frequency(i % width, width).hypot(frequency(i / width, height)) > HIGH_FREQUENCY {
            high += power;
        }
    }
    if total > 0.0 {
        high / total
    } else {
        0.0
    }
}

/// Direct discrete Fourier transform of complex samples `(re, im)`, with the twiddle factors
/// tabulated once per line.
fn dft(line: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let n = line.len();
    let twiddles: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let (sin, cos) = (-2.0 * PI * k as f64 / n as f64).sin_cos();
            (cos, sin)
        })
        .collect();
    (0..n)
        .map(|k| {
            let (mut re, mut im, mut phase) = (0.0, 0.0, 0);
            for &(xr, xi) in line {
                let (c, s) = twiddles[phase];
                re += xr * c - xi * s;
                im += xr * s + xi * c;
                // The twiddle index k·j mod n, advanced without a division.
                phase += k;
                if phase >= n {
                    phase -= n;
                }
            }
            (re, im)
        })
        .collect()
}

pub use murk_core::median;

/// Whether a depth error is within one voxel of `dz_m`. Depths are stored in f32, so an error of
/// exactly one voxel reads up to a few 1e-7 relative above it (2.025 − 2.0 = 0.0250001 in f32).
pub fn within_a_voxel(err_m: f64, dz_m: f64) -> bool {
    err_m.abs() <= dz_m * (1.0 + 1e-5)
}

/// A column's brightest voxel must reach this multiple of the column's mean for it to hold a surface:
/// a flat column (ratio 1) holds none.
const SURFACE_CONTRAST: f32 = 2.0;
/// The nearest surface is the first local maximum reaching this share of the column's brightest.
const SURFACE_SHARE: f32 = 0.5;
/// An object is detected when more than this share of its pixels has a surface within tolerance: more
/// than half, so that the median depth error of a detected object is within tolerance too.
const DETECTED_SHARE: f64 = 0.5;

/// The index of a column's nearest surface (z ascending away from the relay): its first local maximum
/// that reaches half of its brightest voxel. None for a column without one that stands out (the
/// brightest below twice the mean, or not positive). Not the brightest voxel: the virtual aperture
/// sees around a small object, so a wall behind it can be brighter in the object's own column.
pub fn nearest_surface(column: &[f32]) -> Option<usize> {
    let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
    let max = column.iter().map(|&v| finite(v)).fold(0.0, f32::max);
    let mean = column.iter().map(|&v| finite(v)).sum::<f32>() / column.len().max(1) as f32;
    if max <= 0.0 || max < SURFACE_CONTRAST * mean {
        return None;
    }
    let at = |i: usize| finite(column[i]);
    (0..column.len()).find(|&i| {
        at(i) >= SURFACE_SHARE * max
            && (i == 0 || at(i) >= at(i - 1))
            && (i + 1 == column.len() || at(i) >= at(i + 1))
    })
}

/// Whether an object is found at its depth, and how far off its depth is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    /// More than half of the object's pixels have their nearest surface within the tolerance, so its
    /// median depth error is within it too.
    pub detected: bool,
    /// The share of the object's pixels whose nearest surface is within the tolerance.
    pub hit_share: f64,
    /// Median over the object's pixels with a surface of (found − true) depth; NaN without any.
    pub depth_err_m: f64,
}

/// Detects an object from per-pixel nearest-surface depths (`found_m`, NaN where a column holds none,
/// from [`nearest_surface`]) against its true depths, over the pixels of `mask`. A pixel counts when its
/// depth is within `tolerance_m`, so an image without depth structure detects nothing whatever its
/// brightness.
pub fn detect_object(
    found_m: &[f64],
    true_m: &[f64],
    mask: &[bool],
    tolerance_m: f64,
) -> Detection {
    let errs: Vec<f64> = (0..mask.len())
        .filter(|&i| mask[i])
        .map(|i| found_m[i] - true_m[i])
        .collect();
    let pixels = errs.len();
    let found: Vec<f64> = errs.iter().copied().filter(|e| e.is_finite()).collect();
    // The same f32 slack as `within_a_voxel`: depths are stored in f32.
    let hits = found
        .iter()
        .filter(|e| e.abs() <= tolerance_m * (1.0 + 1e-5))
        .count();
    let hit_share = if pixels == 0 {
        0.0
    } else {
        hits as f64 / pixels as f64
    };
    Detection {
        detected: hit_share > DETECTED_SHARE,
        hit_share,
        depth_err_m: median(&found),
    }
}

/// Mean and sample standard deviation (n − 1 denominator) of the finite values: `(NaN, NaN)` for
/// none, and a NaN standard deviation for one (a spread of one value is undefined, not zero).
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let m = moments(values.iter().copied().filter(|v| v.is_finite()));
    match m.n {
        0 => (f64::NAN, f64::NAN),
        1 => (m.mean, f64::NAN),
        n => (m.mean, (m.m2 / (n - 1) as f64).sqrt()),
    }
}

/// Count, mean and sum of squared deviations from the mean.
struct Moments {
    n: usize,
    mean: f64,
    m2: f64,
}

/// Single-pass moments by Welford's update, which avoids the cancellation of Σx² − n·mean².
fn moments(values: impl Iterator<Item = f64>) -> Moments {
    values.fold(
        Moments {
            n: 0,
            mean: 0.0,
            m2: 0.0,
        },
        |m, v| {
            let n = m.n + 1;
            let delta = v - m.mean;
            let mean = m.mean + delta / n as f64;
            Moments {
                n,
                mean,
                m2: m.m2 + delta * (v - mean),
            }
        },
    )
}

#[cfg(test)]
mod tests;
