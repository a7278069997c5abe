"""Electrical spikes swept across the contact's front of zoo traces that are ok without them (issue 9).

    python bench/front_spike_sweep.py                  # 24 traces x 7 samples x 6 amplitudes = 1008 runs
    python bench/front_spike_sweep.py --csv out.csv    # one row per run, to compare two branches

Held-out zoo trace 33:674 was ok with a 1.5 V electrical spike on the second sample of the force's jump taken for
its peak (+32 %). Where the force's curve breaks (the jump from zero, the drop at buckling) a spike's second
differences have no isolated spike's shape, so ``conditioning.remove_spikes`` leaves it, and the zoo's spikes,
drawn anywhere in the record, seldom land there. This sweep puts one there on purpose: on each of TRACES (24 zoo
traces of seeds 1 and 2, ok and right on 8738d3e, drawn at random from them), one spike of AMPLITUDES times the
trace's peak voltage on each sample from OFFSETS (-1: the sample before the contact's first; 0: its first),
besides the trace's own spikes. Rendered and judged as the zoo's traces are (``zoo.run_trace``). Prints the
categories and every ok-but-wrong run.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import csv
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402

#: (seed, index) of zoo traces ok and right without a spike at their front (on 8738d3e).
TRACES = ((1, 5), (1, 342), (1, 365), (1, 388), (1, 467), (1, 587), (1, 647), (1, 1028), (1, 1212), (1, 1713),
          (1, 1765), (1, 1807), (2, 8), (2, 123), (2, 279), (2, 287), (2, 739), (2, 1053), (2, 1317), (2, 1441),
          (2, 1444), (2, 1723), (2, 1823), (2, 1847))
OFFSETS = range(-1, 6)  # the spike's sample from the contact's first [samples]
AMPLITUDES = (-1.0, -0.5, -0.15, 0.15, 0.5, 1.0)  # the spike's height over the trace's peak voltage [-]


def run_one(job):
    """One run: (seed, index, offset, amplitude, category, errors [%], reason)."""
    seed, index, offset, amplitude = job
    base = zoo.trace_for(seed, index)
    fs, n = base.sample_rate_hz, base.voltage_V.size
    k = min(max(int(math.ceil(base.truth.start_s * fs)) + offset, 0), n - 1)
    spikes = tuple(base.rig.spikes) + (((k + 0.5) / n, amplitude * base.rig.peak_volts),)
    trace = zoo.trace_for(seed, index, spikes=spikes)
    result, j = zoo.run_trace(trace)
    return seed, index, offset, amplitude, j.category, {q: 100 * v for q, v in j.errors.items()}, result.reason or ""


def main(argv=None):
    ap = zoo.map_arguments(__doc__)
    ap.add_argument("--csv", help="write one row per run here")
    a = ap.parse_args(argv)
    jobs = [(s, i, off, amp) for s, i in TRACES for off in OFFSETS for amp in AMPLITUDES]
    rows = zoo.map_rows(run_one, jobs, a.workers)
    print(zoo.category_summary(len(rows), 0, "24 zoo traces of seeds 1-2, a spike on each sample of the front",
                               [r[4] for r in rows]).replace("seed 0, ", ""))
    for seed, index, off, amp, cat, err, _ in rows:
        if cat in ("ok_wrong", "faulty_ok"):
            print(f"  {cat} {seed}:{index}, spike {amp:+g} x the peak on sample {off:+d}: TC {err['tc']:+.2f} %, "
                  f"kCAL {err['kcal']:+.2f} %, peak {err['peak']:+.1f} %")
    if a.csv:
        with open(a.csv, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["id", "offset", "amplitude", "category", "tc_err_pct", "kcal_err_pct", "peak_err_pct",
                        "reason"])
            for seed, index, off, amp, cat, err, reason in rows:
                w.writerow([f"{seed}:{index}", off, amp, cat, f"{err['tc']:.4f}", f"{err['kcal']:.4f}",
                            f"{err['peak']:.4f}", reason])


if __name__ == "__main__":
    main()
