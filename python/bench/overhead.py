"""Overhead of the Python package against the CLI (docs/python.md, "Measurements").

1. murk.reconstruct on the paper's Z (128² laser points × 4096 bins, pf on 73×59×73 voxels) vs the
   compute time `murk reconstruct` prints (`seconds`): median of alternating runs, each in a fresh
   process, with the process's peak RSS.
2. murk.dask.render of scenes/z-letter.toml --grid 64 on a 2-worker LocalCluster vs `murk render`'s
   wall time on the same cores.

Run from the repository root after `cargo build --release` and `pip install ./python`:
    .venv/bin/python python/bench/overhead.py [--runs 3] [--spp 256] [--shards 2] [--skip-dask] [--skip-recon]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

MURK = os.path.abspath("target/release/murk")
VOLUME = "-0.99:0.99:73,-0.99:0.99:59,1.5:2.5:73"
Z = ["--kind", "laser-grid", "--wall-size", "2", "--grid", "128", "--bins", "4096",
     "--bin-width", "0.0009", "--start", "3.5", "--target", "z:2.0", "--cosines"]

# Each Python measurement runs in its own process so that its peak RSS is its own.
PY_RECON = """
import json, resource, sys, time, murk
path, volume, mode = sys.argv[1:]
src = murk.read_capture(path) if mode == "capture" else path
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t = time.perf_counter()
rec = murk.reconstruct(src, "pf", volume=volume)
secs = time.perf_counter() - t
print(json.dumps(dict(secs=secs, peak_mib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      before_mib=base / 1024)))
"""


def cli_recon(path, out):
    cmd = ["/usr/bin/time", "-f", "%M", MURK, "reconstruct", path, "--out", out, "--volume", VOLUME]
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    secs = float(next(l for l in p.stdout.splitlines() if l.strip().startswith("seconds:")).split()[1])
    return secs, int(p.stderr.strip().splitlines()[-1]) / 1024


def py_recon(path, mode):
    p = subprocess.run([sys.executable, "-c", PY_RECON, path, VOLUME, mode], capture_output=True,
                       text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def recon_bench(runs, d):
    path = os.path.join(d, "z.h5")
    subprocess.run([MURK, "synth", "--out", path, *Z, "--quiet"], check=True)
    h_mib = 128 * 128 * 4096 * 4 / 2**20
    cli, cap, file = [], [], []
    for _ in range(runs):
        cli.append(cli_recon(path, os.path.join(d, "z.npy")))
        cap.append(py_recon(path, "capture"))
        file.append(py_recon(path, "path"))
    med = lambda xs: statistics.median(xs)
    return {
        "H_mib": h_mib,
        "cli_seconds": [s for s, _ in cli], "cli_peak_mib": max(m for _, m in cli),
        "py_capture_seconds": [r["secs"] for r in cap],
        "py_capture_peak_mib": max(r["peak_mib"] for r in cap),
        "py_capture_before_mib": max(r["before_mib"] for r in cap),
        "py_path_seconds": [r["secs"] for r in file],
        "py_path_peak_mib": max(r["peak_mib"] for r in file),
        "median_cli": med([s for s, _ in cli]),
        "median_py_capture": med([r["secs"] for r in cap]),
        "median_py_path": med([r["secs"] for r in file]),
    }


PY_DASK = """
import sys, time
import murk.dask
from dask.distributed import Client
spp, out, shards = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
t0 = time.perf_counter()
cluster = murk.dask.local_cluster(n_workers=2)
client = Client(cluster)
t1 = time.perf_counter()
murk.dask.render("scenes/z-letter.toml", client, shards=shards, grid=64, spp=spp, threads=1, out=out)
t2 = time.perf_counter()
client.close(); cluster.close()
print(t2 - t0, t2 - t1)
"""


def dask_bench(runs, spp, shards, d):
    cli, dask_total, dask_render = [], [], []
    for _ in range(runs):
        a, b = os.path.join(d, "cli.h5"), os.path.join(d, "dask.h5")
        for f in (a, b):
            if os.path.exists(f):
                os.remove(f)
        t = time.perf_counter()
        subprocess.run([MURK, "render", "scenes/z-letter.toml", "--out", a, "--grid", "64",
                        "--spp", str(spp), "--quiet"], check=True)
        cli.append(time.perf_counter() - t)
        p = subprocess.run([sys.executable, "-c", PY_DASK, str(spp), b, str(shards)], capture_output=True,
                           text=True, check=True)
        total, render = map(float, p.stdout.split())
        dask_total.append(total)
        dask_render.append(render)
        assert open(a, "rb").read() == open(b, "rb").read(), "Dask render differs from the CLI's"
    med = statistics.median
    return {"spp": spp, "shards": shards, "cli_wall": cli, "dask_with_cluster_start": dask_total,
            "dask_render_only": dask_render, "median_cli": med(cli),
            "median_dask_with_cluster_start": med(dask_total),
            "median_dask_render_only": med(dask_render), "bytes_identical": True}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--shards", type=int, default=2, help="Dask tasks (default: one per worker)")
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--skip-recon", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="murk-bench-") as d:
        res = {"cores": os.cpu_count()}
        if not a.skip_recon:
            res["reconstruct"] = recon_bench(a.runs, d)
            print(json.dumps(res["reconstruct"], indent=1), flush=True)
        if not a.skip_dask:
            res["dask"] = dask_bench(a.runs, a.spp, a.shards, d)
            print(json.dumps(res["dask"], indent=1), flush=True)
    print(json.dumps(res))


if __name__ == "__main__":
    main()
