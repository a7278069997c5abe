"""Independent scalar reference of the Goodwill & Haake 2004 model, for the tests only.

A plain Python loop over time steps for ONE impact, written from docs/model.md
(Eqs. (4)-(16) and the readings there), with ``math`` and floats only: it shares
no code with the vectorised :func:`ballimpact.model.simulate_impact` (no numpy,
no compacted active set, no in-place Horner, no early cloth switch-off). The
tests compare the two to ~1e-9; bench/reference_model.c is the same loop in C.

Readings implemented (docs/model.md):
* Eq. (16) explicit central difference, x(0) = 0, x(dt) = VB dt, x' the
  backward difference (x(t) - x(t - dt)) / dt, dt = 0.01 ms.
* kB = kCONST = 80 kN/m on the steps with t < 0.2 ms, else Eq. (4) with x >= 0.
* dCONT from Eq. (5) (x < 0 -> 0), cB = AC dCONT^2 (Eq. (7)), cM from Eq. (13)
  with dCONT(t - dt) of the previous step (0 at the first step), only while x' > 0.
* Cloth: F = 0 (or cloth_k x) while x < 2 mm and x' > 0.
* End: the first step with x' <= 0 and F <= 0; TC and VB' interpolated
  linearly between that step and the one before it.
"""

import math

RHO = 5.212  # shell mass per unit area [kg/m^2], section 3.2.3
K_CONST = 80.0e3  # pre-buckling stiffness [N/m], section 3.2.4
T_BUCKLE = 0.2e-3  # [s]
X_CLOTH = 2.0e-3  # [m]
DT = 0.01e-3  # [s], section 3.3


def d_cont(x):
    """Eq. (5), contact diameter [m] of displacement x [m], alternating signs (docs/model.md)."""
    if x <= 0.0:
        return 0.0
    return -2.776e5 * x**4 + 1.746e4 * x**3 - 453.0 * x**2 + 7.66 * x


def reference_impact(vin, m, kb0, ak, a, ac, dt=DT, cloth_k=0.0, t_max=20.0e-3):
    """One impact: dict with tc [s], vout [m/s], cor [-], peak [N], t_peak [s], xmax [m].

    Also "series": per step from t = 0 to the step that ends the contact, the tuple
    (x [m], x' [m/s], F, kB x, cB x', cM x' [N]); the force parts are zero at t = 0 and the
    cloth force counts as the stiffness part.
    """
    series = [(0.0, vin, 0.0, 0.0, 0.0, 0.0)]
    n_buckle = round(T_BUCKLE / dt)
    n_steps = math.ceil(t_max / dt) + 2
    x_prev, x = 0.0, vin * dt  # x(0), x(dt)
    d_prev = 0.0  # dCONT(t - dt), 0 at t = 0
    f_prev, v_prev = 0.0, vin
    peak, t_peak, xmax = 0.0, 0.0, 0.0
    for step in range(1, n_steps):
        t = step * dt
        v = (x - x_prev) / dt
        d = d_cont(x)
        if step < n_buckle:
            k = K_CONST
        else:
            k = kb0 + ak * max(x, 0.0) ** a  # Eq. (4)
        c_b = ac * d * d  # Eq. (7)
        if v > 0.0:  # Eq. (13), compression only
            m2 = RHO * math.pi * d * d / 4.0  # Eq. (9)
            c_m = m * RHO * math.pi * (d * d - d_prev * d_prev) / (4.0 * dt * (m - m2))
        else:
            c_m = 0.0
        f = k * x + (c_b + c_m) * v  # Eq. (14)
        parts = (k * x, c_b * v, c_m * v)
        if v > 0.0 and x < X_CLOTH:
            f = cloth_k * x
            parts = (f, 0.0, 0.0)
        series.append((x, v, f) + parts)
        if f > peak:
            peak, t_peak = f, t
        xmax = max(xmax, x)
        if v <= 0.0 and f <= 0.0:
            frac = f_prev / (f_prev - f) if f_prev - f > 0.0 else 1.0
            frac = min(max(frac, 0.0), 1.0)
            tc = t - dt + frac * dt
            vout = -(v_prev + frac * (v - v_prev))
            return dict(tc=tc, vout=vout, cor=vout / vin, peak=peak, t_peak=t_peak, xmax=xmax, series=series)
        x_next = 2.0 * x - x_prev - dt * dt / m * f  # Eq. (16)
        x_prev, x = x, x_next
        d_prev, f_prev, v_prev = d, f, v
    return dict(tc=math.nan, vout=math.nan, cor=math.nan, peak=peak, t_peak=t_peak, xmax=xmax, series=series)
