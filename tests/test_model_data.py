"""Model-derived data (ballimpact.model_data) against closed forms and against the measured force it is compared to."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from numpy.testing import assert_allclose

from ballimpact import model_data

# pressurised ball of Table 2 (Goodwill & Haake 2004) in SI: mass [kg], kB(0) [N/m], AK [N m^-(1+a)], a, AC [N s/m^3]
PARAMS = (0.0577, 21e3, 23.9e6, 1.75, 3.5e3)


@pytest.mark.parametrize(("kb", "cb"), [(2.0e5, 0.0), (2.0e5, 20.0), (5.0e4, 5.0)])
def test_kelvin_voigt_contact_lasts_half_a_damped_period(kb, cb):
    m, v = 0.057, 20.0
    t, f = model_data.kelvin_voigt_contact(v, m, kb, cb)
    wn, zeta = math.sqrt(kb / m), cb / (2 * math.sqrt(kb * m))
    wd = wn * math.sqrt(1 - zeta**2)
    assert_allclose(t[-1], math.pi / wd, rtol=1e-12)
    # x(t) = v/wd exp(-zeta wn t) sin(wd t): F = kB x + cB x' (Eqs. 1-3), independently evaluated
    x = v / wd * np.exp(-zeta * wn * t) * np.sin(wd * t)
    xdot = v * np.exp(-zeta * wn * t) * (np.cos(wd * t) - zeta * wn / wd * np.sin(wd * t))
    assert_allclose(f, kb * x + cb * xdot, rtol=1e-9, atol=1e-9 * kb * v / wn)
    assert_allclose(f[0], cb * v, rtol=1e-12, atol=1e-12)  # starts at cB VB, not at zero


@pytest.mark.parametrize(("v", "m", "kb", "cb"), [(0.0, 0.057, 2e5, 10.0), (20.0, np.nan, 2e5, 10.0),
                                                    (20.0, 0.057, 2e5, 2 * math.sqrt(2e5 * 0.057) * 1.01)])
def test_kelvin_voigt_contact_is_none_when_not_an_underdamped_impact(v, m, kb, cb):
    assert model_data.kelvin_voigt_contact(v, m, kb, cb) is None


def test_impact_model_curve_needs_a_fit_and_a_speed():
    assert model_data.impact_model_curve(None, 20.0) is None
    assert model_data.impact_model_curve(PARAMS, 0.0) is None
    assert model_data.impact_model_curve(PARAMS, np.nan) is None


def test_a_heavier_ball_stays_longer_and_a_bad_mass_falls_back_on_the_fitted_one():
    t_fit, _, _ = model_data.impact_model_curve(PARAMS, 20.0)
    t_nan, _, _ = model_data.impact_model_curve(PARAMS, 20.0, np.nan)
    t_heavy, f_heavy, x_heavy = model_data.impact_model_curve(PARAMS, 20.0, 2 * PARAMS[0])
    assert_allclose(t_nan, t_fit, rtol=0)
    assert t_heavy[-1] > t_fit[-1]
    assert np.isfinite(f_heavy).all() and x_heavy.max() > 0


@pytest.mark.parametrize("batch", [1, 3, 64])
def test_impact_model_curves_of_many_impacts_are_the_curves_of_each(monkeypatch, batch):
    """Simulated together (in batches of CURVE_BATCH), each impact keeps its own curve, bit for bit;
    speeds that cannot be simulated give None, and a bad mass falls back on the fitted one."""
    monkeypatch.setattr(model_data, "CURVE_BATCH", batch)
    vin = np.array([14.0, np.nan, 30.0, -1.0, 22.5, 18.0])
    mass = np.array([PARAMS[0], PARAMS[0], 1.2 * PARAMS[0], PARAMS[0], np.nan, 0.0])
    curves = model_data.impact_model_curves(PARAMS, vin, mass)
    assert len(curves) == vin.size
    for v, m, curve in zip(vin, mass, curves):
        alone = model_data.impact_model_curve(PARAMS, v, m)
        if alone is None:
            assert curve is None
            continue
        for got, want in zip(curve, alone):
            assert_allclose(got, want, rtol=0, atol=0)
    assert [c is None for c in curves] == [False, True, False, True, False, False]
    assert model_data.impact_model_curves(None, vin, mass) == [None] * vin.size


def _one_impact_archive(force):
    t = np.arange(force.size) * 1e-5
    return xr.Dataset(
        {"ball_type": ("impact", np.array(["b1"], dtype=object)),
         "vin_m_s": ("impact", [20.0]), "impact_mass_kg": ("impact", [PARAMS[0]]),
         "time_s": (("impact", "sample"), t[None, :]), "force_N": (("impact", "sample"), force[None, :]),
         "mass_kg": ("ball", [PARAMS[0]]), "kb0_kN_m": ("ball", [PARAMS[1] / 1e3]),
         "ak_kN_m": ("ball", [PARAMS[2] / 1e3]), "a": ("ball", [PARAMS[3]]), "ac_kN_s_m3": ("ball", [PARAMS[4] / 1e3])},
        coords={"ball": np.array(["b1"], dtype=object)},
    )


def test_model_forces_agree_fully_with_a_measurement_equal_to_the_model():
    ts, fs, _ = model_data.impact_model_curve(PARAMS, 20.0)
    measured = np.interp(np.arange(400) * 1e-5, ts, fs, right=0.0)
    out = model_data.add_model_forces(_one_impact_archive(measured))
    assert_allclose(out["model_force_N"].values[0], measured, rtol=1e-12, atol=1e-9)
    assert_allclose(out["model_rms_N"].values[0], 0.0, atol=1e-9)
    assert out["model_agreement_fraction"].values[0] == 1.0


def test_model_forces_see_a_measurement_20_percent_off():
    ts, fs, _ = model_data.impact_model_curve(PARAMS, 20.0)
    model = np.interp(np.arange(400) * 1e-5, ts, fs, right=0.0)
    out = model_data.add_model_forces(_one_impact_archive(1.2 * model))
    # the difference is 0.2 x model force, within 10 % of the measured peak (1.2 max) where model < 0.6 max
    late = np.arange(400) * 1e-5 >= model_data.AGREEMENT_START_S
    expected = np.mean(0.2 * model[late] <= 0.10 * 1.2 * model.max())
    assert_allclose(out["model_agreement_fraction"].values[0], expected, rtol=1e-12)
    assert_allclose(out["model_rms_N"].values[0], np.sqrt(np.mean((0.2 * model) ** 2)), rtol=1e-9)
