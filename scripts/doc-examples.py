#!/usr/bin/env python3
"""Runs every code example of README.md and docs/*.md, so that a broken example fails CI.

Each fenced block is an example unless its language is `text` (output, formats). `sh`/`bash` blocks
run under `bash -euo pipefail`, `python`/`py` blocks under this Python, each in a fresh temporary
folder holding links to the repository's `scenes/` and `target/`, with `target/release` first on
PATH (so `murk` is this build). A block that cannot run in CI carries, on the line before its fence,
`<!-- doc-examples: skip: REASON -->`; it is listed with its reason, never silently passed. A block
without a language is an error: say what it is.

Usage: scripts/doc-examples.py [--list] [FILE.md ...]   (default: README.md docs/*.md)
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SKIP = re.compile(r"<!--\s*doc-examples:\s*skip:\s*(.*?)\s*-->")
RUNNERS = {"sh": ["bash", "-euo", "pipefail"], "bash": ["bash", "-euo", "pipefail"],
           "python": [sys.executable], "py": [sys.executable]}
LIMIT_S = 600


def blocks(md: Path):
    """(line of the fence, language, code, skip reason or None) for each fenced block."""
    lines = md.read_text().splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        start, lang = i, m.group(1)
        end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith("```")), len(lines))
        skip = SKIP.search(lines[i - 1]) if i > 0 else None
        yield start + 1, lang, "\n".join(lines[i + 1:end]) + "\n", skip.group(1) if skip else None
        i = end + 1


def run(lang: str, code: str) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory(prefix="murk-doc-") as d:
        for name in ("scenes", "target"):
            os.symlink(ROOT / name, Path(d) / name)
        # This build's murk first, then this Python's folder (its venv: `python`, `pip`).
        path = f"{ROOT / 'target' / 'release'}:{Path(sys.executable).parent}:{os.environ['PATH']}"
        env = dict(os.environ, PATH=path,
                   MURK_ROOT=str(ROOT))
        suffix = ".py" if lang in ("python", "py") else ".sh"
        script = Path(d) / f"example{suffix}"
        script.write_text(code)
        return subprocess.run(RUNNERS[lang] + [str(script)], cwd=d, env=env, capture_output=True,
                              text=True, timeout=LIMIT_S)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\nUsage:")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", metavar="FILE.md", help="default: README.md docs/*.md")
    ap.add_argument("--list", action="store_true",
                    help="say what each block is (run or skipped, and why) without running any")
    a = ap.parse_args(argv)
    files = [Path(f) for f in a.files] or [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    for md in files:
        if not md.is_file():
            ap.error(f"{md}: no such file")
    ran = skipped = failed = 0
    t0 = time.monotonic()
    for md in files:
        rel = md.resolve().relative_to(ROOT)
        for line, lang, code, skip in blocks(md):
            where = f"{rel}:{line}"
            if lang == "text":
                continue
            if skip is not None:
                print(f"SKIP {where} ({lang}): {skip}")
                skipped += 1
                continue
            if lang not in RUNNERS:
                print(f"FAIL {where}: a block of language '{lang or 'none'}': label it sh, python "
                      f"or text, or mark it <!-- doc-examples: skip: why -->")
                failed += 1
                continue
            if a.list:
                print(f"run  {where} ({lang})")
                ran += 1
                continue
            t = time.monotonic()
            try:
                r = run(lang, code)
                ok, out = r.returncode == 0, r.stdout + r.stderr
            except subprocess.TimeoutExpired:
                ok, out = False, f"ran past {LIMIT_S} s"
            dt = time.monotonic() - t
            if ok:
                print(f"ok   {where} ({lang}, {dt:.1f} s)")
                ran += 1
            else:
                print(f"FAIL {where} ({lang}, {dt:.1f} s):\n" + out[-4000:])
                failed += 1
    print(f"doc examples: {ran} {'would run' if a.list else 'ran'}, {skipped} skipped (listed above), {failed} failed, "
          f"{time.monotonic() - t0:.0f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
