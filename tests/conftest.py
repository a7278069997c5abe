"""Shared fixtures: synthetic sessions with known truth (made once per test run)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from ballimpact.threads import one_blas_thread

one_blas_thread()  # before numpy is first imported: the suite processes thousands of traces in this process

import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

from ballimpact.synth import SensorChain, SynthConfig, write_session  # noqa: E402

# Property tests run on a fixed, derandomised set of examples, so that a run of `make test`
# passes or fails the same way every time. HYPOTHESIS_PROFILE=hunt turns them back into a
# random search, for a developer hunting for a breaking case.
settings.register_profile("fixed", derandomize=True, deadline=None)
settings.register_profile("hunt", derandomize=False, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fixed"))


def _make(tmp_path_factory, name, **kw):
    root = tmp_path_factory.mktemp(name)
    session_dir, truth_csv = write_session(root / name, SynthConfig(session_id=name, **kw))
    truth = pd.read_csv(truth_csv, keep_default_na=False).set_index("impact_id")
    return session_dir, truth


@pytest.fixture(scope="session")
def synth_session(tmp_path_factory):
    """Four Table 2 balls, 67 kHz, CSV with and without time_s plus TDMS, one fault of each kind."""
    return _make(tmp_path_factory, "syn-mixed", seed=11, impacts_per_ball=4, faults_per_kind=1,
                 trace_format="mixed")


@pytest.fixture(scope="session")
def synth_session_negative_tdms(tmp_path_factory):
    """Polarity -1, a 50 kHz DAQ and TDMS traces only."""
    return _make(tmp_path_factory, "syn-neg", seed=12, impacts_per_ball=4, faults_per_kind=1,
                 polarity=-1, trace_format="tdms", chain=SensorChain(sample_rate_hz=50_000.0))


@pytest.fixture(scope="session")
def demo_run_output(tmp_path_factory):
    """The workflow run on raw/demo-2004 (once per test run, shared by the xdist workers:
    shared_fixture.build_once; used by test_run.py and test_readme.py).

    A dict: ``workdir`` (the run's working folder, holding ``results/``), ``results``
    (its results folder), ``raw_before`` (path -> (sha256, mtime) of raw/demo-2004 before
    the run) and ``stdout`` (what Snakemake printed, stderr merged).
    """
    from shared_fixture import build_once
    from workflow_helpers import REPO, run_snakemake

    demo = REPO / "raw" / "demo-2004"

    def hashes(folder: Path):
        return {p.relative_to(folder).as_posix(): (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns)
                for p in sorted(folder.rglob("*")) if p.is_file()}

    def run(tmp: Path) -> dict:
        before = hashes(demo)
        results = tmp / "results"
        proc = run_snakemake("--snakefile", REPO / "Snakefile", "--directory", tmp, "--cores", "2",
                             "--config", f"raw_dir={REPO / 'raw'}", f"results_dir={results}",
                             "sessions=[demo-2004]", cwd=tmp)
        assert proc.returncode == 0, proc.stdout[-5000:]
        return {"workdir": tmp, "results": results, "raw_before": before, "stdout": proc.stdout}

    return build_once(tmp_path_factory, "demo-run", run)
