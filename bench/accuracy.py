"""Accuracy of the per-impact processing against the ground truth of a synthetic session.

    python bench/accuracy.py raw/demo-2004            # uses raw/demo-2004.truth.csv
    python bench/accuracy.py /tmp/s1 --json

Prints, over the good impacts, the mean and largest error of TC, kCAL, peak force,
COR, largest displacement and time to peak, and whether every planted fault was
excluded with the expected reason. When the session's ``.truth.yaml`` names the sensor
chain's amplifier, also the error of the time constants estimated from the traces and
the RMS of (estimate - truth) / standard error, which is about 1 when the standard
errors the archive records are honest.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from ballimpact.processing import apply_calibration_check, apply_time_constant_check, iter_process
from ballimpact.session import read_session

QUANTITIES = {  # column: relative (True) or absolute (False) error
    "contact_time_ms": True,
    "kcal_N_per_V": True,
    "peak_force_N": True,
    "cor": False,
    "max_displacement_mm": True,
    "time_to_peak_ms": False,
}


def measure(session_dir: Path) -> dict:
    session = read_session(session_dir)
    results = list(iter_process(session))
    apply_time_constant_check(results)  # the session checks, in the pipeline's order (pipeline.collect_impacts)
    apply_calibration_check(results)
    table = pd.DataFrame([r.row() for r in results]).set_index("impact_id")
    truth = pd.read_csv(session_dir.parent / f"{session_dir.name}.truth.csv", keep_default_na=False)
    truth = truth.set_index("impact_id")
    faults = truth[truth.fault != ""]
    good = truth.index[truth.fault == ""]
    out = {
        "session": session_dir.name,
        "n_impacts": len(table),
        "n_good": int(len(good)),
        "good_excluded": sorted(i for i in good if table.loc[i, "status"] != "ok"),
        "faults_missed": sorted(
            i for i, t in faults.iterrows()
            if table.loc[i, "status"] != "excluded" or t.expected_reason not in table.loc[i, "reason"]
        ),
    }
    ok = [i for i in good if table.loc[i, "status"] == "ok"]
    for col, relative in QUANTITIES.items():
        err = table.loc[ok, col].astype(float) - truth.loc[ok, col].astype(float)
        if relative:
            err = 100 * err / truth.loc[ok, col].astype(float)
        unit = "%" if relative else ("ms" if col.endswith("_ms") else "")
        out[col] = {"mean": float(err.mean()), "rms": float(np.sqrt(np.mean(err**2))),
                    "max_abs": float(err.abs().max()), "unit": unit}
    out["time_constant"] = _time_constant(session_dir, [r for r in results if r.impact_id in set(ok)])
    return out


def _time_constant(session_dir: Path, good) -> dict | None:
    """Error [%] of the estimated amplifier time constants and their z-scores' RMS [-], or None."""
    truth_yaml = session_dir.parent / f"{session_dir.name}.truth.yaml"
    if not truth_yaml.is_file():
        return None
    chain = (yaml.safe_load(truth_yaml.read_text(encoding="utf-8")) or {}).get("sensor_chain", {})
    true_tau = chain.get("amplifier_time_constant_s")
    estimated = [r for r in good if r.tau_source == "estimated"]
    if true_tau is None or not estimated:
        return None
    tau = np.array([r.tau_s for r in estimated])
    z = (tau - true_tau) / np.array([r.tau_se_s for r in estimated])
    err = 100 * (tau - true_tau) / true_tau
    return {"true_s": float(true_tau), "n_estimated": len(estimated), "mean": float(err.mean()),
            "max_abs": float(np.abs(err).max()), "z_rms": float(np.sqrt(np.mean(z**2)))}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("session", type=Path)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    out = measure(args.session)
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(f"{out['session']}: {out['n_impacts']} impacts, {out['n_good']} good")
    print(f"  good impacts excluded: {out['good_excluded'] or 'none'}")
    print(f"  faults missed or with the wrong reason: {out['faults_missed'] or 'none'}")
    for col in QUANTITIES:
        e = out[col]
        print(f"  {col:22s} error mean {e['mean']:+.4f} {e['unit']:2s}  RMS {e['rms']:.4f} {e['unit']:2s}  "
              f"largest {e['max_abs']:.4f} {e['unit']}")
    tau = out["time_constant"]
    if tau is not None:
        print(f"  amplifier time constant ({tau['true_s']:g} s), estimated in {tau['n_estimated']}: error mean "
              f"{tau['mean']:+.2f} %, largest {tau['max_abs']:.2f} %; RMS of error / standard error {tau['z_rms']:.2f}")


if __name__ == "__main__":
    main()
