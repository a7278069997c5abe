"""Where a step in the baseline passes a wrong number: the DAQ's level shifts once, anywhere in the record (issue 9).

    python bench/step_map.py --n 400 --seed 1

A DAQ's or a charge amplifier's offset can shift within a record: a relay, the cannon's valve or a light gate's
driver switching near the wiring, an amplifier's range change. The zoo draws no such step. Apart from the zoo's
seeds: each rig is tests/zoo.py's benign rig (``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s,
noise 0.1-0.5 % of the peak) at 20-200 kHz, three in ten on a plate of 3 kHz to 0.45 fs (damping 0.01-0.3), with the
amplifier's time constant drawn from 0.01-100 s (log-uniform) and given in session.yaml for half of them, and one
step added to the recorded voltage: 0.1-5 % of the peak (log-uniform) either way, at an instant drawn from a
contact's length before the contact to one after it (six in ten) or anywhere in the record. The step is not the
ball's force and the trace stays measurable: an ok must be right. Rendered and judged as the zoo's traces are
(``zoo.run_trace``). Prints the categories by where the step falls, and the ok-but-wrong traces.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
WHERE_BANDS = (0.0, 1.0)  # the step before the contact, inside it, after it [fraction of TC from the start]


def trace_for(seed: int, index: int):
    """One map trace with its step: (ZooTrace, step [fraction of the peak], where [TC from the contact's start])."""
    rng = np.random.default_rng([seed, index, 151])
    fs = zoo._loguniform(rng, 20e3, 200e3)
    plate = bool(rng.uniform() < 0.3)
    fn = zoo._loguniform(rng, 3e3, min(30e3, 0.45 * fs))
    zeta = float(rng.uniform(0.01, 0.3))
    tau = zoo._loguniform(rng, 0.01, 100.0)
    known = bool(rng.uniform() < 0.5)
    shot = zoo.map_shot(rng)
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="step", sample_rate_hz=fs, tau_s=tau,
                         tau_known=known, plate_hz=fn if plate else None, plate_zeta=zeta, **shot))
    trace = zoo.render(rig, rng, f"step {seed}:{index}")
    v = trace.voltage_V.copy()
    t = trace.truth
    peak_v = t.peak_N / t.kcal_N_per_V
    height = float(rng.choice([-1, 1])) * zoo._loguniform(rng, 1e-3, 5e-2) * peak_v
    if rng.uniform() < 0.6:
        at = float(rng.uniform(t.start_s - t.tc_s, t.end_s + t.tc_s))
    else:
        at = float(rng.uniform(0, v.size / fs))
    v[int(np.ceil(at * fs)):] += height
    return dataclasses.replace(trace, voltage_V=v), height / peak_v, (at - t.start_s) / t.tc_s


def run_one(args):
    seed, index = args
    trace, height, where = trace_for(seed, index)
    _, j = zoo.run_trace(trace)
    return index, trace.rig, height, where, j.category, {k: 100 * v for k, v in j.errors.items()}


def main(argv=None):
    a = zoo.map_arguments(__doc__).parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i) for i in range(a.n)], a.workers)
    print(zoo.category_summary(a.n, a.seed, "one step of 0.1-5 % of the peak, fs 20-200 kHz", [r[4] for r in rows]))
    for band, counts in zoo.band_counts([r[3] for r in rows], [r[4] for r in rows], WHERE_BANDS, unit=" TC"):
        print(f"  step at {band:>8}: {counts}")
    for index, rig, height, where, cat, err in rows:
        if cat in ("ok_wrong", "faulty_ok"):
            print(zoo.map_offender(cat, a.seed, index, rig, f"step {100 * height:+.2f} % of the peak at {where:+.2f} TC",
                                   err))


if __name__ == "__main__":
    main()
