//! A bounded mutation fuzzer over murk's readers, run by `cargo test` on stable Rust. Small valid
//! inputs (a tal HDF5 capture, MATLAB v5 files compressed and not, a v7.3-style HDF5 file, .npy
//! arrays, a scene TOML) are mutated deterministically (bit flips, interesting bytes and numbers,
//! cuts, repeats, deletions); every mutant must be read (and, for a capture, reconstructed on a
//! tiny volume) or refused with an error, without a panic, within 5 s. Every 100th mutant also goes
//! through the `murk` binary, which must exit 0 or print one error line.
//!
//! `MURK_FUZZ_MUTANTS` sets the mutants per input (default 2000; a long run: 100000). A failing
//! mutant is written to `tests/fuzz-regressions/<input>/` and replayed by every later run: commit it
//! with the fix.

use murk_render::hash::{fnv1a, Fnv1a};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

const DEADLINE: Duration = Duration::from_secs(5);

/// splitmix64: deterministic, good enough to pick mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One to four random edits of `seed`.
fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    const BYTES: [u8; 6] = [0, 0xff, 0x7f, 0x80, 0x01, 0xfe];
    const WORDS: [u64; 7] = [
        0,
        u64::MAX,
        0x7fff_ffff,
        0x8000_0000,
        0xffff_ffff,
        1 << 40,
        0x7ff8_0000_0000_0000, // f64 NaN
    ];
    const FLOATS: [f32; 6] = [f32::NAN, f32::INFINITY, -1e30, 1e30, 0.0, 1e-30];
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        if v.is_empty() {
            break;
        }
        let at = rng.below(v.len());
        match rng.below(8) {
            0 => v[at] ^= 1 << rng.below(8),
            1 => v[at] = BYTES[rng.below(BYTES.len())],
            2 => {
                let w = WORDS[rng.below(WORDS.len())].to_le_bytes();
                let n = if rng.below(2) == 0 { 4 } else { 8 };
                for (k, b) in w.iter().take(n).enumerate() {
                    if let Some(x) = v.get_mut(at + k) {
                        *x = *b;
                    }
                }
            }
            3 => {
                let f = FLOATS[rng.below(FLOATS.len())].to_le_bytes();
                for (k, b) in f.iter().enumerate() {
                    if let Some(x) = v.get_mut(at + k) {
                        *x = *b;
                    }
                }
            }
            4 => v.truncate(at),
            5 => {
                let end = (at + 1 + rng.below(64)).min(v.len());
                let chunk = v[at..end].to_vec();
                v.splice(at..at, chunk);
            }
            6 => {
                let end = (at + 1 + rng.below(64)).min(v.len());
                v.drain(at..end);
            }
            _ => {
                // A digit in text inputs becomes a huge or negative number.
                let s = ["9e99", "-1", "1e308", "0", "nan", "4294967296"][rng.below(6)];
                v.splice(at..(at + 1).min(v.len()), s.bytes());
            }
        }
    }
    v
}

/// Reads `path` as `kind`; what a user's command would do next with the result, on a tiny scale.
fn exercise(kind: &str, path: &Path) {
    match kind {
        "capture" => {
            if let Ok(cap) = murk_io::read_capture(path) {
                let _ = cap.end_level();
                let vol = murk_core::Volume {
                    x: murk_core::Axis::new(-0.2, 0.2, 3),
                    y: murk_core::Axis::new(-0.2, 0.2, 3),
                    z: murk_core::Axis::new(0.4, 0.8, 3),
                };
                let _ = murk_recon::reconstruct(
                    &cap,
                    &vol,
                    &murk_recon::PfParams::default(),
                    murk_recon::PfForm::Fast,
                    &murk_recon::NoProgress,
                );
            }
        }
        "mat5" => {
            let _ = murk_io::mat5::read_mat_v5(path);
            let _ = murk_io::read_mat_v5_array(path, "rect_data");
        }
        "mat73" => {
            let _ = murk_io::read_mat_v73_array(path, "intensity");
        }
        "npy" => {
            let _ = murk_io::read_npy_f32(path);
        }
        "scene" => {
            let _ = murk_render::Scene::load(path, &Default::default());
        }
        other => unreachable!("no reader for {other}"),
    }
}

/// The `murk` command that reads a file of `kind`.
fn command(kind: &str, path: &Path) -> Vec<String> {
    let p = path.to_string_lossy().into_owned();
    let v: Vec<&str> = match kind {
        "capture" => vec!["info", &p],
        "mat5" => vec!["import", &p, "--format", "lct", "--out"],
        "mat73" => vec!["import", &p, "--format", "cdt", "--wall-size", "1", "--out"],
        "npy" => return vec![],
        _ => vec![
            "render", &p, "--spp", "1", "--grid", "2", "--bins", "64", "--out",
        ],
    };
    let mut v: Vec<String> = v.iter().map(|s| s.to_string()).collect();
    if v.last().is_some_and(|s| s == "--out") {
        v.push(format!("{p}.out.h5"));
    }
    v
}

/// Runs `exercise` on a worker thread: Err(why) on a panic or past the deadline.
fn run_bounded(kind: &'static str, path: PathBuf) -> Result<(), String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(|| exercise(kind, &path));
        let _ = tx.send(r.is_ok());
    });
    match rx.recv_timeout(DEADLINE) {
        Ok(true) => Ok(()),
        Ok(false) => Err("panicked".into()),
        Err(_) => Err(format!("still running after {DEADLINE:?}")),
    }
}

fn cli_contract(kind: &str, path: &Path) -> Result<(), String> {
    let args = command(kind, path);
    if args.is_empty() {
        return Ok(());
    }
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(&args)
        .arg("--quiet")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| e.to_string())?;
    let t0 = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            let mut err = String::new();
            std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).ok();
            let _ = std::fs::remove_file(format!("{}.out.h5", path.display()));
            return match status.code() {
                Some(0) => Ok(()),
                Some(_) if err.lines().count() == 1 && err.starts_with("murk: error: ") => Ok(()),
                _ => Err(format!("{args:?}: exit {status}, stderr:\n{err}")),
            };
        }
        if t0.elapsed() > DEADLINE {
            let _ = child.kill();
            return Err(format!("{args:?}: still running after {DEADLINE:?}"));
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// The seed inputs, written into `dir`: (kind, file name, bytes).
fn seeds(dir: &Path) -> Vec<(&'static str, &'static str, Vec<u8>)> {
    let mut out = Vec::new();
    // A laser-grid capture: 4 × 4 lasers, one SPAD point, 64 bins, a point 0.6 m away.
    let layout = murk_synth::CaptureLayout {
        kind: murk_synth::LayoutKind::LaserGridSinglePoint,
        wall_size_m: 1.0,
        grid: 4,
        point: murk_core::DVec3::ZERO,
        time: murk_core::TimeAxis {
            start_m: 0.8,
            bin_width_m: 0.01,
            bins: 64,
        },
        laser_xyz: None,
        sensor_xyz: None,
    };
    let mut cap = layout.empty_capture().unwrap();
    let target = murk_synth::Target::Point {
        pos: murk_core::DVec3::new(0.1, 0.0, 0.6),
        albedo: 1.0,
    };
    murk_synth::add_first_bounce(&mut cap, &target.scatterers().unwrap(), &Default::default())
        .unwrap();
    let p = dir.join("seed.h5");
    murk_io::write_capture(&p, &cap).unwrap();
    out.push(("capture", "capture", std::fs::read(&p).unwrap()));

    let counts: Vec<f64> = (0..4 * 4 * 8).map(|i| (i % 5) as f64).collect();
    for (name, compress) in [("mat5", false), ("mat5z", true)] {
        let p = dir.join(format!("{name}.mat"));
        let vars = [
            murk_io::MatArray {
                name: "rect_data",
                dims: &[4, 4, 8],
                values: &counts,
                class: murk_io::MatClass::UInt16,
            },
            murk_io::MatArray {
                name: "width",
                dims: &[1, 1],
                values: &[0.4],
                class: murk_io::MatClass::Double,
            },
        ];
        murk_io::write_mat_v5(&p, &vars, compress).unwrap();
        out.push(("mat5", name, std::fs::read(&p).unwrap()));
    }

    let p = dir.join("mat73.mat");
    let axis = murk_core::Axis::new(0.0, 1.0, 3);
    let volume = murk_core::Volume {
        x: axis,
        y: axis,
        z: axis,
    };
    murk_io::write_volume_h5(&p, &volume, &[1.0; 27], None, &[]).unwrap();
    out.push(("mat73", "mat73", std::fs::read(&p).unwrap()));

    let p = dir.join("a.npy");
    murk_io::write_npy_f32(&p, &[2, 3, 4], &[0.5; 24]).unwrap();
    out.push(("npy", "npy", std::fs::read(&p).unwrap()));

    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/t-wall-single.toml");
    out.push(("scene", "scene", std::fs::read(scene).unwrap()));
    out
}

fn extension(kind: &str) -> &'static str {
    match kind {
        "capture" => "h5",
        "mat5" | "mat73" => "mat",
        "npy" => "npy",
        _ => "toml",
    }
}

fn regressions_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-regressions")
        .join(name)
}

#[test]
fn readers_survive_mutated_inputs() {
    let mutants: usize = std::env::var("MURK_FUZZ_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    let dir = std::env::temp_dir().join(format!("murk-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for (kind, name, seed) in seeds(&dir) {
        let ext = extension(kind);
        // Every failure ever found first, then this run's mutants.
        let mut cases: Vec<(String, Vec<u8>)> = std::fs::read_dir(regressions_dir(name))
            .map(|d| {
                d.filter_map(|e| e.ok())
                    .map(|e| {
                        (
                            e.file_name().to_string_lossy().into_owned(),
                            std::fs::read(e.path()).unwrap(),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default();
        cases.sort();
        let seed_hash = name
            .bytes()
            .fold(Fnv1a::with_basis(0x6d75_726b), |h, b| h.word(u64::from(b)));
        let mut rng = Rng(seed_hash.finish());
        cases.extend((0..mutants).map(|i| (format!("mutant {i}"), mutate(&seed, &mut rng))));
        for (i, (label, bytes)) in cases.iter().enumerate() {
            // The scene reads its mesh paths relative to its folder; the mutants live elsewhere.
            let path = dir.join(format!("{name}-{i}.{ext}"));
            std::fs::write(&path, bytes).unwrap();
            let mut verdict = run_bounded(kind, path.clone());
            if verdict.is_ok() && i % 100 == 0 {
                verdict = cli_contract(kind, &path);
            }
            if let Err(why) = verdict {
                let keep = regressions_dir(name);
                std::fs::create_dir_all(&keep).unwrap();
                let h = fnv1a(bytes.iter().copied());
                let kept = keep.join(format!("{h:016x}.{ext}"));
                std::fs::write(&kept, bytes).unwrap();
                failures.push(format!(
                    "{name} {label}: {why} (kept as {})",
                    kept.display()
                ));
            }
            let _ = std::fs::remove_file(&path);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
