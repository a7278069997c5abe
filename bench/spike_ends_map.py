"""Single-sample spikes at a contact's ends: the ball's own at its jump, a plate's overshoot, electrical ones (issue 9).

    python bench/spike_ends_map.py --n 400 --seed 1 --workers 1
    python bench/spike_ends_map.py --n 400 --seed 1 --csv out.csv    # one row per trace, to compare two branches

Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig with a ball of Table 2 (the four in turn,
parameters as ``zoo.map_shot`` draws them) at 8-16 m/s (where the ball's pre-buckling spike after the force's jump
from zero is 0-0.1 ms long, about one sample at 20-60 kHz), a sample rate of 20-60 kHz, an ideal plate or (one in
three) a plate of 3 kHz-0.45 fs with damping 0.02-0.3, and white noise of 0.1-0.5 % of the peak. Two rigs in three
carry one electrical spike of +-20 mV-2 V (the zoo's range) on a sample 4 before to 4 after the contact's start or
end (drawn uniformly); the third carries none. Rendered and judged as the zoo's traces are (``zoo.run_trace``).
Prints the categories per class (no spike / spike at the start / at the end) and every ok-but-wrong trace.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import copy
import csv
import math
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
VIN_M_S = (8.0, 16.0)  # inbound speeds [m/s]
RATE_HZ = (20e3, 60e3)  # sample rates [Hz]
SPIKE_V = (0.02, 2.0)  # electrical spike magnitudes [V] (the zoo's)
SPIKE_OFFSET = 4  # the spike's sample within this many of the contact's first or last sample [samples]


def trace_for(seed: int, index: int, spike: bool = True) -> tuple[zoo.ZooTrace, str]:
    """One map trace, rendered, and where its electrical spike is ("none", "start", "end"); without it when not
    ``spike`` (the same trace otherwise)."""
    rng = np.random.default_rng([seed, index, 12])
    fs = zoo._loguniform(rng, *RATE_HZ)
    shot = zoo.map_shot(rng)
    shot["vin_m_s"] = float(rng.uniform(*VIN_M_S))
    plate = {}
    if rng.uniform() < 1 / 3:
        plate = dict(plate_hz=zoo._loguniform(rng, 3e3, 0.45 * fs), plate_zeta=zoo._loguniform(rng, 0.02, 0.3))
    where = str(rng.choice(["none", "start", "end"]))
    offset = int(rng.integers(-SPIKE_OFFSET, SPIKE_OFFSET + 1))
    amp = float(rng.choice([-1, 1]) * zoo._loguniform(rng, *SPIKE_V))
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="plate" if plate else "benign",
                         sample_rate_hz=fs, **plate, **shot))
    state = copy.deepcopy(rng)
    trace = zoo.render(rig, rng, f"spike ends {seed}:{index}")
    if where == "none" or not spike:
        return trace, where
    n = trace.voltage_V.size
    k = int(math.ceil(trace.truth.start_s * fs)) if where == "start" else int(math.floor(trace.truth.end_s * fs))
    k = min(max(k + offset, 0), n - 1)
    return zoo.render(replace(rig, spikes=((float((k + 0.5) / n), amp),)), state, trace.label), where


def run_one(args):
    seed, index = args
    trace, where = trace_for(seed, index)
    result, j = zoo.run_trace(trace)
    return (index, where, trace.rig, j.category, {k: 100 * v for k, v in j.errors.items()}, j.reason)


def main(argv=None):
    ap = zoo.map_arguments(__doc__)
    ap.add_argument("--csv", help="write one row per trace here")
    a = ap.parse_args(argv)
    jobs = [(a.seed, i) for i in range(a.n)]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(a.n, a.seed, "", [r[3] for r in rows]))
    for where in ("none", "start", "end"):
        c = Counter(r[3] for r in rows if r[1] == where)
        print(f"  electrical spike {where:>5}: " + ", ".join(f"{k} {c[k]}" for k in zoo.CATEGORIES if c[k]))
    for index, where, rig, cat, err, reason in rows:
        if cat == "ok_wrong":
            print(f"  ok but wrong {a.seed}:{index}: {rig.ball} {rig.vin_m_s:.1f} m/s, fs {rig.sample_rate_hz / 1e3:.1f} "
                  f"kHz, plate {'ideal' if rig.plate_hz is None else f'{rig.plate_hz / 1e3:.2f} kHz'}, spike {where} "
                  f"{rig.spikes}: TC {err['tc']:+.2f} %, kCAL {err['kcal']:+.2f} %, peak {err['peak']:+.1f} %")
    if a.csv:
        with open(a.csv, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["id", "where", "category", "tc_err_pct", "kcal_err_pct", "peak_err_pct", "reason"])
            for index, where, rig, cat, err, reason in rows:
                w.writerow([f"{a.seed}:{index}", where, cat, f"{err['tc']:.4f}", f"{err['kcal']:.4f}",
                            f"{err['peak']:.4f}", reason])


if __name__ == "__main__":
    main()
