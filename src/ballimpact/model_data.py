"""Model-derived data of a fitted ball: curves over speed, force components, stiffness law, per-impact model forces."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .archive_read import fitted_parameters

__all__ = [
    "SPEED_GRID_M_S",
    "MODEL_TIME_STEPS",
    "COMPONENT_SPEED_M_S",
    "STIFFNESS_X_M",
    "AGREEMENT_START_S",
    "AGREEMENT_TOLERANCE",
    "force_agreement",
    "CURVE_NAMES",
    "COMPONENT_NAMES",
    "ITF_NAMES",
    "speed_curves",
    "force_components",
    "stiffness_curve",
    "itf_drop_test",
    "impact_model_curve",
    "impact_model_curves",
    "kelvin_voigt_force",
    "kelvin_voigt_contact",
    "add_model_forces",
]

#: Inbound speeds of the model curves (Fig. 7) [m/s]: 3-40 m/s, from below the ITF drop test
#: (about 7 m/s) to above a serve; outside the fitted speeds (``fit_vin_min_m_s`` to
#: ``fit_vin_max_m_s``) the curves are extrapolations.
SPEED_GRID_M_S = np.round(np.arange(3.0, 40.0 + 1e-9, 0.5), 10)
#: Number of 0.01 ms steps of the force components (10 ms, longer than any contact at 20 m/s).
MODEL_TIME_STEPS = 1000
#: Inbound speed of the force components (Fig. 10) [m/s].
COMPONENT_SPEED_M_S = 20.0
#: Displacements of the stiffness curve (Fig. 8) [m].
STIFFNESS_X_M = np.linspace(0.0, 0.03, 61)
#: Start of the window in which model and measured force are compared [s]
#: (after the shell buckles, section 4 of Goodwill & Haake 2004).
AGREEMENT_START_S = 0.2e-3
#: Model and measurement "agree" when within this fraction of the measured peak force [-].
AGREEMENT_TOLERANCE = 0.10
#: Number of samples of the Kelvin-Voigt force curve of one impact up to its end of contact.
KELVIN_VOIGT_SAMPLES = 400

#: Archive curve on the speed grid -> (key of :func:`ballimpact.fitting.model_curves`, scale to archive units).
_CURVE_SOURCES = {
    "model_contact_time_ms": ("contact_time_s", 1e3),
    "model_contact_time_ms_lo": ("contact_time_s_lo", 1e3),
    "model_contact_time_ms_hi": ("contact_time_s_hi", 1e3),
    "model_cor": ("cor", 1.0),
    "model_cor_lo": ("cor_lo", 1.0),
    "model_cor_hi": ("cor_hi", 1.0),
    "model_peak_force_N": ("peak_force_N", 1.0),
    "model_contact_time_ms_pred_lo": ("contact_time_s_pred_lo", 1e3),
    "model_contact_time_ms_pred_hi": ("contact_time_s_pred_hi", 1e3),
    "model_cor_pred_lo": ("cor_pred_lo", 1.0),
    "model_cor_pred_hi": ("cor_pred_hi", 1.0),
}
#: Archive names of the model curves over :data:`SPEED_GRID_M_S`.
CURVE_NAMES = tuple(_CURVE_SOURCES)
#: Archive force component -> attribute of :class:`ballimpact.model.ImpactSimulation`.
_COMPONENT_SOURCES = {
    "comp_total_force_N": "force_N",
    "comp_stiffness_force_N": "stiffness_force_N",
    "comp_damping_force_N": "damping_force_N",
    "comp_momentum_flux_force_N": "momentum_flux_force_N",
    "comp_displacement_m": "displacement_m",
}
#: Archive names of the force components over ``model_time``.
COMPONENT_NAMES = tuple(_COMPONENT_SOURCES)
#: Archive names of the per-ball speed range and ITF drop-test values of :func:`itf_drop_test`.
ITF_NAMES = ("itf_impact_speed_m_s", "itf_model_cor", "itf_rebound_pred_cm", "itf_rebound_pred_cm_lo",
             "itf_rebound_pred_cm_hi", "itf_rebound_cm", "itf_drop_test_cor")


def speed_curves(fit) -> dict[str, np.ndarray]:
    """Model TC [ms], COR [-] and peak force [N] over :data:`SPEED_GRID_M_S` with 95 % bands.

    The improved model (Eq. (14) in Goodwill & Haake 2004) with the fitted
    parameters, through :func:`ballimpact.fitting.model_curves`.

    Parameters
    ----------
    fit : ballimpact.fitting.BallFit or None
        The fit (SI units); None gives NaN curves.

    Returns
    -------
    dict of str to numpy.ndarray
        :data:`CURVE_NAMES` -> values on the speed grid (NaN where not available).
    """
    curves = {k: np.full(SPEED_GRID_M_S.size, math.nan) for k in CURVE_NAMES}
    if fit is None:
        return curves
    from .fitting import model_curves

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        mc = model_curves(fit, SPEED_GRID_M_S)
    for key, (src, scale) in _CURVE_SOURCES.items():
        if src in mc:
            curves[key] = np.asarray(mc[src], dtype=float) * scale
    return curves


def force_components(fit) -> dict[str, np.ndarray]:
    """Total force and its components kB x, cB x', cM x' [N] and displacement [m] at 20 m/s.

    Eq. (14) in Goodwill & Haake 2004 simulated at :data:`COMPONENT_SPEED_M_S` with
    the fitted parameters, on :data:`MODEL_TIME_STEPS` steps of the model's time step
    (NaN after the model's end of contact).

    Parameters
    ----------
    fit : ballimpact.fitting.BallFit or None
        The fit (SI units); None gives NaN components.

    Returns
    -------
    dict of str to numpy.ndarray
        :data:`COMPONENT_NAMES` -> values on the model time steps.
    """
    comps = {k: np.full(MODEL_TIME_STEPS, math.nan) for k in COMPONENT_NAMES}
    if fit is None:
        return comps
    from .model import simulate_impact

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        comp = simulate_impact(COMPONENT_SPEED_M_S, fit.mass_kg, fit.kb0_N_m, fit.ak, fit.a, fit.ac, record=True)
    m = min(comp.time_s.size, MODEL_TIME_STEPS)
    for key, attr in _COMPONENT_SOURCES.items():
        comps[key][:m] = np.asarray(getattr(comp, attr), dtype=float)[:m]
    return comps


def stiffness_curve(fit) -> np.ndarray:
    """Fitted structural stiffness kB(x) = kB(0) + AK x^a (Eq. (4)) on :data:`STIFFNESS_X_M` [kN/m].

    Parameters
    ----------
    fit : ballimpact.fitting.BallFit or None
        The fit (SI units); None gives NaN.

    Returns
    -------
    numpy.ndarray
        kB [kN/m] at each displacement of :data:`STIFFNESS_X_M` [m].
    """
    if fit is None:
        return np.full(STIFFNESS_X_M.size, math.nan)
    from .model import structural_stiffness

    return np.asarray(structural_stiffness(STIFFNESS_X_M, fit.kb0_N_m, fit.ak, fit.a) / 1e3, dtype=float)


def itf_drop_test(fit, mass_kg: float, fit_vin_range_m_s, itf_rebound_cm=None, diameter_m=None,
                  air_density_kg_m3=None) -> dict[str, float]:
    """Fitted speed range and the ITF 254 cm drop test of one ball type, predicted and measured.

    Parameters
    ----------
    fit : ballimpact.fitting.BallFit or None
        The fit (SI units); None leaves the predictions NaN.
    mass_kg : float
        Ball mass [kg].
    fit_vin_range_m_s : tuple of float
        Slowest and fastest inbound speed fitted [m/s].
    itf_rebound_cm : float, optional
        Measured drop-test rebound [cm].
    diameter_m, air_density_kg_m3 : float, optional
        Ball diameter [m] and air density [kg/m^3] of the fall (:mod:`ballimpact.itf`
        defaults when None).

    Returns
    -------
    dict of str to float
        :data:`ITF_NAMES` (impact speed [m/s], model COR [-], predicted rebound and
        its 95 % interval [cm], measured rebound [cm], measured COR [-]) and
        ``fit_vin_min_m_s``, ``fit_vin_max_m_s`` [m/s].
    """
    from .flight import AIR_DENSITY_KG_M3, BALL_DIAMETER_M
    from .itf import drop_impact_speed, drop_test_cor, predict_itf_rebound, predict_itf_rebound_interval

    lo, hi = (float(v) for v in fit_vin_range_m_s)
    flight_kw = {"diameter_m": BALL_DIAMETER_M if diameter_m is None else float(diameter_m),
                 "air_density_kg_m3": AIR_DENSITY_KG_M3 if air_density_kg_m3 is None else float(air_density_kg_m3)}
    out = {k: math.nan for k in ITF_NAMES}
    out.update(fit_vin_min_m_s=lo, fit_vin_max_m_s=hi)
    mass_ok = math.isfinite(mass_kg) and mass_kg > 0
    if mass_ok:
        out["itf_impact_speed_m_s"] = float(drop_impact_speed(mass_kg, **flight_kw))
    if itf_rebound_cm is not None and math.isfinite(float(itf_rebound_cm)):
        out["itf_rebound_cm"] = float(itf_rebound_cm)
        if mass_ok:
            out["itf_drop_test_cor"] = float(drop_test_cor(float(itf_rebound_cm) / 100.0, mass_kg, **flight_kw))
    if fit is not None and mass_ok:
        params = (fit.kb0_N_m, fit.ak, fit.a, fit.ac)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            best, p_lo, p_hi = predict_itf_rebound_interval(mass_kg, params, getattr(fit, "bootstrap", None),
                                                            **flight_kw)
            out["itf_model_cor"] = float(predict_itf_rebound(mass_kg, *params, **flight_kw).cor)
        out.update(itf_rebound_pred_cm=best * 100.0, itf_rebound_pred_cm_lo=p_lo * 100.0,
                   itf_rebound_pred_cm_hi=p_hi * 100.0)
    return out


def impact_model_curve(params, vin_m_s: float, mass_kg: float | None = None):
    """The improved model's force and displacement for one impact, on the model's own time steps.

    Eq. (14) in Goodwill & Haake 2004 (:func:`ballimpact.model.simulate_impact`)
    at the impact's inbound speed and mass.

    Parameters
    ----------
    params : tuple of float or None
        (mass [kg], kB(0) [N/m], AK [N m^-(1+a)], a [-], AC [N s/m^3]) as from
        :func:`ballimpact.archive_read.fitted_parameters`; None gives None.
    vin_m_s : float
        Inbound speed [m/s]; not finite or not positive gives None.
    mass_kg : float, optional
        The impact's ball mass [kg]; the fitted mass when None, NaN or not positive.

    Returns
    -------
    tuple of numpy.ndarray or None
        (time since first contact [s], force [N], displacement [m]) over the
        samples with a finite force; None when fewer than 2.
    """
    from .model import simulate_impact

    if params is None or not np.isfinite(vin_m_s) or vin_m_s <= 0:
        return None
    m, kb0, ak, a, ac = params
    if mass_kg is not None and np.isfinite(mass_kg) and mass_kg > 0:
        m = mass_kg
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sim = simulate_impact(vin_m_s, m, kb0, ak, a, ac, record=True)
    good = np.isfinite(sim.force_N)
    if good.sum() < 2:
        return None
    return sim.time_s[good], np.asarray(sim.force_N)[good], np.asarray(sim.displacement_m)[good]


#: Impacts simulated together by :func:`impact_model_curves` (bounds the recorded series' memory).
CURVE_BATCH = 64


def impact_model_curves(params, vin_m_s, mass_kg):
    """:func:`impact_model_curve` of many impacts of one ball type, simulated together.

    Eq. (14) in Goodwill & Haake 2004 (:func:`ballimpact.model.simulate_impact`, which
    steps many impacts at once, each by its own arithmetic, so each curve is the one
    :func:`impact_model_curve` gives), in batches of :data:`CURVE_BATCH` impacts.

    Parameters
    ----------
    params : tuple of float or None
        (mass [kg], kB(0) [N/m], AK [N m^-(1+a)], a [-], AC [N s/m^3]); None gives all None.
    vin_m_s : array_like
        Inbound speed of each impact [m/s]; not finite or not positive gives None.
    mass_kg : array_like
        Ball mass of each impact [kg]; the fitted mass where NaN or not positive.

    Returns
    -------
    list
        Per impact, (time since first contact [s], force [N], displacement [m]) or None.
    """
    from .model import simulate_impact

    vin = np.asarray(vin_m_s, dtype=float).ravel()
    out = [None] * vin.size
    if params is None:
        return out
    m, kb0, ak, a, ac = params
    mass = np.asarray(mass_kg, dtype=float).ravel()
    with np.errstate(invalid="ignore"):
        mass = np.where(np.isfinite(mass) & (mass > 0), mass, m)
        todo = np.flatnonzero(np.isfinite(vin) & (vin > 0))
    for start in range(0, todo.size, CURVE_BATCH):
        batch = todo[start:start + CURVE_BATCH]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            sim = simulate_impact(vin[batch], mass[batch], kb0, ak, a, ac, record=True)
        for k, i in enumerate(batch):
            force = sim.force_N[:, k]
            good = np.isfinite(force)
            if good.sum() >= 2:
                out[i] = (sim.time_s[good], force[good], sim.displacement_m[:, k][good])
    return out


def kelvin_voigt_force(time_s: np.ndarray, vin_m_s, mass_kg, kv_kN_m, kv_N_s_m) -> np.ndarray:
    """Kelvin-Voigt force F = kB x + cB x' (Eqs. (1)-(3)) of one impact on given times [N].

    Parameters
    ----------
    time_s : numpy.ndarray
        Times since contact start [s] (NaN entries give NaN).
    vin_m_s : float
        Inbound speed [m/s].
    mass_kg : float
        Ball mass [kg].
    kv_kN_m : float
        Kelvin-Voigt stiffness kB [kN/m].
    kv_N_s_m : float
        Kelvin-Voigt damping cB [N s/m].

    Returns
    -------
    numpy.ndarray
        Force [N]; all NaN when a value is missing, not positive, or overdamped.
    """
    from .model import simulate_kelvin_voigt

    out = np.full(time_s.shape, np.nan)
    kb = kv_kN_m * 1e3
    ok = np.isfinite(time_s)
    values = (vin_m_s, mass_kg, kb, kv_N_s_m)
    if not ok.any() or not all(np.isfinite(v) for v in values) or min(vin_m_s, mass_kg, kb) <= 0 or kv_N_s_m < 0:
        return out
    try:
        _, _, force = simulate_kelvin_voigt(time_s[ok], vin_m_s, mass_kg, kb, kv_N_s_m)
    except ValueError:  # overdamped or otherwise outside the analytic solution
        return out
    out[ok] = force
    return out


def kelvin_voigt_contact(vin_m_s, mass_kg, kb_N_m, cb_N_s_m):
    """Kelvin-Voigt force of one impact on a fine grid up to its own end of contact (x back to 0).

    The contact of Eqs. (1)-(3) in Goodwill & Haake 2004 lasts half a damped period,
    pi / (omega_n sqrt(1 - zeta^2)) with omega_n = sqrt(kB / m) and
    zeta = cB / (2 sqrt(kB m)).

    Parameters
    ----------
    vin_m_s : float
        Inbound speed [m/s].
    mass_kg : float
        Ball mass [kg].
    kb_N_m : float
        Stiffness kB [N/m].
    cb_N_s_m : float
        Damping cB [N s/m].

    Returns
    -------
    tuple of numpy.ndarray or None
        (time [s], force [N]) on :data:`KELVIN_VOIGT_SAMPLES` points; None when a
        value is missing or not positive, or the impact is not underdamped.
    """
    from .model import simulate_kelvin_voigt

    values = (vin_m_s, mass_kg, kb_N_m, cb_N_s_m)
    if not all(np.isfinite(values)) or min(vin_m_s, mass_kg, kb_N_m) <= 0 or cb_N_s_m < 0:
        return None
    wn = np.sqrt(kb_N_m / mass_kg)
    zeta = cb_N_s_m / (2.0 * np.sqrt(kb_N_m * mass_kg))
    if zeta >= 1:
        return None
    t_end = np.pi / (wn * np.sqrt(1 - zeta**2))
    t = np.linspace(0.0, t_end, KELVIN_VOIGT_SAMPLES)
    _, _, f = simulate_kelvin_voigt(t, vin_m_s, mass_kg, kb_N_m, cb_N_s_m)
    return t, f


def _impact_agreement(t, f_meas, curve):
    """(model force on the measured times, agreement fraction, RMS difference) of one impact."""
    ok = np.isfinite(t) & np.isfinite(f_meas)
    ts, fs, _ = curve
    f_model = np.interp(t[ok], ts, fs, right=0.0)
    diff = f_model - f_meas[ok]
    rms = float(np.sqrt(np.mean(diff**2)))
    peak = np.nanmax(f_meas[ok])
    late = t[ok] >= AGREEMENT_START_S
    agreement = np.nan
    if late.any() and peak > 0:
        agreement = float(np.mean(np.abs(diff[late]) <= AGREEMENT_TOLERANCE * peak))
    return ok, f_model, agreement, rms


def add_model_forces(ds):
    """Fill ``model_force_N``, ``model_agreement_fraction`` and ``model_rms_N`` from the fitted parameters.

    For every impact with a contact series, a finite inbound speed and a ball with
    finite fitted parameters, the improved model (Eq. (14) in Goodwill & Haake
    2004, :func:`impact_model_curve`) is run at the impact's inbound speed and mass
    and interpolated onto its ``time_s``; after the model's end of contact its
    force is 0. The agreement fraction is the share of samples with ``time_s`` >=
    :data:`AGREEMENT_START_S` where the model is within :data:`AGREEMENT_TOLERANCE`
    of the measured peak force (section 4 of the paper); the RMS difference [N] is
    taken over the whole contact.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive holding the per-impact part and the per-ball fitted parameters.

    Returns
    -------
    xarray.Dataset
        A copy with the three variables filled (NaN where no model applies).
    """
    from .archive import set_variable_attrs

    ds = ds.copy()
    n_impact, n_sample = ds.sizes.get("impact", 0), ds.sizes.get("sample", 0)
    model_force = np.full((n_impact, n_sample), np.nan)
    agreement = np.full(n_impact, np.nan)
    rms = np.full(n_impact, np.nan)
    balls = ds["ball_type"].values.astype(str) if n_impact else np.array([], dtype=str)
    for ball in np.unique(balls):
        params = fitted_parameters(ds, ball)
        if params is None:
            continue
        rows = [i for i in np.flatnonzero(balls == ball)
                if (np.isfinite(ds["time_s"].values[i]) & np.isfinite(ds["force_N"].values[i])).sum() >= 2]
        masses = ds["impact_mass_kg"].values[rows] if "impact_mass_kg" in ds else np.full(len(rows), np.nan)
        # every impact of the ball simulated together (impact_model_curves): the same curves
        curves = impact_model_curves(params, ds["vin_m_s"].values[rows], masses)
        for i, curve in zip(rows, curves):
            if curve is None:
                continue
            t, f_meas = ds["time_s"].values[i], ds["force_N"].values[i]
            ok, model_force_i, agreement[i], rms[i] = _impact_agreement(t, f_meas, curve)
            model_force[i, ok] = model_force_i
    ds["model_force_N"] = (("impact", "sample"), model_force)
    ds["model_agreement_fraction"] = ("impact", agreement)
    ds["model_rms_N"] = ("impact", rms)
    return set_variable_attrs(ds)


def force_agreement(ds) -> dict[str, float]:
    """
    Per ball type, the median over its ok impacts of ``model_agreement_fraction`` [-].

    How much of a typical contact the fitted model's force follows the measured one
    (within :data:`AGREEMENT_TOLERANCE` of the peak after :data:`AGREEMENT_START_S`);
    1 for the paper's balls, far lower for a force of another shape.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive with ``model_agreement_fraction``, ``status`` and the impacts' ball.

    Returns
    -------
    dict
        Ball key -> median [-]; balls without an ok impact with a value are left out.
    """
    from .archive_read import text_values

    ball_name = "ball_type"
    if "model_agreement_fraction" not in ds or "status" not in ds or ball_name not in ds:
        return {}
    share = np.asarray(ds["model_agreement_fraction"].values, dtype=float)
    ok = (text_values(ds["status"].values) == "ok") & np.isfinite(share)
    balls = text_values(ds[ball_name].values)
    return {str(b): float(np.median(share[ok & (balls == b)])) for b in dict.fromkeys(balls[ok])}
