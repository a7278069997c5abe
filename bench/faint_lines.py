"""Faint plate lines: does the processing keep every quantity whose true error is under half its tolerance?

    python bench/faint_lines.py --n 200 --seed 0     # 200 cases (2 worker processes)

Each case (tests/faint.py) is a benign zoo trace on an ideal plate sampled at
60-200 kHz with a damped plate line added from the contact's start: 1-20 kHz,
0.05-1 % of the peak, damping ratio 0.01-0.05. It is run through the real
``process_impact`` and judged per quantity (tests/zoo.py ``judge``). Prints, per
quantity: kept and right, ok but wrong, withheld with a true error under half
its tolerance (a failure of the sweep's rule), withheld otherwise; by line
frequency band; and the failures with their SEED:INDEX.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import math
import multiprocessing as mp
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import faint  # noqa: E402
import zoo  # noqa: E402

TOL = {"tc": zoo.TOL_TC, "kcal": zoo.TOL_KCAL, "peak": zoo.TOL_PEAK}
BANDS = ((1e3, 3e3), (3e3, 10e3), (10e3, 20e3))


def run_one(args):
    """Make, process and judge faint case (seed, index)."""
    seed, index = args
    tr = faint.draw_faint(seed, index)
    result, j = zoo.run_trace(tr)  # in a temporary folder of its own, removed afterwards
    tol = dict(TOL, peak=zoo.TOL_PEAK_SPIKE if tr.truth.peak_is_spike else zoo.TOL_PEAK)
    out = {"id": f"{seed}:{index}", "label": tr.label, "line_hz": float(tr.label.split("line ")[1].split(" Hz")[0]),
           "codes": result.reason_code, "status": result.status}
    for q in TOL:
        err = j.errors[q]
        half = math.isfinite(err) and abs(err) < 0.5 * tol[q]
        o = j.outcomes[q]
        out[q] = ("lost" if o.startswith("withheld") and half else o)
        out[q + "_err"] = err
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    jobs = [(args.seed, i) for i in range(args.n)]
    with mp.get_context("fork").Pool(args.workers) as pool:
        rows = list(pool.imap(run_one, jobs, chunksize=4))
    print(f"### {args.n} faint-line cases, seed {args.seed} (`python bench/faint_lines.py --n {args.n} "
          f"--seed {args.seed}`)\n")
    head = ["line", "n"] + [f"{q} {o}" for q in TOL for o in ("ok right", "ok WRONG", "lost", "withheld")]
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for lo, hi in BANDS + ((0, math.inf),):
        sel = [r for r in rows if lo <= r["line_hz"] < hi]
        c = defaultdict(int)
        for r in sel:
            for q in TOL:
                c[q, "withheld" if r[q] in ("withheld_wrong", "withheld_right") else r[q]] += 1
        name = "all" if hi == math.inf else f"{lo / 1e3:g}-{hi / 1e3:g} kHz"
        cells = [name, len(sel)] + [c[q, o] for q in TOL for o in ("ok_right", "ok_wrong", "lost", "withheld")]
        print("| " + " | ".join(str(x) for x in cells) + " |")
    bad = [r for r in rows if any(r[q] in ("lost", "ok_wrong") for q in TOL)]
    print(f"\nlost (withheld, true error under half the tolerance) or ok but wrong: {len(bad)} of {len(rows)}")
    for r in bad:
        print(f"- `{r['id']}` {r['label']}: " + ", ".join(f"{q} {r[q]} {100 * r[q + '_err']:+.3f} %" for q in TOL)
              + f"; codes {r['codes']!r}")


if __name__ == "__main__":
    main()
