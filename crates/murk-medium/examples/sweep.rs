//! Estimates the medium of several captures of one geometry from one table, and prints a Markdown
//! table of the estimates against the truth that each capture's scene_info records (the table in
//! docs/medium.md): `cargo run --release -p murk-medium --example sweep -- [--given-g] [--rings N]
//! [--spp N] [--forward-spp N] [--grid N] [--seed N] [--g-nodes G,G,…] [--table-cache DIR] CAPTURE.h5 …`. With
//! `--given-g` (first) each capture's true g is given and μt and α are fitted; the others set the
//! table's reduction, renders and g nodes.

use murk_medium::{estimate_with, EstimateOptions, Outcome, ResponseTable};

fn truth(info: &str, key: &str) -> f64 {
    // The scene block holds the medium as `  mu_t = 1.0` lines; an albedo sweep's own albedo follows.
    let scene_value = info
        .lines()
        .rfind(|l| l.trim_start().starts_with(&format!("{key} =")))
        .and_then(|l| l.split('=').nth(1))
        .and_then(|v| v.trim().parse().ok());
    let sweep = (key == "albedo")
        .then(|| {
            info.lines()
                .find(|l| l.starts_with("albedo: "))
                .and_then(|l| l[8..].trim().parse().ok())
        })
        .flatten();
    sweep.or(scene_value).unwrap_or(f64::NAN)
}

fn main() -> murk_core::Result<()> {
    let mut files: Vec<String> = std::env::args().skip(1).collect();
    let given_g = files.first().is_some_and(|f| f == "--given-g");
    if given_g {
        files.remove(0);
    }
    let mut spec = murk_medium::TableSpec::default();
    // `--rings N`, `--spp N`, `--forward-spp N`, `--grid N`, `--seed N`, `--g-nodes`: the table's reduction, renders and
    // nodes (what their accuracy costs); `--table-cache DIR`: where the table is kept between runs.
    let mut table_cache = None;
    while let Some(flag) = files.first().filter(|f| f.starts_with("--")).cloned() {
        let value = files[1].clone();
        let n = || {
            value
                .parse::<usize>()
                .expect("--rings, --spp, --grid or --seed N")
        };
        match flag.as_str() {
            "--rings" => spec.rings = n(),
            "--spp" => spec.spp = n() as u64,
            "--grid" => spec.grid = n(),
            "--seed" => spec.seed = n() as u64,
            "--forward-spp" => spec.forward_spp = n() as u64,
            "--g-nodes" => {
                spec.g = value
                    .split(',')
                    .map(|g| g.parse().expect("--g-nodes G,G,…"))
                    .collect()
            }
            "--table-cache" => table_cache = Some(std::path::PathBuf::from(&value)),
            other => panic!("unknown flag {other}"),
        }
        files.drain(..2);
    }
    let mut table: Option<ResponseTable> = None;
    println!("| μt | α | g | μt est. | α est. | g est. | μt err | α err | g err | s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for f in files {
        let cap = murk_io::read_capture(std::path::Path::new(&f))?;
        let mut opt = EstimateOptions {
            table: spec.clone(),
            table_cache: table_cache.clone(),
            ..EstimateOptions::default()
        };
        if given_g {
            opt.fit = murk_medium::FitParams::parse("mu_t,albedo")?;
            opt.fixed.g = truth(&cap.scene_info, "g");
        }
        let t0 = std::time::Instant::now();
        let (outcome, built) = estimate_with(&cap, &opt, table.take(), &|_, _| {})?;
        table = built;
        let (m, a, g) = (
            truth(&cap.scene_info, "mu_t"),
            truth(&cap.scene_info, "albedo"),
            truth(&cap.scene_info, "g"),
        );
        match outcome {
            Outcome::NoMedium(s) => println!("| {m} | {a} | {g} | no medium: {} |", s.describe()),
            Outcome::Fitted(e) => println!(
                "| {m} | {a} | {g} | {:.3} ± {:.3} | {:.3} ± {:.3} | {:+.2} ± {:.2} | {:+.1} % | {:+.1} % | {:+.2} | {:.1} |",
                e.mu_t_per_m.value,
                e.mu_t_per_m.uncertainty,
                e.albedo.value,
                e.albedo.uncertainty,
                e.g.value,
                e.g.uncertainty,
                100.0 * (e.mu_t_per_m.value / m - 1.0),
                100.0 * (e.albedo.value / a - 1.0),
                e.g.value - g,
                t0.elapsed().as_secs_f64()
            ),
        }
    }
    Ok(())
}
