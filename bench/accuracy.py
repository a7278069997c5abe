"""Accuracy of the per-impact processing against the ground truth of a synthetic session.

    python bench/accuracy.py raw/demo-2004            # uses raw/demo-2004.truth.csv
    python bench/accuracy.py /tmp/s1 --json

Prints, over the good impacts, the mean and largest error of TC, kCAL, peak force,
COR, largest displacement and time to peak, and whether every planted fault was
excluded with the expected reason.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import json
from pathlib import Path

import pandas as pd

from ballimpact.processing import apply_calibration_check, iter_process
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
        out[col] = {"mean": float(err.mean()), "max_abs": float(err.abs().max()), "unit": unit}
    return out


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
        print(f"  {col:22s} error mean {e['mean']:+.4f} {e['unit']:2s}  largest {e['max_abs']:.4f} {e['unit']}")


if __name__ == "__main__":
    main()
