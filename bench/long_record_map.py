"""Where a record of seconds after the contact passes a wrong number or costs an impact (issue 9).

    python bench/long_record_map.py --n 200 --seed 1

raw-format v1.1 lets the post-trigger run "from 5 ms to seconds"; the zoo draws it up to 1 s. Over seconds the
baseline's small errors add up: the mains frequency off its nominal value by up to 0.05 Hz turns a fixed-frequency
hum model's phase by up to half a turn in 5 s, and the amplifier's decay, undone, integrates any offset left over
the whole record. Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig (``zoo.map_shot``: a Table 2
ball, the four in turn, at 10-35 m/s, white noise of 0.1-0.5 % of the peak) at 20-200 kHz, with a pre-trigger of
1-100 ms and a record of 1-5 s after the contact (log-uniform), the amplifier's time constant drawn from 0.01-100 s
(log-uniform) and given in session.yaml for half, hum of 0.5-30 mV (log-uniform) at 50 Hz off by up to +-0.05 Hz,
given for half, and a drift of up to +-0.08 V/s. The trace stays measurable: an ok must be right. Rendered and
judged as the zoo's traces are (``zoo.run_trace``). Prints the categories by the record's length after the
contact, the first reasons of the exclusions, and the ok-but-wrong traces.

    python bench/long_record_map.py --n 200 --seed 1 --cut 0.06

cuts every record 60 ms after the contact: the same rigs, contacts and noise (its samples are drawn in the record's
order), so what the categories lose or gain is what the seconds after the contact cost (banded still by the record
drawn).
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
POST_BANDS_S = (2.0, 3.5)  # bands of the record after the contact [s]


def trace_for(seed: int, index: int, cut_s: float | None = None):
    """One map trace: (ZooTrace, record drawn after the contact [s]), the trace's record cut to ``cut_s`` [s]
    when given (its rig's ``post_s`` is then the cut one)."""
    rng = np.random.default_rng([seed, index, 5000])
    fs = zoo._loguniform(rng, 20e3, 200e3)
    pre = zoo._loguniform(rng, 1e-3, 0.1)
    post = zoo._loguniform(rng, 1.0, 5.0)
    tau = zoo._loguniform(rng, 0.01, 100.0)
    known = bool(rng.uniform() < 0.5)
    hum = zoo._loguniform(rng, 0.5e-3, 30e-3)
    mains_known = bool(rng.uniform() < 0.5)
    deviation = float(rng.uniform(-0.05, 0.05))
    drift = float(rng.uniform(-0.08, 0.08))
    shot = zoo.map_shot(rng)
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="long record", sample_rate_hz=fs, pre_s=pre,
                         post_s=post if cut_s is None else min(post, cut_s), tau_s=tau, tau_known=known,
                         hum_V=hum, mains_known=mains_known, mains_dev_hz=deviation, drift_V_s=drift, **shot))
    return zoo.render(rig, rng, f"long record {seed}:{index}"), post


def run_one(args):
    seed, index, cut_s = args
    trace, post = trace_for(seed, index, cut_s)
    result, j = zoo.run_trace(trace)
    return index, trace.rig, post, j.category, {k: 100 * v for k, v in j.errors.items()}, result.reason


def main(argv=None):
    ap = zoo.map_arguments(__doc__, n=200)
    ap.add_argument("--cut", type=float, default=None, metavar="S",
                    help="cut every record S seconds after the contact (the same rigs, contacts and noise)")
    a = ap.parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i, a.cut) for i in range(a.n)], a.workers)
    what = "a record of 1-5 s after the contact" + (f", cut to {a.cut:g} s" if a.cut is not None else "")
    print("\n".join(zoo.map_report(
        rows, a.seed, what + ", fs 20-200 kHz", [r[2] for r in rows], POST_BANDS_S,
        lambda band: f"  record after the contact {band:>8}",
        lambda r: f"record {1e3 * r[1].pre_s:.0f} ms + {r[1].post_s:.2f} s, hum {1e3 * r[1].hum_V:.1f} mV "
                  f"{r[1].mains_dev_hz:+.3f} Hz off 50 Hz, drift {r[1].drift_V_s:+.3f} V/s", unit=" s")))


if __name__ == "__main__":
    main()
