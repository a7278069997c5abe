"""Where a low-pass in the sensor chain passes a wrong TC: the model's forces through a heavily damped second-order response (issue 9).

    python bench/lowpass_map.py --n 400 --seed 1           # fn 2-40 kHz, damping 0.3-1, fs 20-200 kHz
    python bench/lowpass_map.py --n 400 --seed 1 --show-ok  # also every ok trace with |TC err| above 0.5 %

The zoo's plates are lightly damped (damping ratio 0.01-0.3): they ring, and the ringing shows them. A charge
amplifier's low-pass filter (a second-order Butterworth has damping 0.71, a Bessel 0.87) or a plate on damped
mounts rings little or not at all, and delays the force by its group delay 2 zeta / wn: the contact's end comes
late by it, its start (the foot of the spread jump) hardly, and TC is long. Apart from the zoo's seeds: each rig is
tests/zoo.py's benign rig (``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s, noise 0.1-0.5 % of
the peak) with a sample rate of 20-200 kHz and a unit-gain second-order response of 2-40 kHz (both log-uniform) and
damping ratio 0.3-1.0 (uniform) in the zoo's plate's place (its exact first-order-hold integration). Rendered and
judged as the zoo's traces are (``zoo.run_trace``). The zoo calls a response below 3 kHz marginal (its exclusion is
no failure; an ok must still be right). Prints the categories per band of the response's delay in samples
(2 zeta fs / wn: under a sample, a delay leaves no trace in the samples) and the ok-but-wrong traces.
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
DELAY_BANDS_SAMPLES = (0.5, 1.0, 2.0, 5.0)


def rig_for(seed: int, index: int):
    """The rig of one map trace and the generator to render it with."""
    rng = np.random.default_rng([seed, index, 77])
    fs = zoo._loguniform(rng, 20e3, 200e3)
    fn = zoo._loguniform(rng, 2e3, 40e3)
    zeta = float(rng.uniform(0.3, 1.0))
    shot = zoo.map_shot(rng)
    fields = dict(zoo._BENIGN, ball=BALLS[index % 4], mode="plate", sample_rate_hz=fs, plate_hz=fn,
                  plate_zeta=zeta, **shot)
    return zoo.Rig(**fields), rng


def trace_for(seed: int, index: int) -> zoo.ZooTrace:
    """One map trace, rendered."""
    rig, rng = rig_for(seed, index)
    return zoo.render(rig, rng, f"lowpass {seed}:{index}")


def delay_samples(rig) -> float:
    """The response's group delay at low frequencies, 2 zeta / wn, in samples [samples]."""
    return 2.0 * rig.plate_zeta / (2.0 * math.pi * rig.plate_hz) * rig.sample_rate_hz


def run_one(args):
    seed, index = args
    trace = trace_for(seed, index)
    _, j = zoo.run_trace(trace)
    return index, trace.rig, j.category, 100 * j.errors["tc"], 100 * delay_samples(trace.rig) / (
        trace.rig.sample_rate_hz * trace.truth.tc_s), j.reason


def main(argv=None):
    a = zoo.map_arguments(__doc__, show_ok=True).parse_args(argv)
    jobs = [(a.seed, i) for i in range(a.n)]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(a.n, a.seed, "second-order low-pass 2-40 kHz, damping 0.3-1, fs 20-200 kHz",
                               [r[2] for r in rows]))
    for band, counts in zoo.band_counts([delay_samples(r[1]) for r in rows], [r[2] for r in rows],
                                        DELAY_BANDS_SAMPLES, unit=" samples"):
        print(f"  delay {band:>14}: {counts}")
    for index, rig, cat, tc, delay_pct, reason in rows:
        if cat == "ok_wrong" or (a.show_ok and cat.startswith("ok") and abs(tc) > 0.5):
            print(f"  {cat} {a.seed}:{index}: {rig.ball} {rig.vin_m_s:.1f} m/s, fs {rig.sample_rate_hz / 1e3:.1f} kHz, "
                  f"{rig.plate_hz / 1e3:.1f} kHz damping {rig.plate_zeta:.2f} (delay {delay_samples(rig):.2f} "
                  f"samples, {delay_pct:.2f} % of TC): TC {tc:+.2f} %")


if __name__ == "__main__":
    main()
