"""Compare two results trees (e.g. `make run` before and after a change): CSV, netCDF and JSON to 1e-9.

Usage::

    python bench/compare_outputs.py A B          # A, B: results folders

* every ``*.csv``: same columns in the same order and the same rows; numeric columns
  equal to ``rtol`` 1e-9 (``atol`` 1e-12, NaN equals NaN), text columns exactly;
* every ``*.nc``: same dimensions, variables, variable attributes and global
  attributes; numeric values to ``rtol`` 1e-9, text exactly; the global attributes
  that hold the time of the run (``history``, ``date_created``, ``date_modified``,
  ``date_issued``, ``date_metadata_modified``) are not compared;
* every ``*.json``: same structure, numbers to ``rtol`` 1e-9, text exactly;
* ``*.png`` and ``*.pdf`` are listed when present on both sides but NOT compared:
  matplotlib output is not bitwise reproducible (a PDF holds its creation time);
* ``logs/`` and ``benchmarks/`` folders and dot files (Snakemake timestamps) are
  skipped: they hold run times.

A file present on one side only is a difference. Exit status 0 when the trees agree,
1 on any difference (each one printed), 2 on a usage error.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

RTOL = 1e-9  # relative tolerance of every number [-]
ATOL = 1e-12  # absolute tolerance, for values that should be 0 [unit of the value]
SKIPPED_DIRS = ("logs", "benchmarks")
#: Global netCDF attributes that hold the time of the run.
TIME_ATTRS = ("history", "date_created", "date_modified", "date_issued", "date_metadata_modified")
IMAGE_SUFFIXES = (".png", ".pdf")


def files_of(root: Path) -> set[str]:
    """Relative paths of the files compared or listed (POSIX form)."""
    out = set()
    for path in root.rglob("*"):
        rel = path.relative_to(root)
        if not path.is_file() or any(p.startswith(".") for p in rel.parts):
            continue
        if any(p in SKIPPED_DIRS for p in rel.parts[:-1]):
            continue
        out.add(rel.as_posix())
    return out


def _numbers_equal(a, b) -> bool:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.allclose(a, b, rtol=RTOL, atol=ATOL, equal_nan=True))


def _worst(a, b) -> str:
    a, b = np.asarray(a, dtype=float).ravel(), np.asarray(b, dtype=float).ravel()
    if a.shape != b.shape:
        return f"shape {a.shape} != {b.shape}"
    bad = ~np.isclose(a, b, rtol=RTOL, atol=ATOL, equal_nan=True)
    i = int(np.flatnonzero(bad)[0])
    return f"{int(bad.sum())} value(s) differ, first at flat index {i}: {a[i]!r} != {b[i]!r}"


def compare_csv(a: Path, b: Path) -> list[str]:
    """Differences between two CSV tables (numeric columns to RTOL, text exactly)."""
    import pandas as pd

    ta = pd.read_csv(a, keep_default_na=False, dtype=str)
    tb = pd.read_csv(b, keep_default_na=False, dtype=str)
    if list(ta.columns) != list(tb.columns):
        return [f"columns differ: {list(ta.columns)} != {list(tb.columns)}"]
    if len(ta) != len(tb):
        return [f"{len(ta)} rows != {len(tb)} rows"]
    problems = []
    for col in ta.columns:
        sa, sb = ta[col].to_numpy(), tb[col].to_numpy()
        na, nb = pd.to_numeric(ta[col], errors="coerce"), pd.to_numeric(tb[col], errors="coerce")
        numeric = not (na.isna() & (ta[col] != "")).any() and not (nb.isna() & (tb[col] != "")).any()
        if numeric and (ta[col] != "").any():
            if not _numbers_equal(na, nb):
                problems.append(f"column {col}: {_worst(na, nb)}")
        elif not (sa == sb).all():
            i = int(np.flatnonzero(sa != sb)[0])
            problems.append(f"column {col}, row {i + 2}: {sa[i]!r} != {sb[i]!r}")
    return problems


def _values_differ(va, vb) -> str | None:
    """Why two attribute or variable values differ, or None."""
    aa, ab = np.asarray(va), np.asarray(vb)
    if aa.dtype.kind in "fiub" and ab.dtype.kind in "fiub":
        return None if _numbers_equal(aa, ab) else _worst(aa, ab)
    if aa.shape != ab.shape:
        return f"shape {aa.shape} != {ab.shape}"
    sa = np.array([str(v) for v in aa.ravel()], dtype=object)
    sb = np.array([str(v) for v in ab.ravel()], dtype=object)
    if (sa == sb).all():
        return None
    i = int(np.flatnonzero(sa != sb)[0])
    return f"text differs at flat index {i}: {sa[i][:80]!r} != {sb[i][:80]!r}"


def compare_netcdf(a: Path, b: Path) -> list[str]:
    """Differences between two netCDF files: dims, variables, attributes (run times excepted)."""
    import netCDF4

    problems = []
    with netCDF4.Dataset(a) as da, netCDF4.Dataset(b) as db:
        dims_a = {k: len(v) for k, v in da.dimensions.items()}
        dims_b = {k: len(v) for k, v in db.dimensions.items()}
        if dims_a != dims_b:
            problems.append(f"dimensions differ: {dims_a} != {dims_b}")
        problems += _compare_attrs("global attribute", da, db, skip=TIME_ATTRS)
        names_a, names_b = set(da.variables), set(db.variables)
        for name in sorted(names_a ^ names_b):
            problems.append(f"variable {name} only in {'A' if name in names_a else 'B'}")
        for name in sorted(names_a & names_b):
            va, vb = da.variables[name], db.variables[name]
            va.set_auto_mask(False)
            vb.set_auto_mask(False)
            if va.dimensions != vb.dimensions:
                problems.append(f"variable {name}: dims {va.dimensions} != {vb.dimensions}")
                continue
            why = _values_differ(va[...], vb[...])
            if why:
                problems.append(f"variable {name}: {why}")
            problems += _compare_attrs(f"{name} attribute", va, vb)
    return problems


def _compare_attrs(what: str, a, b, skip=()) -> list[str]:
    keys_a, keys_b = set(a.ncattrs()) - set(skip), set(b.ncattrs()) - set(skip)
    problems = [f"{what} {k} only in {'A' if k in keys_a else 'B'}" for k in sorted(keys_a ^ keys_b)]
    for key in sorted(keys_a & keys_b):
        why = _values_differ(a.getncattr(key), b.getncattr(key))
        if why:
            problems.append(f"{what} {key}: {why}")
    return problems


def _compare_json_values(a, b, where: str) -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return [f"{where}: keys differ: {sorted(set(a) ^ set(b))}"]
        return [p for k in a for p in _compare_json_values(a[k], b[k], f"{where}.{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{where}: {len(a)} items != {len(b)} items"]
        return [p for i, (x, y) in enumerate(zip(a, b)) for p in _compare_json_values(x, y, f"{where}[{i}]")]
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and not isinstance(b, bool):
        same = math.isclose(a, b, rel_tol=RTOL, abs_tol=ATOL) or (math.isnan(a) and math.isnan(b))
        return [] if same else [f"{where}: {a!r} != {b!r}"]
    return [] if a == b else [f"{where}: {str(a)[:80]!r} != {str(b)[:80]!r}"]


def compare_json(a: Path, b: Path) -> list[str]:
    """Differences between two JSON files (numbers to RTOL, everything else exactly)."""
    return _compare_json_values(json.loads(a.read_text()), json.loads(b.read_text()), "$")


COMPARERS = {".csv": compare_csv, ".nc": compare_netcdf, ".json": compare_json}


def compare_trees(a: Path, b: Path) -> tuple[list[str], list[str]]:
    """(differences, images listed but not compared) between results trees ``a`` and ``b``."""
    fa, fb = files_of(a), files_of(b)
    diffs = [f"{rel}: only in {'A' if rel in fa else 'B'}" for rel in sorted(fa ^ fb)]
    images = []
    for rel in sorted(fa & fb):
        suffix = Path(rel).suffix.lower()
        if suffix in IMAGE_SUFFIXES:
            images.append(rel)
        elif suffix in COMPARERS:
            diffs += [f"{rel}: {p}" for p in COMPARERS[suffix](a / rel, b / rel)]
        elif (a / rel).read_bytes() != (b / rel).read_bytes():
            diffs.append(f"{rel}: bytes differ")
    return diffs, images


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path, help="first results folder (e.g. the baseline)")
    parser.add_argument("b", type=Path, help="second results folder")
    args = parser.parse_args(argv)
    for root in (args.a, args.b):
        if not root.is_dir():
            print(f"error: {root} is not a folder", file=sys.stderr)
            return 2
    diffs, images = compare_trees(args.a, args.b)
    n_files = len(files_of(args.a) & files_of(args.b)) - len(images)
    for rel in images:
        print(f"present on both sides, not compared (image): {rel}")
    for line in diffs:
        print(f"DIFFERENT {line}")
    if diffs:
        print(f"{len(diffs)} difference(s) between {args.a} and {args.b}")
        return 1
    print(f"same: {n_files} data files to rtol {RTOL:g} ({len(images)} images listed, not compared)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
