"""Plates stated by their keys: zoo rigs with a resonant plate, processed with plate.resonance_hz and
plate.damping_ratio (a tap test's numbers, exact) and without them.

    python bench/stated_plate_map.py --n 200 --seed 1

Each case is a zoo rig (tests/zoo.py) with a plate drawn log-uniform over 1-30 kHz, damping ratio
0.02-0.15, sampled at 60-200 kHz (aliasing ruled out); half the cases change that factor alone, half
draw every other factor too. Prints, with and without the keys, per quantity: ok and right, ok but wrong,
withheld but right, and the ok-but-wrong cases with their SEED:INDEX.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import math
import multiprocessing as mp
import sys
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402


def stated_trace(seed: int, index: int) -> "zoo.ZooTrace":
    """Case ``index`` of ``seed``: a plate at 1-30 kHz (damping 0.02-0.15) at 60-200 kHz."""
    rng = np.random.default_rng([seed, index, 11])
    fn = float(math.exp(rng.uniform(math.log(1e3), math.log(30e3))))
    zeta = float(rng.uniform(0.02, 0.15))
    fs = float(math.exp(rng.uniform(math.log(60e3), math.log(200e3))))
    mode = "plate" if index % 2 else "random"
    return zoo.make_trace(np.random.default_rng([seed, index]), mode, label=f"stated {seed}:{index}",
                          plate_hz=fn, plate_zeta=zeta, sample_rate_hz=fs, plate_modes=(), antialias_hz=None)


def run_one(args):
    seed, index = args
    tr = stated_trace(seed, index)
    out = {"id": f"{seed}:{index}", "fn": tr.rig.plate_hz, "zeta": tr.rig.plate_zeta, "fault": tr.truth.fault}
    for name, extra in (("keyless", None), ("stated", {"resonance_hz": tr.rig.plate_hz,
                                                       "damping_ratio": tr.rig.plate_zeta})):
        result, j = zoo.run_trace(tr, plate_extra=extra)  # in a temporary folder of its own, removed afterwards
        out[name] = {"status": result.status, "outcomes": j.outcomes, "errors": j.errors,
                     "category": j.category}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    jobs = [(args.seed, i) for i in range(args.n)]
    with mp.get_context("fork").Pool(args.workers) as pool:
        rows = list(pool.imap(run_one, jobs, chunksize=2))
    print(f"### {args.n} zoo rigs with a resonant plate, seed {args.seed} "
          f"(`python bench/stated_plate_map.py --n {args.n} --seed {args.seed}`)\n")
    print("| keys | plate | non-faulty | used in fit | TC ok right | TC ok WRONG | TC withheld right | kCAL ok WRONG "
          "| peak ok WRONG | faulty used |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in ("keyless", "stated"):
        for band, lo, hi in (("1-3 kHz", 1e3, 3e3), ("3-30 kHz", 3e3, 31e3)):
            sel = [r for r in rows if lo <= r["fn"] < hi]
            clean = [r for r in sel if not r["fault"]]
            c = Counter()
            for r in clean:
                res = r[name]
                c["used"] += res["status"] == "ok"
                for q in ("tc", "kcal", "peak"):
                    c[q, res["outcomes"][q]] += 1
            faulty = sum(r[name]["category"] == "faulty_ok" for r in sel)
            print(f"| {name} | {band} | {len(clean)} | {c['used']} | {c['tc', 'ok_right']} | {c['tc', 'ok_wrong']} | "
                  f"{c['tc', 'withheld_right']} | {c['kcal', 'ok_wrong']} | {c['peak', 'ok_wrong']} | {faulty} |")
    for r in rows:
        for name in ("keyless", "stated"):
            if r[name]["category"] in ("ok_wrong", "faulty_ok"):
                print(f"- `{r['id']}` {name}: {r[name]['category']}, plate {r['fn']:.0f} Hz damping {r['zeta']:.3f}, "
                      + ", ".join(f"{q} {100 * v:+.2f} %" for q, v in r[name]["errors"].items()))


if __name__ == "__main__":
    main()
