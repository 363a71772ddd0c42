import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MURK = ROOT / "target" / "release" / "murk"
SCENES = ROOT / "scenes"

needs_cli = pytest.mark.skipif(
    not MURK.exists(), reason=f"{MURK} missing: run `cargo build --release` first"
)


def cli(*args, cwd=None):
    """Runs the murk CLI; returns its stdout."""
    r = subprocess.run([str(MURK), *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, r.stderr
    return r.stdout


# A small laser-grid capture of the paper's Z and a confocal one, as the CLI writes them.
LASER_GRID = ["--kind", "laser-grid", "--wall-size", "2", "--grid", "24", "--bins", "768",
              "--bin-width", "0.005", "--start", "3.5", "--target", "z:2.0", "--cosines"]
CONFOCAL = ["--kind", "confocal", "--wall-size", "1", "--grid", "16", "--bins", "512",
            "--bin-width", "0.006", "--target", "t:0.6", "--cosines"]


def render_z_in_fog(*, spp, seed, grid=16, settings=None, out=None):
    """The medium tests' small capture: the paper's Z in its fog (scenes/z-letter.toml: μt = 1,
    α = 0.5, g = 0) on a `grid`² wall, 1200 bins of 5 mm. settings: further scene settings, as
    murk.render's `set` takes them; out: also write the capture there. Returns the capture."""
    import murk  # here, not at the top: the CLI-only tests import this file without the module

    return murk.render(SCENES / "z-letter.toml", out=out, grid=grid, bins=1200, spp=spp, seed=seed,
                       set={"capture.bin_width": 0.005, **(settings or {})})


@pytest.fixture(scope="session")
def captures(tmp_path_factory):
    if not MURK.exists():
        pytest.skip(f"{MURK} missing: run `cargo build --release` first")
    d = tmp_path_factory.mktemp("captures")
    cli("synth", "--out", d / "grid.h5", *LASER_GRID)
    cli("synth", "--out", d / "confocal.h5", *CONFOCAL)
    return {"grid": d / "grid.h5", "confocal": d / "confocal.h5"}
