"""Viscoelastic tennis ball model of Goodwill & Haake 2004 (Eqs. (1)-(16)) and its Kelvin-Voigt baseline.

Notation follows the paper: x is the displacement of the ball's centre of mass
towards the surface [m], positive in compression, t = 0 at first contact. The
force on the ball is F = kB x + (cB + cM) x' (Eq. (14)).

Readings of the paper (its text lost every minus sign and subscript; see
``docs/model.md`` and the README):

* Eq. (5) is read with alternating signs, SI units:
  dCONT = -2.776e5 x^4 + 1.746e4 x^3 - 453 x^2 + 7.66 x. It gives 46.0 mm at
  x = 10 mm (the geometric chord of a 33 mm ball is 47 mm).
* The momentum flux damper cM (Eq. (13)) acts in compression only (x' > 0).
* Cloth (section 3.2.4): the force is zero while x < 2 mm in compression. An
  optional small cloth stiffness replaces that zero (used by the synthetic
  generator; 0 reproduces the paper).
* Buckling (section 3.2.4): kB = kCONST = 80 kN/m for the first 0.2 ms after first
  contact, then Eq. (4).
* End of impact (section 3.3): the first time after the force peak (x' < 0) that
  F <= 0. The crossing is interpolated linearly between the two time steps that
  bracket it, so that contact time and rebound speed vary smoothly with the
  parameters (the fixed-step solution moves in steps of dt otherwise).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

__all__ = [
    "RHO_AREA_KG_M2",
    "K_CONST_N_M",
    "BUCKLING_TIME_S",
    "CLOTH_DISPLACEMENT_M",
    "TIME_STEP_S",
    "contact_diameter",
    "structural_stiffness",
    "material_damping",
    "momentum_flux_damping",
    "ImpactSimulation",
    "simulate_impact",
    "kelvin_voigt_parameters",
    "simulate_kelvin_voigt",
]

#: Mass per unit surface area of the ball shell, rho_area [kg/m^2] (section 3.2.3).
RHO_AREA_KG_M2 = 5.212
#: Pre-buckling stiffness kCONST [N/m] (section 3.2.4 and 6.1).
K_CONST_N_M = 80.0e3
#: Duration of the pre-buckling phase after first contact [s] (section 3.2.4).
BUCKLING_TIME_S = 0.2e-3
#: Centre-of-mass displacement below which the cloth carries (almost) no load [m] (section 3.2.4).
CLOTH_DISPLACEMENT_M = 2.0e-3
#: Time step of the paper's finite-difference solution [s] (section 3.3).
TIME_STEP_S = 0.01e-3
#: Longest contact simulated before giving up [s].
MAX_CONTACT_TIME_S = 20.0e-3

# Eq. (5) coefficients, highest power first, SI units (x [m] -> dCONT [m]).
_DCONT_COEFFS = (-2.776e5, 1.746e4, -453.0, 7.66, 0.0)


def contact_diameter(x):
    """Diameter of the contact area, Eq. (5) in Goodwill & Haake 2004.

    Parameters
    ----------
    x : array_like
        Centre-of-mass displacement [m]. Negative values are treated as 0.

    Returns
    -------
    numpy.ndarray
        Contact diameter dCONT [m].
    """
    x = np.maximum(np.asarray(x, dtype=float), 0.0)
    c4, c3, c2, c1, _ = _DCONT_COEFFS
    return x * (c1 + x * (c2 + x * (c3 + x * c4)))


def structural_stiffness(x, kb0_N_m, ak, a):
    """Structural stiffness kB = kB(0) + AK x^a, Eq. (4) in Goodwill & Haake 2004.

    Parameters
    ----------
    x : array_like
        Centre-of-mass displacement [m]; negative values are treated as 0.
    kb0_N_m : array_like
        Stiffness at zero displacement kB(0) [N/m].
    ak : array_like
        Stiffness coefficient AK [N/m^(1+a)].
    a : array_like
        Stiffness exponent [-].

    Returns
    -------
    numpy.ndarray
        Spring stiffness kB [N/m].
    """
    x = np.maximum(np.asarray(x, dtype=float), 0.0)
    return kb0_N_m + ak * np.power(x, a)


def material_damping(x, ac):
    """Material damping cB = AC dCONT^2, Eqs. (6)-(7) in Goodwill & Haake 2004.

    Parameters
    ----------
    x : array_like
        Centre-of-mass displacement [m].
    ac : array_like
        Damping area constant AC [N s/m^3].

    Returns
    -------
    numpy.ndarray
        Damping coefficient cB [N s/m].
    """
    d = contact_diameter(x)
    return ac * d * d


def momentum_flux_damping(x, x_previous, dt_s, mass_kg, rho_area_kg_m2=RHO_AREA_KG_M2):
    """Momentum-flux damping coefficient cM, Eq. (13) in Goodwill & Haake 2004.

    cM = m rho pi (d(t)^2 - d(t - dt)^2) / (4 dt M1), with M1 = m - M2 and
    M2 = rho pi d(t)^2 / 4 the mass of the flattened section (Eqs. (8)-(13)).
    Applies in compression only; the caller sets it to zero in restitution.

    Parameters
    ----------
    x, x_previous : array_like
        Displacement at t and at t - dt [m].
    dt_s : float
        Time step [s].
    mass_kg : array_like
        Ball mass m [kg].
    rho_area_kg_m2 : float
        Shell mass per unit surface area [kg/m^2].

    Returns
    -------
    numpy.ndarray
        cM [N s/m].
    """
    d2 = contact_diameter(x) ** 2
    d2_prev = contact_diameter(x_previous) ** 2
    m1 = mass_kg - rho_area_kg_m2 * np.pi * d2 / 4.0
    return mass_kg * rho_area_kg_m2 * np.pi * (d2 - d2_prev) / (4.0 * dt_s * m1)


@dataclass
class ImpactSimulation:
    """Result of :func:`simulate_impact`; arrays have the broadcast shape of the inputs.

    Attributes
    ----------
    contact_time_s : numpy.ndarray
        Contact time TC [s] (interpolated end of contact); NaN if the impact did not end.
    rebound_speed_m_s : numpy.ndarray
        Rebound speed VB' [m/s] (positive, away from the surface).
    cor : numpy.ndarray
        Coefficient of restitution VB'/VB [-].
    peak_force_N : numpy.ndarray
        Largest force on the ball [N].
    time_to_peak_s : numpy.ndarray
        Time of the largest force [s].
    max_displacement_m : numpy.ndarray
        Largest centre-of-mass displacement [m].
    time_s : numpy.ndarray or None
        Time of each step [s], shape (n_steps,), when ``record`` was True.
    displacement_m, velocity_m_s, force_N, stiffness_force_N, damping_force_N, momentum_flux_force_N : numpy.ndarray or None
        Time series, shape (n_steps,) + broadcast shape, NaN after the end of contact;
        force components kB x, cB x' and cM x' [N] (Fig. 10 of the paper).
    """

    contact_time_s: np.ndarray
    rebound_speed_m_s: np.ndarray
    cor: np.ndarray
    peak_force_N: np.ndarray
    time_to_peak_s: np.ndarray
    max_displacement_m: np.ndarray
    time_s: np.ndarray | None = None
    displacement_m: np.ndarray | None = None
    velocity_m_s: np.ndarray | None = None
    force_N: np.ndarray | None = None
    stiffness_force_N: np.ndarray | None = None
    damping_force_N: np.ndarray | None = None
    momentum_flux_force_N: np.ndarray | None = None


def _check_positive(name, value):
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        bad = arr[~(np.isfinite(arr) & (arr > 0))].ravel()[0] if arr.ndim else arr
        raise ValueError(f"{name} must be positive and finite, got {float(bad)!r}")
    return arr


def _check_nonnegative(name, value):
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        bad = arr[~(np.isfinite(arr) & (arr >= 0))].ravel()[0] if arr.ndim else arr
        raise ValueError(f"{name} must be non-negative and finite, got {float(bad)!r}")
    return arr


def simulate_impact(
    vin_m_s,
    mass_kg,
    kb0_N_m,
    ak,
    a,
    ac,
    *,
    dt_s: float = TIME_STEP_S,
    k_const_N_m: float = K_CONST_N_M,
    buckling_time_s: float = BUCKLING_TIME_S,
    cloth_displacement_m: float = CLOTH_DISPLACEMENT_M,
    cloth_stiffness_N_m: float = 0.0,
    rho_area_kg_m2: float = RHO_AREA_KG_M2,
    max_contact_time_s: float = MAX_CONTACT_TIME_S,
    record: bool = False,
) -> ImpactSimulation:
    """Simulate normal impacts on a rigid surface with the improved viscoelastic model.

    Solves m x'' + (cB + cM) x' + kB x = 0 (Eq. (14) in Goodwill & Haake 2004) by
    the explicit central difference of Eq. (16), with x(0) = 0, x(dt) = VB dt and
    the velocity as the backward difference (x(t) - x(t - dt)) / dt. kB from
    Eq. (4) (kCONST for the first ``buckling_time_s``), cB from Eq. (7), cM from
    Eq. (13) in compression only; the force is zero (or ``cloth_stiffness_N_m * x``)
    while x < 2 mm in compression (section 3.2.4).

    All array arguments broadcast against each other: one call simulates many
    impacts (speeds and/or parameter sets) at once.

    Parameters
    ----------
    vin_m_s : array_like
        Inbound speed VB [m/s], > 0.
    mass_kg : array_like
        Ball mass m [kg].
    kb0_N_m : array_like
        kB(0) [N/m].
    ak : array_like
        AK [N/m^(1+a)].
    a : array_like
        Stiffness exponent a [-].
    ac : array_like
        Damping area constant AC [N s/m^3].
    dt_s : float, optional
        Time step [s]; the paper uses 0.01 ms.
    k_const_N_m : float, optional
        Pre-buckling stiffness kCONST [N/m].
    buckling_time_s : float, optional
        Duration of the pre-buckling phase [s].
    cloth_displacement_m : float, optional
        Displacement below which the cloth modification applies [m].
    cloth_stiffness_N_m : float, optional
        Stiffness of the cloth below ``cloth_displacement_m`` [N/m]; 0 (the paper)
        makes the force zero there.
    rho_area_kg_m2 : float, optional
        Shell mass per unit area [kg/m^2].
    max_contact_time_s : float, optional
        Simulation stops here [s]; impacts not ended get NaN and a warning.
    record : bool, optional
        Keep the time series (memory grows as steps x impacts).

    Returns
    -------
    ImpactSimulation
    """
    vin = _check_positive("vin_m_s", vin_m_s)
    mass = _check_positive("mass_kg", mass_kg)
    kb0 = _check_nonnegative("kb0_N_m", kb0_N_m)
    ak_ = _check_nonnegative("ak", ak)
    a_ = _check_positive("a", a)
    ac_ = _check_nonnegative("ac", ac)
    if not dt_s > 0:
        raise ValueError(f"dt_s must be positive, got {dt_s!r}")
    if not max_contact_time_s > 0:
        raise ValueError(f"max_contact_time_s must be positive, got {max_contact_time_s!r}")

    shape = np.broadcast_shapes(vin.shape, mass.shape, kb0.shape, ak_.shape, a_.shape, ac_.shape)
    vin, mass, kb0, ak_, a_, ac_ = (
        np.ascontiguousarray(np.broadcast_to(p, shape), dtype=float).ravel()
        for p in (vin, mass, kb0, ak_, a_, ac_)
    )
    n = vin.size
    n_steps = int(np.ceil(max_contact_time_s / dt_s)) + 2
    n_buckle = int(round(buckling_time_s / dt_s))
    inv_dt = 1.0 / dt_s
    dt2_over_m = dt_s * dt_s / mass
    flux_coef = mass * rho_area_kg_m2 * np.pi / (4.0 * dt_s)  # divided by M1 each step
    quarter_rho_pi = rho_area_kg_m2 * np.pi / 4.0
    c4, c3, c2, c1, _ = _DCONT_COEFFS

    # State; x_prev = x(t - dt), x = x(t). Step 0 is t = 0, step 1 is t = dt.
    x_prev = np.zeros(n)
    x = vin * dt_s
    d2_prev = np.zeros(n)
    f_prev = np.zeros(n)  # force at the previous step
    v_prev = vin.copy()
    t_end = np.full(n, np.nan)
    v_end = np.full(n, np.nan)
    peak = np.zeros(n)
    t_peak = np.zeros(n)
    x_max = np.zeros(n)

    if record:
        rec = {k: np.full((n_steps, n), np.nan) for k in ("x", "v", "f", "fs", "fd", "fm")}
        for k in rec:
            rec[k][0] = 0.0
        rec["x"][0] = 0.0
        rec["v"][0] = vin

    idx = np.arange(n)  # indices of the simulations still being stepped
    # work arrays on the compacted active set
    xa, xpa, d2pa, fpa, vpa = x, x_prev, d2_prev, f_prev, v_prev
    ma, kb0a, aka, aa, aca = mass, kb0, ak_, a_, ac_
    dt2m, fluxc = dt2_over_m, flux_coef
    peak_a, tpeak_a, xmax_a = peak.copy(), t_peak.copy(), x_max.copy()
    cloth_phase = cloth_displacement_m > 0  # until every impact has passed the cloth

    step = 1
    while idx.size and step < n_steps:
        t = step * dt_s
        v = (xa - xpa) * inv_dt
        xc = np.maximum(xa, 0.0)
        # Eq. (5), Horner form, in place
        d = c4 * xc
        d += c3
        d *= xc
        d += c2
        d *= xc
        d += c1
        d *= xc
        d2 = d * d
        if step < n_buckle:  # section 3.2.4: pre-buckling stiffness
            fs = k_const_N_m * xa
        else:  # Eq. (4)
            fs = np.power(xc, aa)
            fs *= aka
            fs += kb0a
            fs *= xa
        compress = v > 0.0
        # Eq. (13) in compression only, Eq. (7)
        cm = d2 - d2pa
        cm *= fluxc
        cm /= ma - quarter_rho_pi * d2
        cm *= compress
        cb = aca * d2
        if record:
            fd = cb * v
            fm = cm * v
            f = fs + fd + fm
        else:
            cb += cm
            cb *= v
            f = cb
            f += fs
        if cloth_phase:
            cloth = compress & (xa < cloth_displacement_m)
            if cloth.any():
                fc = cloth_stiffness_N_m * xa
                f = np.where(cloth, fc, f)
                if record:
                    fs = np.where(cloth, fc, fs)
                    fd = np.where(cloth, 0.0, fd)
                    fm = np.where(cloth, 0.0, fm)
            elif np.all(xa >= cloth_displacement_m):
                cloth_phase = False  # x < 2 mm again only in restitution, where it does not apply

        if record:
            cols = idx
            rec["x"][step, cols] = xa
            rec["v"][step, cols] = v
            rec["f"][step, cols] = f
            rec["fs"][step, cols] = fs
            rec["fd"][step, cols] = fd
            rec["fm"][step, cols] = fm
        upd = f > peak_a
        np.copyto(tpeak_a, t, where=upd)
        np.maximum(peak_a, f, out=peak_a)
        np.maximum(xmax_a, xa, out=xmax_a)

        ended = f <= 0.0
        ended &= ~compress
        if ended.any():
            # Interpolate the zero crossing of F between the previous step and this one.
            fp = fpa[ended]
            fc_ = f[ended]
            denom = fp - fc_
            frac = np.where(denom > 0, fp / np.where(denom > 0, denom, 1.0), 1.0)
            frac = np.clip(frac, 0.0, 1.0)
            sel = idx[ended]
            t_end[sel] = t - dt_s + frac * dt_s
            v_end[sel] = vpa[ended] + frac * (v[ended] - vpa[ended])
            peak[sel], t_peak[sel], x_max[sel] = peak_a[ended], tpeak_a[ended], xmax_a[ended]
            keep = ~ended
            idx = idx[keep]
            xa, xpa, d2, f, v = xa[keep], xpa[keep], d2[keep], f[keep], v[keep]
            ma, kb0a, aka, aa, aca = ma[keep], kb0a[keep], aka[keep], aa[keep], aca[keep]
            dt2m, fluxc = dt2m[keep], fluxc[keep]
            peak_a, tpeak_a, xmax_a = peak_a[keep], tpeak_a[keep], xmax_a[keep]
            if not idx.size:
                break
        # Eq. (16): x(t + dt) = 2 x(t) - x(t - dt) - dt^2 / m * F(t)
        x_next = 2.0 * xa
        x_next -= xpa
        x_next -= dt2m * f
        xpa, xa = xa, x_next
        d2pa, fpa, vpa = d2, f, v
        step += 1

    if idx.size:
        peak[idx], t_peak[idx], x_max[idx] = peak_a, tpeak_a, xmax_a
    if idx.size:
        warnings.warn(
            f"{idx.size} simulated impact(s) did not end within {max_contact_time_s * 1e3:.1f} ms; "
            "their contact time and COR are NaN (parameters far outside the physical range?)",
            RuntimeWarning,
            stacklevel=2,
        )
    rebound = -v_end
    result = ImpactSimulation(
        contact_time_s=t_end.reshape(shape),
        rebound_speed_m_s=rebound.reshape(shape),
        cor=(rebound / vin).reshape(shape),
        peak_force_N=peak.reshape(shape),
        time_to_peak_s=t_peak.reshape(shape),
        max_displacement_m=x_max.reshape(shape),
    )
    if record:
        last = min(step + 1, n_steps)
        result.time_s = np.arange(last) * dt_s
        result.displacement_m = rec["x"][:last].reshape((last,) + shape)
        result.velocity_m_s = rec["v"][:last].reshape((last,) + shape)
        result.force_N = rec["f"][:last].reshape((last,) + shape)
        result.stiffness_force_N = rec["fs"][:last].reshape((last,) + shape)
        result.damping_force_N = rec["fd"][:last].reshape((last,) + shape)
        result.momentum_flux_force_N = rec["fm"][:last].reshape((last,) + shape)
    return result


def kelvin_voigt_parameters(mass_kg, contact_time_s, cor):
    """Kelvin-Voigt stiffness and damping of one impact, Eqs. (2) and (3) in Goodwill & Haake 2004.

    kB = m pi^2 / TC^2 and cB = -2 m ln(COR) / TC.

    Parameters
    ----------
    mass_kg : array_like
        Ball mass [kg].
    contact_time_s : array_like
        Contact time TC [s].
    cor : array_like
        Coefficient of restitution [-], in (0, 1].

    Returns
    -------
    kb_N_m : numpy.ndarray
        Linear stiffness kB [N/m].
    cb_N_s_m : numpy.ndarray
        Linear damping cB [N s/m].
    """
    m = np.asarray(mass_kg, dtype=float)
    tc = np.asarray(contact_time_s, dtype=float)
    e = np.asarray(cor, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        kb = m * np.pi**2 / tc**2
        cb = -2.0 * m * np.log(e) / tc
    return kb, cb


def simulate_kelvin_voigt(time_s, vin_m_s, mass_kg, kb_N_m, cb_N_s_m):
    """Kelvin-Voigt impact, the analytic solution of Eq. (1) in Goodwill & Haake 2004.

    m x'' + cB x' + kB x = 0 with x(0) = 0, x'(0) = VB (underdamped). The force on
    the ball F = kB x + cB x' turns tensile (negative) before x returns to zero,
    the failure shown in the paper's Fig. 2b.

    Parameters
    ----------
    time_s : array_like
        Times since first contact [s].
    vin_m_s : float
        Inbound speed VB [m/s].
    mass_kg : float
        Ball mass [kg].
    kb_N_m : float
        Stiffness kB [N/m].
    cb_N_s_m : float
        Damping cB [N s/m], must give an underdamped system.

    Returns
    -------
    displacement_m, velocity_m_s, force_N : numpy.ndarray
        x [m], x' [m/s] and F [N] at ``time_s``; NaN after x returns to zero
        (t > pi / omega_d).
    """
    for name, val in (("vin_m_s", vin_m_s), ("mass_kg", mass_kg), ("kb_N_m", kb_N_m)):
        _check_positive(name, val)
    _check_nonnegative("cb_N_s_m", cb_N_s_m)
    t = np.asarray(time_s, dtype=float)
    wn = np.sqrt(kb_N_m / mass_kg)
    zeta = cb_N_s_m / (2.0 * np.sqrt(kb_N_m * mass_kg))
    if zeta >= 1.0:
        raise ValueError(f"cb_N_s_m={cb_N_s_m} gives damping ratio {zeta:.3f} >= 1 (not underdamped)")
    wd = wn * np.sqrt(1.0 - zeta**2)
    decay = np.exp(-zeta * wn * t)
    x = vin_m_s / wd * decay * np.sin(wd * t)
    v = vin_m_s * decay * (np.cos(wd * t) - zeta * wn / wd * np.sin(wd * t))
    f = kb_N_m * x + cb_N_s_m * v
    outside = (t < 0) | (t > np.pi / wd)
    return (np.where(outside, np.nan, x), np.where(outside, np.nan, v), np.where(outside, np.nan, f))
