"""Probe of a proposal: the contact's end fitted in the sensed force through a known plate, against the rig zoo.

    python bench/sensed_ends.py --seed 1002 --rigs 40 --impacts 6

Not used by the processing. Undoing a plate of 1-3 kHz amplifies the noise by (fs / 2 fn)^2, and the low-pass that
quiets it spreads the ends (docs/signal-processing.md); in the sensed force the noise is white. Near the end the
sensed force is the plate's free ringing (two terms from the window's start) plus its response to a line and a
parabola falling to zero at te, the plate's state continuous there: linear in its four coefficients for each te.
te is scanned on a grid of 0.25 sample within half a plate period of a guess (the truth moved by up to 0.4 of a
period either way), the window re-anchored at the best until it stays within a sample, then refined on 0.02 sample;
inside the contact the window holds 10 % of TC, after it 1.5 periods. The plate is the rig's true one (as if
stated), the trace conditioned without undoing it (``condition_voltage(..., undo_plate=False)``). Prints the end's
error [samples] against the truth, by rig and overall.
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import rig_zoo  # noqa: E402
from ballimpact.signal.conditioning import condition_voltage  # noqa: E402
from ballimpact.signal.front import front_responses  # noqa: E402


def end_columns(n, te, wn, zeta, lo):
    """Free ringing from ``lo`` and the responses to a line and a parabola ending at ``te`` [samples], per row."""
    u = n - te
    resp = front_responses(u, wn, zeta, 0.0)  # step, ramp, parabola from rest at te (0 before)
    c = 2 * zeta / wn
    p0, p1 = 2 * (4 * zeta * zeta - 1) / wn**2, -4 * zeta / wn
    wd, v = wn * math.sqrt(1 - zeta * zeta), n - lo
    decay = np.exp(-zeta * wn * v)
    return np.stack([decay * np.cos(wd * v), decay * np.sin(wd * v), -(u - c) + resp[:, 1],
                     (u * u + p1 * u + p0) - resp[:, 2]], axis=1)


def _rss(x, lo, hi, grid, wn, zeta):
    n = np.arange(lo, hi, dtype=float)
    a = np.stack([end_columns(n, g, wn, zeta, lo) for g in grid])
    coef = np.linalg.solve(np.einsum("gmp,gmq->gpq", a, a) + 1e-12 * np.eye(4),
                           np.einsum("gmp,m->gp", a, x[lo:hi])[..., None])[..., 0]
    r = x[lo:hi][None] - np.einsum("gmp,gp->gm", a, coef)
    return np.einsum("gm,gm->g", r, r)


def fit_end(x, fs, fn, zeta, guess, inside, outside, reach):
    """The end [samples, fractional index] of a force falling to zero, fitted through the plate (see the module)."""
    wn = 2 * math.pi * fn / fs
    centre = guess
    for it in range(4):
        lo, hi = int(math.floor(centre - inside)), int(math.ceil(centre + outside))
        grid = np.arange(centre - reach, centre + reach + 1e-9, 0.25)
        best = grid[int(np.argmin(_rss(x, lo, hi, grid, wn, zeta)))]
        done = it > 0 and abs(best - centre) <= 1.0
        centre, reach = best, 1.5
        if done:
            break
    lo, hi = int(math.floor(centre - inside)), int(math.ceil(centre + outside))
    fine = np.arange(centre - 1.0, centre + 1.0 + 1e-9, 0.02)
    return float(fine[int(np.argmin(_rss(x, lo, hi, fine, wn, zeta)))])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1002, help="rig seed (develop on 1000 and above)")
    ap.add_argument("--rigs", type=int, default=40, help="rigs drawn; those with a plate are probed")
    ap.add_argument("--impacts", type=int, default=6, help="impacts per rig")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    errors = []
    for index in range(args.rigs):
        rig = rig_zoo.draw_rig(args.seed, index)
        if rig.plate_hz is None:
            continue
        rng, jitter = np.random.default_rng([args.seed, index, 7]), np.random.default_rng(index)
        fs, ball_errors = rig.sample_rate_hz, []
        for k in range(args.impacts):
            ball, vin = rig.balls[k % len(rig.balls)], float(rng.uniform(10, 35))
            peek = copy.deepcopy(rng)
            peek.standard_normal()
            sub = peek.uniform(0.0, 1.0)  # the trace's sub-sample offset, drawn next by render_impact
            volts, truth = rig_zoo.render_impact(rig, ball, vin, "", f"i{k}", rng)
            x = condition_voltage(volts, fs, polarity=rig.polarity, undo_plate=False).voltage_V
            tc_u, period = truth.contact_time_s * fs, fs / rig.plate_hz
            end = math.floor(rig.pre_s * fs) + sub + tc_u
            guess = end + jitter.uniform(-0.4, 0.4) * period
            te = fit_end(x, fs, rig.plate_hz, rig.plate_zeta, guess, max(int(0.1 * tc_u), 4),
                         max(int(1.5 * period), 8), max(0.5 * period, 6.0))
            ball_errors.append(te - end)
        errors += ball_errors
        print(f"rig {args.seed}:{index:03d} fs {fs / 1e3:5.1f} kHz plate {rig.plate_hz / 1e3:5.2f} kHz "
              f"zeta {rig.plate_zeta:.3f} {'AA' if rig.antialias_hz else 'no AA'}: end error "
              + " ".join(f"{e:+.2f}" for e in ball_errors))
    e = np.array(errors)
    q = np.percentile(e, [5, 25, 50, 75, 95])
    print(f"\n{e.size} ends: error [samples] 5/25/50/75/95 % {' '.join(f'{v:+.2f}' for v in q)}; "
          f"|error| > 1 sample {int(np.sum(np.abs(e) > 1))}, > 3 samples {int(np.sum(np.abs(e) > 3))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
