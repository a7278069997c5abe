"""Time per impact of several commits, measured alternately: issue 9's "within 1.5 times" line in one command.

    python bench/time_against.py 3f759dd HEAD              # the issue's baseline against this commit, 7 rounds
    python bench/time_against.py 3f759dd 1d5ff48 . --rounds 5  # "." is the working tree as it is

Each commit is checked out in a temporary git worktree (removed at the end; "." runs this checkout itself), and
``bench/run.py --quick --skip-workflow --json`` runs in it with ``PYTHONPATH=<worktree>/src`` and one BLAS thread
(``OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1``), once per commit per round, the commits in turn, so that a machine
whose speed drifts over the minutes (other work, heat) weighs on each alike. Prints each commit's
``process_seconds_per_impact`` run by run, its range and median [ms], and the median's ratio to the first commit's.
One run takes about 6 s on a 2-core machine (docs/performance.md); the machine's noise moves a single run by up to 15 %,
hence the medians over several rounds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
FIGURE = "process_seconds_per_impact"
RUN_ARGS = ("bench/run.py", "--quick", "--skip-workflow", "--json")
SINGLE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


def summarise(times_s: dict[str, list[float]]) -> list[dict]:
    """Per commit, in the order given: its runs, range and median [ms] and the median's ratio to the first's [-].

    Parameters
    ----------
    times_s : dict of str to list of float
        Each commit's ``process_seconds_per_impact`` runs [s], the baseline first.

    Returns
    -------
    list of dict
        Keys ``rev``, ``runs_ms``, ``min_ms``, ``max_ms``, ``median_ms``, ``ratio``.
    """
    if not times_s or any(not runs for runs in times_s.values()):
        raise ValueError("every commit needs at least one run")
    out = []
    base = None
    for rev, runs in times_s.items():
        ms = [1e3 * t for t in runs]
        med = statistics.median(ms)
        base = med if base is None else base
        out.append(dict(rev=rev, runs_ms=ms, min_ms=min(ms), max_ms=max(ms), median_ms=med, ratio=med / base))
    return out


def _checkout(rev: str, into: Path) -> Path:
    """A worktree of rev under ``into`` (this checkout itself for ".")."""
    if rev == ".":
        return REPO
    sha = subprocess.run(["git", "rev-parse", "--verify", f"{rev}^{{commit}}"], cwd=REPO, capture_output=True,
                         text=True)
    if sha.returncode != 0:
        raise SystemExit(f"time_against: {rev!r} is not a commit of {REPO}: {sha.stderr.strip()}")
    path = into / sha.stdout.strip()[:12]
    subprocess.run(["git", "worktree", "add", "--detach", str(path), sha.stdout.strip()], cwd=REPO, check=True,
                   capture_output=True)
    return path


def _one_run(path: Path) -> float:
    """One ``bench/run.py --quick --skip-workflow --json`` in path: its process_seconds_per_impact [s]."""
    env = dict(os.environ, PYTHONPATH=str(path / "src"), **SINGLE_THREAD)
    run = subprocess.run([sys.executable, *RUN_ARGS], cwd=path, env=env, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"time_against: bench/run.py failed in {path}:\n{run.stderr[-2000:]}")
    return float(json.loads(run.stdout)[FIGURE])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("revs", nargs="+", help="commits to time, the baseline first ('.' = the working tree)")
    parser.add_argument("--rounds", type=int, default=7, help="runs of each commit, alternated (default 7)")
    a = parser.parse_args(argv)
    if a.rounds < 1:
        parser.error(f"--rounds must be at least 1, got {a.rounds}")
    if len(set(a.revs)) != len(a.revs):
        parser.error(f"each commit once, got {' '.join(a.revs)}")
    with tempfile.TemporaryDirectory(prefix="time-against-") as tmp:
        paths = {}
        try:
            for rev in a.revs:
                paths[rev] = _checkout(rev, Path(tmp))
            times: dict[str, list[float]] = {rev: [] for rev in a.revs}
            for _ in range(a.rounds):
                for rev in a.revs:
                    times[rev].append(_one_run(paths[rev]))
        finally:
            for path in paths.values():
                if path != REPO:
                    subprocess.run(["git", "worktree", "remove", "--force", str(path)], cwd=REPO,
                                   capture_output=True)
            subprocess.run(["git", "worktree", "prune"], cwd=REPO, capture_output=True)
    print(f"{FIGURE} of `{' '.join(RUN_ARGS)}`, one BLAS thread, {a.rounds} alternated rounds:")
    for row in summarise(times):
        runs = ", ".join(f"{t:.2f}" for t in row["runs_ms"])
        print(f"  {row['rev']}: {runs} ms; {row['min_ms']:.2f}-{row['max_ms']:.2f} ms, median {row['median_ms']:.2f} ms,"
              f" {row['ratio']:.2f} times {a.revs[0]}'s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
