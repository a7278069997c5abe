"""Where a coarse ADC passes a wrong TC: the model's forces recorded with 12 or 14 bits, noise below the step (issue 9).

    python bench/adc_map.py --n 400 --seed 1           # 12 or 14 bits over +-10 V, noise 0.05-2 mV, fs 20-200 kHz
    python bench/adc_map.py --n 400 --seed 1 --show-ok  # also every ok trace with |TC err| above 0.5 %

The zoo's ADC has 16 bits over +-10 V (a step of 0.31 mV) and noise of 0.2-5 mV: the noise dithers the step. A
12-bit DAQ (a step of 4.9 mV over +-10 V) or a 14-bit one (1.2 mV) under a quiet amplifier records a trace that
moves in whole steps: its quiet stretches hold almost no noise, and a single step before the contact or at its end
stands out by tens of the noise deviations estimated there. Apart from the zoo's seeds: each rig is tests/zoo.py's
benign rig (``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s) with a sample rate of 20-200 kHz, an
ADC of 12 or 14 bits, a peak of 0.3-6 V and white noise of 0.05-2 mV (all log-uniform but the bits), and half of the
rigs a plate of 3 kHz to 0.45 fs (damping 0.01-0.3). Rendered and judged as the zoo's traces are
(``zoo.run_trace``). Prints the categories per ADC and per band of the noise over the step, and the ok-but-wrong
traces.
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
NOISE_OVER_STEP_BANDS = (0.1, 0.3, 1.0)


def rig_for(seed: int, index: int):
    """The rig of one map trace and the generator to render it with."""
    rng = np.random.default_rng([seed, index, 93])
    fs = zoo._loguniform(rng, 20e3, 200e3)
    bits = int(rng.choice([12, 14]))
    peak_v = zoo._loguniform(rng, 0.3, 6.0)
    noise = zoo._loguniform(rng, 0.05e-3, 2e-3)
    plate = bool(rng.uniform() < 0.5)
    fn = zoo._loguniform(rng, 3e3, min(30e3, 0.45 * fs))
    zeta = float(rng.uniform(0.01, 0.3))
    shot = dict(zoo.map_shot(rng), noise_V=noise)
    fields = dict(zoo._BENIGN, ball=BALLS[index % 4], mode="adc", sample_rate_hz=fs, plate_hz=fn if plate else None,
                  plate_zeta=zeta, peak_volts=peak_v, adc_bits=bits, **shot)
    return zoo.Rig(**fields), rng


def trace_for(seed: int, index: int) -> zoo.ZooTrace:
    """One map trace, rendered."""
    rig, rng = rig_for(seed, index)
    return zoo.render(rig, rng, f"adc {seed}:{index}")


def step_V(rig) -> float:
    """The ADC's step [V]."""
    return (rig.adc_range_v[1] - rig.adc_range_v[0]) / 2**rig.adc_bits


def run_one(args):
    seed, index = args
    trace = trace_for(seed, index)
    _, j = zoo.run_trace(trace)
    return index, trace.rig, j.category, {k: 100 * v for k, v in j.errors.items()}, j.reason


def main(argv=None):
    a = zoo.map_arguments(__doc__, show_ok=True).parse_args(argv)
    jobs = [(a.seed, i) for i in range(a.n)]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(a.n, a.seed, "12- or 14-bit ADC, noise 0.05-2 mV, fs 20-200 kHz", [r[2] for r in rows]))
    for bits in (12, 14):
        cats = [r[2] for r in rows if r[1].adc_bits == bits]
        print(f"  {bits} bits: " + ", ".join(f"{k} {cats.count(k)}" for k in zoo.CATEGORIES if cats.count(k)))
    for band, counts in zoo.band_counts([r[1].noise_V / step_V(r[1]) for r in rows], [r[2] for r in rows],
                                        NOISE_OVER_STEP_BANDS):
        print(f"  noise / step {band:>9}: {counts}")
    for index, rig, cat, err, reason in rows:
        if cat in ("ok_wrong", "faulty_ok") or (a.show_ok and cat.startswith("ok") and abs(err["tc"]) > 0.5):
            plate = "ideal plate" if rig.plate_hz is None else f"plate {rig.plate_hz / 1e3:.1f} kHz"
            print(f"  {cat} {a.seed}:{index}: {rig.ball} {rig.vin_m_s:.1f} m/s, fs {rig.sample_rate_hz / 1e3:.1f} kHz, "
                  f"{rig.adc_bits} bits (step {1e3 * step_V(rig):.2f} mV), noise {1e3 * rig.noise_V:.3f} mV, "
                  f"peak {rig.peak_volts:.2f} V, {plate}: "
                  f"TC {err['tc']:+.2f} %, kCAL {err['kcal']:+.2f} %, peak {err['peak']:+.2f} %")


if __name__ == "__main__":
    main()
