import importlib.util

import numpy as np
import pytest

import murk
from conftest import cli

VOL = "-0.99:0.99:17,-0.99:0.99:13,1.5:2.5:15"

# (capture, method, CLI flags, Python keywords): every method, and the flags that change its result.
CASES = [
    ("grid", "pf", [], {}),
    ("grid", "pf", ["--wavefactor", "6", "--cycles", "5", "--gate", "off"],
     dict(wavefactor=6, cycles=5, gate="off")),
    ("grid", "pf", ["--compensate", "paper", "--mu-t", "0.5", "--albedo", "0.3",
                    "--lateral", "full", "--falloff", "inv-r"],
     dict(compensate="paper", mu_t=0.5, albedo=0.3, lateral="full", falloff="inv-r")),
    ("grid", "pf-exact", ["--wavelength", "0.2"], dict(wavelength=0.2)),
    ("grid", "bp", ["--gate", "3.9", "--window-end", "taper"], dict(gate=3.9, window_end="taper")),
    ("grid", "fbp", ["--t-offset", "0.01"], dict(t_offset=0.01)),
    ("confocal", "pf", [], {}),
    ("confocal", "lct", ["--snr", "0.5"], dict(snr=0.5)),
    ("confocal", "lct", ["--weighting", "retroreflective"], dict(weighting="retroreflective")),
    ("confocal", "fk", [], {}),
    ("confocal", "cdt", ["--t-offset", "slab", "--slab-thickness", "0.02"],
     dict(t_offset="slab", slab_thickness=0.02)),
]


@pytest.mark.parametrize("which,method,flags,kw", CASES,
                         ids=[f"{c[0]}-{c[1]}-{i}" for i, c in enumerate(CASES)])
def test_same_bytes_as_the_cli(captures, tmp_path, which, method, flags, kw):
    path = captures[which]
    vol = [] if method in ("lct", "fk", "cdt") else ["--volume", VOL]
    cli("reconstruct", path, "--out", tmp_path / "v.npy", "--method", method, *vol, *flags,
        "--quiet")
    want = np.load(tmp_path / "v.npy")
    volume = VOL if vol else None
    for src in (path, murk.read_capture(path)):  # a file, and a Capture in memory
        rec = murk.reconstruct(src, method, volume=volume, **kw)
        assert rec.intensity.dtype == np.float32 and rec.intensity.flags.c_contiguous
        assert rec.intensity.shape == want.shape
        assert rec.intensity.tobytes() == want.tobytes()
        assert rec.intensity.shape == (len(rec.x), len(rec.y), len(rec.z))
        assert "method" in rec.params and "window_end" in rec.params


def test_axes_are_the_requested_voxel_centres(captures):
    rec = murk.reconstruct(captures["grid"], "bp", volume=VOL)
    assert np.allclose(rec.x, np.linspace(-0.99, 0.99, 17))
    assert np.allclose(rec.z, np.linspace(1.5, 2.5, 15))


def test_progress_callback_sees_the_whole_run(captures):
    seen = []
    murk.reconstruct(captures["grid"], "pf-exact", volume=VOL,
                     progress=lambda done, total: seen.append((done, total)))
    assert seen and seen[-1][0] == seen[-1][1] > 0


def test_an_exception_in_the_callback_stops_the_reconstruction(captures):
    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop()

    with pytest.raises(Stop):
        murk.reconstruct(captures["grid"], "pf-exact",
                         volume="-0.99:0.99:41,-0.99:0.99:41,1.5:2.5:41", progress=stop)


@pytest.mark.skipif(importlib.util.find_spec("tqdm") is None, reason="tqdm is not installed")
def test_progress_true_draws_a_tqdm_bar(captures, capsys):
    murk.reconstruct(captures["grid"], "bp", volume=VOL, progress=True)
    assert "reconstruct" in capsys.readouterr().err


@pytest.fixture(scope="module")
def confocal_128():
    return murk.synth("z:1.5", kind="confocal", wall_size=2.0, grid=128, bins=4096, bin_width=0.0015)


def test_lct_reports_its_plan_then_its_run(confocal_128):
    # The plan's kernel spectrum (about a second here) is one pass of 1000 units, the run three.
    seen = []
    murk.reconstruct(confocal_128, "lct", progress=lambda done, total: seen.append((done, total)))
    totals = [t for _, t in seen]
    assert 1000 in totals and totals[-1] == 3000, seen
    assert seen[-1] == (3000, 3000), seen


@pytest.mark.skipif(importlib.util.find_spec("tqdm") is None, reason="tqdm is not installed")
def test_progress_true_draws_a_bar_per_stage(capsys):
    # What the poller reports when it catches the end of lct's plan: the plan's bar closes there,
    # and the run gets a bar of its own (a single bar, closed at the plan's end, hid the run).
    update = murk._progress(True, "reconstruct")
    for done, total in [(400, 1000), (1000, 1000), (1500, 3000), (3000, 3000)]:
        update(done, total)
    err = capsys.readouterr().err
    assert "1000/1000" in err and "3000/3000" in err, err


def test_methods_are_the_clis():
    # One table in the library: murk.methods() lists what --method takes, in --help's order.
    methods = murk.methods()
    assert list(methods)[:4] == ["pf", "pf-exact", "bp", "fbp"] and "cdt" in methods
    assert {case[1] for case in CASES} <= set(methods)
    text = cli("reconstruct", "--help")
    for name, line in methods.items():
        assert f"- {name}:" in text and line.split(" (")[0] in text, name
