//! The foam slab of the CDT calibration captures (Lindell & Wetzstein 2020) fitted from its
//! transmission captures through 1.0–8.0 inch of foam.

use murk_medium::slab::{fit_slab, read_calibration, SlabOptions};
use std::path::Path;

const DIR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/data/real/cdt_lindell2020/calibration"
);

/// The published foam is μa = 0.53 /m, μs′ = 262 /m (n = 1.12). The fit's own standard deviations
/// (0.012 /m, 1.4 /m) are smaller than what its choices move it by: fitting only the 4–8 inch
/// captures gives 0.49 /m and 247 /m, 2–8 inch 0.558 and 259, a 0.3 % or 5 % level 0.569/261 and
/// 0.550/257. The tolerances, 0.08 /m (15 %) and 13 /m (5 %), are about twice those spreads.
#[test]
#[ignore = "reads the real calibration captures ../shared/data/real/cdt_lindell2020; .ci/run runs it with --ignored when that folder is there"]
fn cdt_foam_matches_the_published_values() {
    let cal = read_calibration(Path::new(DIR)).unwrap();
    assert_eq!(cal.slabs.len(), 15);
    let e = fit_slab(&cal, &SlabOptions::default(), &murk_core::NoProgress).unwrap();
    let (a, s) = (e.mu_a_per_m, e.mu_s_prime_per_m);
    assert!((a.value - 0.53).abs() < 0.08, "{e:?}");
    assert!((s.value - 262.0).abs() < 13.0, "{e:?}");
    assert!(a.constrained && s.constrained, "{e:?}");
    // The model describes every thickness to within 10 % of its peak (rms), 5 % overall.
    assert!(e.residual_rms_of_peak < 0.05, "{e:?}");
    assert!(
        e.captures.iter().all(|c| c.residual_rms_of_peak < 0.10),
        "{e:?}"
    );
}
