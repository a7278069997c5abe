"""Sessions of one rig: what the session time-constant check catches and what it costs (issue 9).

    python bench/session_tau_map.py --n 100 --seed 1

The zoo and the other maps run one-impact sessions, which the session checks never see. Here each session is
one rig of the zoo (``zoo.trace_for(seed, index).rig``: every factor drawn from its whole range; the time constant
not given in session.yaml, which is where the check works) fired SHOTS times at 10-35 m/s (a new shot, noise and
hum phase each time), and STEPPED of the shots get a step of the recorded level within the contact (0.5-5 % of the
peak either way, at
0.3-0.95 of TC: a DAQ's offset changing, which with the decay estimated is what the amplifier's undershoot looks
like to one trace). Each shot is processed and judged as the zoo's are (``zoo.run_trace``); then
``processing.apply_time_constant_check`` runs on the session, as ``pipeline.collect_impacts`` does. Prints, before
and after the check, the ok-but-wrong shots with a step and without one, and what the check excluded: shots with
a step (caught) and without one (the check's cost: ok and right shots, or ok but wrong ones it also caught).
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
from ballimpact.processing import apply_time_constant_check  # noqa: E402

SHOTS = 8  # shots per session [-]
STEPPED = 2  # of them with a step within the contact [-]


def session_for(seed: int, index: int):
    """The shots of session ``index``: [(ZooTrace, stepped)], the first STEPPED with a step."""
    rig = dataclasses.replace(zoo.trace_for(seed, index).rig, tau_known=False)  # the check's domain
    rng = np.random.default_rng([seed, index, 4242])
    shots = []
    for k in range(SHOTS):
        trace = zoo.render(dataclasses.replace(rig, vin_m_s=float(rng.uniform(10.0, 35.0))), rng, f"{index}.{k}")
        if k < STEPPED:
            t = trace.truth
            fs = rig.sample_rate_hz
            height = float(rng.choice([-1, 1])) * zoo._loguniform(rng, 0.005, 0.05) * t.peak_N / t.kcal_N_per_V
            at = t.start_s + float(rng.uniform(0.3, 0.95)) * t.tc_s
            v = trace.voltage_V.copy()
            v[int(np.ceil(at * fs)):] += height
            trace = dataclasses.replace(trace, voltage_V=v)
        shots.append((trace, k < STEPPED))
    return rig, shots


def run_one(args):
    seed, index = args
    rig, shots = session_for(seed, index)
    runs = [(zoo.run_trace(trace), stepped) for trace, stepped in shots]
    results = [r for (r, _), _ in runs]
    before = [j.category for (_, j), _ in runs]
    apply_time_constant_check(results)
    caught = [r.status == "excluded" and c.startswith("ok_") for r, c in zip(results, before)]
    return index, rig, [(c, s, k) for c, (_, s), k in zip(before, runs, caught)]


def main(argv=None):
    a = zoo.map_arguments(__doc__, n=100).parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i) for i in range(a.n)], a.workers)
    shots = [(c, s, k) for _, _, per in rows for c, s, k in per]

    def count(pred):
        return sum(1 for c, s, k in shots if pred(c, s, k))

    print(f"{a.n} sessions of {SHOTS} shots (seed {a.seed}; {STEPPED} with a step within the contact each; the "
          "time constant estimated)")
    for stepped in (True, False):
        what = "with a step" if stepped else "without one"
        print(f"  shots {what}: ok but wrong {count(lambda c, s, k: s == stepped and c == 'ok_wrong')} before the "
              f"check, {count(lambda c, s, k: s == stepped and c == 'ok_wrong' and not k)} after; ok and right "
              f"{count(lambda c, s, k: s == stepped and c == 'ok_right')}, of them excluded by the check "
              f"{count(lambda c, s, k: s == stepped and c == 'ok_right' and k)}")
    for index, rig, per in rows:
        for n, (c, s, k) in enumerate(per):
            if k and not s or c == "ok_wrong" and not k:
                print(f"  {'excluded' if k else 'left ok'} {a.seed}:{index}.{n} ({'step' if s else 'no step'}, {c}): "
                      f"fs {rig.sample_rate_hz / 1e3:.1f} kHz, tau {rig.tau_s:.3g} s "
                      f"{'given' if rig.tau_known else 'estimated'}, pre {1e3 * rig.pre_s:.1f} ms, "
                      f"post {1e3 * rig.post_s:.1f} ms")


if __name__ == "__main__":
    main()
