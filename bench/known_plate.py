"""What knowing the plate exactly would give: zoo traces with a plate, processed as they are and with the true plate
stated by its keys (plate.resonance_hz, plate.damping_ratio: a perfect identification, or a perfect tap test).

    python bench/known_plate.py --n 3000 --seed 704              # the random rigs with a plate at 3 kHz or above
    python bench/known_plate.py --n 3000 --seed 704 --class "one factor"

For each non-faulty trace of the target class (bench/robustness.py's, from ``tests/zoo.py``) whose rig has a
resonant plate, prints TC's outcome keyless against stated (ok and right, ok but wrong, withheld but right,
withheld and wrong), split by whether the plate lies above half the sample rate (its ringing aliases, and no key
about the plate can help), and the findings that still withhold a right TC with the plate stated, by code. It
bounds what any identification of the plate, from one trace or from a session, can give the zoo's targets.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import multiprocessing as mp
import sys
import tempfile
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402
from ballimpact.verdicts import unestimated  # noqa: E402
from robustness import target_class  # noqa: E402

OUTCOMES = ("ok_right", "ok_wrong", "withheld_right", "withheld_wrong")


def run_one(job):
    """Trace (seed, index) keyless and with its plate stated, or None outside the class."""
    seed, index, wanted = job
    tr = zoo.trace_for(seed, index)
    labels = "|".join(zoo.factor_labels(tr.rig, tr.truth))
    if not tr.truth.measurable or tr.rig.plate_hz is None or target_class({"labels": labels}) != wanted:
        return None
    out = {"id": f"{seed}:{index}", "aliases": tr.rig.plate_hz > tr.rig.sample_rate_hz / 2}
    with tempfile.TemporaryDirectory(prefix="known-plate-") as scratch:
        for name, extra in (("keyless", None), ("stated", {"resonance_hz": tr.rig.plate_hz,
                                                           "damping_ratio": tr.rig.plate_zeta})):
            result, j = zoo.run_trace(tr, scratch, plate_extra=extra)
            out[name] = j.outcomes["tc"]
            out[f"{name}_unestimated"] = unestimated(result.problems, "contact_time")
    return out


def table(records) -> str:
    lines = ["| plate | TC keyless | n | " + " | ".join(f"stated: {o.replace('_', ' ')}" for o in OUTCOMES) + " |",
             "|---|---|---|" + "---|" * len(OUTCOMES)]
    for aliases in (False, True):
        for before in OUTCOMES:
            rows = [r for r in records if r["aliases"] == aliases and r["keyless"] == before]
            if rows:
                after = Counter(r["stated"] for r in rows)
                lines.append(f"| {'above' if aliases else 'below'} fs / 2 | {before.replace('_', ' ')} | "
                             f"{len(rows)} | " + " | ".join(str(after[o]) for o in OUTCOMES) + " |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=3000, help="zoo traces drawn (those of the class are run)")
    ap.add_argument("--seed", type=int, default=704)
    ap.add_argument("--class", dest="cls", default="random, ideal plate or >= 3 kHz",
                    help="target class of bench/robustness.py")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    jobs = [(args.seed, i, args.cls) for i in range(args.n)]
    with mp.get_context("fork").Pool(args.workers) as pool:
        records = [r for r in pool.imap(run_one, jobs, chunksize=8) if r is not None]
    n = len(records)
    count = {name: Counter(r[name] for r in records) for name in ("keyless", "stated")}
    print(f"{n} non-faulty traces with a plate, class {args.cls!r}, seed {args.seed} "
          f"(`python bench/known_plate.py --n {args.n} --seed {args.seed}`)\n")
    for name in ("keyless", "stated"):
        print(f"{name}: TC " + ", ".join(f"{o.replace('_', ' ')} {count[name][o]}" for o in OUTCOMES))
    print("\n" + table(records) + "\n")
    left = Counter(code for r in records if r["stated"] == "withheld_right" and not r["aliases"]
                   for code in (r["stated_unestimated"] or ["(the budget alone)"]))
    for name in ("keyless", "stated"):
        wrong = [r["id"] for r in records if r[name] == "ok_wrong"]
        if wrong:
            print(f"{name}: TC ok but wrong on {', '.join(wrong)} (`python bench/robustness.py --replay SEED:INDEX`)")
    print("plate stated, below fs / 2, TC withheld but right, by the findings without an estimate of their effect: "
          + ", ".join(f"{code} {k}" for code, k in left.most_common()))


if __name__ == "__main__":
    main()
