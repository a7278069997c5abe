"""Coverage of the fitted parameters' 95 % intervals on model-generated data.

For each seed and ball type: 10 impacts at random speeds in 14-30 m/s simulated
with known parameters (Table 2, plus a ball unlike Table 2), measurement noise
added (TC 0.4 % relative, COR 0.003 absolute, the scatter our processing leaves
on synthetic sessions), then fitted with ``fit_ball_model``; counts how often the
true AK, a and AC lie inside the reported intervals.

    python bench/coverage.py --seeds 20 [--kb0 config|extrapolated] [--json]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from ballimpact.balls import BALLS, BallModelParameters
from ballimpact.fitting import fit_ball_model
from ballimpact.model import simulate_impact

UNLIKE_TABLE2 = BallModelParameters.from_table_units(58.0, 30.0, 40_000, 1.9, 2.5)


def run(seeds: int, kb0_mode: str, n_impacts: int = 10, tc_noise=0.004, cor_noise=0.003):
    sets = {k: b.params for k, b in BALLS.items()} | {"unlike_table2": UNLIKE_TABLE2}
    hits = {k: {"ak": 0, "a": 0, "ac": 0} for k in sets}
    total = 0
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        for key, p in sets.items():
            vin = np.sort(rng.uniform(14, 30, n_impacts))
            s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
            tc = s.contact_time_s * (1 + tc_noise * rng.standard_normal(n_impacts))
            e = s.cor + cor_noise * rng.standard_normal(n_impacts)
            f = fit_ball_model(vin, tc, e, p.mass_kg,
                               kb0_N_m=p.kb0_N_m if kb0_mode == "config" else None, seed=seed)
            for name, true in (("ak", p.ak), ("a", p.a), ("ac", p.ac)):
                lo, hi = getattr(f, f"{name}_lo"), getattr(f, f"{name}_hi")
                hits[key][name] += int(lo <= true <= hi)
        total += 1
    return {k: {n: v / total for n, v in h.items()} for k, h in hits.items()}, total


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--kb0", choices=("config", "extrapolated"), default="config")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    cov, n = run(args.seeds, args.kb0)
    out = {"seeds": n, "kb0": args.kb0, "coverage": cov, "seconds": time.perf_counter() - t0}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"coverage of nominal 95 % intervals over {n} seeds (kB(0) {args.kb0}):")
        for k, c in cov.items():
            print(f"  {k:15s} AK {c['ak']:.2f}  a {c['a']:.2f}  AC {c['ac']:.2f}")
        print(f"({out['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
