"""Where a plate's first overshoot passes for the peak: the model's forces through second-order plates (issue 9).

    python bench/overshoot_map.py --n 600 --seed 2            # plates sampled 2.2-8 times a period
    python bench/overshoot_map.py --n 600 --seed 1 --all      # any plate of 3-30 kHz below 0.45 fs

Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig ("plate" mode) with a ball of Table 2 (the
four in turn, parameters within the zoo's +-20 %) at 10-35 m/s, a plate of 3-30 kHz with damping 0.02-0.3
(log-uniform), a sample rate of 20-200 kHz (by default 2.2-8 samples per plate period), white noise of 0.1-0.5 %
of the peak and a random sample phase; it is rendered and judged as the zoo's traces are (``zoo.run_trace``).
Prints the categories per samples-per-period and damping band and the ok-but-wrong traces.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
RATIO_BANDS = (2.0, 3.0, 4.0, 6.0, 10.0, 20.0, 100.0)  # sample rate / plate resonance [-]
ZETA_BANDS = (0.02, 0.05, 0.1, 0.2, 0.3)  # damping ratio [-]


def rig_for(seed: int, index: int, few: bool):
    """The rig of one map trace and the generator to render it with."""
    rng = np.random.default_rng([seed, index])
    if few:
        while True:
            fn = zoo._loguniform(rng, 3e3, 30e3)
            fs = fn * zoo._loguniform(rng, 2.2, 8.0)
            if 20e3 <= fs <= 200e3:
                break
    else:
        fs = zoo._loguniform(rng, 20e3, 200e3)
        fn = zoo._loguniform(rng, 3e3, min(30e3, 0.45 * fs))
    zeta = zoo._loguniform(rng, 0.02, 0.3)
    shot = zoo.map_shot(rng)
    fields = dict(zoo._BENIGN, ball=BALLS[index % 4], mode="plate", sample_rate_hz=fs, plate_hz=fn, plate_zeta=zeta,
                  **shot)
    return zoo.Rig(**fields), rng


def run_one(args):
    seed, index, few = args
    rig, rng = rig_for(seed, index, few)
    trace = zoo.render(rig, rng, f"map {seed}:{index}")
    result, j = zoo.run_trace(trace)
    return (index, rig, j.category, 100 * j.errors["tc"], 100 * j.errors["peak"], trace.truth.peak_is_spike,
            result.plate_resonance_hz)


def main(argv=None):
    ap = zoo.map_arguments(__doc__, n=600, seed=2)
    ap.add_argument("--all", action="store_true", help="any plate below 0.45 fs (default: 2.2-8 samples a period)")
    a = ap.parse_args(argv)
    jobs = [(a.seed, i, not a.all) for i in range(a.n)]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(a.n, a.seed, "any plate" if a.all else "2.2-8 samples a period", [r[2] for r in rows]))
    for name, key, edges in (("samples per period", lambda r: r[1].sample_rate_hz / r[1].plate_hz, RATIO_BANDS),
                             ("damping ratio", lambda r: r[1].plate_zeta, ZETA_BANDS)):
        for band, counts in zoo.band_counts([key(r) for r in rows], [r[2] for r in rows], edges):
            print(f"  {name} {band:>9}: {counts}")
    for index, rig, cat, tc, peak, spike, undone in rows:
        if cat == "ok_wrong":
            print(f"  ok but wrong {a.seed}:{index}: {rig.ball} {rig.vin_m_s:.1f} m/s, fs {rig.sample_rate_hz / 1e3:.1f} kHz,"
                  f" plate {rig.plate_hz / 1e3:.2f} kHz ({rig.sample_rate_hz / rig.plate_hz:.2f} samples a period)"
                  f" damping {rig.plate_zeta:.3f}: TC {tc:+.2f} %, peak {peak:+.1f} %{' (spike)' if spike else ''}"
                  f"{'' if math.isnan(undone) else ', plate undone'}")


if __name__ == "__main__":
    main()
