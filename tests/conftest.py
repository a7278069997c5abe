"""Shared fixtures: synthetic sessions with known truth (made once per test run)."""

from __future__ import annotations

import os

import pandas as pd
import pytest
from hypothesis import settings

from ballimpact.synth import SensorChain, SynthConfig, write_session

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
