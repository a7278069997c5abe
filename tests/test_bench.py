"""Tests of the benchmarks' extrapolation (bench/run.py): the year-of-sessions figure is a straight line."""

from __future__ import annotations

import pytest
from numpy.testing import assert_allclose

from workflow_helpers import bench_module


def _bench():
    return bench_module("run")


@pytest.mark.parametrize(("ns", "t0", "per"), [((2, 4, 8), 12.0, 3.5), ((1, 3), 0.0, 7.25)])
def test_extrapolation_recovers_a_straight_line(ns, t0, per):
    value, slope, intercept, residual = _bench().extrapolate_linear(ns, [t0 + per * n for n in ns], 100)
    assert_allclose([value, slope, intercept], [t0 + per * 100, per, t0], rtol=1e-9, atol=1e-9)
    assert residual < 1e-9


def test_extrapolation_reports_the_misfit_of_a_curve():
    # wall time that bends upwards (e.g. swapping): the line's misfit at the measured sizes says so
    _, _, _, residual = _bench().extrapolate_linear([1, 2, 4], [1.0, 4.0, 16.0], 100)
    assert residual > 1.0


@pytest.mark.parametrize("ns", [(4,), (4, 4)])
def test_extrapolation_needs_two_sizes(ns):
    with pytest.raises(ValueError, match="at least two distinct sizes"):
        _bench().extrapolate_linear(ns, [10.0] * len(ns), 100)
