"""One rig of bench/overshoot_map.py fired as a session: the plate each shot undid, against the truth (issue 9).

    python bench/session_plate_probe.py --seed 5 --index 210 --shots 8

One plate serves a session, as one amplifier does, so the resonance each impact identifies and undoes should
agree between impacts; the archive now holds it per impact (``plate_resonance_hz``, ``plate_damping_ratio``).
This probe renders map rig SEED:INDEX (``overshoot_map.rig_for(seed, index, few=True)``: the map's first shot)
and SHOTS - 1 more shots on the same rig at 10-35 m/s, processes and judges each as the zoo's traces are
(``zoo.run_trace``), and prints per shot the category, the plate undone (frequency and damping ratio, and the
frequency's offset from the true plate) and the errors of TC, kCAL and the peak. A probe for a session plate
check, which is not built: it would need the identified resonance's uncertainty.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import dataclasses
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import overshoot_map  # noqa: E402
import zoo  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--index", type=int, default=210)
    ap.add_argument("--shots", type=int, default=8)
    a = ap.parse_args(argv)
    rig, rng = overshoot_map.rig_for(a.seed, a.index, True)
    more = np.random.default_rng([a.seed, a.index, 99])
    print(f"map rig {a.seed}:{a.index}: plate {rig.plate_hz / 1e3:.3f} kHz, damping {rig.plate_zeta:.3f}, "
          f"fs {rig.sample_rate_hz / 1e3:.1f} kHz, {rig.ball}")
    for k in range(a.shots):
        shot = rig if k == 0 else dataclasses.replace(rig, vin_m_s=float(more.uniform(10.0, 35.0)))
        result, j = zoo.run_trace(zoo.render(shot, rng if k == 0 else more, f"{a.seed}:{a.index}.{k}"))
        fn = result.plate_resonance_hz
        plate = ("no plate undone" if not math.isfinite(fn) else
                 f"plate {fn / 1e3:.3f} kHz ({100 * (fn / rig.plate_hz - 1):+.1f} %), "
                 f"damping {result.plate_damping_ratio:.3f}")
        errors = ", ".join(f"{name} {100 * e:+.2f} %" for name, e in j.errors.items())
        print(f"  shot {k} at {shot.vin_m_s:.1f} m/s: {j.category}; {plate}; {errors}")


if __name__ == "__main__":
    main()
