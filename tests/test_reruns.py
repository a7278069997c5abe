"""Reruns: after a complete run, editing one raw file reruns exactly its session, and a
changed config key reruns exactly the jobs that depend on it (Snakemake's default rerun
triggers: modification times and params).

One complete two-session run is made once (module fixture); every case then asks a dry
run which jobs would run, on a copy of that state, so the cases do not disturb each other.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from ballimpact.balls import BALLS
from ballimpact.synth import SynthConfig, write_session
from shared_fixture import build_once
from workflow_helpers import run_snakemake

pytestmark = pytest.mark.slow

SESSIONS = ("alpha", "beta")


def _args(root: Path, *extra):
    # --directory: Snakemake's records (.snakemake/, which hold the params of each job) live
    # in root, keyed by paths relative to it, so a copy of root keeps them
    return ["--cores", "2", "--directory", str(root), "--config", f"raw_dir={root / 'raw'}",
            f"results_dir={root / 'results'}", "bootstrap=10", *extra]


@pytest.fixture(scope="module")
def done_run(tmp_path_factory) -> Path:
    """A folder holding raw/ (two small synthetic sessions) and results/ after a complete run
    (built once per test run and shared by the xdist workers: shared_fixture.build_once)."""
    def run(root: Path) -> Path:
        raw = root / "raw"
        for k, name in enumerate(SESSIONS):
            write_session(raw / name, SynthConfig(session_id=name, impacts_per_ball=4, faults_per_kind=0,
                                                  balls={"pressurised": BALLS["pressurised"].params}, seed=20 + k))
            for truth in raw.glob(f"{name}.truth.*"):
                truth.unlink()
        run_snakemake(*_args(root), check=True)
        return root

    return build_once(tmp_path_factory, "reruns", run)


@pytest.fixture
def state(done_run, tmp_path) -> Path:
    """A private copy of the completed run, Snakemake's records included (modification times kept)."""
    copy = tmp_path / "state"
    shutil.copytree(done_run, copy, symlinks=True, copy_function=shutil.copy2)
    return copy


def planned(root: Path, *extra) -> dict[str, set[str]]:
    """Rule -> sessions of the jobs a dry run would run."""
    proc = run_snakemake("-n", *_args(root, *extra), check=True)
    jobs: dict[str, set[str]] = {}
    for block in re.split(r"\n(?=(?:local)?rule \w+:)", proc.stdout):
        head = re.match(r"(?:local)?rule (\w+):", block)
        if not head or head.group(1) == "all":
            continue
        session = re.search(r"wildcards: .*?session=([^,\s]+)", block)
        jobs.setdefault(head.group(1), set()).add(session.group(1) if session else "")
    return jobs


def _edit(path: Path) -> None:
    """Change a raw file's bytes but not its meaning: a comment line in a trace (the reader
    keeps `# key: value` lines as metadata) or session.yaml, a blank line at the end of
    impacts.csv. Snakemake compares checksums, so a rewrite of the same bytes would rightly
    rerun nothing."""
    if path.name == "impacts.csv":
        path.write_bytes(path.read_bytes() + b"\n")
    else:
        path.write_bytes(b"# edited: yes\n" + path.read_bytes())


def test_complete_run_plans_nothing(state):
    assert planned(state) == {}


@pytest.mark.parametrize("what", ["trace", "impacts.csv", "session.yaml"])
def test_editing_one_raw_file_reruns_exactly_its_session(state, what):
    session = state / "raw" / "beta"
    path = {"trace": next(iter(sorted((session / "traces").iterdir()))),
            "impacts.csv": session / "impacts.csv",
            "session.yaml": session / "session.yaml"}[what]
    _edit(path)
    jobs = planned(state)
    assert jobs, f"editing {path.name} planned nothing"
    # the jobs of that session, and the catalogue across sessions (no session wildcard)
    assert {s for sessions in jobs.values() for s in sessions} == {"beta", ""}
    assert {rule for rule, sessions in jobs.items() if "" in sessions} == {"catalogue"}
    # the whole chain of that session, down to its report (a small session processed as one
    # chunk is one small_session job; a large one's are per-stage jobs)
    assert {"small_session"} == set(jobs) - {"catalogue"} or (
        {"validate_session", "process_chunk", "collect_impacts"} <= set(jobs)
        and ({"session_outputs"} <= set(jobs) or {"archive", "report"} <= set(jobs)))


def test_changed_mains_reruns_processing_of_every_session(state):
    jobs = planned(state, "mains_hz=60")
    # processing: rule process_chunk, or small_session for a small session (these are small)
    assert jobs["small_session"] == set(SESSIONS)
    assert "validate_session" not in jobs  # the raw files did not change


@pytest.mark.parametrize("key", ["bootstrap=12", "seed=3"])
def test_changed_fit_setting_reruns_each_session_once(state, key):
    # these small sessions are each one small_session job, whose fits rerun with its
    # processing (issue 48: one job per small session); a session run per stage would
    # rerun fit_session, fit_ball or session_outputs without process_chunk
    jobs = planned(state, key)
    fits = ("fit_session", "fit_ball", "session_outputs", "small_session")
    assert set().union(*(jobs.get(rule, set()) for rule in fits)) == set(SESSIONS)
    assert "process_chunk" not in jobs and "collect_impacts" not in jobs and "validate_session" not in jobs
    assert set(jobs) == {"small_session", "catalogue"}
