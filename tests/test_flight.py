"""Ball flight with drag and gravity: closed forms against analytic cases and a numerical integration."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from ballimpact import flight

K = 0.0192  # [1/m] a tennis ball in air (rho 1.2, Cd 0.55, D 65.4 mm, m 57.7 g)
G = 9.81


def _integrate(v0, distance, k, g_along, *, max_time=10.0):
    """Speed and time after `distance` by solve_ivp at tight tolerance: dv/dt = g_s - k v^2, ds/dt = v."""

    def rhs(t, y):
        return [y[1], g_along - k * y[1] * abs(y[1])]

    def arrive(t, y):
        return y[0] - distance

    arrive.terminal = True
    arrive.direction = 1
    sol = solve_ivp(rhs, (0.0, max_time), [0.0, v0], method="DOP853", rtol=1e-12, atol=1e-13,
                    events=arrive)
    assert sol.t_events[0].size == 1, "the ball did not reach the distance"
    return sol.y_events[0][0][1], sol.t_events[0][0]


def test_drag_constant_from_its_definition():
    # k = rho Cd pi D^2 / 8 m, by hand for the defaults and a 57.7 g ball
    expected = 1.2 * 0.55 * math.pi * 0.0654**2 / 4 / (2 * 0.0577)
    assert_allclose(flight.drag_constant(0.0577), expected, rtol=1e-12)
    assert 0.018 < expected < 0.020  # about 2 % of speed per metre, as the issue says
    assert flight.drag_constant(0.0577, air_density_kg_m3=0.0) == 0.0


@pytest.mark.parametrize("v0", [3.0, 7.0, 20.0, 40.0])
@pytest.mark.parametrize("s", [0.05, 0.3, 1.0])
def test_horizontal_speed_decays_exponentially_with_distance(v0, s):
    # analytic: m dv/dt = -k m v^2  =>  v dv/ds = -k v^2  =>  v(s) = v0 exp(-k s), t = (e^{ks} - 1) / (k v0)
    assert_allclose(flight.speed_after(v0, s, K), v0 * math.exp(-K * s), rtol=1e-13)
    assert_allclose(flight.flight_time(v0, s, K), (math.exp(K * s) - 1) / (K * v0), rtol=1e-12)
    assert_allclose(flight.speed_before(v0 * math.exp(-K * s), s, K), v0, rtol=1e-12)


@pytest.mark.parametrize("g_along", [0.0, G, -G])
@pytest.mark.parametrize("v0", [4.0, 12.0, 30.0])
def test_speed_and_time_match_numerical_integration(g_along, v0):
    s = 0.35 if g_along >= 0 else 0.3
    v_num, t_num = _integrate(v0, s, K, g_along)
    assert_allclose(flight.speed_after(v0, s, K, g_along), v_num, rtol=1e-9)
    assert_allclose(flight.flight_time(v0, s, K, g_along), t_num, rtol=1e-9)
    assert_allclose(flight.speed_before(v_num, s, K, g_along), v0, rtol=1e-9)


def test_falling_faster_than_terminal_speed_matches_integration():
    # fired down at 40 m/s, above the terminal speed sqrt(g/k) = 22.6 m/s: the ball slows down
    v_num, t_num = _integrate(40.0, 0.5, K, G)
    assert v_num < 40.0
    assert_allclose(flight.speed_after(40.0, 0.5, K, G), v_num, rtol=1e-9)
    assert_allclose(flight.flight_time(40.0, 0.5, K, G), t_num, rtol=1e-9)


def test_without_drag_free_fall_is_recovered():
    # v^2 = v0^2 + 2 g s, t = (v - v0) / g
    assert_allclose(flight.speed_after(0.0, 2.54, 0.0, G), math.sqrt(2 * G * 2.54), rtol=1e-13)
    assert_allclose(flight.flight_time(5.0, 1.0, 0.0, G), (math.sqrt(25 + 2 * G) - 5.0) / G, rtol=1e-12)
    assert_allclose(flight.rise_height(7.0, 0.0), 49 / (2 * G), rtol=1e-13)
    assert_allclose(flight.speed_to_rise(1.389, 0.0), math.sqrt(2 * G * 1.389), rtol=1e-13)


def test_rise_height_matches_integration_to_the_apex():
    v0 = 5.3

    def rhs(t, y):
        return [y[1], -G - K * y[1] * abs(y[1])]

    def apex(t, y):
        return y[1]

    apex.terminal = True
    sol = solve_ivp(rhs, (0, 5), [0.0, v0], method="DOP853", rtol=1e-12, atol=1e-13, events=apex)
    h_num = sol.y_events[0][0][0]
    assert_allclose(flight.rise_height(v0, K), h_num, rtol=1e-9)
    assert_allclose(flight.speed_to_rise(h_num, K), v0, rtol=1e-9)
    assert math.isnan(flight.speed_after(v0, h_num * 1.01, K, -G))  # it never gets there


@pytest.mark.parametrize("g_along", [0.0, G, -G])
def test_entry_speed_inverts_flight_time(g_along):
    v0 = np.array([6.0, 15.0, 33.0])
    t = np.array([_integrate(v, 0.1, K, g_along)[1] for v in v0])
    assert_allclose(flight.entry_speed(t, 0.1, K, g_along), v0, rtol=1e-9)
    assert np.isnan(flight.entry_speed(np.nan, 0.1, K, g_along))


@pytest.mark.parametrize("orientation, g_in, g_out", [("horizontal", 0.0, 0.0), ("vertical", G, -G)])
def test_plate_speeds_invert_a_simulated_flight(orientation, g_in, g_out):
    # Simulate the whole flight numerically: gate 1 -> gate 2 -> plate, then plate -> gate 2 -> gate 1.
    L, d, D = 0.1, 0.25, 0.0654
    vin_plate, vout_plate = 22.0, 14.0
    # inbound: find the speed at gate 1 that arrives at vin_plate, by integrating backwards
    v_g1 = flight.speed_before(vin_plate, L + d, K, g_in)
    t_in = _integrate(v_g1, L, K, g_in)[1]
    # rebound: times at gate 2 and gate 1 from the plate
    t2 = _integrate(vout_plate, d - D, K, g_out)[1]
    t1 = _integrate(vout_plate, d - D + L, K, g_out)[1]
    vin, vout = flight.plate_speeds(L / t_in, L / (t1 - t2), L, d, K, orientation=orientation, diameter_m=D)
    assert_allclose([vin, vout], [vin_plate, vout_plate], rtol=1e-9)
    # and the gate speeds alone are off by about 1 % in COR
    cor_gate = (L / (t1 - t2)) / (L / t_in)
    assert 0.005 < vout_plate / vin_plate - cor_gate < 0.02


def test_plate_speeds_horizontal_closed_form():
    L, d, D, k = 0.1, 0.25, 0.0654, K
    vin, vout = flight.plate_speeds(20.0, 12.0, L, d, k, diameter_m=D)
    assert_allclose(vin, 20.0 * (1 - math.exp(-k * L)) / (k * L) * math.exp(-k * d), rtol=1e-12)
    assert_allclose(vout, 12.0 * (math.exp(k * L) - 1) / (k * L) * math.exp(k * (d - D)), rtol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    ({"orientation": "sideways"}, "orientation must be"),
    ({"diameter_m": 0.3}, "must exceed the ball diameter"),
    ({"diameter_m": -1.0}, "diameter_m must be positive"),
])
def test_plate_speeds_rejects_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        flight.plate_speeds(20.0, 12.0, 0.1, 0.25, K, **kwargs)


@pytest.mark.parametrize("func, args, match", [
    (flight.drag_constant, (-0.05,), "mass_kg must be positive"),
    (flight.speed_after, (-1.0, 1.0, K), "v0_m_s must be non-negative"),
    (flight.flight_time, (0.0, 1.0, K), "v0_m_s must be positive"),
    (flight.rise_height, (5.0, -K), "k_per_m must be non-negative"),
    (flight.entry_speed, (-0.01, 0.1, K), "interval_s must be positive"),
])
def test_bad_arguments_are_rejected(func, args, match):
    with pytest.raises(ValueError, match=match):
        func(*args)
