"""Fitting the ball model: recovery of known parameters from model-generated impacts."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ballimpact.balls import BALLS, BallModelParameters
from ballimpact.fitting import (
    FitError,
    fit_ball_model,
    fit_contact_time,
    fit_kb0,
    fit_restitution,
    model_curves,
)
from ballimpact.model import simulate_impact

UNLIKE_TABLE2 = BallModelParameters.from_table_units(58.0, 30.0, 40_000, 1.9, 2.5)
SPEEDS = np.linspace(14, 30, 9)


def _impacts(p, n=10, seed=0, tc_noise=0.0, cor_noise=0.0):
    rng = np.random.default_rng(seed)
    vin = np.sort(rng.uniform(14, 30, n))
    s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    tc = s.contact_time_s * (1 + tc_noise * rng.standard_normal(n))
    e = s.cor + cor_noise * rng.standard_normal(n)
    return vin, tc, e


def test_fit_kb0_recovers_line():
    vin = np.array([14.0, 18, 22, 26, 30])
    kv = 25e3 + 600.0 * vin
    f = fit_kb0(vin, kv + np.array([50, -40, 10, 30, -50]))
    assert_allclose(f.kb0_N_m, 25e3, rtol=0.01)
    assert f.kb0_lo < 25e3 < f.kb0_hi
    assert_allclose(f.slope_N_s_m2, 600, rtol=0.02)


@pytest.mark.parametrize(
    "vin, kv, match",
    [
        ([20.0, 25.0], [3e4, 3.1e4], "at least 3 impacts"),
        ([20.0, 20.0, 20.0], [3e4, 3.1e4, 3.2e4], "more than one inbound speed"),
        ([14.0, 20.0, 30.0], [1e3, 3e4, 7e4], "not positive"),
    ],
)
def test_fit_kb0_refuses_bad_data(vin, kv, match):
    with pytest.raises(FitError, match=match):
        fit_kb0(vin, kv)


@pytest.mark.parametrize("ball", ["pressurised", "punctured"])
def test_stages_recover_noise_free_parameters(ball):
    p = BALLS[ball].params
    vin, tc, e = _impacts(p)
    s1 = fit_contact_time(vin, tc, p.mass_kg, p.kb0_N_m, ac=p.ac)
    assert_allclose([s1.ak, s1.a], [p.ak, p.a], rtol=0.02)
    assert s1.rmse_pct < 0.01
    s2 = fit_restitution(vin, e, p.mass_kg, p.kb0_N_m, p.ak, p.a)
    assert_allclose(s2.ac, p.ac, rtol=1e-3)
    assert s1.result.success and s2.result.success


@pytest.mark.parametrize("key", ["pressurised", "pressureless", "oversize", "punctured", "unlike_table2"])
def test_joint_fit_curves_within_2pct_of_truth(key):
    p = UNLIKE_TABLE2 if key == "unlike_table2" else BALLS[key].params
    vin, tc, e = _impacts(p, seed=3, tc_noise=0.004, cor_noise=0.003)
    f = fit_ball_model(vin, tc, e, p.mass_kg, kb0_N_m=p.kb0_N_m, n_bootstrap=100, seed=1)
    true = simulate_impact(SPEEDS, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    c = model_curves(f, SPEEDS)
    assert_allclose(c["contact_time_s"], true.contact_time_s, rtol=0.02)
    assert_allclose(c["cor"], true.cor, rtol=0.02)
    # residuals are of the order of the noise put in (0.4 % TC, 0.003/0.6 = 0.5 % COR)
    assert f.contact_time_rmse_pct < 1.0 and f.cor_rmse_pct < 1.5
    assert f.kb0_source == "config" and np.isnan(f.kb0_lo)
    # intervals are ordered, bracket the estimate, and the band brackets the curve
    for name in ("ak", "a", "ac"):
        lo, val, hi = getattr(f, f"{name}_lo"), getattr(f, name), getattr(f, f"{name}_hi")
        assert lo <= val <= hi
    assert np.all(c["contact_time_s_lo"] <= c["contact_time_s_hi"])
    # AK and a trade off: strongly positively correlated
    assert f.ak_a_correlation > 0.5


def test_extrapolated_kb0_still_reproduces_curves():
    p = BALLS["pressurised"].params
    vin, tc, e = _impacts(p, seed=5, tc_noise=0.003, cor_noise=0.002)
    f = fit_ball_model(vin, tc, e, p.mass_kg, n_bootstrap=60, seed=2)
    assert f.kb0_source == "extrapolated"
    assert f.kb0_lo < f.kb0_N_m < f.kb0_hi
    true = simulate_impact(SPEEDS, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    c = model_curves(f, SPEEDS)
    assert_allclose(c["contact_time_s"], true.contact_time_s, rtol=0.02)
    assert_allclose(c["cor"], true.cor, rtol=0.02)


def test_true_parameters_inside_intervals_for_most_seeds():
    p = BALLS["pressurised"].params
    inside = 0
    for seed in range(4):
        vin, tc, e = _impacts(p, seed=10 + seed, tc_noise=0.004, cor_noise=0.003)
        f = fit_ball_model(vin, tc, e, p.mass_kg, kb0_N_m=p.kb0_N_m, n_bootstrap=100, seed=seed)
        inside += (f.ak_lo <= p.ak <= f.ak_hi) and (f.a_lo <= p.a <= f.a_hi) and (f.ac_lo <= p.ac <= f.ac_hi)
    assert inside >= 3


def test_too_few_impacts_raises():
    p = BALLS["pressurised"].params
    vin, tc, e = _impacts(p, n=2)
    with pytest.raises(FitError, match="at least 3 good impacts"):
        fit_ball_model(vin, tc, e, p.mass_kg, kb0_N_m=p.kb0_N_m)


def test_rejects_mismatched_lengths():
    with pytest.raises(ValueError, match="contact_time_s must have 3 values"):
        fit_ball_model([14.0, 20, 30], [4e-3, 3.8e-3], [0.7, 0.6, 0.5], 0.057, kb0_N_m=2e4)


@pytest.mark.slow
@pytest.mark.parametrize("kb0_in_config", [True, False], ids=["kb0-config", "kb0-extrapolated"])
def test_synthetic_session_through_the_sensor_chain(tmp_path, kb0_in_config):
    """Issue 4: a session made with parameters unlike Table 2, through the whole sensor
    chain and the processing; the fitted TC and COR curves within 2 % of the true ones."""
    from ballimpact.pipeline import fit_arrays
    from ballimpact.archive import impacts_dataset
    from ballimpact.processing import apply_calibration_check, iter_process
    from ballimpact.session import read_session
    from ballimpact.synth import SynthConfig, write_session

    config = SynthConfig(session_id="unlike", balls={"custom": UNLIKE_TABLE2}, labels={"custom": "custom"},
                         impacts_per_ball=10, faults_per_kind=0, seed=21, kb0_in_config=kb0_in_config)
    session_dir, _ = write_session(tmp_path / "unlike", config)
    session = read_session(session_dir)
    results = list(iter_process(session))
    apply_calibration_check(results)
    assert all(r.status == "ok" for r in results)
    ball = session.meta.balls["custom"]
    f = fit_ball_model(**fit_arrays(impacts_dataset(results), "custom", ball.mass_kg),
                       kb0_N_m=ball.kb0_N_m, n_bootstrap=50, seed=0)
    assert f.kb0_source == ("config" if kb0_in_config else "extrapolated")
    p = UNLIKE_TABLE2
    speeds = np.linspace(14, 30, 9)
    true = simulate_impact(speeds, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    c = model_curves(f, speeds)
    assert_allclose(c["contact_time_s"], true.contact_time_s, rtol=0.02)
    assert_allclose(c["cor"], true.cor, rtol=0.02)
