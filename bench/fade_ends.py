"""Is a zoo trace's contact end determined by its data, or was a right TC luck? (issue 9)

    python bench/fade_ends.py 1:636 3:315            # 20 other noise draws of each trace
    python bench/fade_ends.py 1:707 --draws 40

Each trace (tests/zoo.py, ``SEED:INDEX`` as in ``bench/robustness.py --replay``)
is rendered again from its rig with other noise, hum phases and sub-sample
placement (``zoo.render`` with a generator seeded [99, SEED, INDEX, draw]), and
conditioned as ``process_impact`` conditions it (``condition_voltage`` with the
rig's polarity, tau and mains when the session gives them). Printed per trace,
in per cent of the true TC: the conditioned contact's end against the truth
(mean and standard deviation over the draws), the same for the end from the
force's curve (``ContactResult.curve_end_s``), in how many draws the curve's
uncertainty is finite and twice it within 0.5 % of TC (what the conditioning
asks before it takes the curve's end), the largest error among those and how
many of them are off by more than 0.5 % of TC (half the 1 % budget), and in
how many draws the conditioning found no problem at all.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402

from ballimpact.signal.end_checks import SPREAD_MAX_FRACTION  # noqa: E402
from ballimpact.signal.conditioning import condition_voltage  # noqa: E402


def draws(seed: int, index: int, n: int) -> np.ndarray:
    """Per draw: end error, curve end error, curve uncertainty [% of TC], no problem (1/0)."""
    rig = zoo.trace_for(seed, index).rig
    out = []
    for j in range(n):
        trace = zoo.render(rig, np.random.default_rng([99, seed, index, j]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c = condition_voltage(trace.voltage_V, trace.sample_rate_hz, polarity=rig.polarity,
                                  mains_hz=rig.mains_hz if rig.mains_known else "auto",
                                  tau_s=rig.tau_s if rig.tau_known else None)
        t, ct = trace.truth, c.contact
        out.append((100 * (ct.end_s - t.end_s) / t.tc_s, 100 * (ct.curve_end_s - t.end_s) / t.tc_s,
                    100 * ct.curve_end_se_s / t.tc_s, float(not c.problems)))
    return np.array(out, dtype=float)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ids", nargs="+", metavar="SEED:INDEX")
    ap.add_argument("--draws", type=int, default=20)
    args = ap.parse_args(argv)
    print(f"{'trace':>8} {'ball':>12} {'fs kHz':>7} | end err mean sd | curve err mean sd | se finite | "
          "2 se <= 0.5 %: n, largest |err|, > 0.5 % | no problem")
    for sid in args.ids:
        seed, index = (int(s) for s in sid.split(":"))
        rig = zoo.trace_for(seed, index).rig
        a = draws(seed, index, args.draws)
        finite = np.isfinite(a[:, 2])
        kept = 2 * a[:, 2] <= 100 * SPREAD_MAX_FRACTION
        worst = f"{np.max(np.abs(a[kept, 1])):.2f}" if kept.any() else "-"
        off = int(np.sum(np.abs(a[kept, 1]) > 0.5))
        print(f"{sid:>8} {rig.ball:>12} {rig.sample_rate_hz / 1e3:7.1f} | {np.mean(a[:, 0]):+.2f} "
              f"{np.std(a[:, 0]):.2f} | {np.nanmean(a[:, 1]):+.2f} {np.nanstd(a[:, 1]):.2f} | "
              f"{finite.sum()}/{len(a)} | {kept.sum()}, {worst}, {off} | {int(a[:, 3].sum())}/{len(a)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
