"""Dask's monitors at their defaults vs murk.dask.QUIET_MONITORS (docs/python.md, "Measurements").

Each round renders scenes/z-letter.toml --grid 64 once with the CLI, then on a fresh 2-worker
LocalCluster with each configuration, in alternating order, each in its own process; every Dask
capture must equal the CLI's bytes. Prints the medians and the median of each configuration's ratio
to the CLI run of its round.

Run from the repository root after `cargo build --release` and `pip install ./python`:
    .venv/bin/python python/bench/dask_monitors.py [--rounds 8]
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

MURK = os.path.abspath("target/release/murk")

CHILD = """
import sys, time, dask
import murk.dask
from dask.distributed import Client, LocalCluster
if __name__ == "__main__":
    config = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
    if sys.argv[1] == "quiet":
        config.update(murk.dask.QUIET_MONITORS)
    with dask.config.set(config):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    t = time.perf_counter()
    murk.dask.render("scenes/z-letter.toml", client, shards=2, grid=64, threads=1, out=sys.argv[2])
    print(time.perf_counter() - t)
    client.close()
    cluster.close()
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=8)
    rounds = ap.parse_args().rounds
    secs = {"cli": [], "default": [], "quiet": []}
    with tempfile.TemporaryDirectory(prefix="murk-bench-") as d:
        want = os.path.join(d, "cli.h5")
        for r in range(rounds):
            if os.path.exists(want):
                os.remove(want)
            t = time.perf_counter()
            subprocess.run([MURK, "render", "scenes/z-letter.toml", "--out", want, "--grid", "64",
                            "--quiet"], check=True)
            secs["cli"].append(time.perf_counter() - t)
            for kind in ("default", "quiet") if r % 2 == 0 else ("quiet", "default"):
                out = os.path.join(d, f"{kind}.h5")
                p = subprocess.run([sys.executable, "-c", CHILD, kind, out], capture_output=True,
                                   text=True, check=True)
                secs[kind].append(float(p.stdout.split()[-1]))
                with open(out, "rb") as a, open(want, "rb") as b:
                    assert a.read() == b.read(), f"{kind}: the Dask render differs from the CLI's"
                os.remove(out)
            print({k: [round(x, 2) for x in v] for k, v in secs.items()}, flush=True)
    med = statistics.median
    for kind in ("default", "quiet"):
        ratio = med([b / a for a, b in zip(secs["cli"], secs[kind])])
        print(f"{kind}: median {med(secs[kind]):.2f} s against the CLI's {med(secs['cli']):.2f} s, "
              f"median pair ratio {ratio:.3f}")


if __name__ == "__main__":
    main()
