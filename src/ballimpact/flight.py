"""Ball flight in still air with quadratic drag and gravity: gate-to-plate speed correction and the ITF drop.

A ball of mass m and diameter D moving along a straight line through still air
obeys

    dv/dt = g_s - k v^2,   k = rho Cd A / (2 m),   A = pi D^2 / 4,

with g_s the component of gravity along the motion (+g falling, -g rising,
0 on a horizontal rig). With u = v^2 and s the distance travelled
(v dv/ds = dv/dt), du/ds = 2 g_s - 2 k u, which integrates exactly:

    v(s)^2 = g_s/k + (v0^2 - g_s/k) exp(-2 k s)           (drag and gravity)
    v(s)   = v0 exp(-k s)                                  (horizontal, g_s = 0)

and the flight time t(s) = integral ds / v has closed forms too (below). These
are not in Goodwill & Haake (2004), who took the gate speeds as the speeds at the
plate; the flight model is the standard one for a sphere at constant drag
coefficient (e.g. Cross & Lindsey, Physics Teacher 2014; Cd ~ 0.55 for a tennis
ball at Re ~ 1e5). Lift (spin) and the crosswise drop on a horizontal rig are
neglected (a few 1e-5 of the speed over the gate distances).
"""

from __future__ import annotations

import math

import numpy as np

from ._checks import nonnegative_array as _nonnegative, positive_array as _positive

__all__ = [
    "G_M_S2",
    "AIR_DENSITY_KG_M3",
    "DRAG_COEFFICIENT",
    "BALL_DIAMETER_M",
    "drag_constant",
    "speed_after",
    "speed_before",
    "flight_time",
    "entry_speed",
    "rise_height",
    "speed_to_rise",
    "plate_speeds",
]

#: Acceleration of gravity g [m/s^2].
G_M_S2 = 9.81
#: Default density of air rho [kg/m^3] (about 20 C at sea level); ``rig.air_density_kg_m3``.
AIR_DENSITY_KG_M3 = 1.2
#: Drag coefficient Cd of a tennis ball [-], taken constant over 3-40 m/s.
DRAG_COEFFICIENT = 0.55
#: Default ball diameter D [m] (ITF: 6.54-6.86 cm); ``balls.<key>.diameter_mm``.
BALL_DIAMETER_M = 0.0654
_ORIENTATIONS = ("horizontal", "vertical")


def _finite(name, value):
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


def _out(value):
    return float(value) if np.ndim(value) == 0 else value


def drag_constant(mass_kg, diameter_m=BALL_DIAMETER_M, air_density_kg_m3=AIR_DENSITY_KG_M3,
                  drag_coefficient=DRAG_COEFFICIENT):
    """Drag constant k = rho Cd (pi D^2 / 4) / (2 m) of a ball in flight.

    Parameters
    ----------
    mass_kg : float or array_like
        Ball mass m [kg].
    diameter_m : float or array_like
        Ball diameter D [m].
    air_density_kg_m3 : float
        Air density rho [kg/m^3]; 0 switches drag off.
    drag_coefficient : float
        Drag coefficient Cd [-].

    Returns
    -------
    float or numpy.ndarray
        k [1/m]: the relative speed lost per metre of horizontal flight.
    """
    m = _positive("mass_kg", mass_kg)
    d = _positive("diameter_m", diameter_m)
    rho = _nonnegative("air_density_kg_m3", air_density_kg_m3)
    cd = _nonnegative("drag_coefficient", drag_coefficient)
    return _out(rho * cd * np.pi * d**2 / 4.0 / (2.0 * m))


def speed_after(v0_m_s, distance_m, k_per_m, gravity_m_s2=0.0):
    """Speed after travelling a distance along a straight line with drag and gravity.

    v(s)^2 = g_s/k + (v0^2 - g_s/k) exp(-2 k s); for k = 0, v^2 = v0^2 + 2 g_s s.

    Parameters
    ----------
    v0_m_s : float or array_like
        Speed at s = 0 [m/s], >= 0.
    distance_m : float or array_like
        Distance travelled s [m], >= 0.
    k_per_m : float or array_like
        Drag constant k [1/m] (:func:`drag_constant`), >= 0.
    gravity_m_s2 : float
        Component of gravity along the motion g_s [m/s^2]: +9.81 falling, -9.81
        rising, 0 horizontal.

    Returns
    -------
    float or numpy.ndarray
        Speed v(s) [m/s]; NaN where a rising ball stops before s.
    """
    v0 = _nonnegative("v0_m_s", v0_m_s)
    s = _nonnegative("distance_m", distance_m)
    k = _nonnegative("k_per_m", k_per_m)
    g = _finite("gravity_m_s2", gravity_m_s2)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # (1 - exp(-2ks)) / k, finite as k -> 0 (= 2 s)
        two_s_eff = np.where(k > 0, -np.expm1(-2.0 * k * s) / np.where(k > 0, k, 1.0), 2.0 * s)
        u = v0**2 * np.exp(-2.0 * k * s) + g * two_s_eff
        v = np.where(u >= 0, np.sqrt(np.maximum(u, 0.0)), np.nan)
    return _out(v)


def speed_before(v_m_s, distance_m, k_per_m, gravity_m_s2=0.0):
    """Speed a distance earlier on the same flight: the inverse of :func:`speed_after`.

    v0^2 = g_s/k + (v^2 - g_s/k) exp(+2 k s).

    Parameters
    ----------
    v_m_s : float or array_like
        Speed after the distance [m/s], >= 0.
    distance_m : float or array_like
        Distance travelled s [m], >= 0.
    k_per_m : float or array_like
        Drag constant k [1/m], >= 0.
    gravity_m_s2 : float
        Component of gravity along the motion [m/s^2] (as in :func:`speed_after`).

    Returns
    -------
    float or numpy.ndarray
        Speed at the start [m/s]; NaN where no start speed gives v (a falling ball
        slower than v over a short distance from rest).
    """
    v = _nonnegative("v_m_s", v_m_s)
    s = _nonnegative("distance_m", distance_m)
    k = _nonnegative("k_per_m", k_per_m)
    g = _finite("gravity_m_s2", gravity_m_s2)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        two_s_eff = np.where(k > 0, np.expm1(2.0 * k * s) / np.where(k > 0, k, 1.0), 2.0 * s)
        u0 = v**2 * np.exp(2.0 * k * s) - g * two_s_eff
        v0 = np.where(u0 >= 0, np.sqrt(np.maximum(u0, 0.0)), np.nan)
    return _out(v0)


def flight_time(v0_m_s, distance_m, k_per_m, gravity_m_s2=0.0):
    """Time to travel a distance along a straight line with drag and gravity.

    t(s) = integral_0^s ds' / v(s'), in closed form with w = v(s), w0 = v0:

    * g_s = 0:        t = (exp(k s) - 1) / (k v0)
    * k = 0:          t = (w - w0) / g_s              (s / v0 when g_s = 0 too)
    * g_s > 0 (fall): t = [artanh(w/c) - artanh(w0/c)] / (k c), c = sqrt(g_s/k)
      the terminal speed (artanh(c/w) when w > c: faster than terminal);
    * g_s < 0 (rise): t = [arctan(w0/c) - arctan(w/c)] / (k c), c = sqrt(|g_s|/k).

    Parameters
    ----------
    v0_m_s : float or array_like
        Speed at s = 0 [m/s], > 0.
    distance_m : float or array_like
        Distance s [m], >= 0.
    k_per_m : float or array_like
        Drag constant k [1/m], >= 0.
    gravity_m_s2 : float
        Component of gravity along the motion [m/s^2].

    Returns
    -------
    float or numpy.ndarray
        Flight time [s]; NaN where a rising ball stops before s.
    """
    v0 = _positive("v0_m_s", v0_m_s)
    s = _nonnegative("distance_m", distance_m)
    k = _nonnegative("k_per_m", k_per_m)
    g = _finite("gravity_m_s2", gravity_m_s2)
    v0, s, k = np.broadcast_arrays(v0, s, k)
    w = np.asarray(speed_after(v0, s, k, g), dtype=float)
    t = np.full(v0.shape, np.nan)
    drag = k > 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        kk = np.where(drag, k, 1.0)
        if g == 0.0:
            t = np.where(drag, np.expm1(k * s) / (kk * v0), s / v0)
        else:
            c = np.sqrt(abs(g) / kk)
            if g > 0:
                def primitive(x):  # integral of dw / (c^2 - w^2), per unit 1/k handled below
                    r = x / c
                    return np.where(r < 1, np.arctanh(np.minimum(r, 1 - 1e-16)),
                                    np.arctanh(1.0 / np.maximum(r, 1 + 1e-16)))
                at_terminal = np.isclose(v0, c, rtol=1e-12, atol=0.0)
                t_drag = np.where(at_terminal, s / c, (primitive(w) - primitive(v0)) / (kk * c))
            else:
                t_drag = (np.arctan(v0 / c) - np.arctan(w / c)) / (kk * c)
            t_free = (w - v0) / g
            t = np.where(drag, t_drag, t_free)
        t = np.where(np.isfinite(w), t, np.nan)
    return _out(t)


def entry_speed(interval_s, length_m, k_per_m, gravity_m_s2=0.0, *, max_iter=30):
    """Speed at the start of a stretch of given length that the ball crossed in a given time.

    Solves flight_time(v0, L) = interval for v0: closed form without gravity,
    v0 = (exp(k L) - 1) / (k interval); with gravity by Newton's method from the
    mean speed L / interval (flight time falls monotonically with v0).

    Parameters
    ----------
    interval_s : float or array_like
        Time taken to cross the stretch [s], > 0 (NaN passes through).
    length_m : float
        Length of the stretch L [m], > 0 (the gate spacing).
    k_per_m : float or array_like
        Drag constant k [1/m], >= 0.
    gravity_m_s2 : float
        Component of gravity along the motion [m/s^2].
    max_iter : int
        Newton iterations at most.

    Returns
    -------
    float or numpy.ndarray
        v0 [m/s]; NaN where the interval is NaN or not reachable.
    """
    dt = np.asarray(interval_s, dtype=float)
    if np.any(dt[np.isfinite(dt)] <= 0):
        raise ValueError(f"interval_s must be positive, got {dt[np.isfinite(dt) & (dt <= 0)].ravel()[0]!r}")
    L = float(_positive("length_m", length_m))
    k = _nonnegative("k_per_m", k_per_m)
    g = _finite("gravity_m_s2", gravity_m_s2)
    dt, k = np.broadcast_arrays(dt, k)
    ok = np.isfinite(dt)
    dts = np.where(ok, dt, 1.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = np.where(k > 0, np.expm1(k * L) / (np.where(k > 0, k, 1.0) * dts), L / dts)
    if g != 0.0:
        for _ in range(max_iter):
            h = 1e-6 * v
            f = np.asarray(flight_time(v, L, k, g)) - dts
            df = (np.asarray(flight_time(v + h, L, k, g)) - np.asarray(flight_time(v - h, L, k, g))) / (2 * h)
            step = np.where(np.isfinite(f) & np.isfinite(df) & (df < 0), f / df, np.nan)
            v_new = np.where(np.isfinite(step), v - step, v * 1.05)  # a rising ball that stopped: go faster
            v_new = np.maximum(v_new, 0.5 * v)
            if np.all(np.abs(v_new - v) <= 1e-13 * v):
                v = v_new
                break
            v = v_new
        bad = np.abs(np.asarray(flight_time(v, L, k, g)) - dts) > 1e-9 * dts
        v = np.where(bad, np.nan, v)
    return _out(np.where(ok, v, np.nan))


def rise_height(v0_m_s, k_per_m, g_m_s2=G_M_S2):
    """Height a ball launched straight up reaches: h = ln(1 + k v0^2 / g) / (2 k) (v0^2 / 2g at k = 0).

    Parameters
    ----------
    v0_m_s : float or array_like
        Launch speed [m/s], >= 0.
    k_per_m : float or array_like
        Drag constant k [1/m], >= 0.
    g_m_s2 : float
        Gravity [m/s^2], > 0.

    Returns
    -------
    float or numpy.ndarray
        Rise height [m].
    """
    v0 = _nonnegative("v0_m_s", v0_m_s)
    k = _nonnegative("k_per_m", k_per_m)
    g = float(_positive("g_m_s2", g_m_s2))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(k > 0, np.log1p(k * v0**2 / g) / (2.0 * np.where(k > 0, k, 1.0)), v0**2 / (2 * g))
    return _out(h)


def speed_to_rise(height_m, k_per_m, g_m_s2=G_M_S2):
    """Launch speed needed to rise a height straight up: v0^2 = (g/k) (exp(2 k h) - 1) (2 g h at k = 0).

    Parameters
    ----------
    height_m : float or array_like
        Rise height h [m], >= 0.
    k_per_m : float or array_like
        Drag constant k [1/m], >= 0.
    g_m_s2 : float
        Gravity [m/s^2], > 0.

    Returns
    -------
    float or numpy.ndarray
        Launch speed [m/s]; the inverse of :func:`rise_height`.
    """
    h = _nonnegative("height_m", height_m)
    k = _nonnegative("k_per_m", k_per_m)
    g = float(_positive("g_m_s2", g_m_s2))
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(k > 0, g * np.expm1(2.0 * k * h) / np.where(k > 0, k, 1.0), 2 * g * h)
    return _out(np.sqrt(u))


def plate_speeds(vin_gate_m_s, vout_gate_m_s, spacing_m, distance_to_plate_m, k_per_m, *,
                 orientation="horizontal", diameter_m=BALL_DIAMETER_M, g_m_s2=G_M_S2):
    """Inbound and rebound speeds at the plate from the gate speeds, with drag (and gravity).

    Geometry: gate 1 is ``spacing_m`` beyond gate 2, gate 2 is ``distance_to_plate_m``
    (d) from the plate surface; a beam is broken by the ball's leading surface.
    Inbound, the leading surface travels L from gate 1 to gate 2 in L / vin_gate,
    then d to the plate (first contact): the speed at gate 1 is
    :func:`entry_speed`, the speed at the plate :func:`speed_after` over L + d.
    Rebound, the ball leaves the plate with its far side D (the diameter) from
    the surface, which reaches gate 2 after d - D and gate 1 after d - D + L: the
    speed at gate 2 is :func:`entry_speed` over L, the speed at the plate
    :func:`speed_before` over d - D. On a horizontal rig (drag only) this is

        vin_plate  = vin_gate  (1 - exp(-kL)) / kL  exp(-k d)
        vout_plate = vout_gate (exp(kL) - 1) / kL  exp(+k (d - D)).

    On a vertical rig the ball is fired down: gravity +g along the inbound flight,
    -g along the rebound. Not in Goodwill & Haake (2004), who used the gate speeds.

    Parameters
    ----------
    vin_gate_m_s, vout_gate_m_s : float or array_like
        Speeds from the gates, spacing / interval [m/s] (NaN passes through).
    spacing_m : float
        Gate spacing L [m].
    distance_to_plate_m : float
        Distance d from gate 2 to the plate surface [m]; must exceed ``diameter_m``.
    k_per_m : float or array_like
        Drag constant k [1/m] (:func:`drag_constant`).
    orientation : str
        "horizontal" or "vertical" (fired down onto the plate).
    diameter_m : float or array_like
        Ball diameter D [m].
    g_m_s2 : float
        Gravity [m/s^2].

    Returns
    -------
    vin_plate_m_s, vout_plate_m_s : float or numpy.ndarray
        Speeds at first contact and at the end of contact [m/s].
    """
    if orientation not in _ORIENTATIONS:
        raise ValueError(f"orientation must be 'horizontal' or 'vertical', got {orientation!r}")
    L = float(_positive("spacing_m", spacing_m))
    d = float(_positive("distance_to_plate_m", distance_to_plate_m))
    D = _positive("diameter_m", diameter_m)
    if np.any(d <= D):
        raise ValueError(
            f"distance_to_plate_m ({d:g} m) must exceed the ball diameter ({float(np.max(D)):g} m): "
            "gate 2 would be blocked by the ball during the contact"
        )
    g = float(_positive("g_m_s2", g_m_s2)) if orientation == "vertical" else 0.0
    vin_g = np.asarray(vin_gate_m_s, dtype=float)
    vout_g = np.asarray(vout_gate_m_s, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        dt_in = np.where(vin_g > 0, L / vin_g, np.nan)
        dt_out = np.where(vout_g > 0, L / vout_g, np.nan)
    v_gate1 = np.asarray(entry_speed(dt_in, L, k_per_m, +g))
    vin_p = np.asarray(speed_after(np.nan_to_num(v_gate1), L + d, k_per_m, +g))
    v_gate2 = np.asarray(entry_speed(dt_out, L, k_per_m, -g))
    vout_p = np.asarray(speed_before(np.nan_to_num(v_gate2), d - D, k_per_m, -g))
    vin_p = np.where(np.isfinite(v_gate1), vin_p, np.nan)
    vout_p = np.where(np.isfinite(v_gate2), vout_p, np.nan)
    return _out(vin_p), _out(vout_p)
