import os
import re
import shutil

import pytest

from conftest import ROOT, needs_cli

pytest.importorskip("matplotlib", reason="matplotlib is not installed")

REAL = ROOT.parent / "shared" / "data" / "real" / "cdt_lindell2020"


def python_blocks(md):
    """The ```python blocks of a Markdown file (```py blocks are examples not run here)."""
    return re.findall(r"^```python\n(.*?)^```", md.read_text(), flags=re.S | re.M)


@needs_cli
def test_worked_example_runs(capsys):
    block = python_blocks(ROOT / "docs" / "python.md")[0]  # the worked example comes first
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        exec(compile(block, "docs/python.md", "exec"), {})
        assert (ROOT / "murk-example" / "two-methods.png").stat().st_size > 10_000
    finally:
        os.chdir(cwd)
        shutil.rmtree(ROOT / "murk-example", ignore_errors=True)
    out = capsys.readouterr().out
    # The fallback must be visible, and must not happen where the real data exist.
    assert ("SYNTHETIC" in out) == (not REAL.exists())
    with capsys.disabled():
        print("\n[docs/python.md example used", "the real letter S]" if REAL.exists()
              else "a SYNTHETIC capture: ../shared/data/real/cdt_lindell2020 is missing]")
