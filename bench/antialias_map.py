"""What stating the DAQ's anti-aliasing filter (daq.bandwidth_hz) changes, on rigs that have one (issue 9).

    python bench/antialias_map.py --n 400 --seed 1     # fs 20-100 kHz, a sigma-delta ADC's filter at 0.40-0.45 fs

The zoo's DAQ has no anti-aliasing filter, so it can state a bandwidth only for a resonant plate, and most of the
traces whose peak alone is in doubt are ideal plates (docs/robustness.md). A sigma-delta ADC, the usual DAQ of a
force platform today, filters before it decimates: linear phase, flat to about 0.45 fs, 100 dB down from 0.55 fs.
Its rigs are what ``daq.bandwidth_hz`` is for. Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig
(``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s, noise 0.1-0.5 % of the peak, an ideal plate)
with a sample rate of 20-100 kHz (log-uniform) and such a filter (``zoo.Rig.antialias_hz``) with its cut-off at
0.40-0.45 fs (uniform). Each trace is run twice: without the key (aliasing not ruled out: a problem of the peak
alone excludes the impact) and with ``daq.bandwidth_hz`` the filter's cut-off (the peak withheld instead). Prints
the categories of both, the traces ok with the peak withheld (their TC and kCAL judged), and every ok but wrong.
The truth is the ball's force: a filter smooths the pre-buckling spike's top, which a withheld peak does not
report and an ok peak must still match.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
CUTOFF_FS = (0.40, 0.45)  # the filter's cut-off [fraction of fs]


def rig_for(seed: int, index: int):
    """The rig of one map trace and the generator to render it with."""
    rng = np.random.default_rng([seed, index, 91])
    fs = zoo._loguniform(rng, 20e3, 100e3)
    cutoff = float(rng.uniform(*CUTOFF_FS)) * fs
    shot = zoo.map_shot(rng)
    fields = dict(zoo._BENIGN, ball=BALLS[index % 4], mode="sample_rate", sample_rate_hz=fs, antialias_hz=cutoff,
                  **shot)
    return zoo.Rig(**fields), rng


def trace_for(seed: int, index: int) -> zoo.ZooTrace:
    """One map trace, rendered."""
    rig, rng = rig_for(seed, index)
    return zoo.render(rig, rng, f"antialias {seed}:{index}")


def run_one(args):
    seed, index = args
    trace = trace_for(seed, index)
    out = []
    for extra in (None, {"bandwidth_hz": trace.rig.antialias_hz}):
        result, j = zoo.run_trace(trace, daq_extra=extra)
        out.append((j.category, {k: 100 * v for k, v in j.errors.items()}, result.reason, result.peak_note))
    return index, trace.rig, trace.truth.peak_is_spike, out


def main(argv=None):
    a = zoo.map_arguments(__doc__).parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i) for i in range(a.n)], a.workers)
    what = f"fs 20-100 kHz, anti-aliasing filter at {CUTOFF_FS[0]:g}-{CUTOFF_FS[1]:g} fs"
    for k, name in enumerate(("daq.bandwidth_hz absent", "daq.bandwidth_hz = the filter's cut-off")):
        print(zoo.category_summary(a.n, a.seed, f"{what}, {name}", [r[3][k][0] for r in rows]))
        withheld = [r for r in rows if r[3][k][3]]
        if withheld:
            heads = Counter(r[3][k][3].split(":")[0] for r in withheld)
            tc = max(abs(r[3][k][1]["tc"]) for r in withheld)
            kcal = max(abs(r[3][k][1]["kcal"]) for r in withheld)
            print(f"  ok with the peak withheld: {len(withheld)} ({dict(heads)}); TC within {tc:.2f} %, "
                  f"kCAL within {kcal:.2f} %")
        print(zoo.first_reasons([r[3][k][0] for r in rows], [r[3][k][2] for r in rows]))
        excluded = [r[3][k][1] for r in rows if r[3][k][0] == "excluded_measurable"]
        right = sum(abs(e["tc"]) <= 100 * zoo.TOL_TC and abs(e["kcal"]) <= 100 * zoo.TOL_KCAL for e in excluded)
        print(f"  of the {len(excluded)} measurable excluded, {right} had TC and kCAL within 1 % all the same")
    for index, rig, spike, out in rows:
        for k, (cat, err, reason, note) in enumerate(out):
            if cat in ("ok_wrong", "faulty_ok"):
                print(f"  {cat} {a.seed}:{index} ({'key' if k else 'no key'}): {rig.ball} {rig.vin_m_s:.1f} m/s, "
                      f"fs {rig.sample_rate_hz / 1e3:.1f} kHz, filter {rig.antialias_hz / 1e3:.1f} kHz"
                      f"{', peak = spike' if spike else ''}: TC {err['tc']:+.2f} %, kCAL {err['kcal']:+.2f} %, "
                      f"peak {err['peak']:+.2f} %")


if __name__ == "__main__":
    main()
