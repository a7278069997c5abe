"""Check that a change of model.simulate_impact's code leaves its numbers as they were.

    python bench/model_equivalence.py save before.npz      # on the code before the change
    python bench/model_equivalence.py compare before.npz   # on the code after it

Every output of simulate_impact (the time series of ``record=True`` included) for the four
Table 2 balls at 71 speeds from 5 to 40 m/s, with and without a cloth stiffness; batches of
perturbed parameter sets (2-D, seed 3); single impacts with kB(0) = 0; and an impact that
does not end. ``compare`` asserts rtol 1e-12 (NaN equal to NaN) and prints whether the
numbers are also identical bit for bit; exit status 1 on a difference.
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

FIELDS = ("contact_time_s", "rebound_speed_m_s", "cor", "peak_force_N", "time_to_peak_s", "max_displacement_m")


def outputs() -> dict:
    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    res = {}
    rng = np.random.default_rng(3)
    vins = np.linspace(5, 40, 71)
    for name, ball in BALLS.items():
        p = ball.params
        for record in (False, True):
            for cloth_k in (0.0, 2000.0):
                r = simulate_impact(vins, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, record=record,
                                    cloth_stiffness_N_m=cloth_k)
                for f in r.__dataclass_fields__:
                    if getattr(r, f) is not None:
                        res[f"{name}_{record}_{cloth_k}_{f}"] = getattr(r, f)
        ak, a, ac = (p.ak * rng.uniform(0.5, 1.5, (9, 1)), p.a * rng.uniform(0.8, 1.2, (9, 1)),
                     p.ac * rng.uniform(0.5, 1.5, (9, 1)))
        r = simulate_impact(vins[::5], p.mass_kg, p.kb0_N_m, ak, a, ac)
        for f in FIELDS:
            res[f"{name}_perturbed_{f}"] = getattr(r, f)
        for v in (3.0, 17.3, 30.0):
            r = simulate_impact(v, p.mass_kg, 0.0, p.ak, p.a, p.ac)
            res[f"{name}_one_{v}"] = np.array([getattr(r, f) for f in FIELDS])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = simulate_impact(np.array([20.0, 1e-3]), 0.057, 0.0, 1e3, 1.0, 0.0, max_contact_time_s=2e-3)
    res["unended"] = np.array([getattr(r, f) for f in FIELDS])
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("action", choices=("save", "compare"))
    ap.add_argument("file", help=".npz file of the outputs")
    args = ap.parse_args(argv)
    res = outputs()
    if args.action == "save":
        np.savez(args.file, **res)
        print(f"saved {len(res)} arrays to {args.file}")
        return 0
    ref = np.load(args.file)
    if sorted(ref.files) != sorted(res):
        print(f"different arrays: {sorted(set(ref.files) ^ set(res))}")
        return 1
    identical = True
    for key in ref.files:
        try:
            np.testing.assert_allclose(res[key], ref[key], rtol=1e-12, atol=0, equal_nan=True, err_msg=key)
        except AssertionError as exc:
            print(exc)
            return 1
        identical &= bool(np.array_equal(res[key], ref[key], equal_nan=True))
    print(f"same to rtol 1e-12: {len(ref.files)} arrays; identical bit for bit: {identical}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
