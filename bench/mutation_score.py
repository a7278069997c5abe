"""Mutation score per module from a finished `mutmut run` (the last step of `make mutation`).

    python bench/mutation_score.py            # table per module, then the survivors
    python bench/mutation_score.py --json
    python bench/mutation_score.py --selection  # the mutant name patterns `make mutation` runs
    python bench/mutation_score.py --checked-only  # score over the mutants a partial run checked
    python bench/mutation_score.py --generate   # write mutants/ (all mutants, none run) and stop
    python bench/mutation_score.py --sample 150 --seed 0 --names  # a seeded sample's names, one a line
    python bench/mutation_score.py --sample 150 --seed 0  # score of that sample, 95 % intervals

The sample: per module, the selected mutant names sorted, shuffled with random.Random(seed),
the first N taken (so the sample of 100 is the first 100 of the sample of 150). Its score
is killed / (sampled - equivalent) with a 95 % Clopper-Pearson interval for the score of
the whole selection of that module.

Reads the mutants/src/ballimpact/<module>.py.meta files mutmut 3 writes (exit code of the
test run per mutant) and bench/mutation_equivalent.txt (mutants judged equivalent: they
change no behaviour any input can show, each with its reason). Score = (killed + timeout)
/ (mutants - equivalent). A mutant with no test covering its function counts as not killed.
Only mutants matching SELECTION are counted: whole modules, and the core of the fit
(fitting_core.py, split from fitting.py; the model inversion: kB(0), the two stages, the
joint least squares and its residual scatter; not the interval profiles, outlier search,
bootstrap and bands).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import random
import sys
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
META_DIR = REPO / "mutants" / "src" / "ballimpact"
EQUIVALENT = REPO / "bench" / "mutation_equivalent.txt"

FITTING_CORE = (
    "fit_kb0", "_to_theta", "_from_theta", "_theta_bounds", "_simulate", "_least_squares", "_rmse_pct",
    "_start_grid", "fit_contact_time", "fit_restitution", "_relative_offset", "_batched_lm", "_residuals",
    "_jacobian", "_full_bounds", "_fit_weighted", "_block_scatter", "_satterthwaite_dof",
)
SELECTION = (
    ["ballimpact.model.*", "ballimpact.gates.*", "ballimpact.calibration.*",
     "ballimpact.signal.*", "ballimpact.fitting_core.x\u01c1_Problem\u01c1*"]
    + [f"ballimpact.fitting_core.x_{name}__mutmut_*" for name in FITTING_CORE]
)

# mutmut 3.8 (mutmut/stats.py): exit code of the mutant's test run -> status
STATUS = {1: "killed", 3: "killed", 0: "survived", 5: "no tests", 33: "no tests", 34: "skipped",
          36: "timeout", -24: "timeout", 24: "timeout", 152: "timeout", 255: "timeout",
          -11: "segfault", -9: "segfault", None: "not checked"}


def equivalent_mutants(path: Path = EQUIVALENT) -> dict[str, str]:
    """Mutants judged equivalent, name without 'ballimpact.' -> reason (lines 'name  reason', # comments)."""
    out = {}
    if path.exists():
        for line in path.read_text().splitlines():
            line = line.split("#", 1)[0].strip()
            if line:
                name, _, reason = line.partition(" ")
                out[name] = reason.strip()
    return out


def _metas(meta_dir: Path) -> list[Path]:
    """mutmut's .meta files of every module, the signal subpackage's (``signal/*.py.meta``) included."""
    return sorted(meta_dir.rglob("*.py.meta"))


def _module(meta: Path, meta_dir: Path) -> str:
    """The module a .meta file is of, dotted under ballimpact (``signal.contact``)."""
    return meta.relative_to(meta_dir).as_posix().removesuffix(".py.meta").replace("/", ".")


def selected(name: str) -> bool:
    return any(fnmatch.fnmatchcase(name, pat) for pat in SELECTION)


def sample_names(n: int, seed: int, meta_dir: Path = META_DIR) -> dict[str, list[str]]:
    """Per module, the first n of the selected mutant names (sorted) shuffled with seed."""
    out = {}
    for meta in _metas(meta_dir):
        names = sorted(k for k in json.loads(meta.read_text())["exit_code_by_key"] if selected(k))
        random.Random(seed).shuffle(names)
        out[_module(meta, meta_dir)] = names[:n]
    return out


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact binomial interval for a proportion, k successes of n trials [fraction, fraction]."""
    from scipy.stats import beta

    a = (1.0 - level) / 2.0
    lo = 0.0 if k == 0 else float(beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1.0 - a, k + 1, n - k))
    return lo, hi


def generate(max_children: int = 2) -> None:
    """Write mutants/ as `mutmut run` does before it runs anything (mutmut 3.8 internals)."""
    # bench/ is sys.path[0] when this file is run as a script, and bench/coverage.py would
    # shadow the `coverage` package mutmut imports
    here = Path(__file__).resolve().parent
    sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != here]
    sys.modules.pop("coverage", None)
    from mutmut.__main__ import (copy_also_copy_files, copy_src_dir, create_mutants, setup_source_paths,
                                 store_lines_covered_by_tests)

    os.chdir(REPO)
    os.makedirs("mutants", exist_ok=True)
    copy_src_dir()
    copy_also_copy_files()
    setup_source_paths()
    store_lines_covered_by_tests()
    create_mutants(max_children)


def scores(meta_dir: Path = META_DIR, checked_only: bool = False, only: dict | None = None) -> dict:
    equivalent = equivalent_mutants()
    table, survivors = {}, []
    for meta in _metas(meta_dir):
        codes = json.loads(meta.read_text())["exit_code_by_key"]
        module = _module(meta, meta_dir)
        if only is not None:
            codes = {k: codes[k] for k in only.get(module, [])}
        counts = Counter()
        for name, code in codes.items():
            if not selected(name):
                continue
            status = STATUS.get(code, "suspicious")
            if checked_only and status == "not checked":
                counts["not checked"] += 1
                continue
            if name.removeprefix("ballimpact.") in equivalent and status != "killed":
                status = "equivalent"
            counts[status] += 1
            if status in ("survived", "no tests", "not checked", "suspicious", "skipped"):
                survivors.append((name, status))
        total = sum(counts.values())
        detected = counts["killed"] + counts["timeout"] + counts["segfault"]
        judged = total - counts["equivalent"] - (counts["not checked"] if checked_only else 0)
        row = dict(counts, mutants=total, score_pct=round(100.0 * detected / judged, 1) if judged else None)
        if only is not None and judged:
            lo, hi = clopper_pearson(detected, judged)
            row["ci95_pct"] = [round(100.0 * lo, 1), round(100.0 * hi, 1)]
        table[module] = row
    return {"modules": table, "not_killed": survivors}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--selection", action="store_true", help="print the mutant name patterns run, one a line")
    ap.add_argument("--checked-only", action="store_true",
                    help="score only the mutants that were run (a run stopped early, or run on a subset)")
    ap.add_argument("--generate", action="store_true", help="write mutants/ (every mutant, none run)")
    ap.add_argument("--sample", type=int, help="a seeded random sample of N mutants per module")
    ap.add_argument("--seed", type=int, default=0, help="seed of --sample (default 0)")
    ap.add_argument("--names", action="store_true", help="with --sample: print the sample's names")
    args = ap.parse_args(argv)
    if args.selection:
        print("\n".join(SELECTION))
        return 0
    if args.generate:
        generate()
        return 0
    if not META_DIR.exists():
        print(f"no mutmut results in {META_DIR}: run `make mutation` first", file=sys.stderr)
        return 2
    only = sample_names(args.sample, args.seed) if args.sample else None
    if args.names:
        if only is None:
            ap.error("--names needs --sample N")
        print("\n".join(name for names in only.values() for name in names))
        return 0
    res = scores(checked_only=args.checked_only, only=only)
    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    cols = ("mutants", "killed", "timeout", "equivalent", "survived", "no tests", "not checked", "score_pct")
    if only is not None:
        print(f"seeded sample: {args.sample} mutants per module, seed {args.seed}; "
              "ci95_pct: 95 % Clopper-Pearson interval of the module's score")
        cols += ("ci95_pct",)
    print(f"{'module':14s}" + "".join(f"{c:>12s}" for c in cols))
    for mod, c in res["modules"].items():
        print(f"{mod:14s}" + "".join(f"{'-'.join(map(str, v)) if isinstance(v := c.get(k, 0), list) else v!s:>12s}"
                                     for k in cols))
    print("\nnot killed (and not listed as equivalent):")
    for name, status in res["not_killed"]:
        if status != "not checked":
            print(f"  {name}  [{status}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
