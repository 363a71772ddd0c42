#!/usr/bin/env python3
"""The results tables of docs/study.md, from a run of this build's study, so that they cannot go
stale: `--check` (CI) fails when the quick table in the doc differs from what today's code computes,
`--write` replaces it. Seeded renders give identical bytes on any machine, so a table is the same
wherever it is computed. The paper-scale table (CPU-hours) is written only from a finished paper-scale
study's folder: `--scale paper --from DIR --write`.

Usage: scripts/study-table.py [--check | --write | --print] [--scale quick|paper] [--from STUDY_DIR]
"""

import argparse
import csv
import json
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "study.md"


def markers(scale: str) -> tuple:
    """The comments that bracket `scale`'s table in docs/study.md."""
    flags = "--write" if scale == "quick" else "--scale paper --from DIR --write"
    return (f"<!-- results:{scale}:begin (scripts/study-table.py {flags}) -->",
            f"<!-- results:{scale}:end -->")


def show(v: float) -> str:
    """Three significant digits in plain decimals, as the report writes numbers; — for none."""
    if math.isnan(v):
        return "—"
    if v == 0:
        return "0"
    digits = 2 - math.floor(math.log10(abs(v)))
    t = f"{v:.{max(digits, 0)}f}"
    return t[1:] if t.startswith("-") and float(t) == 0 else t.replace("-", "−")


def table(study: Path) -> str:
    every = list(csv.DictReader(open(study / "metrics.csv")))
    rows = [r for r in every if r["compensation"] == "paper"]
    aware = {(r["figure"], r["row"], r["col"]): r for r in every if r["compensation"] == "aware"}
    objects = list(csv.DictReader(open(study / "objects.csv")))
    out = ["| figure | cell | IoU (best) | depth error (m) | SSIM | CNR | high-freq. share | objects found "
           "| medium-aware IoU | SSIM | estimated μt, α, g |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        a = aware.get((r["figure"], r["row"], r["col"]), {})
        # The estimate is a posterior mean on the fit's grid: round off the sums' last bits (a g of
        # 1e-18 is the grid's 0).
        est = ", ".join(show(round(float(a[k]), 3)) for k in ("est_mu_t", "est_albedo", "est_g")) \
            if a.get("est_mu_t") else "none detected"
        cell = " ".join(x for x in (r["row"], r["col"]) if x)
        found = [o for o in objects if o["figure"] == r["figure"] and o["col"] == r["col"]
                 and o["compensation"] == "paper" and o["seed"] == "0"]
        n = f"{sum(o['detected'] == 'true' for o in found)} of {len(found)}" if found else ""
        out.append("| " + " | ".join([r["figure"], cell] + [show(float(r[k] or "nan")) for k in
                   ("iou_best", "depth_err_m", "ssim", "cnr", "hf_share")] + [n]
                   + [show(float(a.get(k) or "nan")) for k in ("iou_best", "ssim")] + [est]) + " |")
    return "\n".join(out) + "\n"


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\nUsage:")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true", help="fail when docs/study.md's table is stale")
    mode.add_argument("--write", action="store_true", help="replace docs/study.md's table")
    mode.add_argument("--print", action="store_true", help="print the table (the default)")
    ap.add_argument("--scale", choices=("quick", "paper"), default="quick",
                    help="which table (paper: only with --from)")
    ap.add_argument("--from", dest="study", metavar="STUDY_DIR", type=Path,
                    help="read a finished study's folder instead of running a quick one (minutes)")
    a = ap.parse_args(argv)
    if a.scale == "paper" and a.study is None:
        ap.error("--scale paper needs --from STUDY_DIR (a paper-scale study takes CPU-hours)")
    BEGIN, END = markers(a.scale)
    doc = DOC.read_text()
    m = re.search(re.escape(BEGIN) + r"\n(.*?)" + re.escape(END), doc, flags=re.S)
    if m is None:
        sys.exit(f"{DOC}: no {BEGIN} … {END} markers")
    if a.study is not None:
        if not (a.study / "metrics.csv").is_file():
            ap.error(f"{a.study}: no metrics.csv (not a finished study's folder)")
        ran = json.loads((a.study / "plan.json").read_text()).get("scale")
        if ran != a.scale:
            ap.error(f"{a.study}: a {ran}-scale study, not {a.scale}")
        text = table(a.study)
    else:
        with tempfile.TemporaryDirectory(prefix="murk-study-table-") as d:
            subprocess.run([str(ROOT / "target" / "release" / "murk"), "experiment", "paper", "--out", d,
                            "--scenes", str(ROOT / "scenes"), "--quiet"], check=True)
            text = table(Path(d))
    if a.write:
        DOC.write_text(doc[:m.start(1)] + text + doc[m.end(1):])
        print(f"{DOC}: results table written")
    elif a.check:
        if m.group(1) != text:
            print(f"{DOC}: the {a.scale}-scale results table is stale; today's code gives:\n{text}"
                  "run scripts/study-table.py --write and commit it", file=sys.stderr)
            return 1
        print(f"{DOC}: the {a.scale}-scale results table matches today's code")
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
