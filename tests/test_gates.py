"""Tests for ballimpact.gates: speeds, COR and timer-resolution uncertainty."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ballimpact.gates import check_gate_times, coefficient_of_restitution, gate_speeds, speed_uncertainty
from ballimpact.problems import ProblemKind


def test_gate_speeds_scalar():
    # ball at 20 m/s in, 12 m/s out over 0.1 m: 5 ms in, 8.333 ms out
    vin, vout = gate_speeds(10.0, 10.005, 10.020, 10.020 + 0.1 / 12.0, 0.1)
    assert isinstance(vin, float) and isinstance(vout, float)
    assert_allclose([vin, vout], [20.0, 12.0], rtol=1e-9)


def test_gate_speeds_arrays_and_nan():
    t1 = np.array([0.0, 0.0, np.nan, 0.0, 0.0])
    t2 = np.array([0.004, 0.005, 0.005, 0.005, -0.001])  # last: interval negative
    t3 = np.array([0.02, 0.02, 0.02, 0.02, 0.02])
    t4 = np.array([0.03, 0.02, 0.03, np.nan, 0.03])  # second: zero interval
    vin, vout = gate_speeds(t1, t2, t3, t4, 0.1)
    assert_allclose(vin, [25.0, 20.0, np.nan, 20.0, np.nan], rtol=1e-12)
    assert_allclose(vout, [10.0, np.nan, 10.0, np.nan, 10.0], rtol=1e-12)


@pytest.mark.parametrize("spacing", [0.0, -0.1, math.nan, math.inf])
def test_gate_speeds_bad_spacing(spacing):
    with pytest.raises(ValueError, match="spacing_m must be positive"):
        gate_speeds(0.0, 0.005, 0.01, 0.02, spacing)


def test_cor():
    assert_allclose(coefficient_of_restitution(20.0, 12.0), 0.6, rtol=1e-12)
    cor = coefficient_of_restitution(np.array([20.0, np.nan, 0.0, 10.0]), np.array([12.0, 5.0, 5.0, np.nan]))
    assert_allclose(cor, [0.6, np.nan, np.nan, np.nan])


def test_speed_uncertainty_formula():
    # v^2 r / (s sqrt 6): 20 m/s, 1 us, 0.1 m
    assert_allclose(speed_uncertainty(20.0, 0.1, 1e-6), 400 * 1e-6 / (0.1 * math.sqrt(6)), rtol=1e-12)
    assert speed_uncertainty(20.0, 0.1, 0.0) == 0.0
    assert_allclose(speed_uncertainty(np.array([10.0, 20.0]), 0.1, 1e-6)[1] / speed_uncertainty(10.0, 0.1, 1e-6),
                    4.0, rtol=1e-12)


def test_speed_uncertainty_monte_carlo():
    """Independent check: round both beam-break times to the timer resolution.

    The interval's position relative to the timer ticks is random from impact
    to impact, which the speeds spread over +-0.5 m/s ensure.
    """
    rng = np.random.default_rng(1)
    spacing, res = 0.1, 20e-6
    v = rng.uniform(24.5, 25.5, 200_000)
    t1 = rng.uniform(0, 1, v.size)
    t2 = t1 + spacing / v
    measured = spacing / (np.round(t2 / res) * res - np.round(t1 / res) * res)
    # measured: 0.088 % from the formula with this seed (the spread of a standard deviation
    # from 200 000 draws is 1/sqrt(2N) = 0.16 %); tolerance 0.2 %. The worst-case formula
    # (sqrt(6) = 2.45x larger) or r/sqrt(12) instead of r/sqrt(6) (1.41x) would fail it.
    assert_allclose(np.std(measured - v), speed_uncertainty(25.0, spacing, res), rtol=0.002)


def test_speed_uncertainty_bad_resolution():
    with pytest.raises(ValueError, match="resolution_s must be non-negative"):
        speed_uncertainty(20.0, 0.1, -1e-6)


def _messages(problems):
    return [p.message for p in problems]


def test_check_gate_times():
    assert check_gate_times(0.0, 0.005, 0.02, 0.03) == []
    assert _messages(check_gate_times(0.0, math.nan, 0.02, math.nan)) == [
        "missing gate time gate_in_2_s", "missing gate time gate_out_1_s"]
    assert {p.kind for p in check_gate_times(0.0, math.nan, 0.02, math.nan)} == {ProblemKind.GATE_TIME_MISSING}
    problems = check_gate_times(0.0, -0.005, 0.02, 0.01)
    assert [p.kind for p in problems] == [ProblemKind.GATE_INTERVAL] * 2
    assert problems[0].message.startswith("inbound gate interval not positive")
    assert problems[1].message.startswith("rebound gate interval not positive")


# Cases found by mutation testing (`make mutation`, docs/mutation-testing.md).


def test_gate_speeds_zero_inbound_interval_is_nan():
    vin, vout = gate_speeds(np.array([0.0, 0.0]), np.array([0.005, 0.0]), 0.02, 0.03, 0.1)
    assert_allclose(vin, [20.0, np.nan], rtol=1e-12)
    assert_allclose(vout, [10.0, 10.0], rtol=1e-12)


def test_gate_speeds_incompatible_shapes():
    with pytest.raises(ValueError, match="gate time arrays do not have compatible shapes"):
        gate_speeds(np.zeros(3), np.ones(2), 2.0, 3.0, 0.1)


def test_cor_types_and_edges():
    # floats for scalars, arrays as soon as one speed is an array (either one)
    assert isinstance(coefficient_of_restitution(20.0, 12.0), float)
    assert_allclose(coefficient_of_restitution(np.array([20.0, 10.0]), 6.0), [0.3, 0.6], rtol=1e-12)
    assert_allclose(coefficient_of_restitution(20.0, np.array([12.0, 6.0])), [0.6, 0.3], rtol=1e-12)
    # slow balls, a dead stop, and impossible rebounds
    assert_allclose(coefficient_of_restitution(0.5, 0.3), 0.6, rtol=1e-12)
    assert_allclose(coefficient_of_restitution(0.5, 0.5), 1.0, rtol=1e-12)
    assert coefficient_of_restitution(20.0, 0.0) == 0.0
    assert_allclose(coefficient_of_restitution(20.0, 0.5), 0.025, rtol=1e-12)
    assert math.isnan(coefficient_of_restitution(20.0, -1.0))
    assert math.isnan(coefficient_of_restitution(20.0, math.inf))


def test_speed_uncertainty_types_and_bad_input():
    assert isinstance(speed_uncertainty(20.0, 0.1, 1e-6), float)
    u = speed_uncertainty(np.array([-20.0, np.nan]), 0.1, 1e-6)
    assert isinstance(u, np.ndarray)
    assert_allclose(u, [400 * 1e-6 / (0.1 * math.sqrt(6)), np.nan], rtol=1e-12)
    with pytest.raises(ValueError, match="spacing_m must be positive"):
        speed_uncertainty(20.0, 0.0, 1e-6)
    with pytest.raises(ValueError, match="resolution_s must be a number, got 'abc'"):
        speed_uncertainty(20.0, 0.1, "abc")
    with pytest.raises(ValueError, match="resolution_s must be non-negative and finite"):
        speed_uncertainty(20.0, 0.1, math.inf)


def test_check_gate_times_edges():
    # a value that is not a number is reported as missing, not an exception
    assert _messages(check_gate_times("abc", 0.005, 0.02, 0.03)) == ["missing gate time gate_in_1_s"]
    assert _messages(check_gate_times(None, 0.005, 0.02, 0.03)) == ["missing gate time gate_in_1_s"]
    # a zero interval is not positive; the interval is a difference of the times
    assert _messages(check_gate_times(0.0, 0.0, 0.02, 0.03)) == [
        "inbound gate interval not positive (gate_in_2_s - gate_in_1_s = 0 s)"]
    assert _messages(check_gate_times(10.0, 9.995, 10.02, 10.03)) == [
        "inbound gate interval not positive (gate_in_2_s - gate_in_1_s = -0.005 s)"]
    assert _messages(check_gate_times(10.0, 10.005, 10.03, 10.03)) == [
        "rebound gate interval not positive (gate_out_1_s - gate_out_2_s = 0 s)"]


def test_infinite_inputs_give_nan_without_warnings():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        vin, vout = gate_speeds(math.inf, math.inf, 0.02, 0.03, 0.1)  # inf - inf
        cor = coefficient_of_restitution(np.array([math.inf, 20.0]), np.array([math.inf, 12.0]))  # inf / inf
    assert math.isnan(vin) and vout == pytest.approx(10.0, rel=1e-12)
    assert math.isnan(cor[0]) and cor[1] == pytest.approx(0.6, rel=1e-12)
