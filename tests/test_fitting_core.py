"""Tests of the core of ballimpact.fitting (the model inversion) that the sampled mutation run asked for.

The rest of fitting's tests are in tests/test_fitting.py.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ballimpact.balls import BALLS
from ballimpact.fitting import fit_contact_time, fit_restitution

P = BALLS["pressurised"].params
VIN = np.array([15.0, 20.0, 25.0])


@pytest.mark.parametrize(("fit", "name"), [(fit_contact_time, "contact_time_s"), (fit_restitution, "cor")])
@pytest.mark.parametrize(("bad", "what"), [
    ([0.6, np.nan, 0.6], r"must be finite, got .*nan.*"),
    ([0.6, 0.6], r"must have 3 values \(one per impact\), got 2"),
])
def test_stages_name_the_bad_argument(fit, name, bad, what):
    """A bad measured series is refused with its argument's name (as in the signature) and what is wrong."""
    args = {"contact_time_s": (VIN, bad, P.mass_kg, P.kb0_N_m),
            "cor": (VIN, bad, P.mass_kg, P.kb0_N_m, P.ak, P.a)}[name]
    with pytest.raises(ValueError, match=rf"^{name} {what}$"):
        fit(*args)


@pytest.mark.parametrize(("jac", "dof", "expected"), [
    # TC and COR rows carry equal variance, each estimated with 8 degrees of freedom: their sum
    # has 16 (two independent chi-square estimates of the same size add their dof)
    ([[1.0], [1.0], [1.0], [1.0]], (8.0, 8.0), 16.0),
    # the COR rows carry no information on the parameter: only the TC scatter counts
    ([[1.0], [2.0], [0.0], [0.0]], (5.0, 9.0), 5.0),
    # unequal: Welch-Satterthwaite (v1 + v2)^2 / (v1^2 / n1 + v2^2 / n2) with v1 = 1/25, v2 = 4/25
    # (jac rows 1 and 2; cov = 1/5, v = cov * grad, v_k = (jac_k v)^2), n1 = 4, n2 = 6
    ([[1.0], [0.0], [2.0], [0.0]], (4.0, 6.0), (1 / 25 + 4 / 25) ** 2 / ((1 / 25) ** 2 / 4 + (4 / 25) ** 2 / 6)),
])
def test_satterthwaite_degrees_of_freedom(jac, dof, expected):
    """Degrees of freedom of a variance built from the TC and the COR scatter (Satterthwaite 1946)."""
    from ballimpact.fitting import _satterthwaite_dof

    got = _satterthwaite_dof(np.array([1.0]), np.array(jac), 2, *dof)
    assert got == pytest.approx(expected, rel=1e-12)


# --- the residuals, the start grid, the convergence test and the failure message ------------
# Independent truth: simulate_impact (the model itself, called directly, one parameter set at
# a time) and the textbook definitions written out here, not fitting.py's batched code.

from ballimpact.model import simulate_impact  # noqa: E402

THETA = np.array([np.log(P.ak * 0.020**P.a), P.a, np.log(P.ac)])  # (log kR, a, log AC), kR = AK (20 mm)^a
MASS = np.full(VIN.size, P.mass_kg)


def _model(ak, a, ac, kb0=P.kb0_N_m):
    sim = simulate_impact(VIN, MASS, kb0, ak, a, ac)
    return np.asarray(sim.contact_time_s, dtype=float), np.asarray(sim.cor, dtype=float)


def test_simulate_gives_nan_for_invalid_parameter_sets_and_the_model_for_the_others():
    """_simulate's contract: a set that is not finite and positive gives NaN; the others, the model's TC and COR."""
    from ballimpact.fitting import _simulate

    bad_a = THETA.copy()
    bad_a[1] = -0.5
    bad_ac = THETA.copy()
    bad_ac[2] = np.nan
    tc, cor = _simulate(np.stack([THETA, bad_a, bad_ac]), VIN, MASS, P.kb0_N_m)
    assert tc.shape == cor.shape == (3, VIN.size)
    assert np.isnan(tc[1:]).all() and np.isnan(cor[1:]).all()
    tc_true, cor_true = _model(P.ak, P.a, P.ac)
    assert_allclose(tc[0], tc_true, rtol=1e-12)
    assert_allclose(cor[0], cor_true, rtol=1e-12)


@pytest.mark.parametrize(("d_tc", "d_cor", "s_tc", "s_cor"), [(0.02, -0.05, 1.0, 1.0), (-0.01, 0.08, 0.005, 0.02)])
def test_residuals_are_relative_and_weighted(d_tc, d_cor, s_tc, s_cor):
    """Weighted relative residuals (model - measured) / measured / sigma, TC then COR, of a known case.

    Measured = model (1 + d), so each residual is (1 / (1 + d) - 1) / sigma whatever the
    model's values: a COR residual scaled by the COR instead of divided by it is off by COR^2.
    """
    from ballimpact.fitting import _residuals

    tc_true, cor_true = _model(P.ak, P.a, P.ac)
    r = _residuals(THETA, VIN, tc_true * (1 + d_tc), cor_true * (1 + d_cor), MASS, P.kb0_N_m, s_tc, s_cor)
    expected = np.concatenate([np.full(VIN.size, (1 / (1 + d_tc) - 1) / s_tc),
                               np.full(VIN.size, (1 / (1 + d_cor) - 1) / s_cor)])
    assert_allclose(r, expected, rtol=1e-9)
    bad = THETA.copy()
    bad[1] = -0.5  # a <= 0: no model, a large finite residual the optimiser steps away from
    assert_allclose(_residuals(bad, VIN, tc_true, cor_true, MASS, P.kb0_N_m, 1.0, 1.0), 1.0e3)


def test_problem_residuals_of_a_batch_of_any_shape():
    """_Problem.residuals_batch: points of any leading shape give each point's residuals, TC then COR."""
    from ballimpact.fitting import _Problem

    tc_true, cor_true = _model(P.ak, P.a, P.ac)
    prob = _Problem(VIN, tc_true * 1.01, cor_true * 0.98, MASS, P.kb0_N_m, True, True, 0.01, 0.02)
    one = np.concatenate([np.full(VIN.size, (1 / 1.01 - 1) / 0.01), np.full(VIN.size, (1 / 0.98 - 1) / 0.02)])
    assert_allclose(prob.residuals_batch(THETA), one, rtol=1e-9)
    assert_allclose(prob.residuals_batch(np.broadcast_to(THETA, (2, 2, 3))), np.broadcast_to(one, (2, 2, 6)),
                    rtol=1e-9)


def test_start_grid_is_the_best_grid_point_for_the_contact_times():
    """_start_grid: of the grid kR = 3e3..1e5 N/m (9, geometric) x a = 0.8..2.6 (7), the point whose
    model TC is closest (sum of squared relative differences) to the measured TC, with AC given."""
    from ballimpact.fitting import _start_grid

    tc_meas, _ = _model(P.ak, P.a, P.ac)
    grid = [(kr, a) for kr in np.geomspace(3e3, 1e5, 9) for a in np.linspace(0.8, 2.6, 7)]
    kr, a = (np.array(v)[:, None] for v in zip(*grid))
    tc_grid, _ = _model(kr / 0.020**a, a, 2.0e3)  # one simulation of the 63 parameter sets, (63, 3)
    best, best_cost = None, np.inf
    for (kr, a), tc in zip(grid, tc_grid):
        cost = np.sum(((tc - tc_meas) / tc_meas) ** 2) if np.all(np.isfinite(tc)) else np.inf
        if cost < best_cost:
            best, best_cost = (np.log(kr), a, np.log(2.0e3)), cost
    assert_allclose(_start_grid(VIN, tc_meas, MASS, P.kb0_N_m, 2.0e3), best, rtol=1e-12)


def _offset_by_qr(jac, r):
    """Bates & Watts (1981) relative offset: |Q'r| / sqrt(p) over |r - QQ'r| / sqrt(m - p), Q from QR."""
    q, _ = np.linalg.qr(jac)
    m, p = jac.shape
    along = q.T @ r
    return np.sqrt((along @ along / p) / (np.sum((r - q @ along) ** 2) / (m - p)))


@pytest.mark.parametrize("m", [3, 4, 7])
def test_relative_offset_against_the_textbook_formula(m):
    """Interior point: the relative offset with m residuals and 2 free parameters (m - 2 dof, 1 for m = 3)."""
    from ballimpact.fitting import _relative_offset

    rng = np.random.default_rng(3)
    jac, r = rng.normal(size=(m, 2)), rng.normal(size=m)
    got = _relative_offset(jac[None], r[None], np.zeros((1, 2)), np.full((1, 2), -1.0), np.full((1, 2), 1.0))
    assert_allclose(got, [_offset_by_qr(jac, r)], rtol=1e-9)


def test_relative_offset_of_a_batch_is_each_problems_own():
    """Three problems of different size of residuals in one batch: each gets the offset it has alone."""
    from ballimpact.fitting import _relative_offset

    rng = np.random.default_rng(5)
    jac, r = rng.normal(size=(3, 6, 2)), rng.normal(size=(3, 6)) * np.array([[0.1], [1.0], [30.0]])
    got = _relative_offset(jac, r, np.zeros((3, 2)), np.full((3, 2), -1.0), np.full((3, 2), 1.0))
    assert_allclose(got, [_offset_by_qr(j, ri) for j, ri in zip(jac, r)], rtol=1e-9)


def test_stage_two_started_at_the_optimum_stays_there():
    """Noise-free COR of AC = 5e4 N s/m^3 (inside the search bounds 1e1-1e5): started there, the fit returns it."""
    _, cor = _model(P.ak, P.a, 5.0e4)
    fit = fit_restitution(VIN, cor, MASS, P.kb0_N_m, P.ak, P.a, ac_start=5.0e4)
    assert_allclose(fit.ac, 5.0e4, rtol=1e-12)


def test_relative_offset_leaves_out_a_parameter_held_on_its_bound():
    """A parameter on its lower bound with the cost falling outward (J'r > 0) is not in the plane."""
    from ballimpact.fitting import _relative_offset

    rng = np.random.default_rng(4)
    jac, r = rng.normal(size=(6, 2)), rng.normal(size=6)
    if jac[:, 0] @ r < 0:
        jac[:, 0] = -jac[:, 0]
    lo, hi = np.array([[0.0, -1.0]]), np.array([[1.0, 1.0]])
    got = _relative_offset(jac[None], r[None], np.array([[0.0, 0.0]]), lo, hi)
    assert_allclose(got, [_offset_by_qr(jac[:, 1:], r)], rtol=1e-9)
    # off the bound, both parameters count
    got = _relative_offset(jac[None], r[None], np.array([[0.5, 0.0]]), lo, hi)
    assert_allclose(got, [_offset_by_qr(jac, r)], rtol=1e-9)


@pytest.mark.parametrize("call", ["stage one", "stage two", "joint"])
def test_a_fit_that_runs_out_of_evaluations_raises_with_the_documented_message(call, monkeypatch):
    """The optimiser allowed one evaluation from a far start cannot converge: FitError naming the fit."""
    from scipy import optimize

    import ballimpact.fitting as fitting

    real = optimize.least_squares
    monkeypatch.setattr(fitting.optimize, "least_squares", lambda *a, **kw: real(*a, **{**kw, "max_nfev": 1}))
    tc, cor = _model(P.ak, P.a, P.ac)
    with pytest.raises(fitting.FitError) as err:
        if call == "stage one":
            fitting.fit_contact_time(VIN, tc, MASS, P.kb0_N_m, start=(1e6, 1.0))
        elif call == "stage two":
            fitting.fit_restitution(VIN, cor, MASS, P.kb0_N_m, P.ak, P.a, ac_start=300.0)
        else:
            fitting._fit_weighted(VIN, tc, cor, MASS, P.kb0_N_m, THETA + [1.0, 0.5, 1.0], 1.0, 1.0, "joint fit")
    what = {"stage one": r"stage one \(AK, a on contact time\)", "stage two": r"stage two \(AC on COR\)",
            "joint": "joint fit"}[call]
    assert re.fullmatch(rf"{what}: the optimiser did not converge \(The maximum number of function "
                        r"evaluations is exceeded\.\)", str(err.value))
