"""The repository's scripts answer --help and bad arguments on their own, without running anything
(study-table.py once read any unknown argument as "print" and started a quick study of minutes)."""

import re
import subprocess
import sys

import pytest

from conftest import ROOT

SCRIPTS = ROOT / "scripts"


def script(name, *args):
    return subprocess.run([sys.executable, str(SCRIPTS / name), *args], capture_output=True,
                          text=True, timeout=60)


@pytest.mark.parametrize("name", ["doc-examples.py", "study-table.py"])
def test_help_describes_and_runs_nothing(name):
    r = script(name, "--help")
    assert r.returncode == 0 and r.stdout.startswith("usage: "), r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("name, args, needle", [
    ("doc-examples.py", ["no-such.md"], "no-such.md: no such file"),
    ("study-table.py", ["--bogus"], "unrecognized arguments: --bogus"),
    ("study-table.py", ["--check", "--write"], "not allowed with"),
    ("study-table.py", ["--from", "/nonexistent"], "/nonexistent: no metrics.csv"),
])
def test_bad_arguments_fail_on_one_line(name, args, needle):
    r = script(name, *args)
    assert r.returncode == 2 and needle in r.stderr.splitlines()[-1], r.stderr
    assert "Traceback" not in r.stderr


def test_every_doc_block_runs_or_says_why_not():
    # --list classifies without running: a block of no known language fails here, not in CI's run.
    r = script("doc-examples.py", "--list")
    assert r.returncode == 0, r.stdout
    skips = [line for line in r.stdout.splitlines() if line.startswith("SKIP")]
    assert all(line.split("): ", 1)[1].strip() for line in skips), skips


def test_ignored_rust_tests_say_when_they_run():
    # `cargo test` prints the reason of each ignored test: one that reads the real captures must say
    # that .ci/run runs it where they are, not "needs …" as if they were missing on a machine that has them.
    reasons = []
    for f in [*ROOT.glob("tests/*.rs"), *ROOT.glob("crates/*/tests/*.rs"), *ROOT.glob("crates/*/src/**/*.rs")]:
        reasons += [(f.relative_to(ROOT), r) for r in re.findall(r'#\[ignore = "([^"]*)"\]', f.read_text())]
    real = [(f, r) for f, r in reasons if "shared/data/real" in r]
    assert real, "no test reads the real captures?"
    assert all(".ci/run runs" in r and "--ignored" in r for _, r in real), real
