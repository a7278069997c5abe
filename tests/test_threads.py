"""Tests of threads.py: one BLAS thread is asked for only where the environment says nothing."""

import os
import sys

import pytest

from ballimpact.threads import BLAS_THREAD_VARIABLES, one_blas_thread


@pytest.fixture
def no_numpy(monkeypatch):
    """As before numpy's first import (restored after the test)."""
    monkeypatch.delitem(sys.modules, "numpy")


def test_sets_one_thread_where_unset(monkeypatch, no_numpy):
    for name in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    one_blas_thread()
    assert [os.environ[name] for name in BLAS_THREAD_VARIABLES] == ["1"] * len(BLAS_THREAD_VARIABLES)


def test_a_value_already_set_wins(monkeypatch, no_numpy):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    one_blas_thread()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "4"
    assert os.environ["OMP_NUM_THREADS"] == "1"


def test_warns_after_numpy_is_imported(monkeypatch):
    import numpy  # noqa: F401

    for name in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    with pytest.warns(UserWarning, match="after numpy was imported"):
        one_blas_thread()
