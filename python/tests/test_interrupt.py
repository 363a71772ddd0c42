import signal
import subprocess
import sys
import time

from conftest import SCENES


def child(setup: str, call: str) -> str:
    """A child script: `setup`, then "started", then `call`; exit status 3 on KeyboardInterrupt. The
    child installs Python's usual SIGINT handler itself: a process started in the background (as CI
    may start pytest) inherits SIGINT ignored, and Python then installs none."""
    return f"""
import signal, sys, murk
signal.signal(signal.SIGINT, signal.default_int_handler)
{setup}
print("started", flush=True)
try:
    {call}
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
"""


def seconds_to_stop(script: str) -> float:
    """Runs `script` in a child, sends it Ctrl-C a second after it says "started", checks that it
    ended with KeyboardInterrupt, and returns how long that took."""
    p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "started"
        time.sleep(1.0)
        t0 = time.time()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=60)
        assert p.returncode == 3 and "interrupted" in out, out
        return time.time() - t0
    finally:
        p.kill()  # a call that ignored Ctrl-C must not outlive the test
        p.wait()


def test_ctrl_c_interrupts_a_long_render():
    # 64 units of about 0.5 s each.
    scene = str(SCENES / "z-letter.toml")
    assert seconds_to_stop(child("", f"murk.render({scene!r}, grid=64, spp=256)")) < 10


def test_ctrl_c_interrupts_a_long_backprojection():
    # About 15 s on two cores: 16 384 histograms read at 64³ voxels off the wall's lattice. The
    # tiles in flight finish; the rest are skipped.
    setup = ('cap = murk.synth("z:1.0", kind="laser-grid", wall_size=2.0, grid=128, bins=2048, '
             'bin_width=0.002, start=1.0)')
    call = 'murk.reconstruct(cap, "bp", volume="-0.9:0.9:64,-0.9:0.9:64,0.5:1.5:64")'
    assert seconds_to_stop(child(setup, call)) < 3


def test_ctrl_c_interrupts_a_long_fk_migration():
    # About 4 s on two cores: a 2 GB spectrum, transformed, Stolt-mapped and transformed back. Each
    # piece of a pass asks whether to stop; the rest of the passes are skipped (the package before
    # that ran on for 8.5 s).
    setup = ('cap = murk.synth("z:1.5", kind="confocal", wall_size=2.0, grid=128, bins=4096, '
             'bin_width=0.0015)')
    assert seconds_to_stop(child(setup, 'murk.reconstruct(cap, "fk")')) < 1.5
