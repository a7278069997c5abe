"""What limits the low-passed undone force on zoo traces whose plate undoing was refused as too noisy (issue 9).

    python bench/robustness.py --n 2000 --seed 0        # writes bench/out/robustness-s0-n2000.csv
    python bench/lowpass_limits.py bench/out/robustness-s0-n2000.csv [more CSVs]

For every measurable trace of the CSVs excluded with "the undone force is too
noisy ...; low-passed to ..." (the plate identified and undone, the exact force
too noisy, the low-passed ones refused), the conditioning is redone up to the
plate's undoing (lag 5, refined as ``conditioning._plate_undone`` does) and the
low-passed undone force is checked (``conditioning._undone_contact`` and the
peak guard ``conditioning._lowpass_hides_peak``) at every cutoff from fs / 2 down
in steps of sqrt(2) to the resonance, not only at those the processing tries.
Per trace it reports the reason most cutoffs fail on ("pass" when one passes
every check, with TC and peak errors against the zoo's truth), and prints the
tally, the traces' fs / fn and, for those limited by TC's uncertainty, the
samples across TC (below about 141, half a sample charged to each end's jump
alone is 1 % of TC).
"""

from __future__ import annotations

import argparse
import collections
import csv
import math
import re
import statistics
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402
from ballimpact.signal.baseline import (MAINS_CANDIDATES_HZ, MIN_QUIET_SAMPLES, POST_GUARD_S, PRE_GUARD_S,  # noqa: E402
                                       mains_frequencies, rough_trend)
from ballimpact.signal.contact import detect_contact  # noqa: E402
from ballimpact.signal.end_checks import curve_end_contact  # noqa: E402
from ballimpact.signal.spikes import remove_spikes  # noqa: E402
from ballimpact.signal.undone import PLATE_ID_AFTER_S, PLATE_REFINE_S, _undone_contact  # noqa: E402
from ballimpact.signal.undone_peak import lowpass_hides_peak  # noqa: E402
from ballimpact.signal.window import iterate  # noqa: E402
from ballimpact.signal.plate import identify_plate_resonance, refine_plate_resonance  # noqa: E402
from ballimpact.signal.undo import lowpass_zero_phase, undo_plate_resonance  # noqa: E402
from ballimpact.processing import HUM_HARMONICS  # noqa: E402

REFUSED = re.compile(r"not undone: the undone force is too noisy \(noise [\d.]+ % of the peak\); low-passed to")
KINDS = [("TC is known", "TC known to more than 1 %"), ("end not determined", "end not determined"),
         ("start not determined", "start not determined"), ("lowers the peak by about", "low-pass's own peak loss"),
         ("plate ringing", "still rings"), ("keeps its peak", "peak guard: too noisy to show"),
         ("lowers the exact undone", "peak guard: a loss seen"), ("below zero", "force below zero"),
         ("single contact", "no single contact")]


def conditioned(trace):
    """The state of ``condition_voltage`` just before the plate's undoing: (corrected trace, fit, contact)."""
    rig, fs = trace.rig, trace.sample_rate_hz
    tau = rig.tau_s if (rig.tau_known and math.isfinite(rig.tau_s)) else None
    raw = trace.voltage_V
    scale = float(np.max(np.abs(raw)))
    v, _ = remove_spikes(rig.polarity * raw / scale)
    if rig.mains_known:
        candidates = {float(rig.mains_hz): mains_frequencies(rig.mains_hz, HUM_HARMONICS, fs)}
    else:
        candidates = {0.0: [], **{f: mains_frequencies(f, HUM_HARMONICS, fs) for f in MAINS_CANDIDATES_HZ}}
    trend = rough_trend(v)
    k_peak = int(np.argmax(v - trend))
    if k_peak >= MIN_QUIET_SAMPLES:
        trend = np.full(v.size, float(np.median(v[:k_peak])))
    rough = detect_contact(v - trend, fs)
    it = iterate(v, fs, candidates, rough, PRE_GUARD_S * fs, POST_GUARD_S * fs, tau,
                    None if tau is None else 1.0 / tau, scale)
    contact = curve_end_contact(detect_contact(it.x, fs, t0_s=0.0, noise_rms_V=it.fit.noise, spread=True,
                                                    curve=True), fs, 0.0)
    return it.x, it.fit, contact, 1.0 / (trace.truth.kcal_N_per_V * scale)


def limits(trace):
    """Per cutoff at or above the resonance: the reason the low-passed undone force fails, or "pass" (TC and peak
    errors [%]); None when the plate is not identified."""
    fs = trace.sample_rate_hz
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        x, fit, contact, unit = conditioned(trace)
    s_u, e_u = contact.start_s * fs, contact.end_s * fs
    a, b = int(math.ceil(s_u)) + 2, min(int(math.floor(e_u)) + int(round(PLATE_ID_AFTER_S * fs)), x.size)
    plate = identify_plate_resonance(x[a:b], fs, lag=5, noise_rms=fit.noise)
    if plate is None:
        return None
    plate = refine_plate_resonance(x[max(int(s_u - PLATE_REFINE_S[0] * fs), 0):
                                     min(int(e_u + PLATE_REFINE_S[1] * fs), x.size)], fs, plate)
    exact = undo_plate_resonance(x, fs, plate.frequency_hz, plate.damping_ratio)
    out, cutoff = [], 0.5 * fs
    while cutoff / math.sqrt(2.0) >= plate.frequency_hz:
        cutoff /= math.sqrt(2.0)
        c = _undone_contact(lowpass_zero_phase(exact, fs, cutoff), x, fs, fit, s_u, 0.0, cutoff, plate)
        if not isinstance(c, str):
            c = lowpass_hides_peak(exact, fs, fit.noise, plate, c[0], 0.0) or c
        if isinstance(c, str):
            if "too noisy (noise" not in c:
                out.append(next((name for key, name in KINDS if key in c), "other"))
        else:
            tc = (c[0].end_s - c[0].start_s) / trace.truth.tc_s - 1.0
            peak = c[0].peak_V / (trace.truth.peak_N * unit) - 1.0
            out.append(f"pass (TC {100 * tc:+.2f} %, peak {100 * peak:+.2f} %)")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv", nargs="+", help="per-trace CSVs of bench/robustness.py")
    args = ap.parse_args(argv)
    ids = [r["id"] for path in args.csv for r in csv.DictReader(open(path, encoding="utf-8"))
           if r["category"] == "excluded_measurable" and REFUSED.search(r["reason"])]
    tally, ratio, samples = collections.Counter(), collections.defaultdict(list), []
    for tid in ids:
        seed, index = (int(v) for v in tid.split(":"))
        trace = zoo.trace_for(seed, index)
        found = limits(trace)
        kinds = [k for k in (found or []) if not k.startswith("pass")]
        passes = [k for k in (found or []) if k.startswith("pass")]
        top = ("pass" if passes else collections.Counter(kinds).most_common(1)[0][0] if kinds
               else "no plate identified" if found is None else "no quiet cutoff at or above fn")
        tally[top] += 1
        ratio[top].append(trace.sample_rate_hz / trace.rig.plate_hz)
        if top == "TC known to more than 1 %":
            samples.append(trace.truth.tc_s * trace.sample_rate_hz)
        print(f"{tid}: {top}" + (f" {passes[0][4:]}" if passes else ""), flush=True)
    print(f"\n{len(ids)} traces refused as too noisy, then low-passed; what most cutoffs at or above fn fail on:")
    for kind, n in tally.most_common():
        print(f"  {n:4d}  {kind} (fs / fn median {statistics.median(ratio[kind]):.1f})")
    if samples:
        print(f"TC's uncertainty: {len(samples)} traces, median {statistics.median(samples):.0f} samples across TC, "
              f"{100 * sum(n < 141 for n in samples) / len(samples):.0f} % under 141")
    return 0


if __name__ == "__main__":
    sys.exit(main())
