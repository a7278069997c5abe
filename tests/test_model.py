"""The ball model against the paper's own statements, analytic cases and the spec's sanity figures."""

import numpy as np
import pytest
from numpy.testing import assert_allclose
import reference_model
from reference_model import reference_impact

from ballimpact.balls import BALLS
from ballimpact.model import (
    contact_diameter,
    kelvin_voigt_parameters,
    material_damping,
    momentum_flux_damping,
    simulate_impact,
    simulate_kelvin_voigt,
    structural_stiffness,
)


def _sim(ball, vin, **kw):
    p = BALLS[ball].params
    return simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, **kw)


def test_contact_diameter_close_to_geometric_chord():
    # Eq. (5) against the chord 2 sqrt(2 R x - x^2) of a sphere of radius 33 mm; the
    # measured relation (Fig. 3b) lies below the chord at small x, near it at 10-15 mm
    x = np.array([10e-3, 15e-3])
    chord = 2 * np.sqrt(2 * 0.033 * x - x**2)
    assert_allclose(contact_diameter(x), chord, rtol=0.05)
    assert contact_diameter(0.0) == 0.0
    assert contact_diameter(-1e-3) == 0.0


def test_material_damping_is_area_law():
    x = 0.01
    assert_allclose(material_damping(x, 3500.0), 3500.0 * contact_diameter(x) ** 2, rtol=1e-12)


def test_readme_check_values_ball1_20ms():
    # docs/accuracy.md / docs/model.md print TC 3.72 ms, COR 0.631, peak 844 N, largest displacement
    # 18.6 mm for ball 1 at 20 m/s: each must hold to the rounding of the printed figure
    # (half a unit of its last digit).
    r = _sim("pressurised", 20.0)
    assert_allclose(r.contact_time_s * 1e3, 3.72, rtol=0, atol=0.005)
    assert_allclose(r.cor, 0.631, rtol=0, atol=0.0005)
    assert_allclose(r.peak_force_N, 844.0, rtol=0, atol=0.5)
    assert_allclose(r.max_displacement_m * 1e3, 18.6, rtol=0, atol=0.05)


# Against tests/reference_model.py, a plain scalar loop written from docs/model.md that
# shares no code with simulate_impact. The same arithmetic in a different order: the
# measured largest relative difference over these 28 impacts is 2.4e-14 (COR); the
# tolerance 1e-10 leaves room for another libm's pow, and a change of one ulp-level
# operation order, but not for any change of the physics (a 1e-6 change of AK moves TC
# by ~4e-7).
REFERENCE_RTOL = 1e-10


@pytest.mark.parametrize("ball", ["pressurised", "pressureless", "oversize", "punctured"])
@pytest.mark.parametrize("vin", [3.0, 5.0, 10.0, 14.0, 20.0, 25.0, 30.0])
def test_matches_independent_scalar_reference(ball, vin):
    p = BALLS[ball].params
    ref = reference_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    r = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    assert_allclose(r.contact_time_s, ref["tc"], rtol=REFERENCE_RTOL)
    assert_allclose(r.cor, ref["cor"], rtol=REFERENCE_RTOL)
    assert_allclose(r.rebound_speed_m_s, ref["vout"], rtol=REFERENCE_RTOL)
    assert_allclose(r.peak_force_N, ref["peak"], rtol=REFERENCE_RTOL)
    assert_allclose(r.time_to_peak_s, ref["t_peak"], rtol=REFERENCE_RTOL)
    assert_allclose(r.max_displacement_m, ref["xmax"], rtol=REFERENCE_RTOL)


@pytest.mark.parametrize("kw, ref_kw", [
    (dict(dt_s=5e-6), dict(dt=5e-6)),
    (dict(cloth_stiffness_N_m=2.0e4), dict(cloth_k=2.0e4)),
])
def test_matches_reference_with_options(kw, ref_kw):
    p = BALLS["oversize"].params
    ref = reference_impact(22.0, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, **ref_kw)
    r = simulate_impact(22.0, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, **kw)
    got = [r.contact_time_s, r.cor, r.peak_force_N, r.max_displacement_m]
    assert_allclose(got, [ref["tc"], ref["cor"], ref["peak"], ref["xmax"]], rtol=REFERENCE_RTOL)


@pytest.mark.parametrize("ball", ["pressurised", "punctured"])
def test_momentum_flux_dominates_first_06_ms(ball):
    # Section 5 / Fig. 10: the momentum flux is the main component for t < ~0.6 ms,
    # the structural stiffness at the largest displacement.
    r = _sim(ball, 20.0, record=True)
    t = r.time_s
    fm, fs, fd = r.momentum_flux_force_N, r.stiffness_force_N, r.damping_force_N
    loaded = (t > 0.12e-3) & (t < 0.45e-3)  # after the cloth phase (x > 2 mm at 20 m/s)
    assert np.all(fm[loaded] > fs[loaded]) and np.all(fm[loaded] > fd[loaded])
    late = (t > 0.8e-3) & (t < 1.2e-3)
    assert np.all(fm[late] < fs[late])
    i = np.nanargmax(r.displacement_m)
    assert fs[i] > fd[i] and fs[i] > fm[i]
    # the crossover lies near 0.6 ms
    cross = t[np.argmax((t > 0.2e-3) & (fs > fm))]
    assert 0.4e-3 < cross < 0.8e-3


def test_momentum_flux_similar_for_stiffest_and_softest_ball():
    # Fig. 10: the flux components of balls 1 and 4 are "very similar" early on
    r1 = _sim("pressurised", 20.0, record=True)
    r4 = _sim("punctured", 20.0, record=True)
    n = min(r1.time_s.size, r4.time_s.size)
    early = (r1.time_s[:n] > 0.25e-3) & (r1.time_s[:n] < 0.5e-3)
    assert_allclose(r1.momentum_flux_force_N[:n][early], r4.momentum_flux_force_N[:n][early], rtol=0.1)


def test_stiffness_order_as_fig8():
    x = np.array([2e-3, 20e-3])
    k = {b: structural_stiffness(x, BALLS[b].params.kb0_N_m, BALLS[b].params.ak, BALLS[b].params.a) for b in BALLS}
    # at large displacement ball 1 is stiffest, ball 3 next, balls 2 and 4 similar and lowest
    assert k["pressurised"][1] > k["oversize"][1] > max(k["pressureless"][1], k["punctured"][1])
    assert_allclose(k["pressureless"][1], k["punctured"][1], rtol=0.05)
    # at small displacement the punctured ball is the least stiff, the pressureless one high
    assert k["punctured"][0] == min(v[0] for v in k.values())
    assert k["pressureless"][0] == max(v[0] for v in k.values())


def test_linear_spring_has_analytic_period():
    # No cloth, no buckling, no damping, no momentum flux, AK = 0: a linear spring,
    # TC = pi sqrt(m/k) and COR = 1 (to the accuracy of the central difference).
    m, k, vin = 0.0577, 40e3, 20.0
    r = simulate_impact(vin, m, k, 0.0, 1.0, 0.0, cloth_displacement_m=0.0, buckling_time_s=0.0,
                        rho_area_kg_m2=0.0, dt_s=1e-6)
    assert_allclose(r.contact_time_s, np.pi * np.sqrt(m / k), rtol=2e-3)
    assert_allclose(r.cor, 1.0, atol=2e-3)
    assert_allclose(r.max_displacement_m, vin * np.sqrt(m / k), rtol=1e-3)
    assert_allclose(r.peak_force_N, vin * np.sqrt(m * k), rtol=1e-3)


def test_vectorised_equals_one_by_one():
    p = BALLS["oversize"].params
    vin = np.array([14.0, 19.0, 26.0, 30.0])
    ak = np.array([3000e3, 3600e3, 4000e3, 3600e3])
    batch = simulate_impact(vin, p.mass_kg, p.kb0_N_m, ak, p.a, p.ac)
    for i in range(vin.size):
        one = simulate_impact(vin[i], p.mass_kg, p.kb0_N_m, ak[i], p.a, p.ac)
        assert_allclose(batch.contact_time_s[i], one.contact_time_s, rtol=1e-12)
        assert_allclose(batch.cor[i], one.cor, rtol=1e-12)
        assert_allclose(batch.peak_force_N[i], one.peak_force_N, rtol=1e-12)


def test_impacts_ending_at_different_steps_equal_one_by_one():
    # ended impacts stay in the arrays, marked, until they are a quarter of them: a batch
    # of 24 whose impacts end over ~100 steps gives each impact's own simulation
    rng = np.random.default_rng(5)
    p = BALLS["pressurised"].params
    vin = rng.uniform(3.0, 35.0, 24)
    ak, a, ac = p.ak * rng.uniform(0.7, 1.3, 24), p.a * rng.uniform(0.9, 1.1, 24), p.ac * rng.uniform(0.5, 1.5, 24)
    batch = simulate_impact(vin, p.mass_kg, p.kb0_N_m, ak, a, ac)
    for i in range(vin.size):
        one = simulate_impact(vin[i], p.mass_kg, p.kb0_N_m, ak[i], a[i], ac[i])
        for key in ("contact_time_s", "rebound_speed_m_s", "peak_force_N", "time_to_peak_s", "max_displacement_m"):
            assert_allclose(getattr(batch, key)[i], getattr(one, key), rtol=1e-12, err_msg=key)


def test_unended_impacts_beside_an_ended_one():
    # one impact of eight ends (still marked in the arrays when the others run out of time)
    p = BALLS["pressurised"].params
    kb0 = np.array([10.0] * 7 + [p.kb0_N_m])
    ak = np.array([0.0] * 7 + [p.ak])
    with pytest.warns(RuntimeWarning, match="7 simulated impact"):
        r = simulate_impact(20.0, p.mass_kg, kb0, ak, p.a, 0.0)
    one = simulate_impact(20.0, p.mass_kg, p.kb0_N_m, p.ak, p.a, 0.0)
    assert np.isnan(r.contact_time_s[:7]).all() and np.isnan(r.cor[:7]).all()
    assert_allclose(r.contact_time_s[7], one.contact_time_s, rtol=1e-12)
    assert_allclose(r.cor[7], one.cor, rtol=1e-12)
    with pytest.warns(RuntimeWarning, match="1 simulated impact"):
        soft = simulate_impact(20.0, p.mass_kg, 10.0, 0.0, p.a, 0.0)
    assert_allclose(r.max_displacement_m[:7], soft.max_displacement_m, rtol=1e-12)
    assert_allclose(r.peak_force_N[:7], soft.peak_force_N, rtol=1e-12)


def test_broadcast_shape():
    p = BALLS["pressurised"].params
    r = simulate_impact(np.array([[15.0], [25.0]]), p.mass_kg, p.kb0_N_m, np.array([1e7, 1.6e7, 2e7]), p.a, p.ac)
    assert r.contact_time_s.shape == (2, 3)
    # stiffer balls have shorter contacts, faster impacts too
    assert np.all(np.diff(r.contact_time_s, axis=1) < 0)
    assert np.all(np.diff(r.contact_time_s, axis=0) < 0)


def test_contact_time_and_cor_are_smooth_in_parameters():
    # model.md pitfall: without an interpolated end, TC moves in steps of dt
    p = BALLS["pressurised"].params
    ak = p.ak * (1 + np.linspace(0, 1e-3, 11))
    r = simulate_impact(20.0, p.mass_kg, p.kb0_N_m, ak, p.a, p.ac)
    dtc = np.diff(r.contact_time_s)
    assert np.all(dtc < 0)  # strictly monotone: no flat steps
    assert np.ptp(dtc) < 0.5 * abs(np.mean(dtc))  # and nearly linear at this scale
    ac = p.ac * (1 + np.linspace(0, 1e-3, 11))
    e = simulate_impact(20.0, p.mass_kg, p.kb0_N_m, p.ak, p.a, ac).cor
    assert np.all(np.diff(e) < 0)


def test_cor_decreases_with_speed_and_damping():
    r = _sim("pressurised", np.linspace(14, 30, 5))
    assert np.all(np.diff(r.cor) < 0)
    assert np.all((r.cor > 0) & (r.cor < 1))


def test_time_step_convergence():
    coarse = _sim("pressureless", 22.0)
    fine = _sim("pressureless", 22.0, dt_s=2.5e-6)
    assert_allclose(coarse.contact_time_s, fine.contact_time_s, rtol=0.01)
    assert_allclose(coarse.cor, fine.cor, rtol=0.02)


def test_kelvin_voigt_parameters_eqs_2_3():
    kb, cb = kelvin_voigt_parameters(0.0577, 4e-3, 0.7)
    assert_allclose(kb, 0.0577 * np.pi**2 / 16e-6, rtol=1e-12)
    assert_allclose(cb, -2 * 0.0577 * np.log(0.7) / 4e-3, rtol=1e-12)


def test_kelvin_voigt_tensile_force_near_end():
    # Fig. 2b: with constant kB and cB the force turns tensile in the last part of contact
    r = _sim("pressurised", 28.0)
    m = BALLS["pressurised"].params.mass_kg
    kb, cb = kelvin_voigt_parameters(m, r.contact_time_s, r.cor)
    t = np.linspace(0, 1.2 * r.contact_time_s, 4000)
    x, v, f = simulate_kelvin_voigt(t, 28.0, m, kb, cb)
    inside = np.isfinite(f)
    tensile = t[inside & (f < 0)]
    assert tensile.size > 0
    t_end = t[inside][-1]
    assert tensile.min() > 0.5 * t_end  # only near the end
    assert (t_end - tensile.min()) < 0.3 * t_end
    # displacement is zero at start and end, velocity starts at vin
    assert_allclose(x[0], 0.0, atol=1e-12)
    assert_allclose(v[0], 28.0, rtol=1e-12)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"vin_m_s": -1.0}, r"^vin_m_s must be positive and finite, got -1.0$"),
        ({"mass_kg": 0.0}, r"^mass_kg must be positive and finite, got 0.0$"),
        ({"a": np.nan}, r"^a must be positive and finite, got nan$"),
        ({"ak": -5.0}, r"^ak must be non-negative and finite, got -5.0$"),
        ({"kb0_N_m": -1.0}, r"^kb0_N_m must be non-negative and finite, got -1.0$"),
        ({"ac": -1.0}, r"^ac must be non-negative and finite, got -1.0$"),
        ({"dt_s": 0.0}, r"^dt_s must be positive, got 0.0$"),
        ({"max_contact_time_s": 0.0}, r"^max_contact_time_s must be positive, got 0.0$"),
        # the first bad element of an array is named
        ({"vin_m_s": np.array([20.0, 0.0, -3.0])}, r"^vin_m_s must be positive and finite, got 0.0$"),
        ({"vin_m_s": np.array([0.5, -3.0])}, r"^vin_m_s must be positive and finite, got -3.0$"),
        ({"ak": np.array([1.0, 0.0, -2.0, -3.0])}, r"^ak must be non-negative and finite, got -2.0$"),
        ({"ak": np.array([0.5, -2.0])}, r"^ak must be non-negative and finite, got -2.0$"),
    ],
)
def test_simulate_validates_arguments(kwargs, match):
    args = dict(vin_m_s=20.0, mass_kg=0.0577, kb0_N_m=21e3, ak=16e6, a=1.65, ac=3.5e3)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        simulate_impact(**args)


def test_unended_impact_warns_and_gives_nan():
    with pytest.warns(RuntimeWarning, match="did not end"):
        r = simulate_impact(20.0, 0.0577, 10.0, 0.0, 1.0, 0.0, max_contact_time_s=2e-3)
    assert np.isnan(r.contact_time_s)


# Cases found by mutation testing (`make mutation`, docs/mutation-testing.md).


def test_momentum_flux_damping_eq_13():
    # Eq. (13) written out with the reference's Eq. (5): cM = m rho pi (d^2 - d_prev^2) / (4 dt M1),
    # M1 = m - rho pi d^2 / 4
    m, dt, x, x_prev = 0.0577, 1e-5, 8e-3, 7.8e-3
    d, dp = reference_model.d_cont(x), reference_model.d_cont(x_prev)
    m1 = m - 5.212 * np.pi * d**2 / 4
    expected = m * 5.212 * np.pi * (d**2 - dp**2) / (4 * dt * m1)
    assert_allclose(momentum_flux_damping(x, x_prev, dt, m), expected, rtol=1e-12)
    assert_allclose(momentum_flux_damping(np.array([x, 2e-3]), np.array([x_prev, 1.9e-3]), dt, m, rho_area_kg_m2=4.0),
                    [m * 4.0 * np.pi * (d**2 - dp**2) / (4 * dt * (m - 4.0 * np.pi * d**2 / 4)),
                     m * 4.0 * np.pi * (reference_model.d_cont(2e-3) ** 2 - reference_model.d_cont(1.9e-3) ** 2)
                     / (4 * dt * (m - 4.0 * np.pi * reference_model.d_cont(2e-3) ** 2 / 4))], rtol=1e-12)


def test_eq_4_and_5_against_reference():
    x = np.array([-1e-3, 0.0, 1e-3, 10e-3, 20e-3])
    assert_allclose(contact_diameter(x), [reference_model.d_cont(v) for v in x], rtol=1e-13, atol=0)
    p = BALLS["pressurised"].params
    assert_allclose(structural_stiffness(x, p.kb0_N_m, p.ak, p.a),
                    [p.kb0_N_m + p.ak * max(v, 0.0) ** p.a for v in x], rtol=1e-13)


def test_time_series_only_when_recorded():
    assert _sim("pressurised", 20.0).force_N is None
    r = _sim("pressurised", 20.0, record=True)
    assert r.force_N is not None and r.time_s.shape == r.force_N.shape


@pytest.mark.parametrize("name", ["mass_kg", "kb0_N_m", "ak", "a", "ac"])
def test_each_parameter_broadcasts(name):
    p = BALLS["pressurised"].params
    args = dict(vin_m_s=20.0, mass_kg=p.mass_kg, kb0_N_m=p.kb0_N_m, ak=p.ak, a=p.a, ac=p.ac)
    values = np.array([1.0, 1.1]) * args[name]
    batch = simulate_impact(**{**args, name: values})
    assert batch.contact_time_s.shape == (2,)
    for i, v in enumerate(values):
        one = simulate_impact(**{**args, name: v})
        assert_allclose(batch.contact_time_s[i], one.contact_time_s, rtol=1e-12)
        assert_allclose(batch.cor[i], one.cor, rtol=1e-12)


def test_max_contact_time_bounds_the_simulated_contact():
    # ball 1 at 20 m/s touches for 3.72 ms: simulated to the end with a 3.73 ms limit,
    # given up (NaN and a warning) with a limit shorter than the contact
    full = _sim("pressurised", 20.0)
    assert_allclose(_sim("pressurised", 20.0, max_contact_time_s=3.73e-3).contact_time_s, full.contact_time_s,
                    rtol=1e-12)
    with pytest.warns(RuntimeWarning, match="did not end within 3.7 ms"):
        assert np.isnan(_sim("pressurised", 20.0, max_contact_time_s=3.705e-3).contact_time_s)


def test_kelvin_voigt_parameters_edges_without_warnings():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kb, cb = kelvin_voigt_parameters(0.0577, np.array([0.0, 4e-3, 4e-3]), np.array([0.7, 0.0, -0.1]))
    assert kb[0] == np.inf and cb[1] == np.inf and np.isnan(cb[2])


def test_kelvin_voigt_solution_against_ode_solver():
    # Eq. (1) integrated numerically (scipy solve_ivp, tight tolerances) as independent truth
    from scipy.integrate import solve_ivp

    m, k, c, vin = 0.0577, 60e3, 12.0, 20.0
    zeta = c / (2 * np.sqrt(k * m))
    t_end = np.pi / (np.sqrt(k / m) * np.sqrt(1 - zeta**2))
    t = np.linspace(0, t_end, 201)
    sol = solve_ivp(lambda _, y: [y[1], -(c * y[1] + k * y[0]) / m], (0, t_end), [0.0, vin], t_eval=t,
                    rtol=1e-12, atol=1e-14, method="DOP853")
    x, v, f = simulate_kelvin_voigt(t, vin, m, k, c)
    assert_allclose(x, sol.y[0], rtol=0, atol=1e-9 * np.max(sol.y[0]))
    assert_allclose(v, sol.y[1], rtol=0, atol=1e-9 * vin)
    assert_allclose(f, k * sol.y[0] + c * sol.y[1], rtol=0, atol=1e-8 * k * np.max(sol.y[0]))
    # x returns to zero at pi / omega_d (the last point is still inside), NaN outside [0, pi / omega_d]
    assert_allclose(x[-1], 0.0, atol=1e-12)
    xo, vo, fo = simulate_kelvin_voigt(np.array([-1e-6, t_end * (1 + 1e-9)]), vin, m, k, c)
    assert np.all(np.isnan(xo)) and np.all(np.isnan(vo)) and np.all(np.isnan(fo))


@pytest.mark.parametrize("kwargs, match", [
    ({"vin_m_s": -1.0}, r"^vin_m_s must be positive"),
    ({"mass_kg": 0.0}, r"^mass_kg must be positive"),
    ({"kb_N_m": 0.0}, r"^kb_N_m must be positive"),
    ({"cb_N_s_m": -1.0}, r"^cb_N_s_m must be non-negative"),
    # critical damping c = 2 sqrt(k m) is not underdamped
    ({"cb_N_s_m": 2 * np.sqrt(60e3 * 0.0577)}, r"^cb_N_s_m=.* gives damping ratio 1.000 >= 1 \(not underdamped\)$"),
    ({"cb_N_s_m": 1.5 * 2 * np.sqrt(60e3 * 0.0577)}, r"gives damping ratio 1.500 >= 1"),
])
def test_simulate_kelvin_voigt_validates(kwargs, match):
    args = dict(time_s=np.linspace(0, 1e-3, 5), vin_m_s=20.0, mass_kg=0.0577, kb_N_m=60e3, cb_N_s_m=10.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        simulate_kelvin_voigt(**args)


@pytest.mark.parametrize("cloth_k", [0.0, 2.0e4])
def test_recorded_series_match_reference(cloth_k):
    # two speeds in one call: the faster impact ends first, its columns are NaN after that
    p = BALLS["pressurised"].params
    vins = np.array([20.0, 12.0])
    r = simulate_impact(vins, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, cloth_stiffness_N_m=cloth_k, record=True)
    recorded = (r.displacement_m, r.velocity_m_s, r.force_N, r.stiffness_force_N, r.damping_force_N,
                r.momentum_flux_force_N)
    assert_allclose(r.time_s, np.arange(r.time_s.size) * 1e-5, rtol=1e-12)
    for j, vin in enumerate(vins):
        ref = np.array(reference_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, cloth_k=cloth_k)["series"])
        n = ref.shape[0]
        for k, got in enumerate(recorded):
            scale = np.max(np.abs(ref[:, k]))
            assert_allclose(got[:n, j], ref[:, k], rtol=0, atol=REFERENCE_RTOL * scale, err_msg=f"series {k}")
            assert np.all(np.isnan(got[n:, j]))


def test_result_shapes_follow_the_inputs():
    p = BALLS["oversize"].params
    vin = np.array([[15.0], [25.0]])
    ak = p.ak * np.array([0.9, 1.0, 1.1])
    r = simulate_impact(vin, p.mass_kg, p.kb0_N_m, ak, p.a, p.ac, record=True)
    for name in ("contact_time_s", "rebound_speed_m_s", "cor", "peak_force_N", "time_to_peak_s",
                 "max_displacement_m"):
        assert getattr(r, name).shape == (2, 3), name
    n = r.time_s.size
    for name in ("displacement_m", "velocity_m_s", "force_N", "stiffness_force_N", "damping_force_N",
                 "momentum_flux_force_N"):
        assert getattr(r, name).shape == (n, 2, 3), name
    # the series end with the step that ends the longest contact: no all-NaN row
    assert np.isfinite(r.force_N[-1]).any()
    assert_allclose(np.nanmax(r.displacement_m, axis=0), r.max_displacement_m, rtol=1e-12)


def test_unended_warning_message():
    with pytest.warns(RuntimeWarning) as rec:
        simulate_impact(20.0, 0.0577, 10.0, 0.0, 1.0, 0.0, max_contact_time_s=3.949e-3)
    assert str(rec[0].message) == ("1 simulated impact(s) did not end within 3.9 ms; their contact time and COR "
                                   "are NaN (parameters far outside the physical range?)")
