"""How often the session's identified plate interval holds the true plate, on sessions kept by bench/rigs.py.

    python bench/rigs.py --n 200 --seed 9 --keep /tmp/r9
    python bench/plate_intervals.py /tmp/r9

For every session of the folder whose archive (``results/<id>/<id>.nc``) identified the plate's resonance and
damping ratio (``rig_source`` "identified"), and whose rig had a plate (``raw/<id>.truth.yaml``), compares the
identified value with the truth: the error over the interval's half-width (the larger side), for fn and for the
damping ratio. Prints the share of sessions whose error is within one and within two half-widths, and the
sessions beyond two.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import xarray as xr
import yaml


def session_rows(folder: Path):
    """(session id, quantity, value, half-width, true value) of every identified plate quantity."""
    for archive in sorted((folder / "results").glob("*/*.nc")):
        sid = archive.stem
        truth_file = folder / "raw" / f"{sid}.truth.yaml"
        if archive.parent.name != sid or not truth_file.exists():
            continue
        truth = yaml.safe_load(truth_file.read_text(encoding="utf-8"))
        if truth.get("plate_hz") is None:
            continue
        with xr.open_dataset(archive) as ds:
            names = [str(q) for q in ds["rig_quantity"].values]
            for q, true in (("plate_resonance_hz", truth["plate_hz"]), ("plate_damping_ratio", truth["plate_zeta"])):
                k = names.index(q)
                if str(ds["rig_source"].values[k]) != "identified":
                    continue
                value, low, high = (float(ds[v].values[k]) for v in ("rig_value", "rig_low", "rig_high"))
                yield sid, q, value, max(high - value, value - low), float(true)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="a --keep folder of bench/rigs.py (raw/ and results/)")
    args = parser.parse_args(argv)
    rows = list(session_rows(args.folder))
    if not rows:
        print(f"no session with an identified plate in {args.folder}", file=sys.stderr)
        return 1
    for q in ("plate_resonance_hz", "plate_damping_ratio"):
        ratio = np.array([abs(v - t) / h if h > 0 else np.inf for _, qq, v, h, t in rows if qq == q])
        beyond = [f"{sid} ({abs(v - t) / h:.2g})" for sid, qq, v, h, t in rows if qq == q and abs(v - t) > 2 * h]
        print(f"{q}: {ratio.size} sessions; truth within the interval {100 * np.mean(ratio <= 1):.0f} %, "
              f"within twice it {100 * np.mean(ratio <= 2):.0f} %; beyond twice: {', '.join(beyond) or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
