import signal
import subprocess
import sys
import time

from conftest import SCENES

# The child installs Python's usual SIGINT handler itself: a process started in the background
# (as CI may start pytest) inherits SIGINT ignored, and Python then installs none.
LONG_RENDER = f"""
import signal, sys, murk
signal.signal(signal.SIGINT, signal.default_int_handler)
print("started", flush=True)
try:
    murk.render({str(SCENES / 'z-letter.toml')!r}, grid=64, spp=256)  # 64 units of about 0.5 s each
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
"""


def test_ctrl_c_interrupts_a_long_render():
    p = subprocess.Popen([sys.executable, "-c", LONG_RENDER], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "started"
        time.sleep(1.0)
        t0 = time.time()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=30)
        assert p.returncode == 3 and "interrupted" in out
        assert time.time() - t0 < 10
    finally:
        p.kill()  # a render that ignored Ctrl-C must not outlive the test
        p.wait()
