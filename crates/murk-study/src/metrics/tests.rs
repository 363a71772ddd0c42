//! Tests of `metrics`.

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
