"""Compiled time loop of the Goodwill & Haake 2004 ball model (Eqs. (4), (5), (7), (13), (14), (16)).

:func:`ballimpact.model.simulate_impact` validates and broadcasts its arguments and,
for calls of fewer than ``model.COMPILED_LOOP_MAX_IMPACTS`` impacts, calls
:func:`simulate_flat`; this module holds the loop alone. It is compiled by numba
(``cache=True``: compiled once per machine and Python, then loaded from the cache
beside this file) and steps every impact still in contact at each time step, so that
an impact costs its own steps only, with no per-step call overhead, whether one or
thousands of impacts are simulated.

The arithmetic is written operation by operation in the order of the numpy loop of
:mod:`ballimpact.model`, which runs the larger calls (Horner form of Eq. (5), force
kB x + (cB + cM) x', or kB x + cB x' + cM x' when the components are recorded), so
that the two give the same numbers to rounding.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["run_impacts", "simulate_flat"]

# Eq. (5) coefficients, highest power first, SI units (x [m] -> dCONT [m]); as model._DCONT_COEFFS.
_C4, _C3, _C2, _C1 = -2.776e5, 1.746e4, -453.0, 7.66


def simulate_flat(params, n_steps: int, dt_s: float, n_buckle: int, constants, record: bool):
    """Run :func:`run_impacts` on validated, flattened parameters.

    Parameters
    ----------
    params : tuple of numpy.ndarray
        VB [m/s], m [kg], kB(0) [N/m], AK [N/m^(1+a)], a [-], AC [N s/m^3], 1-D float
        arrays of one length n.
    n_steps : int
        Steps of the longest contact simulated, x(0) included [-].
    dt_s : float
        Time step [s].
    n_buckle : int
        Steps with the pre-buckling stiffness [-].
    constants : tuple of float
        kCONST [N/m], rho [kg/m^2], cloth displacement [m], cloth stiffness [N/m].
    record : bool
        Keep the time series.

    Returns
    -------
    out : numpy.ndarray
        (5, n): end time [s], velocity at the end [m/s] (NaN for an impact that did not
        end), peak force [N], its time [s], largest displacement [m].
    rec : numpy.ndarray or None
        (6, n_steps, n): x [m], x' [m/s], F, kB x, cB x', cM x' [N], NaN after the end;
        None unless recording.
    last : int
        Rows of ``rec`` up to the last step stepped by any impact [-].
    """
    k_const, rho, cloth_x, cloth_k = constants
    vin = params[0]
    n = vin.size
    scalars = np.array([dt_s, k_const, rho * np.pi / 4.0, cloth_x, cloth_k, rho], dtype=float)
    out = np.full((5, n), np.nan)
    out[2:] = 0.0  # peak force, its time, largest displacement: from 0
    rec = np.full((6, n_steps if record else 0, n), np.nan)
    if record:  # t = 0: x = 0, x' = VB, no force
        rec[:, 0] = 0.0
        rec[1, 0] = vin
    last = run_impacts(*params, scalars, n_buckle, n_steps, out, rec)
    return out, (rec if record else None), min(last + 1, n_steps)


@njit(cache=True, nogil=True, inline="always")
def _force(step, x, x_prev, d2_prev, mass, kb0, ak, a, ac, fluxc, scalars, n_buckle, record):  # noqa: PLR0913
    """The force at one step of one impact, Eq. (14): kB from Eq. (4) (kCONST before buckling),
    dCONT from Eq. (5), cB from Eq. (7), cM from Eq. (13) in compression only, the cloth
    (section 3.2.4). Returns x' [m/s], dCONT^2 [m^2], F, kB x, cB x', cM x' [N]."""
    dt, k_const, quarter_rho_pi, cloth_x, cloth_k = scalars[0], scalars[1], scalars[2], scalars[3], scalars[4]
    v = (x - x_prev) * (1.0 / dt)
    xc = max(x, 0.0)
    d = ((((_C4 * xc) + _C3) * xc + _C2) * xc + _C1) * xc  # Eq. (5)
    d2 = d * d
    if step < n_buckle:  # section 3.2.4: pre-buckling stiffness
        fs = k_const * x
    else:  # Eq. (4)
        fs = (xc**a * ak + kb0) * x
    cb = ac * d2  # Eq. (7)
    cm = 0.0
    if v > 0.0:  # Eq. (13), compression only
        cm = (d2 - d2_prev) * fluxc / (mass - quarter_rho_pi * d2)
    fd, fm = cb * v, cm * v
    f = fs + fd + fm if record else (cb + cm) * v + fs  # Eq. (14)
    if v > 0.0 and cloth_x > 0.0 and x < cloth_x:  # section 3.2.4: the cloth
        f = fs = cloth_k * x
        fd = fm = 0.0
    return v, d2, f, fs, fd, fm


@njit(cache=True, nogil=True)
def run_impacts(vin, mass, kb0, ak, a, ac, scalars, n_buckle, n_steps, out, rec):  # noqa: PLR0913
    """Simulate every impact of the flattened parameter arrays, stepped together until each ends.

    Each step runs over the impacts still in contact (ended ones are dropped from the
    list), so that the work of independent impacts overlaps in the processor; every
    impact sees the same arithmetic as if it were simulated alone.

    Parameters
    ----------
    vin, mass, kb0, ak, a, ac : numpy.ndarray
        1-D float arrays of one length n: VB [m/s], m [kg], kB(0) [N/m], AK [N/m^(1+a)],
        a [-], AC [N s/m^3].
    scalars : numpy.ndarray
        (dt [s], kCONST [N/m], rho pi / 4 [kg/m^2], cloth displacement [m], cloth
        stiffness [N/m], rho [kg/m^2]).
    n_buckle : int
        Steps with the pre-buckling stiffness kCONST [-].
    n_steps : int
        Steps of the longest contact simulated, x(0) included [-].
    out : numpy.ndarray
        (5, n), filled: end time [s] and velocity at the end [m/s] (left as they are,
        NaN, for an impact that does not end), peak force [N], its time [s], largest
        displacement [m].
    rec : numpy.ndarray
        (6, n_steps, n) to record x [m], x' [m/s], F, kB x, cB x', cM x' [N] of each
        step until the impact ends (other rows left as they are), or (6, 0, n) not to.

    Returns
    -------
    int
        The last step stepped: the ending step of the last impact to end, or n_steps
        when one did not end [-].
    """
    n = vin.size
    dt, rho = scalars[0], scalars[5]
    record = rec.shape[1] > 0
    x_prev, x = np.zeros(n), vin * dt  # x(0) = 0, x(dt) = VB dt
    d2_prev, f_prev, v_prev = np.zeros(n), np.zeros(n), vin.copy()
    dt2m = dt * dt / mass
    fluxc = mass * rho * np.pi / (4.0 * dt)  # Eq. (13), divided by M1 each step
    active = np.arange(n)
    n_active, step = n, 1
    while n_active and step < n_steps:
        t = step * dt
        kept = 0
        for k in range(n_active):
            i = active[k]
            v, d2, f, fs, fd, fm = _force(step, x[i], x_prev[i], d2_prev[i], mass[i], kb0[i], ak[i], a[i], ac[i],
                                          fluxc[i], scalars, n_buckle, record)
            if record:
                rec[0, step, i], rec[1, step, i], rec[2, step, i] = x[i], v, f
                rec[3, step, i], rec[4, step, i], rec[5, step, i] = fs, fd, fm
            if f > out[2, i]:  # running peak force and its time
                out[2, i], out[3, i] = f, t
            out[4, i] = max(out[4, i], x[i])
            if not v > 0.0 and f <= 0.0:  # end of impact (section 3.3), interpolated
                denom = f_prev[i] - f
                frac = min(max(f_prev[i] / denom if denom > 0 else 1.0, 0.0), 1.0)
                out[0, i] = t - dt + frac * dt
                out[1, i] = v_prev[i] + frac * (v - v_prev[i])
                continue
            x_next = 2.0 * x[i] - x_prev[i] - dt2m[i] * f  # Eq. (16)
            x_prev[i], x[i] = x[i], x_next
            d2_prev[i], f_prev[i], v_prev[i] = d2, f, v
            active[kept] = i
            kept += 1
        n_active = kept
        step += 1
    return step if n_active else step - 1
