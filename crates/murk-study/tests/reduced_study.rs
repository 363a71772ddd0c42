//! A reduced study at quick scale (128 spp): Fig. 3a, the α = 0.5 column of Fig. 3b and Fig. 4, rendered,
//! reconstructed and scored end to end. It asserts what the study must show (docs/study.md), as measured.
//! Fig. 3b's μt = 1 α = 0.5 cell and Fig. 4 (α = 0.83) come from one albedo sweep.
//! At 64 spp one seed's noise could order the 2λ0 and 3λ0 cells' high-frequency shares either way
//! (0.00202 against 0.00257 once the renderer's random stream changed); at 96, 128 and 192 spp the
//! order holds by 2× or more.

use murk_study::plan::{Figure, Scale, StudyOptions, StudyPlan};
use murk_study::run::{self, CellResult, Scores, Silent};
use std::path::Path;

/// The first seed's scores with the paper's K(x_v).
fn paper(c: &CellResult) -> &Scores {
    &c.by_compensation[1].1[0]
}

fn results(dir: &Path) -> Vec<CellResult> {
    let opt = StudyOptions {
        scale: Scale::Quick,
        only: vec![Figure::Fig3a, Figure::Fig3b, Figure::Fig4],
        cells: vec!["no medium".into(), "α = 0.5".into(), "λ".into()],
        seeds: 1,
        shards: 1,
        spp: Some(128),
        scenes_dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes"),
    };
    let plan = StudyPlan::new(&opt).unwrap();
    assert_eq!(plan.cells.len(), 1 + 3 + 3);
    // Fig. 3a, μt = 0.5 and μt = 2 alone, and the μt = 1 sweep over α = 0.5 and 0.83.
    let sweeps: Vec<_> = plan.captures.iter().map(|j| j.albedos.clone()).collect();
    assert_eq!(sweeps.iter().filter(|a| *a == &[0.5, 0.83]).count(), 1);
    assert_eq!(run::render_missing(&plan, dir, &Silent).unwrap(), 4);
    // A second run finds every capture and renders nothing.
    assert_eq!(run::render_missing(&plan, dir, &Silent).unwrap(), 0);
    let r = run::evaluate(&plan, dir, &Silent).unwrap();
    murk_study::report::write(&plan, &r, dir).unwrap();
    r
}

#[test]
fn reduced_study_shows_what_the_paper_claims() {
    let dir = std::env::temp_dir().join(format!("murk-study-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let r = results(&dir);
    let find = |fig: Figure, col: &str, mu_t: f64| {
        r.iter()
            .find(|c| c.cell.figure == fig && c.cell.col == col && c.cell.medium.mu_t_per_m == mu_t)
            .unwrap()
    };
    let clear = find(Figure::Fig3a, "", 0.0);
    let dz = clear.voxel_dz_m;
    let s = paper(clear);
    eprintln!(
        "no medium: IoU {:.3}, depth error {:.3} m",
        s.iou.best, s.depth_err_m
    );
    assert!(s.iou.best >= 0.7, "no-medium IoU {}", s.iou.best);
    assert!(
        murk_study::metrics::within_a_voxel(s.depth_err_m, dz),
        "no-medium depth error {}",
        s.depth_err_m
    );

    let fog: Vec<_> = [0.5, 1.0, 2.0]
        .map(|mu| paper(find(Figure::Fig3b, "α = 0.5", mu)).clone())
        .into();
    for (mu, s) in [0.5, 1.0, 2.0].iter().zip(&fog) {
        eprintln!(
            "μt {mu}: IoU {:.3}, SSIM {:.3}, PSNR {:.2}, CNR {:.2}, depth {:.3}",
            s.iou.best, s.ssim, s.psnr_db, s.cnr, s.depth_err_m
        );
    }
    assert!(
        fog[0].ssim > fog[1].ssim && fog[1].ssim > fog[2].ssim,
        "SSIM falls with μt"
    );
    assert!(fog[0].psnr_db > fog[2].psnr_db, "PSNR falls with μt");

    let lam: Vec<_> = ["λ = λ0", "λ = 2λ0", "λ = 3λ0"]
        .map(|col| paper(find(Figure::Fig4, col, 1.0)).clone())
        .into();
    for s in &lam {
        eprintln!(
            "λ: high-frequency share {:.5}, IoU {:.3}, depth {:.3}",
            s.hf_share, s.iou.best, s.depth_err_m
        );
    }
    assert!(lam[0].hf_share > lam[1].hf_share && lam[1].hf_share > lam[2].hf_share);
    // Still found: the Z's depth within one voxel and an IoU over three times that of a blank image
    // (the Z covers 6 % of the front view; measured 0.29–0.32 at α = 0.83 for every λ).
    for s in &lam {
        assert!(
            s.iou.best >= murk_study::report::FOUND_IOU
                && murk_study::metrics::within_a_voxel(s.depth_err_m, dz),
            "{s:?}"
        );
    }
    // The report states each of these with its numbers and verdict.
    let page = std::fs::read_to_string(dir.join("index.html")).unwrap();
    for claim in [
        "(IoU ≥ 0.7, depth within a voxel): holds. IoU ",
        "Fig. 3b, α = 0.5: quality falls as μt grows (SSIM against the clear scene decreasing): holds.",
        "the Z is found (IoU ≥ 0.2) at every λ: holds.",
    ] {
        assert!(page.contains(claim), "{claim} not in the report's findings");
    }
    for f in [
        "metrics.csv",
        "objects.csv",
        "index.html",
        "fig3b-paper-shared.png",
        "fig4-none-cell.png",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
