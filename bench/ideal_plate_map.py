"""Where an ideal plate's TC passes wrong: the model's forces on a benign rig with no resonance (issue 9).

    python bench/ideal_plate_map.py --n 400 --seed 1           # fs 20-60 kHz
    python bench/ideal_plate_map.py --n 400 --seed 1 --show-ok  # also every ok trace's end errors

Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig with an ideal plate (no resonance), a ball of
Table 2 (the four in turn, parameters within the zoo's +-20 %) at 10-35 m/s, a sample rate of 20-60 kHz
(log-uniform), white noise of 0.1-0.5 % of the peak and a random sample phase; it is rendered and judged as the
zoo's traces are (``zoo.run_trace``), and conditioned again (``condition_voltage``) for the contact's ends.
Prints the categories per sample-rate band, and for the ok-but-wrong traces
(and with --show-ok every ok trace with |TC err| above 0.5 %) which end is off, in per cent of the true TC, and
the end's flags (``end_curve``: the end from the force's curve; ``end_jump``: located to half a sample).
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

from ballimpact.signal.conditioning import condition_voltage  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
RATE_BANDS_KHZ = (20.0, 30.0, 40.0, 50.0, 60.0)
Z_OUTLIER = 5.0  # an end off by more than this many standard uncertainties is counted apart [-]


def rig_for(seed: int, index: int):
    """The rig of one map trace and the generator to render it with."""
    rng = np.random.default_rng([seed, index, 10])
    fs = zoo._loguniform(rng, 20e3, 60e3)
    shot = zoo.map_shot(rng)
    fields = dict(zoo._BENIGN, ball=BALLS[index % 4], mode="plate", sample_rate_hz=fs, plate_hz=None, **shot)
    return zoo.Rig(**fields), rng


def trace_for(seed: int, index: int) -> zoo.ZooTrace:
    """One map trace, rendered."""
    rig, rng = rig_for(seed, index)
    return zoo.render(rig, rng, f"ideal {seed}:{index}")


def run_one(args):
    seed, index = args
    trace = trace_for(seed, index)
    result, j = zoo.run_trace(trace)
    t = trace.truth
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rig = trace.rig
        c = condition_voltage(trace.voltage_V, trace.sample_rate_hz, polarity=rig.polarity, mains_hz=rig.mains_hz,
                              tau_s=rig.tau_s).contact  # as process_impact conditions it (tau and mains given)
    start_err = end_err = end_z = np.nan
    flags = ()
    if c.found:
        start_err = 100 * (c.start_s - t.start_s) / t.tc_s
        end_err = 100 * (c.end_s - t.end_s) / t.tc_s
        end_z = (c.end_s - t.end_s) / c.end_se_s if c.end_se_s > 0 else np.nan  # inf: not pinned, z 0
        flags = c.flags
    return (index, trace.rig, j.category, 100 * j.errors["tc"], start_err, end_err, flags, j.reason, end_z)


def main(argv=None):
    a = zoo.map_arguments(__doc__, show_ok=True).parse_args(argv)
    jobs = [(a.seed, i) for i in range(a.n)]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(a.n, a.seed, "ideal plate, fs 20-60 kHz", [r[2] for r in rows]))
    for band, counts in zoo.band_counts([r[1].sample_rate_hz / 1e3 for r in rows], [r[2] for r in rows],
                                        RATE_BANDS_KHZ):
        print(f"  fs {band:>5} kHz: {counts}")
    # the end's bias and the honesty of its uncertainty, over the ends that are not jumps (a jump's is half a sample)
    ends = [r for r in rows if np.isfinite(r[5]) and "end_jump" not in r[6]]
    err = np.array([r[5] for r in ends])
    zr = [(r[1], r[8]) for r in ends if np.isfinite(r[8]) and r[8] != 0.0]  # (rig, z) where the end is pinned
    z = np.array([zz for _, zz in zr])
    if err.size and z.size:
        print(f"  ends not jumps: {err.size}, error {np.mean(err):+.3f} % of TC on average (standard deviation "
              f"{np.std(err):.3f} %); z = error / end_se_s over the {z.size} with a finite uncertainty: mean "
              f"{np.mean(z):+.2f}, RMS {np.sqrt(np.mean(z * z)):.2f}, abs(z) > 2: {np.count_nonzero(np.abs(z) > 2)}")
        # by ball and by rate band, over the ends off by at most Z_OUTLIER uncertainties (a few ends far off, all
        # excluded, would hide how honest the rest are: count them apart)
        far = sum(abs(zz) > Z_OUTLIER for _, zz in zr)
        groups = {}
        for rig, zz in zr:
            if abs(zz) <= Z_OUTLIER:
                k = min(max(int(np.searchsorted(RATE_BANDS_KHZ, rig.sample_rate_hz / 1e3, side="right")), 1),
                        len(RATE_BANDS_KHZ) - 1)
                groups.setdefault(rig.ball, []).append(zz)
                groups.setdefault(f"fs {RATE_BANDS_KHZ[k - 1]:g}-{RATE_BANDS_KHZ[k]:g} kHz", []).append(zz)
        print(f"  RMS of z with abs(z) <= {Z_OUTLIER:g} ({far} beyond): "
              + ", ".join(f"{k} {np.sqrt(np.mean(np.square(v))):.2f} ({len(v)})" for k, v in sorted(groups.items())))
    for index, rig, cat, tc, se, ee, flags, reason, _ in rows:
        if cat == "ok_wrong" or (a.show_ok and cat.startswith("ok") and abs(tc) > 0.5):
            print(f"  {cat} {a.seed}:{index}: {rig.ball} {rig.vin_m_s:.1f} m/s, fs {rig.sample_rate_hz / 1e3:.1f} kHz, "
                  f"noise {100 * rig.noise_V / rig.peak_volts:.2f} % of the peak: TC {tc:+.2f} % (start {se:+.2f} %, "
                  f"end {ee:+.2f} %), flags {' '.join(f for f in flags if f.startswith(('end', 'start', 'cloth')))}")


if __name__ == "__main__":
    main()
