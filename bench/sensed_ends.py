"""The contact's ends fitted in the sensed force through a known plate, against the rig zoo's truth.

    python bench/sensed_ends.py --seed 1002 --rigs 80 --impacts 3
    python bench/sensed_ends.py --seed 1003 --rigs 80 --impacts 3 --zeta-scale 0.5

For every rig of ``bench/rigs.py``'s zoo with a plate, draws impacts as the zoo renders them, conditions each trace
without undoing the plate (``condition_voltage(..., undo_plate=False)``) and fits its contact's ends through the
rig's plate (``ballimpact.signal.sensed_ends.sensed_contact``), the resonance and damping ratio scaled by
``--fn-scale`` and ``--zeta-scale`` (a plate known wrong). A TC is kept when twice its standard uncertainty (the
ends' in quadrature and the fit's bound as a uniform) is within 1 %, as the verdicts keep it. Prints, over all
impacts and over those sampled at 60 kHz or more: fitted, kept, kept and right (within 1 % of the true TC), kept
but wrong, and the refusals by reason.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import warnings
from collections import Counter
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import rig_zoo  # noqa: E402
from ballimpact.signal.cloth import cloth_phase_s  # noqa: E402
from ballimpact.signal.conditioning import condition_voltage  # noqa: E402
from ballimpact.signal.sensed_ends import SensedContact, sensed_contact  # noqa: E402

TOLERANCE = 0.01  # TC's [-]


def rig_rows(task):
    """(relative TC error, expanded relative uncertainty, sample rate [Hz], refusal) per impact of one rig."""
    seed, index, n_impacts, fn_scale, zeta_scale = task
    warnings.simplefilter("ignore")
    rig = rig_zoo.draw_rig(seed, index)
    if rig.plate_hz is None:
        return []
    rng = np.random.default_rng([seed, index, 7])
    fs, out = rig.sample_rate_hz, []
    for k in range(n_impacts):
        ball, vin = rig.balls[k % len(rig.balls)], float(rng.uniform(10, 35))
        volts, truth = rig_zoo.render_impact(rig, ball, vin, "", f"i{k}", rng)
        cond = condition_voltage(volts, fs, polarity=rig.polarity, undo_plate=False)
        c = cond.contact
        if not c.found:
            out.append((math.nan, math.nan, fs, "no contact"))
            continue
        fit = sensed_contact(cond.voltage_V, fs, rig.plate_hz * fn_scale, rig.plate_zeta * zeta_scale,
                             c.start_s * fs, c.end_s * fs, noise_rms=cond.noise_rms_V,
                             cloth_phase_samples=cloth_phase_s(vin) * fs)
        if not isinstance(fit, SensedContact):
            out.append((math.nan, math.nan, fs, re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", fit)[:80]))
            continue
        tc_true = truth.contact_time_s * fs
        err = (fit.end - fit.start) / tc_true - 1.0
        expanded = 2.0 * math.sqrt(fit.start_se ** 2 + fit.end_se ** 2 + fit.bias ** 2 / 3.0) / tc_true
        out.append((err, expanded, fs, ""))
    return out


def _line(label, rows):
    err = np.array([r[0] for r in rows])
    u = np.array([r[1] for r in rows])
    kept = u <= TOLERANCE
    right = np.abs(err) <= TOLERANCE
    return (f"{label}: {len(rows)} impacts, fitted {int(np.isfinite(err).sum())}, kept {int(kept.sum())}, "
            f"kept and right {int((kept & right).sum())}, kept but wrong {int((kept & ~right).sum())}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1002, help="rig seed (develop on 1000 and above)")
    ap.add_argument("--rigs", type=int, default=80, help="rigs drawn; those with a plate are fitted")
    ap.add_argument("--impacts", type=int, default=3, help="impacts per rig")
    ap.add_argument("--fn-scale", type=float, default=1.0, help="the plate's resonance given times this")
    ap.add_argument("--zeta-scale", type=float, default=1.0, help="its damping ratio given times this")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    tasks = [(args.seed, i, args.impacts, args.fn_scale, args.zeta_scale) for i in range(args.rigs)]
    with Pool(args.jobs) as pool:
        rows = [r for rs in pool.map(rig_rows, tasks, chunksize=1) for r in rs]
    print(_line("all", rows))
    print(_line("fs >= 60 kHz", [r for r in rows if r[2] >= 60e3]))
    for reason, n in Counter(r[3] for r in rows if r[3]).most_common():
        print(f"  {n:4d}  {reason}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
