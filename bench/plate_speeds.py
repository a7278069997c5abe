"""Speeds at the plate: how much the gate-to-plate correction matters, and how well it is recovered.

    python bench/plate_speeds.py            # gates 0.25 m from the plate, 0.1 m apart
    python bench/plate_speeds.py --json

1. The correction itself (ballimpact.flight.plate_speeds) for a 57.7 g, 65.4 mm ball
   in air of 1.2 kg/m^3 (Cd 0.55): vin, vout and COR at the plate over at the gates,
   horizontal and vertical rig, at 5-40 m/s (COR 0.6).
2. Synthetic sessions made with drag between the gates and the plate (ballimpact synth,
   flight_drag, 4-30 m/s, ball 1 of Table 2, 10 impacts, seeds 1-3): the largest COR
   error against the truth at the plate, with the correction and without it (the same
   files read without gates.distance_to_plate_m).
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from ballimpact.balls import BALLS
from ballimpact.flight import drag_constant, plate_speeds
from ballimpact.processing import iter_process
from ballimpact.session import read_session
from ballimpact.synth import SensorChain, SynthConfig, write_session

SPACING_M, DISTANCE_M = 0.1, 0.25


def correction_table():
    k = drag_constant(0.0577)
    rows = []
    for orientation in ("horizontal", "vertical"):
        for v in (5.0, 10.0, 20.0, 30.0, 40.0):
            vin, vout = plate_speeds(v, 0.6 * v, SPACING_M, DISTANCE_M, k, orientation=orientation)
            rows.append({"orientation": orientation, "vin_gate_m_s": v, "vin_ratio": vin / v,
                         "vout_ratio": vout / (0.6 * v), "cor_ratio": (vout / vin) / 0.6})
    return k, rows


def recovery(seeds=(1, 2, 3)):
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for orientation in ("horizontal", "vertical"):
            for seed in seeds:
                root = Path(tmp) / f"{orientation}{seed}"
                config = SynthConfig(
                    session_id="drag", seed=seed, balls={"pressurised": BALLS["pressurised"].params},
                    impacts_per_ball=10, faults_per_kind=0, vin_range_m_s=(4.0, 30.0), flight_drag=True,
                    rig_orientation=orientation, chain=SensorChain(gate_to_plate_m=DISTANCE_M),
                )
                session_dir, truth_csv = write_session(root / "drag", config)
                truth = pd.read_csv(truth_csv).set_index("impact_id")
                plain = root / "plain" / "drag"
                shutil.copytree(session_dir, plain)
                doc = yaml.safe_load((plain / "session.yaml").read_text())
                del doc["gates"]["distance_to_plate_m"]
                (plain / "session.yaml").write_text(yaml.safe_dump(doc))
                for label, folder in (("corrected", session_dir), ("gate speeds", plain)):
                    res = [r for r in iter_process(read_session(folder)) if r.status == "ok"]
                    err = np.array([r.cor - truth.loc[r.impact_id, "cor"] for r in res])
                    out.append({"orientation": orientation, "seed": seed, "speeds": label, "n_ok": len(res),
                                "max_abs_cor_error": float(np.max(np.abs(err))),
                                "mean_cor_error": float(np.mean(err))})
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    k, table = correction_table()
    rec = recovery()
    if args.json:
        print(json.dumps({"k_per_m": k, "correction": table, "recovery": rec}, indent=2))
        return
    print(f"drag constant k = {k:.5f} 1/m; gates {SPACING_M} m apart, gate 2 {DISTANCE_M} m from the plate")
    print(f"{'rig':>10} {'v gate':>7} {'vin plate/gate':>15} {'vout plate/gate':>16} {'COR plate/gate':>15}")
    for r in table:
        print(f"{r['orientation']:>10} {r['vin_gate_m_s']:7.1f} {r['vin_ratio']:15.4f} {r['vout_ratio']:16.4f} "
              f"{r['cor_ratio']:15.4f}")
    print("\nsynthetic sessions with drag (4-30 m/s): COR error against the truth at the plate")
    print(f"{'rig':>10} {'seed':>4} {'speeds':>12} {'ok':>3} {'max |error|':>12} {'mean error':>11}")
    for r in rec:
        print(f"{r['orientation']:>10} {r['seed']:4d} {r['speeds']:>12} {r['n_ok']:3d} "
              f"{r['max_abs_cor_error']:12.4f} {r['mean_cor_error']:+11.4f}")


if __name__ == "__main__":
    main()
