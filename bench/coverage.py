"""Coverage of the fitted parameters' 95 % intervals on model-generated data.

For each seed and ball type (Table 2 and a ball unlike Table 2): 10 impacts at random
speeds in 14-30 m/s (``--vmin`` to change the lowest speed) simulated with known
parameters, measurement noise added (TC 0.4 % relative, COR 0.003 absolute, the
scatter our processing leaves on synthetic sessions), optionally one planted outlier
per ball type (``--outlier``: TC +15 %, COR -6 % or inbound speed +4 %, in turn by
seed), then fitted with ``fit_ball_model`` (intervals only, no bootstrap). Counts how
often the true AK, a, AC, kB(20 mm) (and kB(0) when estimated) lie inside the reported
intervals, the median relative interval width, how often the planted outlier was named
and how many good impacts were removed (sessions of the four Table 2 balls with no
removal at all).

    python bench/coverage.py --seeds 100 --kb0 config|extrapolated [--outlier] [--json]

Results of the runs quoted in the README are in bench/out/ (one JSON per run).
"""

from __future__ import annotations

import argparse
import json
import time
import warnings

import numpy as np

from ballimpact.balls import BALLS, BallModelParameters
from ballimpact.fitting import FitError, fit_ball_model
from ballimpact.model import simulate_impact

UNLIKE_TABLE2 = BallModelParameters.from_table_units(58.0, 30.0, 40_000, 1.9, 2.5)
KINDS = ("tc+15%", "cor-6%", "vin+4%")


def session(p, rng, n_impacts=10, vmin=14.0, vmax=30.0, tc_noise=0.004, cor_noise=0.003, outlier=None):
    """Impacts (vin, tc, cor) of one ball type; ``outlier`` plants one bad impact (index returned)."""
    vin = np.sort(rng.uniform(vmin, vmax, n_impacts))
    s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    tc = s.contact_time_s * (1 + tc_noise * rng.standard_normal(n_impacts))
    e = s.cor + cor_noise * rng.standard_normal(n_impacts)
    bad = None
    if outlier is not None:
        bad = int(rng.integers(n_impacts))
        if outlier == "tc+15%":
            tc[bad] *= 1.15
        elif outlier == "cor-6%":
            e[bad] *= 0.94
        else:  # the gates read the inbound speed 4 % high: vin up, COR = vout / vin down
            vin[bad] *= 1.04
            e[bad] /= 1.04
    return vin, tc, e, bad


def run(seeds: int, kb0_mode: str, outlier: bool, vmin: float = 14.0, n_impacts: int = 10, first_seed: int = 0):
    sets = {k: b.params for k, b in BALLS.items()} | {"unlike_table2": UNLIKE_TABLE2}
    names = ["ak", "a", "ac", "kb_20mm"] + (["kb0"] if kb0_mode == "extrapolated" else [])
    hits = {k: {nm: 0 for nm in names} for k in sets}
    widths = {k: {nm: [] for nm in names} for k in sets}
    found = {k: 0 for k in sets}
    false_removed = {k: 0 for k in sets}
    sessions_clean = 0
    fails = {k: 0 for k in sets}
    total = 0
    for seed in range(first_seed, first_seed + seeds):
        rng = np.random.default_rng(1000 + seed)
        removed_table2 = 0
        for key, p in sets.items():
            kind = KINDS[seed % 3] if outlier else None
            vin, tc, e, bad = session(p, rng, n_impacts, vmin=vmin, outlier=kind)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    f = fit_ball_model(vin, tc, e, p.mass_kg, n_bootstrap=0, seed=seed,
                                       kb0_N_m=p.kb0_N_m if kb0_mode == "config" else None)
            except FitError:
                fails[key] += 1
                continue
            removed = np.flatnonzero(~f.used)
            if bad is not None and bad in removed:
                found[key] += 1
            n_false = int(sum(i != bad for i in removed))
            false_removed[key] += n_false
            if key in BALLS:
                removed_table2 += n_false
            truth = {"ak": p.ak, "a": p.a, "ac": p.ac, "kb0": p.kb0_N_m,
                     "kb_20mm": p.kb0_N_m + p.ak * 0.020**p.a}
            for nm in names:
                lo, hi = getattr(f, f"{nm}_lo"), getattr(f, f"{nm}_hi")
                hits[key][nm] += int(lo <= truth[nm] <= hi)
                widths[key][nm].append((hi - lo) / truth[nm])
        sessions_clean += int(removed_table2 == 0)
        total += 1
    cov = {k: {nm: v / total for nm, v in h.items()} for k, h in hits.items()}
    pooled = {nm: float(np.mean([cov[k][nm] for k in sets])) for nm in names}
    width = {k: {nm: float(np.median(w)) if w else float("nan") for nm, w in ws.items()} for k, ws in widths.items()}
    return {
        "seeds": total, "kb0": kb0_mode, "outlier": outlier, "vmin": vmin, "n_impacts": n_impacts,
        "coverage": cov, "pooled_coverage": pooled, "median_relative_width": width,
        "planted_outlier_named": {k: v / total for k, v in found.items()} if outlier else None,
        "good_impacts_removed_per_ball": {k: v / total for k, v in false_removed.items()},
        "sessions_without_removal": sessions_clean / total,
        "fit_failures": fails,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--kb0", choices=("config", "extrapolated"), default="config")
    ap.add_argument("--outlier", action="store_true", help="plant one outlier per ball type")
    ap.add_argument("--vmin", type=float, default=14.0, help="lowest inbound speed [m/s]")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    out = run(args.seeds, args.kb0, args.outlier, vmin=args.vmin, first_seed=args.first_seed)
    out["seconds"] = time.perf_counter() - t0
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(f"coverage of nominal 95 % intervals over {out['seeds']} seeds (kB(0) {args.kb0}, "
          f"{'one planted outlier per ball' if args.outlier else 'no outlier'}):")
    for k, c in out["coverage"].items():
        print(f"  {k:15s} " + "  ".join(f"{nm} {v:.2f}" for nm, v in c.items()))
    print("  pooled          " + "  ".join(f"{nm} {v:.3f}" for nm, v in out["pooled_coverage"].items()))
    if args.outlier:
        print("planted outlier named: " + ", ".join(f"{k} {v:.2f}" for k, v in out["planted_outlier_named"].items()))
    print(f"sessions (4 Table 2 balls) without a good impact removed: {out['sessions_without_removal']:.3f}")
    print(f"({out['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
