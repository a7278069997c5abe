"""Re-run the zoo traces a conditioning check could change, against per-trace CSVs of bench/robustness.py (issue 9).

    python bench/rerun_changed.py OLD-s0.csv OLD-s1.csv ... --out NEW.csv

A check that adds a plate problem changes a trace's category only where it was ok, or excluded for problems
of the plate's kinds that show no ringing themselves (a peak between samples, an end not determined or between
two samples: its evidence then lets the plate's undoing be tried); the first-overshoot check acts only on a
largest sample early in the contact, so only traces on a plate or whose peak is the pre-buckling spike are
taken. Each is run again (``zoo.trace_for``, ``zoo.run_trace``, as bench/robustness.py does); prints the
counts per seed before and after on those traces, and every trace whose category or numbers changed.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import csv
import math
import multiprocessing as mp
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402
from ballimpact.problems import ProblemKind, kind_of_message  # noqa: E402

NO_EVIDENCE = {ProblemKind.PEAK_BETWEEN_SAMPLES, ProblemKind.CONTACT_END_UNDETERMINED,
               ProblemKind.CONTACT_JUMP_UNRESOLVED}


def may_change(row: dict) -> bool:
    """Whether a plate problem added by an early-peak check could change this trace's category."""
    if row["category"] not in ("ok_right", "ok_wrong"):
        kinds = {kind_of_message(m) for m in row["reason"].split("; ")} - {None}
        if not (row["category"].startswith("excluded") and kinds and kinds <= NO_EVIDENCE):
            return False
    return "plate ideal" not in row["factors"] or row["peak_is_spike"] == "True"


def run_one(tid: str) -> dict:
    seed, index = map(int, tid.split(":"))
    result, j = zoo.run_trace(zoo.trace_for(seed, index))
    return {"id": tid, "category": j.category, "reason": j.reason, "tc_err_pct": 100 * j.errors["tc"],
            "kcal_err_pct": 100 * j.errors["kcal"], "peak_err_pct": 100 * j.errors["peak"]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+", help="per-trace CSVs of bench/robustness.py (the state before)")
    ap.add_argument("--out", required=True, help="per-trace CSV of the traces run again")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    old = {r["id"]: r for f in a.csv for r in csv.DictReader(open(f, encoding="utf-8"))}
    ids = [tid for tid, r in old.items() if may_change(r)]
    with mp.Pool(a.workers) as pool:
        rows = pool.map(run_one, ids, chunksize=8)
    with open(a.out, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"{len(ids)} of {len(old)} traces run again")
    for seed in sorted({tid.split(":")[0] for tid in ids}, key=int):
        before = Counter(old[r["id"]]["category"] for r in rows if r["id"].startswith(seed + ":"))
        after = Counter(r["category"] for r in rows if r["id"].startswith(seed + ":"))
        print(f"seed {seed}: " + ", ".join(f"{c} {before[c]} -> {after[c]}" for c in zoo.CATEGORIES if before[c] or after[c]))
    for r in rows:
        o = old[r["id"]]
        moved = max(abs(float(r[k]) - float(o[k])) for k in ("tc_err_pct", "kcal_err_pct", "peak_err_pct"))
        if r["category"] != o["category"] or not moved <= 1e-6:
            print(f"  {r['id']}: {o['category']} -> {r['category']}, TC {float(o['tc_err_pct']):+.2f} -> "
                  f"{float(r['tc_err_pct']):+.2f} %, peak {float(o['peak_err_pct']):+.2f} -> "
                  f"{float(r['peak_err_pct']):+.2f} %{'' if math.isfinite(moved) else ' (not reported)'}")


if __name__ == "__main__":
    main()
