//! murk's confocal f-k and LCT against y-tal's `fk` and `lct` on the same synthetic confocal capture.
//!
//! Python is `$MURK_PYTHON` or `<repo>/.venv/bin/python`, with `import tal`; without it the test
//! prints "skipped: <why>" and passes. y-tal 0.20.0 has no `lct`: that part is skipped with a message.
//!
//! What is compared: the maximum projections along depth (correlation ≥ 0.95) and the peak voxel
//! (±1). Whole volumes differ by design: y-tal weights H by t (murk and the reference by √H·t) and
//! reads bin n at its start (murk at its centre, half a bin later), which moves every depth by
//! half a sample.

use std::process::Command;

mod common;
use common::python;

fn murk(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(args)
        .output()
        .expect("run murk");
    assert!(
        out.status.success(),
        "murk {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Writes y-tal's reconstruction as .npy [nx, ny, nt] (or prints "missing" when y-tal lacks it).
const SCRIPT: &str = r#"
import sys, numpy as np, tal
cap, method, out = sys.argv[1:4]
if not hasattr(tal.reconstruct, method):
    print("missing"); sys.exit(0)
r = getattr(tal.reconstruct, method).solve(tal.io.read_capture(cap))
np.save(out, np.ascontiguousarray(np.moveaxis(np.abs(r), 0, -1)).astype(np.float32))
print("ok")
"#;

fn mip(shape: &[usize], v: &[f32], nz: usize) -> Vec<f64> {
    v.chunks(shape[2])
        .map(|c| c[..nz].iter().fold(0f64, |m, &x| m.max(x as f64)))
        .collect()
}

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += (x - ma) * (y - mb);
        aa += (x - ma).powi(2);
        bb += (y - mb).powi(2);
    }
    ab / (aa * bb).sqrt()
}

fn argmax(shape: &[usize], v: &[f32]) -> [usize; 3] {
    let i = (0..v.len()).fold(0, |b, i| if v[i] > v[b] { i } else { b });
    [
        i / (shape[1] * shape[2]),
        i / shape[2] % shape[1],
        i % shape[2],
    ]
}

#[test]
fn fk_and_lct_match_y_tal() {
    let py = match python() {
        Ok(p) => p,
        Err(why) => {
            println!("skipped: {why}");
            return;
        }
    };
    let dir = std::env::temp_dir().join(format!("murk-interop-baselines-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |n: &str| dir.join(n).to_str().unwrap().to_string();
    // Two points and a letter T at three depths, 32² confocal scan, 512 bins of 4.8 mm.
    murk(&[
        "synth",
        "-q",
        "--out",
        &p("c.h5"),
        "--kind",
        "confocal",
        "--wall-size",
        "0.64",
        "--grid",
        "32",
        "--bins",
        "512",
        "--bin-width",
        "0.0048",
        "--target",
        "point:0.11,-0.05,0.4",
        "--target",
        "point:-0.1,0.1,0.6",
        "--target",
        "t:0.5",
    ]);
    for method in ["fk", "lct"] {
        let out = Command::new(&py)
            .args(["-c", SCRIPT, &p("c.h5"), method, &p("tal.npy")])
            .output()
            .expect("run python");
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "y-tal {method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        if said.trim() == "missing" {
            println!("skipped: the installed y-tal has no tal.reconstruct.{method}");
            continue;
        }
        murk(&[
            "reconstruct",
            "-q",
            &p("c.h5"),
            "--method",
            method,
            "--out",
            &p("murk.npy"),
        ]);
        let (ts, tv) = murk_io::read_npy_f32(&dir.join("tal.npy")).unwrap();
        let (ms, mv) = murk_io::read_npy_f32(&dir.join("murk.npy")).unwrap();
        assert_eq!(ts[..2], ms[..2], "{method}: lateral shapes differ");
        let nz = ts[2].min(ms[2]);
        let r = pearson(&mip(&ts, &tv, nz), &mip(&ms, &mv, nz));
        let (a, b) = (argmax(&ts, &tv), argmax(&ms, &mv));
        println!("{method}: MIP correlation with y-tal {r:.4}; peaks {a:?} (y-tal), {b:?} (murk)");
        assert!(r >= 0.95, "{method}: MIP correlation {r:.4} < 0.95");
        assert!(
            (0..3).all(|k| a[k].abs_diff(b[k]) <= 1),
            "{method}: peaks {a:?} vs {b:?}"
        );
    }
}
