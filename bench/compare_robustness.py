"""Compare two runs of bench/robustness.py trace by trace: what a change did to each zoo trace (issue 9).

    python bench/compare_robustness.py OLD NEW            # OLD, NEW: per-trace CSVs, or folders of them

With folders (e.g. ``bench/out`` of a worktree on the old commit and of this one), every
``robustness-s<SEED>-n<N>.csv`` present in both is compared. For each pair it prints the counts per category
before and after, every trace whose category changed (with its TC and kCAL errors before and after and, where it
is excluded now, the start of its reason), and over the traces ok in both runs the mean and standard deviation of
the TC, kCAL and peak errors, the number off by more than 0.5 %, and the largest change of each; and whether every
other column is identical to the last bit (a change meant to make the processing faster must leave them so), or
which columns differ on how many traces. A last line sums the categories over every pair. The two runs must hold
the same traces (seed and index), or it stops with a message naming the file. The timing columns are not compared,
and the temporary folders a reason may name are masked.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections import Counter
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import zoo  # noqa: E402

CATEGORIES = zoo.CATEGORIES + ("crash",)  # bench/robustness.py's: the zoo's judgements, and a crash of the processing
QUANTITIES = (("TC", "tc_err_pct"), ("kCAL", "kcal_err_pct"), ("peak", "peak_err_pct"))
FAR_PCT = 0.5  # an ok trace's error beyond this many per cent is counted [%]
REASON_CHARS = 150  # the start of a changed trace's reason shown [-]
CSV_NAME = re.compile(r"robustness-s(\d+)-n(\d+)\.csv$")
TIMING = ("make_s", "process_s", "process_cpu_s")  # what a run's machine decides, not its processing
TEMP_PATH = re.compile(r"/\S*?zoo-bench-[^/\s]+/zoo-[^/\s]+/")  # each run's own temporary session folder


def pairs(old: Path, new: Path) -> list[tuple[Path, Path]]:
    """The CSV pairs to compare: the two files, or the robustness CSVs of the same name in both folders."""
    if old.is_dir() != new.is_dir():
        raise SystemExit(f"give two CSV files or two folders, got {old} and {new}")
    if not old.is_dir():
        return [(old, new)]
    pattern = "robustness-s*-n*.csv"
    names = sorted({p.name for p in old.glob(pattern)} & {p.name for p in new.glob(pattern)},
                   key=lambda s: tuple(int(g) for g in CSV_NAME.search(s).groups()))
    if not names:
        raise SystemExit(f"no robustness-s<SEED>-n<N>.csv in both {old} and {new}")
    return [(old / n, new / n) for n in names]


def read(path: Path) -> pd.DataFrame:
    """One per-trace CSV of bench/robustness.py, indexed by trace id ("seed:index")."""
    try:
        df = pd.read_csv(path, float_precision="round_trip")  # every bit of the written numbers
    except (OSError, pd.errors.ParserError) as exc:
        raise SystemExit(f"{path}: cannot read it as a CSV: {exc}") from None
    missing = ({"id", "category", "reason"} | {c for _, c in QUANTITIES}) - set(df.columns)
    if missing:
        raise SystemExit(f"{path}: not a bench/robustness.py CSV, it lacks the columns {sorted(missing)}")
    return df.set_index("id")


def compare(old: pd.DataFrame, new: pd.DataFrame, name: str = "") -> tuple[str, Counter, Counter]:
    """The report of one pair, and the category counts before and after."""
    if set(old.index) != set(new.index):
        only = sorted(set(old.index) ^ set(new.index))[:5]
        raise SystemExit(f"{name}: the two runs hold different traces (e.g. {only}): compare runs of the same "
                         "--seed and --n")
    new = new.loc[old.index]
    before, after = Counter(old.category), Counter(new.category)
    lines = [f"{name}: {len(old)} traces"]
    for cat in CATEGORIES:
        if before[cat] or after[cat]:
            lines.append(f"  {cat}: {before[cat]} -> {after[cat]}")
    changed = old.index[old.category != new.category]
    lines.append(f"  category changed: {len(changed)}")
    for i in changed:
        line = (f"    {i}: {old.category[i]} -> {new.category[i]}; TC {_pct(old.tc_err_pct[i])} -> "
                f"{_pct(new.tc_err_pct[i])}, kCAL {_pct(old.kcal_err_pct[i])} -> {_pct(new.kcal_err_pct[i])}")
        if not str(new.category[i]).startswith("ok") and isinstance(new.reason[i], str):
            line += f"; {new.reason[i][:REASON_CHARS]}"
        lines.append(line)
    both = old.category.str.startswith("ok") & new.category.str.startswith("ok")
    lines.append(f"  ok in both: {int(both.sum())}")
    for label, col in QUANTITIES:
        a, b = old.loc[both, col].astype(float), new.loc[both, col].astype(float)
        if a.empty:
            continue
        moved = float((b - a).abs().max())
        lines.append(f"    {label} error: mean {a.mean():+.4f} -> {b.mean():+.4f} %, standard deviation "
                     f"{a.std():.4f} -> {b.std():.4f} %, beyond {FAR_PCT:g} %: {int((a.abs() > FAR_PCT).sum())} -> "
                     f"{int((b.abs() > FAR_PCT).sum())}; largest change of one trace {moved:.3g} %")
    diff = differences(old, new)
    if diff:
        lines.append("  differ: " + "; ".join(f"{col} on {len(ids)} traces (e.g. {', '.join(map(str, ids[:3]))})"
                                              for col, ids in diff.items()))
    else:
        lines.append("  every other column identical to the last bit")
    return "\n".join(lines), before, after


def differences(old: pd.DataFrame, new: pd.DataFrame) -> dict[str, list]:
    """Columns (but the timing ones) whose values differ between two runs of the same traces, with the traces
    where they do; NaN equals NaN, numbers must be equal to the last bit, text equal once temporary paths are
    masked."""
    new = new.loc[old.index]
    out = {}
    for col in old.columns:
        if col in TIMING or col not in new.columns:
            continue
        a, b = old[col], new[col]
        if pd.api.types.is_numeric_dtype(a) and pd.api.types.is_numeric_dtype(b):
            same = (a == b) | (a.isna() & b.isna())
        else:
            same = a.map(_masked) == b.map(_masked)
        if not same.all():
            out[col] = list(old.index[~same])
    for col in sorted(set(new.columns) - set(old.columns) - set(TIMING)):
        out[col] = ["(only in the new run)"]
    return out


def _masked(text) -> str:
    return "nan" if isinstance(text, float) and math.isnan(text) else TEMP_PATH.sub("<tmp>/", str(text))


def _pct(x) -> str:
    return "nan" if not math.isfinite(float(x)) else f"{float(x):+.2f} %"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path, help="per-trace CSV of bench/robustness.py, or a folder of them (before)")
    ap.add_argument("new", type=Path, help="the same, after")
    a = ap.parse_args(argv)
    total_before, total_after = Counter(), Counter()
    for o, n in pairs(a.old, a.new):
        report, before, after = compare(read(o), read(n), n.name)
        print(report)
        total_before += before
        total_after += after
    print("all: " + ", ".join(f"{c} {total_before[c]} -> {total_after[c]}" for c in CATEGORIES
                              if total_before[c] or total_after[c]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
