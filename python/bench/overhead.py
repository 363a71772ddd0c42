"""Overhead of the Python package against the CLI (docs/python.md, "Measurements").

1. murk.reconstruct on the paper's Z (128² laser points × 4096 bins, pf on 73×59×73 voxels) vs the
   compute time `murk reconstruct` prints (`seconds`): median of alternating runs, each in a fresh
   process, with the process's peak RSS.
2. murk.dask.render of scenes/z-letter.toml --grid 64 on a 2-worker LocalCluster vs `murk render`'s
   wall time on the same cores, with murk's quiet Dask monitors, Dask's defaults, or both in turn.

Run from the repository root after `cargo build --release` and `pip install ./python`:
    .venv/bin/python python/bench/overhead.py [--runs 3] [--spp 256] [--shards 2] [--monitors quiet|default|both] [--skip-dask] [--skip-recon]
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
spp, out, shards, monitors = int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), sys.argv[4]
t0 = time.perf_counter()
cluster = murk.dask.local_cluster(n_workers=2, monitors=murk.dask.QUIET_MONITORS if monitors == "quiet" else {})
client = Client(cluster)
t1 = time.perf_counter()
murk.dask.render("scenes/z-letter.toml", client, shards=shards, grid=64, spp=spp, threads=1, out=out)
t2 = time.perf_counter()
client.close(); cluster.close()
print(t2 - t0, t2 - t1)
"""


def dask_bench(runs, spp, shards, monitors, d):
    """Each run: the CLI, then a Dask render per monitor setting (their order alternating from run to
    run); the pair ratio is a Dask render's time over the CLI run just before it."""
    cli = []
    dask = {m: {"total": [], "render": []} for m in monitors}
    a = os.path.join(d, "cli.h5")
    for r in range(runs):
        if os.path.exists(a):
            os.remove(a)
        t = time.perf_counter()
        subprocess.run([MURK, "render", "scenes/z-letter.toml", "--out", a, "--grid", "64",
                        "--spp", str(spp), "--quiet"], check=True)
        cli.append(time.perf_counter() - t)
        for m in monitors if r % 2 == 0 else monitors[::-1]:
            b = os.path.join(d, f"dask-{m}.h5")
            p = subprocess.run([sys.executable, "-c", PY_DASK, str(spp), b, str(shards), m],
                               capture_output=True, text=True, check=True)
            total, render = map(float, p.stdout.split())
            dask[m]["total"].append(total)
            dask[m]["render"].append(render)
            with open(a, "rb") as x, open(b, "rb") as y:
                assert x.read() == y.read(), f"Dask render ({m} monitors) differs from the CLI's"
            os.remove(b)
    med = statistics.median
    res = {"spp": spp, "shards": shards, "cli_wall": cli, "median_cli": med(cli), "bytes_identical": True}
    for m, t in dask.items():
        total, render = t["total"], t["render"]
        res[m + "_monitors"] = {
            "dask_with_cluster_start": total, "dask_render_only": render,
            "median_dask_with_cluster_start": med(total), "median_dask_render_only": med(render),
            "median_pair_ratio": med([y / x for x, y in zip(cli, render)]),
        }
    return res


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--shards", type=int, default=2, help="Dask tasks (default: one per worker)")
    ap.add_argument("--monitors", choices=["quiet", "default", "both"], default="quiet",
                    help="Dask's monitors: murk.dask.QUIET_MONITORS, Dask's defaults, or both in turn")
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--skip-recon", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="murk-bench-") as d:
        res = {"cores": os.cpu_count()}
        if not a.skip_recon:
            res["reconstruct"] = recon_bench(a.runs, d)
            print(json.dumps(res["reconstruct"], indent=1), flush=True)
        if not a.skip_dask:
            monitors = ["quiet", "default"] if a.monitors == "both" else [a.monitors]
            res["dask"] = dask_bench(a.runs, a.spp, a.shards, monitors, d)
            print(json.dumps(res["dask"], indent=1), flush=True)
    print(json.dumps(res))


if __name__ == "__main__":
    main()
