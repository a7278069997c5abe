"""The ITF drop test predicted by the model, against the paper's Table 1 and an independent flight integration."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from ballimpact import itf
from ballimpact.balls import BALLS
from ballimpact.model import simulate_impact

RHO, CD, D, G = 1.2, 0.55, 0.0654, 9.81


def _k(m):
    return RHO * CD * math.pi * D**2 / 4 / (2 * m)


def _fall_speed(m, h=2.54):
    """Speed after falling h from rest with drag, by solve_ivp (independent of ballimpact.flight)."""
    k = _k(m)

    def rhs(t, y):
        return [y[1], G - k * y[1] ** 2]

    def land(t, y):
        return y[0] - h

    land.terminal = True
    sol = solve_ivp(rhs, (0, 5), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-13, events=land)
    return sol.y_events[0][0][1]


def _rise(m, v0):
    """Apex height of a ball launched up at v0 with drag, by solve_ivp."""
    k = _k(m)

    def rhs(t, y):
        return [y[1], -G - k * y[1] * abs(y[1])]

    def apex(t, y):
        return y[1]

    apex.terminal = True
    sol = solve_ivp(rhs, (0, 5), [0.0, v0], method="DOP853", rtol=1e-12, atol=1e-13, events=apex)
    return sol.y_events[0][0][0]


def test_drop_impact_speed_matches_integration_and_free_fall():
    m = 0.0577
    assert_allclose(itf.drop_impact_speed(m), _fall_speed(m), rtol=1e-9)
    assert_allclose(itf.drop_impact_speed(m, air_density_kg_m3=0.0), math.sqrt(2 * G * 2.54), rtol=1e-12)
    # drag costs about 2.4 % of the 7.06 m/s of a drag-free fall
    assert 6.85 < itf.drop_impact_speed(m) < 6.93


@pytest.mark.parametrize("key", list(BALLS))
def test_prediction_chains_fall_model_and_rise(key):
    p = BALLS[key].params
    pred = itf.predict_itf_rebound(p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    vb = _fall_speed(p.mass_kg)
    cor = float(simulate_impact(vb, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac).cor)
    assert_allclose(pred.impact_speed_m_s, vb, rtol=1e-9)
    assert_allclose(pred.cor, cor, rtol=1e-9)
    assert_allclose(pred.rebound_height_m, _rise(p.mass_kg, cor * vb), rtol=1e-8)


# The model's over-prediction of the drop test, per Table 2 ball: model COR at the ITF
# impact speed minus the COR of Table 1's rebound (both with drag on fall and rise),
# and the model's rebound minus Table 1's. Measured by this test; quoted in docs/speeds-itf.md.
OVER_PREDICTION = {  # key: (COR difference, rebound difference [cm])
    "pressurised": (0.083, 30.6),
    "pressureless": (0.068, 25.1),
    "oversize": (0.098, 36.3),
    "punctured": (0.091, 29.8),
}


@pytest.mark.parametrize("key", list(BALLS))
def test_table2_model_over_predicts_table1_drop_test(key):
    ball = BALLS[key]
    p = ball.params
    vb = _fall_speed(p.mass_kg)
    h1 = ball.itf_rebound_cm / 100
    # Table 1's COR: the launch speed that rises exactly h1, over the impact speed
    cor_table1 = brentq(lambda v: _rise(p.mass_kg, v) - h1, 1.0, 10.0, xtol=1e-12) / vb
    cor_model = float(simulate_impact(vb, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac).cor)
    assert_allclose(itf.drop_test_cor(h1, p.mass_kg), cor_table1, rtol=1e-9)
    d_cor, d_cm = OVER_PREDICTION[key]
    assert_allclose(cor_model - cor_table1, d_cor, atol=0.0015)
    pred = itf.predict_itf_rebound(p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    assert_allclose(float(pred.rebound_height_m) * 100 - ball.itf_rebound_cm, d_cm, atol=0.15)
    # the issue's statement: the model over-predicts low-speed COR by 0.07-0.10
    assert 0.065 < cor_model - cor_table1 < 0.10
    # and without drag the drop-test COR is sqrt(h / H), lower still
    assert_allclose(itf.drop_test_cor(h1, p.mass_kg, air_density_kg_m3=0.0), math.sqrt(h1 / 2.54), rtol=1e-12)


def test_drag_free_model_cor_at_7_06_is_the_issues_0_85():
    p = BALLS["pressurised"].params
    pred = itf.predict_itf_rebound(p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, air_density_kg_m3=0.0)
    assert_allclose(pred.impact_speed_m_s, 7.06, atol=0.005)
    assert_allclose(pred.cor, 0.85, atol=0.005)


def test_interval_from_bootstrap_brackets_the_prediction():
    p = BALLS["pressurised"].params
    rng = np.random.default_rng(1)
    n = 60
    boot = np.column_stack([
        np.full(n, p.kb0_N_m),
        p.ak * np.exp(0.03 * rng.standard_normal(n)),
        np.full(n, p.a),
        p.ac * np.exp(0.03 * rng.standard_normal(n)),
    ])
    best, lo, hi = itf.predict_itf_rebound_interval(p.mass_kg, (p.kb0_N_m, p.ak, p.a, p.ac), boot)
    assert lo < best < hi
    assert hi - lo < 0.1  # [m] 3 % parameter scatter moves the rebound by centimetres
    best2, lo2, hi2 = itf.predict_itf_rebound_interval(p.mass_kg, (p.kb0_N_m, p.ak, p.a, p.ac), boot[:5])
    assert best2 == best and math.isnan(lo2) and math.isnan(hi2)


@pytest.mark.parametrize("kwargs, match", [
    ({"confidence": 1.5}, "confidence must be in"),
    ({"bootstrap": np.zeros((20, 3))}, r"bootstrap must have shape \(n, 4\)"),
])
def test_interval_rejects_bad_arguments(kwargs, match):
    p = BALLS["pressurised"].params
    with pytest.raises(ValueError, match=match):
        itf.predict_itf_rebound_interval(p.mass_kg, (p.kb0_N_m, p.ak, p.a, p.ac), **kwargs)


def test_drop_height_must_be_positive():
    with pytest.raises(ValueError, match="drop_height_m must be positive"):
        itf.drop_impact_speed(0.0577, drop_height_m=0.0)
