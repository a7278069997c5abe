"""Viscoelastic tennis ball model of Goodwill & Haake 2004 (Eqs. (1)-(16)) and its Kelvin-Voigt baseline.

Notation follows the paper: x is the displacement of the ball's centre of mass
towards the surface [m], positive in compression, t = 0 at first contact. The
force on the ball is F = kB x + (cB + cM) x' (Eq. (14)).

Readings of the paper (its text lost every minus sign and subscript; see
``docs/model.md`` and ``docs/physics.md``):

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

from ._checks import nonnegative_array as _check_nonnegative, positive_array as _check_positive

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
    impacts (speeds and/or parameter sets) at once. The steps: :func:`_step_force`
    (the force, Eqs. (4), (5), (7), (13), (14)), :func:`_apply_cloth`,
    :meth:`_Active.retire` (end of contact, interpolated) and :meth:`_Active.advance`
    (Eq. (16)).

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
    if not dt_s > 0:
        raise ValueError(f"dt_s must be positive, got {dt_s!r}")
    if not max_contact_time_s > 0:
        raise ValueError(f"max_contact_time_s must be positive, got {max_contact_time_s!r}")
    shape, (vin, mass, kb0, ak_, a_, ac_) = _broadcast_parameters(vin_m_s, mass_kg, kb0_N_m, ak, a, ac)
    n_steps = int(np.ceil(max_contact_time_s / dt_s)) + 2
    c = _StepConstants(dt_s, int(round(buckling_time_s / dt_s)), k_const_N_m, rho_area_kg_m2 * np.pi / 4.0,
                       cloth_displacement_m, cloth_stiffness_N_m)
    out = _Outcome(vin.size)
    s = _Active(vin, mass, kb0, ak_, a_, ac_, dt_s, rho_area_kg_m2)
    rec = _Recorder(n_steps, vin) if record else None
    cloth_phase = cloth_displacement_m > 0  # until every impact has passed the cloth
    step = 1
    while s.n_alive and step < n_steps:
        t = step * dt_s
        v, d2, compress, n_compress, f, parts = _step_force(s, step, c, record)
        if cloth_phase:
            f, parts, cloth_phase = _apply_cloth(s.x, compress, f, parts, c)
        if rec is not None:
            rec.store(step, s.idx, s.x, v, f, parts)
        s.track_extremes(f, t, n_compress)
        if n_compress < s.idx.size:  # an impact ends only in restitution
            ended = f <= 0.0
            if n_compress:
                ended &= ~compress
            if s.alive is not None:
                ended &= s.alive
            if np.count_nonzero(ended):
                d2, f, v = s.retire(ended, t, dt_s, d2, f, v, out, compact_now=record)
                if not s.n_alive:
                    break
        s.advance(d2, f, v)
        step += 1
    return _finish(s, out, vin, shape, max_contact_time_s, rec, min(step + 1, n_steps), dt_s)


def _broadcast_parameters(vin_m_s, mass_kg, kb0_N_m, ak, a, ac):
    """Validated parameters broadcast to one shape and flattened: (shape, six 1-D float arrays)."""
    params = (
        _check_positive("vin_m_s", vin_m_s),
        _check_positive("mass_kg", mass_kg),
        _check_nonnegative("kb0_N_m", kb0_N_m),
        _check_nonnegative("ak", ak),
        _check_positive("a", a),
        _check_nonnegative("ac", ac),
    )
    shape = np.broadcast_shapes(*(p.shape for p in params))
    return shape, tuple(np.ascontiguousarray(np.broadcast_to(p, shape), dtype=float).ravel() for p in params)


@dataclass(frozen=True)
class _StepConstants:
    """Scalars of the time stepping: dt [s], buckling steps [-], kCONST [N/m], rho pi / 4
    [kg/m^2], cloth displacement [m] and stiffness [N/m]."""

    dt_s: float
    n_buckle: int
    k_const_N_m: float
    quarter_rho_pi: float
    cloth_displacement_m: float
    cloth_stiffness_N_m: float


class _Outcome:
    """Per impact results, filled as each impact ends: end time [s], velocity at the end
    [m/s], peak force [N], its time [s], largest displacement [m]."""

    def __init__(self, n: int):
        self.t_end = np.full(n, np.nan)
        self.v_end = np.full(n, np.nan)
        self.peak = np.zeros(n)
        self.t_peak = np.zeros(n)
        self.x_max = np.zeros(n)


class _Active:
    """The simulations still being stepped, compacted: state at t and t - dt, parameters and
    running extremes. ``idx`` maps each back to its place in the flattened input.

    Ended impacts are dropped from the arrays once they are a quarter of them (``alive``
    marks the others until then, None when all are); stepping a few ended ones costs
    less than copying every array at each end.
    """

    # compacted when impacts end (d2_prev, f_prev, v_prev are replaced by advance())
    _FIELDS = ("idx", "x", "x_prev", "mass", "kb0", "ak", "a", "ac", "dt2m", "fluxc", "peak", "t_peak", "x_max",
               "zeros")

    def __init__(self, vin, mass, kb0, ak, a, ac, dt_s, rho_area_kg_m2):
        n = vin.size
        self.idx = np.arange(n)
        self.x_prev, self.x = np.zeros(n), vin * dt_s  # x(0) = 0, x(dt) = VB dt
        self.d2_prev, self.f_prev, self.v_prev = np.zeros(n), np.zeros(n), vin.copy()
        self.mass, self.kb0, self.ak, self.a, self.ac = mass, kb0, ak, a, ac
        self.dt2m = dt_s * dt_s / mass
        self.fluxc = mass * rho_area_kg_m2 * np.pi / (4.0 * dt_s)  # Eq. (13), divided by M1 each step
        self.peak, self.t_peak, self.x_max = np.zeros(n), np.zeros(n), np.zeros(n)
        self.zeros = np.zeros(n)  # max(x, 0) against an array: faster than against the scalar
        self.alive, self.n_alive = None, n

    def track_extremes(self, f, t, n_compress):
        """Running peak force [N], its time [s] and the largest displacement [m].

        x grows only in compression: with none of ``n_compress`` impacts compressing,
        x <= x(t - dt) <= x_max already, and x_max is left as it is.
        """
        np.copyto(self.t_peak, t, where=f > self.peak)
        np.maximum(self.peak, f, out=self.peak)
        if n_compress:
            np.maximum(self.x_max, self.x, out=self.x_max)

    def retire(self, ended, t, dt_s, d2, f, v, out: _Outcome, compact_now: bool = False):
        """Record the impacts whose force crossed zero in restitution and drop them.

        The crossing is interpolated linearly between the previous step and this one
        (end of impact, section 3.3). Returns this step's d2, f, v of those kept in the
        arrays (all of them until the ended ones are dropped, see the class).
        """
        fp, fc = self.f_prev[ended], f[ended]
        denom = fp - fc
        frac = np.clip(np.where(denom > 0, fp / np.where(denom > 0, denom, 1.0), 1.0), 0.0, 1.0)
        sel = self.idx[ended]
        out.t_end[sel] = t - dt_s + frac * dt_s
        out.v_end[sel] = self.v_prev[ended] + frac * (v[ended] - self.v_prev[ended])
        out.peak[sel], out.t_peak[sel], out.x_max[sel] = self.peak[ended], self.t_peak[ended], self.x_max[ended]
        self.n_alive -= np.count_nonzero(ended)
        if self.alive is None:
            self.alive = ~ended
        else:
            self.alive &= ~ended
        if compact_now or 4 * (self.idx.size - self.n_alive) >= self.idx.size:
            return self.compact(d2, f, v)
        return d2, f, v

    def compact(self, d2=None, f=None, v=None):
        """Drop the ended impacts from every array; returns d2, f, v (if given) of those kept."""
        keep, self.alive = self.alive, None
        for name in self._FIELDS:
            setattr(self, name, getattr(self, name)[keep])
        if d2 is None:
            return None
        return d2[keep], f[keep], v[keep]

    def advance(self, d2, f, v):
        """Eq. (16): x(t + dt) = 2 x(t) - x(t - dt) - dt^2 / m * F(t)."""
        x_next = 2.0 * self.x
        x_next -= self.x_prev
        x_next -= self.dt2m * f
        self.x_prev, self.x = self.x, x_next
        self.d2_prev, self.f_prev, self.v_prev = d2, f, v


def _step_force(s: _Active, step: int, c: _StepConstants, record: bool):
    """Force on the ball at one step, Eq. (14), with kB from Eq. (4) (kCONST before buckling),
    dCONT from Eq. (5), cB from Eq. (7) and cM from Eq. (13) in compression only.

    Returns velocity [m/s], dCONT^2 [m^2], compression flags, their count, force [N] and,
    when recording, the components (kB x, cB x', cM x') [N], else None. The count spares
    the steps where every impact compresses, or none does, the work that changes nothing
    there (cM x' is zero in restitution: not computed; the flags multiply by one in
    compression: not applied); the numbers are those of the full formula (whose cM is
    finite while the flattened section weighs less than the ball, M1 > 0).
    """
    v = s.x - s.x_prev
    v *= 1.0 / c.dt_s
    compress = v > 0.0
    n_compress = np.count_nonzero(compress)
    xc = np.maximum(s.x, s.zeros)
    c4, c3, c2, c1, _ = _DCONT_COEFFS
    d = c4 * xc  # Eq. (5), Horner form, in place
    d += c3
    d *= xc
    d += c2
    d *= xc
    d += c1
    d *= xc
    d2 = d * d
    if step < c.n_buckle:  # section 3.2.4: pre-buckling stiffness
        fs = c.k_const_N_m * s.x
    else:  # Eq. (4)
        fs = np.power(xc, s.a)
        fs *= s.ak
        fs += s.kb0
        fs *= s.x
    cb = s.ac * d2  # Eq. (7)
    if n_compress or record:
        cm = d2 - s.d2_prev  # Eq. (13)
        cm *= s.fluxc
        cm /= s.mass - c.quarter_rho_pi * d2
        if record or n_compress < v.size:
            cm *= compress
        if record:
            fd, fm = cb * v, cm * v
            return v, d2, compress, n_compress, fs + fd + fm, (fs, fd, fm)
        cb += cm
    cb *= v
    cb += fs
    return v, d2, compress, n_compress, cb, None


def _apply_cloth(x, compress, f, parts, c: _StepConstants):
    """Section 3.2.4: force cloth_stiffness x (zero in the paper) while x < 2 mm in compression.

    Returns the force [N], its components (or None) and whether the cloth can still
    apply to any impact (False once every one is past 2 mm).
    """
    cloth = compress & (x < c.cloth_displacement_m)
    if cloth.any():
        fc = c.cloth_stiffness_N_m * x
        f = np.where(cloth, fc, f)
        if parts is not None:
            fs, fd, fm = parts
            parts = (np.where(cloth, fc, fs), np.where(cloth, 0.0, fd), np.where(cloth, 0.0, fm))
        return f, parts, True
    # x < 2 mm again only in restitution, where it does not apply
    return f, parts, not np.all(x >= c.cloth_displacement_m)


class _Recorder:
    """Time series of every impact (rows: steps), NaN after its end."""

    _KEYS = ("x", "v", "f", "fs", "fd", "fm")

    def __init__(self, n_steps: int, vin):
        self.rec = {k: np.full((n_steps, vin.size), np.nan) for k in self._KEYS}
        for k in self._KEYS:
            self.rec[k][0] = 0.0
        self.rec["v"][0] = vin

    def store(self, step, idx, x, v, f, parts):
        for key, values in zip(self._KEYS, (x, v, f, *parts)):
            self.rec[key][step, idx] = values


def _finish(s: _Active, out: _Outcome, vin, shape, max_contact_time_s, rec, last, dt_s) -> ImpactSimulation:
    """The ImpactSimulation: impacts still active keep their extremes, NaN end and a warning."""
    if s.alive is not None:
        s.compact()
    if s.idx.size:
        out.peak[s.idx], out.t_peak[s.idx], out.x_max[s.idx] = s.peak, s.t_peak, s.x_max
        warnings.warn(
            f"{s.idx.size} simulated impact(s) did not end within {max_contact_time_s * 1e3:.1f} ms; "
            "their contact time and COR are NaN (parameters far outside the physical range?)",
            RuntimeWarning,
            stacklevel=3,
        )
    rebound = -out.v_end
    result = ImpactSimulation(
        contact_time_s=out.t_end.reshape(shape),
        rebound_speed_m_s=rebound.reshape(shape),
        cor=(rebound / vin).reshape(shape),
        peak_force_N=out.peak.reshape(shape),
        time_to_peak_s=out.t_peak.reshape(shape),
        max_displacement_m=out.x_max.reshape(shape),
    )
    if rec is not None:
        series = {k: rec.rec[k][:last].reshape((last,) + shape) for k in rec._KEYS}
        result.time_s = np.arange(last) * dt_s
        result.displacement_m, result.velocity_m_s, result.force_N = series["x"], series["v"], series["f"]
        result.stiffness_force_N = series["fs"]
        result.damping_force_N, result.momentum_flux_force_N = series["fd"], series["fm"]
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
