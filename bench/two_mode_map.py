"""Where a plate with two modes passes a wrong number: a second resonance beside the first (issue 9).

    python bench/two_mode_map.py --n 400 --seed 1

A force platform has more than one mode: the plate bouncing on its sensors, and above it the plate's bending and
rocking, excited the more the farther from the centre the ball lands. The zoo's plate has one (a second-order
response), and the pipeline identifies and undoes one. Here the sensed force is a modal sum of two: the first at
3 kHz to 0.45 fs / 1.3 (log-uniform), the second 1.3-4 times higher (at most 0.45 fs: no aliasing, the zoo's
aliased plates are a class of their own), each damped 0.01-0.3, the second's residue (its share of the static
gain, the first's being 1 less it) of either sign, 3-50 % in size (log-uniform). Apart from the zoo's seeds: each
rig is tests/zoo.py's benign rig (``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s, white noise
of 0.1-0.5 % of the peak) at 20-200 kHz, with a pre-trigger of 1-100 ms and a record of 5 ms to 1 s after the
contact (log-uniform, as the zoo draws them), the amplifier's time constant drawn from 0.01-100 s (log-uniform)
and given in session.yaml for half of them. A second mode is not the ball's force and the trace stays measurable
(a mode below 3 kHz would make it marginal, as the zoo's plates do): an ok must be right. Rendered and judged as
the zoo's traces are (``zoo.run_trace``). Prints the categories by the second mode's residue, the first reasons
of the exclusions, and the ok-but-wrong traces; ``--one-mode`` runs the same rigs and shots with the first mode
alone, to tell what the second costs.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
RESIDUE_BANDS = (0.1, 0.3)  # bands of the second mode's residue, in size [-]


def rig_for(seed: int, index: int, second_mode: bool = True) -> tuple[zoo.Rig, np.random.Generator]:
    """One map rig and the generator to render it with; without ``second_mode`` the same rig with its first mode
    alone (the second still drawn, not used)."""
    rng = np.random.default_rng([seed, index, 2203])
    fs = zoo._loguniform(rng, 20e3, 200e3)
    fn1 = zoo._loguniform(rng, 3e3, min(30e3, 0.45 * fs) / 1.3)
    fn2 = min(fn1 * float(rng.uniform(1.3, 4.0)), 0.45 * fs)
    zeta1, zeta2 = (float(z) for z in rng.uniform(0.01, 0.3, 2))
    residue = float(rng.choice([-1.0, 1.0])) * zoo._loguniform(rng, 0.03, 0.5)
    pre = zoo._loguniform(rng, 1e-3, 0.1)
    post = zoo._loguniform(rng, 5e-3, 1.0)
    tau = zoo._loguniform(rng, 0.01, 100.0)
    known = bool(rng.uniform() < 0.5)
    shot = zoo.map_shot(rng)
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="two modes", sample_rate_hz=fs, pre_s=pre,
                         post_s=post, tau_s=tau, tau_known=known, plate_hz=fn1, plate_zeta=zeta1, **shot))
    if second_mode:
        rig = dataclasses.replace(rig, plate_modes=((fn2, zeta2, residue),))
    return rig, rng


def second_of(rig: zoo.Rig) -> str:
    """The second mode, for a line of output."""
    if not rig.plate_modes:
        return "first mode alone"
    fn2, zeta2, residue = rig.plate_modes[0]
    return f"second mode {fn2 / 1e3:.1f} kHz damping {zeta2:.3f} residue {residue:+.3f}"


def run_one(args):
    seed, index, second_mode = args
    rig, rng = rig_for(seed, index, second_mode)
    result, j = zoo.run_trace(zoo.render(rig, rng, f"two modes {seed}:{index}"))
    residue = abs(rig.plate_modes[0][2]) if rig.plate_modes else 0.0
    return index, rig, residue, j.category, {k: 100 * v for k, v in j.errors.items()}, result.reason


def main(argv=None):
    ap = zoo.map_arguments(__doc__)
    ap.add_argument("--one-mode", action="store_true", help="the same rigs with the first mode alone, to compare")
    a = ap.parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i, not a.one_mode) for i in range(a.n)], a.workers)
    what = "first mode alone" if a.one_mode else "two modes, the second's residue 3-50 %"
    print(zoo.category_summary(a.n, a.seed, f"{what}, fs 20-200 kHz", [r[3] for r in rows]))
    if not a.one_mode:
        for band, counts in zoo.band_counts([r[2] for r in rows], [r[3] for r in rows], RESIDUE_BANDS):
            print(f"  residue {band:>10}: {counts}")
    print(zoo.first_reasons([r[3] for r in rows], [r[-1] for r in rows]))
    for index, rig, _, cat, err, _ in rows:
        if cat in ("ok_wrong", "faulty_ok"):
            print(zoo.map_offender(cat, a.seed, index, rig, f"damping {rig.plate_zeta:.3f}, {second_of(rig)}", err))


if __name__ == "__main__":
    main()
