"""Where a stage that saturates below the ADC's rails passes a wrong number: a flat top the ADC never sees (issue 9).

    python bench/saturation_map.py --n 400 --seed 1

The zoo clips at the ADC's rails only, and a sample at a rail is easy to see. A charge amplifier's output (or a
filter's, or a DAQ's input stage) saturates at its own level: set too sensitive, it holds its output there while
the force goes on rising, and the ADC records a flat top well inside its range. The impulse is then short (kCAL
high by up to tens of per cent) and the peak low, with TC about right. Apart from the zoo's seeds: each rig is
tests/zoo.py's benign rig (``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s, white noise of
0.1-0.5 % of the peak) at 20-200 kHz, with a pre-trigger of 1-100 ms and a record of 5 ms to 1 s after the
contact (log-uniform, as the zoo draws them), either polarity, three in ten on a plate of 3 kHz to 0.45 fs
(damping 0.01-0.3), the amplifier's time constant drawn from 0.01-100 s (log-uniform) and given in session.yaml
for half of them, mains hum of 0.5-30 mV (log-uniform; 50 or 60 Hz, given for half), and the amplifier's output
saturating at 50-95 % of the force's peak (offset and drift included; ``zoo.Rig.saturation_V``), the hum picked up
before it for half the rigs (cut with it) and after it for the others (riding on the flat top), with 0-100 % of
the noise's variance added after it by the DAQ. A trace it
cuts is faulty: ok is a failure whatever the numbers. Rendered and judged as the zoo's traces are
(``zoo.run_trace``). Prints the categories by the level of the cut, the first reasons of the exclusions, and
the faulty traces passed as ok. ``--margin`` instead runs the saturation test alone on the zoo's own traces (of
``--seed``, ``--n`` of them, the faulty left out) over their true contacts, and prints how close the largest of its
statistic comes to the threshold.
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
LEVEL_BANDS = (0.7, 0.85)  # bands of the saturation level [fraction of the peak]


def trace_for(seed: int, index: int):
    """One map trace: (ZooTrace, saturation level [fraction of the peak], DAQ noise share [-])."""
    rng = np.random.default_rng([seed, index, 5015])
    chain = zoo.map_chain(rng)
    polarity = 1 if rng.uniform() < 0.5 else -1
    level = float(rng.uniform(0.5, 0.95))
    daq = float(rng.uniform(0.0, 1.0))
    hum = zoo._loguniform(rng, 0.5e-3, 30e-3)
    mains = float(rng.choice([50.0, 60.0]))
    mains_known = bool(rng.uniform() < 0.5)
    hum_after = bool(rng.uniform() < 0.5)
    shot = zoo.map_shot(rng)
    offset = zoo._BENIGN["offset_V"]
    peak = zoo._BENIGN["peak_volts"]
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="saturation", **chain, polarity=polarity,
                         saturation_V=level * peak + polarity * offset, daq_noise_fraction=daq, hum_V=hum,
                         mains_hz=mains, mains_known=mains_known, hum_after_saturation=hum_after, **shot))
    return zoo.render(rig, rng, f"saturation {seed}:{index}"), level, daq


def run_one(args):
    seed, index = args
    trace, level, daq = trace_for(seed, index)
    result, j = zoo.run_trace(trace)
    return index, trace.rig, level, daq, j.category, {k: 100 * v for k, v in j.errors.items()}, result.reason


def margin_one(args):
    """The evidence of ``contact.detect_saturation`` on zoo trace (seed, index) over its true contact, the
    noise floored at the ADC step's error as the pipeline floors it; None for a faulty trace."""
    from ballimpact.signal.clipping import SATURATION_MIN_SAMPLES, detect_saturation
    from ballimpact.signal.noise import quantization_step

    seed, index = args
    trace = zoo.trace_for(seed, index)
    if trace.truth.fault:
        return None
    fs = trace.sample_rate_hz
    v = trace.rig.polarity * trace.voltage_V
    lo, hi = max(int(np.ceil(trace.truth.start_s * fs)), 0), min(int(trace.truth.end_s * fs), v.size - 1)
    sigma = max(trace.rig.noise_V, quantization_step(trace.voltage_V) / np.sqrt(12.0))
    x = v[lo:hi + 1]
    if x.size < SATURATION_MIN_SAMPLES:
        return None
    sat = detect_saturation(x, sigma)
    return trace.label, sat.saturated, sat.flat, sat.n_top, sat.n_below, sat.evidence


def margin(seed: int, n: int, workers: int) -> None:
    """How far the zoo's own traces (the faulty left out) stay from the saturation test's threshold."""
    from ballimpact.signal.clipping import SATURATION_MIN_SAMPLES, SATURATION_RATIO

    rows = [r for r in zoo.map_rows(margin_one, [(seed, i) for i in range(n)], workers) if r]
    judged = [r for r in rows if r[2] and r[3] >= SATURATION_MIN_SAMPLES]
    worst = sorted(judged, key=lambda r: r[5])[-5:]
    print(f"zoo seed {seed}, {len(rows)} traces not faulty: {sum(r[1] for r in rows)} saturated; {len(judged)} with a "
          f"top of {SATURATION_MIN_SAMPLES} or more samples within its noise, their bounded ratio at most "
          f"{max((r[5] for r in judged), default=float('nan')):.2f} (threshold {SATURATION_RATIO:g}): "
          + ", ".join(f"{r[0]} {r[3]}/{r[4]} -> {r[5]:.2f}" for r in reversed(worst)))


def main(argv=None):
    ap = zoo.map_arguments(__doc__)
    ap.add_argument("--margin", action="store_true", help="instead: the test's statistic on the zoo's own traces "
                    "of --seed (--n of them), its margin from the threshold")
    a = ap.parse_args(argv)
    if a.margin:
        margin(a.seed, a.n, a.workers)
        return
    rows = zoo.map_rows(run_one, [(a.seed, i) for i in range(a.n)], a.workers)
    hum = []
    for after in (False, True):
        cats = [r[4] for r in rows if r[1].hum_after_saturation == after]
        counts = zoo.category_summary(len(cats), a.seed, "", cats).split(": ", 1)[1]
        hum.append(f"  hum {'after' if after else 'before'} the saturating stage: {counts}")
    print("\n".join(zoo.map_report(
        rows, a.seed, "a stage saturating at 50-95 % of the peak, fs 20-200 kHz",
        [r[2] for r in rows], LEVEL_BANDS, lambda band: f"  saturating at {band:>10} of the peak",
        lambda r: f"saturating at {100 * r[2]:.0f} % of the peak, {100 * r[3]:.0f} % of the noise after it",
        scale=0.01, unit=" %", extra=hum)))


if __name__ == "__main__":
    main()
