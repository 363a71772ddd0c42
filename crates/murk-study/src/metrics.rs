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
mod tests {
    use super::*;

    fn assert_close(actual: f64, expected: f64, tolerance: f64) {
        assert!(
            (actual - expected).abs() <= tolerance,
            "got {actual}, expected {expected} ± {tolerance}"
        );
    }

    /// A deterministic structured image: a Gaussian blob on a tilted sinusoid.
    fn blob(width: usize, height: usize, cx: f64, cy: f64) -> Vec<f32> {
        (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f64, (i / width) as f64);
                let r2 = (x - cx).powi(2) + (y - cy).powi(2);
                ((-r2 / 8.0).exp() + 0.2 * (1.0 + (0.9 * x + 0.4 * y).sin())) as f32
            })
            .collect()
    }

    #[test]
    fn normalised_scales_max_to_one_and_zeroes_non_finite() {
        let out = normalised(&[2.0, f32::NAN, 1.0, f32::INFINITY, -1.0]);
        assert_eq!(out, vec![1.0, 0.0, 0.5, 0.0, -0.5]);
    }

    #[test]
    fn normalised_leaves_images_without_positive_max_unscaled() {
        assert_eq!(normalised(&[0.0, 0.0]), vec![0.0, 0.0]);
        assert_eq!(normalised(&[-2.0, -1.0]), vec![-2.0, -1.0]);
        assert!(normalised(&[]).is_empty());
    }

    #[test]
    fn iou_hand_computed() {
        // Intersection {1, 2} = 2 pixels, union {0, 1, 2, 3} = 4 pixels: 2 / 4.
        let a = [true, true, true, false, false];
        let b = [false, true, true, true, false];
        assert_close(iou(&a, &b), 0.5, 1e-15);
    }

    #[test]
    fn iou_properties() {
        let a = [true, false, true, false];
        assert_eq!(iou(&a, &a), 1.0);
        assert_eq!(iou(&a, &[false, true, false, true]), 0.0);
        assert!(iou(&[false; 3], &[false; 3]).is_nan());
        assert!(iou(&[], &[]).is_nan());
        assert!(iou(&a, &a[..3]).is_nan());
    }

    #[test]
    fn otsu_threshold_hand_computed() {
        // Range 0..3 in 256 bins of 3/256: 0 → bin 0, 1 → bin 85, 3 → bin 255. Splitting after bins
        // 0..=84 gives between-class variance w0·w1·(μ0 − μ1)² = 3·3·(0 − 425/3)² ≈ 180 625 (counts
        // and bin indices), after bins 85..=254 gives 5·1·(34 − 255)² = 244 205, the best. The
        // plateau's upper edges are bins 86 and 255, so the threshold is
        // 170.5 · 3/256 = 1.998046875.
        let t = otsu_threshold(&[0.0, 0.0, 0.0, 1.0, 1.0, 3.0, f32::NAN]);
        assert_close(f64::from(t), 1.998_046_875, 1e-6);
        // Two values: every split between them is equally good, so the threshold is halfway.
        assert_close(f64::from(otsu_threshold(&[2.0, 5.0, 2.0, 5.0])), 3.5, 1e-6);
    }

    #[test]
    fn otsu_threshold_degenerate_inputs() {
        assert!(otsu_threshold(&[]).is_nan());
        assert!(otsu_threshold(&[f32::NAN, f32::INFINITY]).is_nan());
        assert!(otsu_threshold(&[4.0, 4.0, f32::NAN]).is_nan());
    }

    #[test]
    fn iou_scores_hand_computed() {
        // Normalised by 4: [0, 0.155, 0.555, 1] against truth {2, 3}. Thresholds ≤ 0.15 keep
        // {1, 2, 3} (IoU 2/3), 0.16..=0.55 keep exactly {2, 3} (IoU 1), higher ones keep {3} (1/2);
        // the best is 1, first reached at 0.16. Otsu in bins of 1/256: 0 → 0, 0.155 → 39,
        // 0.555 → 142, 1 → 255; splits after bins 39..=141 score 2·2·(19.5 − 198.5)² = 128 164,
        // beating 1·3·(0 − 436/3)² ≈ 63 365 and 3·1·(181/3 − 255)² ≈ 113 688, so the threshold is
        // the mean of upper edges 40 and 142, 91/256 = 0.35546875, which keeps {2, 3}: IoU 1.
        let scores = iou_scores(&[0.0, 0.62, 2.22, 4.0], &[false, false, true, true]);
        assert_eq!(scores.best, 1.0);
        assert_close(f64::from(scores.best_threshold), 0.16, 1e-6);
        assert_eq!(scores.otsu, 1.0);
        assert_close(f64::from(scores.otsu_threshold), 0.355_468_75, 1e-6);
    }

    #[test]
    fn iou_scores_degenerate_inputs() {
        let scores = iou_scores(&[1.0, 0.0], &[true]);
        assert!(scores.best.is_nan() && scores.best_threshold.is_nan() && scores.otsu.is_nan());
        // An all-zero image never reaches a threshold and has no Otsu threshold, so its masks are
        // empty and score 0 against a non-empty truth.
        let scores = iou_scores(&[0.0, 0.0], &[true, false]);
        assert_eq!(
            (scores.best, scores.best_threshold, scores.otsu),
            (0.0, 0.01, 0.0)
        );
        assert!(scores.otsu_threshold.is_nan());
    }

    #[test]
    fn psnr_hand_computed() {
        // Normalised: test [1, 0.5, 0, 0] vs reference [1, 0, 0, 0]; MSE = 0.25 / 4 = 1/16, so
        // PSNR = 10·log10(16) ≈ 12.0412 dB.
        assert_close(
            psnr(&[2.0, 1.0, 0.0, 0.0], &[1.0, 0.0, 0.0, 0.0]),
            10.0 * 16f64.log10(),
            1e-9,
        );
    }

    #[test]
    fn psnr_properties() {
        let img = blob(8, 8, 3.0, 4.0);
        assert_eq!(psnr(&img, &img), f64::INFINITY);
        let doubled: Vec<f32> = img.iter().map(|v| v * 2.0).collect();
        assert_eq!(psnr(&doubled, &img), f64::INFINITY);
        assert!(psnr(&[], &[]).is_nan());
        assert!(psnr(&img, &img[1..]).is_nan());
    }

    #[test]
    fn ssim_identical_and_scaled_copies_are_one() {
        let img = blob(9, 7, 4.0, 3.0);
        assert_close(ssim(&img, &img, 9, 7), 1.0, 1e-12);
        let scaled: Vec<f32> = img.iter().map(|v| v * 3.0).collect();
        assert_close(ssim(&scaled, &img, 9, 7), 1.0, 1e-6);
    }

    #[test]
    fn ssim_zero_against_constant_is_analytic() {
        // Everywhere μa = 0, μb = 1 and all variances vanish, so SSIM = C1 / (1 + C1) · C2 / C2.
        let expected = SSIM_C1 / (1.0 + SSIM_C1);
        assert_close(ssim(&[0.0; 12], &[5.0; 12], 4, 3), expected, 1e-12);
    }

    #[test]
    fn ssim_two_pixel_hand_computed() {
        // a = [1, 0], b = [0, 1] on a 2 × 1 image. At pixel 0 the truncated window has weights
        // w0 = 1/(1 + g), w1 = g/(1 + g) with g = exp(−1/(2·1.5²)) ≈ 0.8007 (mirrored at pixel 1),
        // so μa = w0, μb = w1, σa² = σb² = w0·w1 = p, σab = −p and
        // SSIM = (2p + C1)(C2 − 2p) / ((w0² + w1² + C1)(2p + C2)) ≈ −0.9722 at both pixels.
        let g = (-1.0 / (2.0 * 1.5 * 1.5_f64)).exp();
        let (w0, w1) = (1.0 / (1.0 + g), g / (1.0 + g));
        let p = w0 * w1;
        let expected = (2.0 * p + SSIM_C1) * (SSIM_C2 - 2.0 * p)
            / ((w0 * w0 + w1 * w1 + SSIM_C1) * (2.0 * p + SSIM_C2));
        assert_close(expected, -0.9722, 1e-4);
        assert_close(ssim(&[1.0, 0.0], &[0.0, 1.0], 2, 1), expected, 1e-12);
    }

    /// SSIM straight from the definition: for every pixel, the 2-D Gaussian window clipped to the
    /// image, renormalised, and the weighted moments summed directly.
    fn direct_ssim(a: &[f32], b: &[f32], width: usize, height: usize) -> f64 {
        let (a, b) = (normalised(a), normalised(b));
        let r = SSIM_RADIUS as i64;
        let mut total = 0.0;
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let (mut w_sum, mut ma, mut mb, mut maa, mut mbb, mut mab) =
                    (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
                for v in (y - r).max(0)..=(y + r).min(height as i64 - 1) {
                    for u in (x - r).max(0)..=(x + r).min(width as i64 - 1) {
                        let d2 = ((u - x).pow(2) + (v - y).pow(2)) as f64;
                        let w = (-d2 / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
                        let i = v as usize * width + u as usize;
                        let (p, q) = (f64::from(a[i]), f64::from(b[i]));
                        w_sum += w;
                        ma += w * p;
                        mb += w * q;
                        maa += w * p * p;
                        mbb += w * q * q;
                        mab += w * p * q;
                    }
                }
                let (ma, mb) = (ma / w_sum, mb / w_sum);
                let (va, vb, cov) = (
                    maa / w_sum - ma * ma,
                    mbb / w_sum - mb * mb,
                    mab / w_sum - ma * mb,
                );
                total += (2.0 * ma * mb + SSIM_C1) * (2.0 * cov + SSIM_C2)
                    / ((ma * ma + mb * mb + SSIM_C1) * (va + vb + SSIM_C2));
            }
        }
        total / (width * height) as f64
    }

    #[test]
    fn ssim_matches_direct_window_formula() {
        // Larger than the window on one axis and smaller on the other, so both the full and the
        // truncated windows are exercised; the shifted blob makes SSIM well below 1.
        let (width, height) = (13, 7);
        let (a, b) = (blob(width, height, 5.0, 3.0), blob(width, height, 7.0, 2.0));
        let expected = direct_ssim(&a, &b, width, height);
        assert!(expected < 0.95, "test images too similar: {expected}");
        assert_close(ssim(&a, &b, width, height), expected, 1e-12);
        assert_close(
            ssim(&a[..9], &b[..9], 3, 3),
            direct_ssim(&a[..9], &b[..9], 3, 3),
            1e-12,
        );
    }

    #[test]
    fn ssim_interior_matches_scikit_image() {
        // The same 36 × 32 pair went through scikit-image 0.26 as
        // `structural_similarity(a / a.max(), b / b.max(), gaussian_weights=True, sigma=1.5,
        // use_sample_covariance=False, data_range=1)` with a[y, x], b[y, x] by these formulas
        // (float64, cast to float32 before normalising) and gave 0.30226455468213637. It averages
        // only pixels at least 5 from the border, where the windows are whole and the two
        // implementations coincide, so the interior of our map must give the same mean.
        let (width, height) = (36, 32);
        let image = |f: &dyn Fn(f64, f64, usize, usize) -> f64| -> Vec<f32> {
            (0..width * height)
                .map(|i| {
                    let (x, y) = (i % width, i / width);
                    f(x as f64, y as f64, x, y) as f32
                })
                .collect()
        };
        let a = image(&|x, y, _, _| {
            (-((x - 12.0).powi(2) + (y - 16.0).powi(2)) / 40.0).exp()
                + 0.3 * (1.0 + (0.9 * x + 0.4 * y).sin()) / 2.0
        });
        let b = image(&|x, y, xi, yi| {
            (-((x - 14.0).powi(2) + (y - 15.0).powi(2)) / 30.0).exp()
                + 0.3 * (1.0 + (0.7 * x - 0.5 * y).cos()) / 2.0
                + 0.1 * ((xi * 7 + yi * 3) % 5) as f64 / 4.0
        });
        let map = ssim_map(&a, &b, width, height).expect("valid images");
        let r = SSIM_RADIUS;
        let interior: Vec<f64> = (r..height - r)
            .flat_map(|y| (r..width - r).map(move |x| y * width + x))
            .map(|i| map[i])
            .collect();
        let interior_mean = interior.iter().sum::<f64>() / interior.len() as f64;
        assert_close(interior_mean, 0.302_264_554_682_136_37, 1e-9);
    }

    #[test]
    fn ssim_degenerate_inputs() {
        assert!(ssim(&[], &[], 0, 0).is_nan());
        assert!(ssim(&[1.0; 4], &[1.0; 4], 3, 1).is_nan());
        assert!(ssim(&[1.0; 4], &[1.0; 3], 2, 2).is_nan());
        assert!(ssim(&[1.0; 4], &[1.0; 4], usize::MAX, 2).is_nan());
        // A NaN pixel counts as 0, exactly like a zero pixel.
        let with_nan = ssim(&[1.0, f32::NAN, 0.5, 0.2], &[0.3, 1.0, 0.5, 0.0], 2, 2);
        let with_zero = ssim(&[1.0, 0.0, 0.5, 0.2], &[0.3, 1.0, 0.5, 0.0], 2, 2);
        assert_eq!(with_nan, with_zero);
        assert!((-1.0..=1.0).contains(&with_nan));
    }

    #[test]
    fn cnr_hand_computed() {
        // Normalised by 4: object {1, 0.5} has μ = 0.75, σ² = 0.0625; the rest {0.25, 0.25, 0, 0.5}
        // has μ = 0.25, σ² = (0 + 0 + 0.0625 + 0.0625) / 4 = 0.03125, so
        // CNR = 0.5 / √0.09375 ≈ 1.63299.
        let img = [4.0, 2.0, 1.0, 1.0, 0.0, 2.0];
        let mask = [true, true, false, false, false, false];
        assert_close(cnr(&img, &mask), 0.5 / 0.09375f64.sqrt(), 1e-12);
        assert_close(cnr(&img, &mask), 1.632_993, 1e-6);
    }

    #[test]
    fn cnr_degenerate_inputs() {
        assert!(cnr(&[1.0, 2.0], &[true, true]).is_nan());
        assert!(cnr(&[1.0, 2.0], &[false, false]).is_nan());
        assert!(cnr(&[1.0, 2.0], &[true]).is_nan());
        assert_eq!(cnr(&[1.0, 0.0], &[true, false]), f64::INFINITY);
    }

    /// A `width × 8` image with the given (frequency in cycles/pixel, amplitude) cosines along x.
    fn stripes(width: usize, components: &[(f64, f64)]) -> Vec<f32> {
        (0..width * 8)
            .map(|i| {
                let x = (i % width) as f64;
                let wave: f64 = components
                    .iter()
                    .map(|&(f, amp)| amp * (2.0 * PI * f * x).cos())
                    .sum();
                (2.0 + wave) as f32
            })
            .collect()
    }

    #[test]
    fn high_frequency_share_hand_computed() {
        // Cosines at 1/8 (amplitude 1, below 0.25) and 3/8 cycles/pixel (amplitude 0.5, above):
        // power goes as amplitude², so the high share is 0.25 / (1 + 0.25) = 0.2.
        let img = stripes(8, &[(0.125, 1.0), (0.375, 0.5)]);
        assert_close(high_frequency_share(&img, 8, 8), 0.2, 1e-6);
        // A checkerboard has all its energy at (0.5, 0.5) cycles/pixel.
        let checker: Vec<f32> = (0..16).map(|i| ((i % 4 + i / 4) % 2) as f32).collect();
        assert_close(high_frequency_share(&checker, 4, 4), 1.0, 1e-12);
        // Exactly 0.25 cycles/pixel is not above half of Nyquist.
        assert_close(
            high_frequency_share(&stripes(8, &[(0.25, 1.0)]), 8, 8),
            0.0,
            1e-12,
        );
    }

    #[test]
    fn high_frequency_share_matches_direct_2d_dft() {
        // Odd, non-square sizes check the separable transform and the frequency axes together.
        let (width, height) = (5, 3);
        let img = blob(width, height, 1.0, 2.0);
        let norm = normalised(&img);
        let mean = norm.iter().map(|&v| f64::from(v)).sum::<f64>() / norm.len() as f64;
        let (mut high, mut total) = (0.0, 0.0);
        for v in 0..height {
            for u in 0..width {
                let (mut re, mut im) = (0.0, 0.0);
                for (i, &p) in norm.iter().enumerate() {
                    let (x, y) = ((i % width) as f64, (i / width) as f64);
                    let phase =
                        -2.0 * PI * (u as f64 * x / width as f64 + v as f64 * y / height as f64);
                    re += (f64::from(p) - mean) * phase.cos();
                    im += (f64::from(p) - mean) * phase.sin();
                }
                // Aliased frequencies |u − width| / width are the same as u / width when signed.
                let fu = (u as f64 / width as f64).min(1.0 - u as f64 / width as f64);
                let fv = (v as f64 / height as f64).min(1.0 - v as f64 / height as f64);
                let power = re * re + im * im;
                total += power;
                if fu.hypot(fv) > 0.25 {
                    high += power;
                }
            }
        }
        assert!(
            high > 0.0 && high < total,
            "test image should mix frequencies"
        );
        assert_close(
            high_frequency_share(&img, width, height),
            high / total,
            1e-12,
        );
    }

    #[test]
    fn high_frequency_share_properties() {
        assert_eq!(high_frequency_share(&[3.0; 9], 3, 3), 0.0);
        assert!(high_frequency_share(&[], 0, 0).is_nan());
        assert!(high_frequency_share(&[1.0; 9], 4, 2).is_nan());
        // A 3-tap box blur of a sharp pattern removes more high than low frequencies.
        let sharp: Vec<f32> = (0..32 * 32).map(|i| ((i * 7919) % 13) as f32).collect();
        let blurred: Vec<f32> = (0..32 * 32)
            .map(|i| {
                let (x, y) = (i % 32, i / 32);
                let at = |x: usize| sharp[y * 32 + x.min(31)];
                (at(x.saturating_sub(1)) + at(x) + at(x + 1)) / 3.0
            })
            .collect();
        assert!(high_frequency_share(&blurred, 32, 32) < high_frequency_share(&sharp, 32, 32));
    }

    #[test]
    fn one_voxel_read_in_f32_is_within_a_voxel() {
        let err = (2.025f32 - 2.0f32) as f64;
        assert!(err > 0.025 && within_a_voxel(err, 0.025));
        assert!(within_a_voxel(-0.0125, 0.025));
        assert!(!within_a_voxel(0.0251, 0.025));
    }

    #[test]
    fn median_hand_computed() {
        assert_eq!(median(&[3.0, 1.0, f64::NAN, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0, f64::INFINITY]), 2.5);
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN]).is_nan());
    }

    #[test]
    fn mean_std_hand_computed() {
        // Mean 40 / 8 = 5; squared deviations 9+1+1+1+0+0+4+16 = 32, sample variance 32/7.
        let (mean, std) = mean_std(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0, f64::NAN]);
        assert_close(mean, 5.0, 1e-12);
        assert_close(std, (32.0f64 / 7.0).sqrt(), 1e-12);
        let (one, spread) = mean_std(&[3.5]);
        assert!(one == 3.5 && spread.is_nan(), "{one} ± {spread}");
        let (mean, std) = mean_std(&[f64::NEG_INFINITY]);
        assert!(mean.is_nan() && std.is_nan());
    }

    /// A column with a near and a brighter far surface: the near one is the surface; a flat or
    /// zero column holds none, and one whose near peak is below half the brightest gives the far one.
    #[test]
    fn nearest_surface_is_the_first_peak_that_stands_out() {
        let mut col = vec![0.05f32; 20];
        col[5] = 0.6;
        col[12] = 1.0;
        assert_eq!(nearest_surface(&col), Some(5));
        col[5] = 0.4;
        assert_eq!(nearest_surface(&col), Some(12));
        assert_eq!(nearest_surface(&[0.7; 20]), None);
        assert_eq!(nearest_surface(&[0.0; 20]), None);
        // Brightest at 1.9× the mean: not a surface.
        let weak: Vec<f32> = (0..20).map(|i| if i == 3 { 1.9 } else { 0.95 }).collect();
        assert_eq!(nearest_surface(&weak), None);
    }

    /// A constant volume (a flat image at any brightness) detects no object; the same objects placed
    /// at their true depths are detected with zero error, and 3 voxels off they are not.
    #[test]
    fn a_flat_volume_detects_no_object() {
        let (n, nz, dz) = (16usize, 41usize, 0.025);
        let z = |iz: usize| 1.5 + iz as f64 * dz;
        let truth: Vec<f64> = (0..n).map(|i| if i < 8 { 1.85 } else { 2.2 }).collect();
        let masks = [
            (0..n).map(|i| i < 8).collect::<Vec<bool>>(),
            (0..n).map(|i| i >= 8).collect(),
        ];
        let found = |vol: &[Vec<f32>]| -> Vec<f64> {
            vol.iter()
                .map(|c| nearest_surface(c).map_or(f64::NAN, z))
                .collect()
        };
        let run = |vol: &[Vec<f32>]| {
            let f = found(vol);
            masks
                .iter()
                .map(|m| detect_object(&f, &truth, m, 2.0 * dz))
                .collect::<Vec<_>>()
        };
        for level in [0.0f32, 1e-6, 1.0, 1e6] {
            let flat = vec![vec![level; nz]; n];
            assert!(run(&flat).iter().all(|d| !d.detected && d.hit_share == 0.0));
        }
        let peaked = |shift: usize| -> Vec<Vec<f32>> {
            truth
                .iter()
                .map(|&t| {
                    let at = ((t - 1.5) / dz).round() as usize + shift;
                    (0..nz)
                        .map(|iz| if iz == at { 1.0 } else { 0.01 })
                        .collect()
                })
                .collect()
        };
        for d in run(&peaked(0)) {
            assert!(d.detected && d.hit_share == 1.0, "{d:?}");
            assert_close(d.depth_err_m, 0.0, 1e-9);
        }
        for d in run(&peaked(3)) {
            assert!(!d.detected, "{d:?}");
            assert_close(d.depth_err_m, 3.0 * dz, 1e-9);
        }
    }
}
