"""Fitting the ball model to measured contact times and COR (section 3.4 of Goodwill & Haake 2004).

What the code does (details in :func:`fit_ball_model`):

* Fit outliers (:func:`detect_fit_outliers`): a robust (soft-L1) fit, then each
  suspect impact is tested against the ordinary fit of the others (externally
  studentised TC, COR and inbound-speed directions, Bonferroni over the impacts at
  :data:`OUTLIER_LEVEL` per ball type); at most :data:`OUTLIER_MAX_SHARE` of the
  impacts are removed, every removal with its residuals in a note.
* kB(0): fixed from session.yaml when given ("config"; the other parameters are then
  conditional on it); fitted with AK, a and AC when impacts reach below
  :data:`LOW_SPEED_M_S` ("fitted"); otherwise the paper's straight-line
  extrapolation of the Kelvin-Voigt stiffness (Eq. (2), :func:`fit_kb0`,
  "extrapolated"), with an interval that includes the extrapolation-model
  uncertainty (the hull with the model's own, curved, extrapolation).
* Stage one (:func:`fit_contact_time`) and stage two (:func:`fit_restitution`) start
  a joint least-squares fit on the relative TC and COR residuals of the impacts,
  each kind weighted by its own unbiased scatter.
* Intervals (AK, a, AC, kB(10 mm), kB(20 mm), kB(0) when fitted): profile likelihood
  with a critical value calibrated by a parametric bootstrap
  (:func:`_calibrated_critical_values`: sessions simulated from the fit with its TC and
  COR scatter, fitted in the linearised model with the scatters re-estimated, the 0.95
  quantile of their statistic), in place of the F(1, nu) quantile with Satterthwaite's
  nu, which only approximates the effect of two scatters estimated from few residuals.
  ``bench/coverage.py`` measures their coverage.
* A case-resampling bootstrap over impacts gives the AK-a correlation and the
  confidence bands of the model curves; :func:`model_curves` adds the impacts'
  own scatter for prediction bands.

Internally the stiffness law is parametrised by the stiffness increment at a
reference displacement, kR = AK xR^a with xR = 20 mm, instead of AK: AK and a
trade off strongly (a slightly larger a with a much larger AK gives nearly the
same kB over the displacements reached), and the (log kR, a) pair is far better
conditioned. Results are reported as AK, a as in Table 2, together with the
correlation between log AK and a, and with the well-determined kB(10 mm) and
kB(20 mm).

The objective is smooth in the parameters because the model's end of contact is
interpolated between time steps (see :mod:`ballimpact.model`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from .model import kelvin_voigt_parameters, simulate_impact

# The model inversion, the intervals and the fit-outlier search have their own modules;
# their names stay importable from here (the tests and bench/coverage.py use some of the
# private ones).
from .fitting_core import (  # noqa: F401  (re-exported)
    CONVERGENCE_OFFSET,
    KB0_BOUNDS_N_M,
    PARAMETER_BOUNDS,
    REFERENCE_DISPLACEMENT_M,
    FitError,
    Kb0Fit,
    StageFit,
    _as_1d,
    _batched_lm,
    _block_scatter,
    _bound_messages,
    _chi2_ppf,
    _f_ppf,
    _fit_weighted,
    _from_theta,
    _full_bounds,
    _jacobian,
    _kb0_lines,
    _Problem,
    _relative_offset,
    _residuals,
    _rmse_pct,
    _satterthwaite_dof,
    _simulate,
    _start_grid,
    _t_ppf,
    _t_sf,
    _to_theta,
    fit_contact_time,
    fit_kb0,
    fit_restitution,
)
from .fitting_intervals import (  # noqa: F401  (re-exported)
    CALIBRATION_REFITS,
    CALIBRATION_SESSIONS,
    _calibrated_critical_values,
    _linear_sessions,
    _profile_intervals,
    _quantities,
    _quantity_gradient,
    _refit_sessions,
)
from .fitting_outliers import OUTLIER_LEVEL, OUTLIER_MAX_SHARE, FitOutliers, detect_fit_outliers  # noqa: F401

__all__ = [
    "REFERENCE_DISPLACEMENT_M",
    "PARAMETER_BOUNDS",
    "Kb0Fit",
    "StageFit",
    "BallFit",
    "FitError",
    "FitOutliers",
    "LOW_SPEED_M_S",
    "OUTLIER_LEVEL",
    "OUTLIER_MAX_SHARE",
    "CONVERGENCE_OFFSET",
    "CALIBRATION_SESSIONS",
    "CALIBRATION_REFITS",
    "detect_fit_outliers",
    "fit_kb0",
    "fit_contact_time",
    "fit_restitution",
    "fit_ball_model",
    "model_curves",
]

#: kB(0) is fitted with AK, a and AC when some impact is slower than this [m/s].
LOW_SPEED_M_S = 10.0



@dataclass
class BallFit:
    """Result of :func:`fit_ball_model`, SI units.

    Attributes
    ----------
    mass_kg : float
        Mean mass of the impacts used [kg].
    n_impacts : int
        Impacts used.
    kb0_N_m, kb0_lo, kb0_hi : float
        kB(0) and its 95 % interval [N/m] (interval NaN when fixed from the config).
    kb0_source : str
        "config", "extrapolated" or "fitted" (with AK, a, AC; impacts below LOW_SPEED_M_S).
    ak, ak_lo, ak_hi : float
        AK and its 95 % interval [N/m^(1+a)].
    a, a_lo, a_hi : float
        Exponent a and its 95 % interval [-].
    ac, ac_lo, ac_hi : float
        AC and its 95 % interval [N s/m^3].
    ak_a_correlation : float
        Correlation between log AK and a over the bootstrap resamples [-].
    contact_time_rmse_pct, cor_rmse_pct : float
        RMS of the relative residuals over the impacts used [%].
    interval_method : str
        How the intervals were obtained.
    messages : list of str
        Warnings about the fit (a parameter on a bound, few impacts, ...).
    result : scipy.optimize.OptimizeResult
        The joint least-squares result.
    bootstrap : numpy.ndarray
        Resampled parameters, columns kb0 [N/m], ak, a, ac (SI); rows that failed are dropped.
    kb_10mm_N_m, kb_10mm_lo, kb_10mm_hi, kb_20mm_N_m, kb_20mm_lo, kb_20mm_hi : float
        Structural stiffness kB(x) = kB(0) + AK x^a (Eq. (4)) at 10 and 20 mm and its
        95 % interval [N/m].
    contact_time_scatter, cor_scatter : float
        Unbiased relative scatter of the impacts about the fitted TC and COR curves [-].
    scatter_dof : float
        Residual degrees of freedom of the smaller of the two scatters [-].
    bootstrap_dropped : int
        Bootstrap resamples dropped (unconverged refit or no kB(0) extrapolation).
    used : numpy.ndarray of bool
        Per impact given: True when used in the fit, False for a fit outlier.
    outlier_notes : list of str
        Per impact given: why it was left out of the fit, else empty.
    outlier_steps : list of (int, float)
        Steps of the fit-outlier search: (impact index, p value) in order [-].
    kb0_linear_N_m, kb0_quadratic_N_m : float
        Linear (the paper's) and quadratic extrapolations of the Kelvin-Voigt
        stiffness to zero speed [N/m] (NaN when kB(0) is from the config).
    free_kb0_intervals : dict
        When kB(0) is extrapolated: the profile intervals of the fit with kB(0) free
        alone, {"ak", "a", "ac", "kb_10mm", "kb_20mm", "kb0": (lo, hi)} (SI, as above),
        one half of the reported hull (``bench/coverage.py`` measures their coverage
        too); else empty.
    """

    mass_kg: float
    n_impacts: int
    kb0_N_m: float
    kb0_lo: float
    kb0_hi: float
    kb0_source: str
    ak: float
    ak_lo: float
    ak_hi: float
    a: float
    a_lo: float
    a_hi: float
    ac: float
    ac_lo: float
    ac_hi: float
    ak_a_correlation: float
    contact_time_rmse_pct: float
    cor_rmse_pct: float
    interval_method: str
    messages: list[str] = field(default_factory=list)
    result: optimize.OptimizeResult | None = None
    bootstrap: np.ndarray | None = None
    kb_10mm_N_m: float = float("nan")
    kb_10mm_lo: float = float("nan")
    kb_10mm_hi: float = float("nan")
    kb_20mm_N_m: float = float("nan")
    kb_20mm_lo: float = float("nan")
    kb_20mm_hi: float = float("nan")
    contact_time_scatter: float = float("nan")
    cor_scatter: float = float("nan")
    scatter_dof: float = float("nan")
    bootstrap_dropped: int = 0
    used: np.ndarray | None = None
    outlier_notes: list = field(default_factory=list)
    outlier_steps: list = field(default_factory=list)
    kb0_linear_N_m: float = float("nan")
    kb0_quadratic_N_m: float = float("nan")
    free_kb0_intervals: dict = field(default_factory=dict)


def fit_ball_model(
    vin_m_s,
    contact_time_s,
    cor,
    mass_kg,
    *,
    kb0_N_m=None,
    kv_stiffness_N_m=None,
    n_bootstrap=200,
    seed=0,
    confidence=0.95,
    detect_outliers=True,
    outlier_level=OUTLIER_LEVEL,
    max_outlier_share=OUTLIER_MAX_SHARE,
    intervals=True,
) -> BallFit:
    """Fit kB(0), AK, a and AC of one ball type to its impacts, with calibrated intervals.

    The model is Eqs. (4)-(16) of Goodwill & Haake 2004; the residuals are the relative
    TC and COR misfits of the impacts, each kind weighted by its own scatter.

    1. Fit outliers (``detect_outliers``): :func:`detect_fit_outliers`; the impacts it
       names are left out of everything below and listed in ``outlier_notes``.
    2. kB(0):
       * ``kb0_N_m`` given: fixed (source "config"); AK, a, AC and their intervals are
         conditional on it.
       * else, impacts below :data:`LOW_SPEED_M_S`: fitted with AK, a and AC (source
         "fitted"), intervals by profile likelihood like the others.
       * else extrapolated (source "extrapolated"): the paper's straight line through
         the Kelvin-Voigt stiffness (Eq. (2)) against speed gives the value. Its
         interval is the hull of the line's t interval and of the profile-likelihood
         interval of kB(0) fitted jointly with AK, a, AC (the model's own, curved,
         extrapolation): it carries the extrapolation-model uncertainty. The intervals
         of AK, a, AC, kB(10 mm) and kB(20 mm) are likewise the hull of their profile
         intervals with kB(0) fixed at the line's value and with kB(0) free.
    3. Stage one (:func:`fit_contact_time`), stage two (:func:`fit_restitution`), then
       a joint least-squares fit of AK, a, AC (and kB(0) when fitted) on both kinds of
       residual, re-weighted to each kind's unbiased scatter RSS / (n - p_kind).
    4. Intervals: profile likelihood (:func:`_profile_intervals`) for AK, a, AC,
       kB(10 mm), kB(20 mm) (kB = kB(0) + AK x^a, Eq. (4)) and kB(0) when fitted; the
       critical value of each is calibrated by a parametric bootstrap of the fit
       (:func:`_calibrated_critical_values`), the F(1, nu) quantile (nu the
       Satterthwaite degrees of freedom) only when that is switched off.
    5. A case-resampling bootstrap over impacts (``n_bootstrap`` resamples, kB(0)
       re-extrapolated in each when extrapolated, refitted when fitted) gives the AK-a
       correlation and the confidence bands of the model curves (:func:`model_curves`).
       Resamples count as converged by the relative offset criterion (:func:`_batched_lm`);
       the others are dropped and counted in ``bootstrap_dropped``.

    Parameters
    ----------
    vin_m_s, contact_time_s, cor, mass_kg : array_like
        Inbound speed [m/s], contact time [s], COR [-] and mass [kg] of each good impact.
    kb0_N_m : float, optional
        Fixed kB(0) [N/m].
    kv_stiffness_N_m : array_like, optional
        Kelvin-Voigt stiffness per impact [N/m]; computed from TC and COR when omitted.
    n_bootstrap : int
        Bootstrap resamples (0: no correlation, no bands).
    seed : int
        Seed of the resampling.
    confidence : float
        Interval level [-].
    detect_outliers : bool
        Search for fit outliers first.
    outlier_level, max_outlier_share : float
        Level of the outlier test per ball type [-] and largest share removed [-].
    intervals : bool
        Compute the profile intervals (step 4). False: point estimates only, every
        interval end NaN (for a fit whose residuals alone are needed, e.g. the
        catalogue's change test, :func:`ballimpact.catalogue.compare_sessions`).

    Returns
    -------
    BallFit

    Raises
    ------
    FitError
        Too few impacts, or an optimiser that did not succeed.
    """
    vin, tc, e, mass, kv_all = _fit_inputs(vin_m_s, contact_time_s, cor, mass_kg, kb0_N_m, kv_stiffness_N_m,
                                           n_bootstrap, confidence)
    used, outlier_notes, start, steps, messages = _outlier_search(vin, tc, e, mass, kb0_N_m, detect_outliers,
                                                                  outlier_level, max_outlier_share)
    vin, tc, e, mass = vin[used], tc[used], e[used], mass[used]
    n = vin.size
    if n < 6:
        messages.append(f"only {n} impacts: the intervals are rough")
    kv = kv_all[used] if kv_all is not None else kelvin_voigt_parameters(mass, tc, e)[0]
    kb0, kb0_source, kb0_fit, line = _kb0_choice(vin, kv, kb0_N_m, confidence)
    main, free = _joint_fits(vin, tc, e, mass, kb0, kb0_source, confidence, start, intervals=intervals)
    theta = main["theta"]
    if kb0_source == "fitted":
        kb0 = float(np.exp(theta[3]))
    ak, a, ac = (float(v) for v in _from_theta(theta[:3]))
    messages += _bound_messages(theta[:3])
    if intervals:
        lo_hi = _interval_ends(main, free, kb0_source, kb0_fit, messages)
        method = _interval_method(kb0_source)
    else:
        lo_hi = {k: (float("nan"), float("nan")) for k in ("kb0", "ak", "a", "ac", "kb_10mm", "kb_20mm")}
        method = "none (intervals=False: point estimates only)"
    tc_m, cor_m = _simulate(theta, vin, mass, kb0)
    s_tc, s_cor = main["sigma_tc"], main["sigma_cor"]
    boot, dropped, corr = np.empty((0, 4)), 0, float("nan")
    if n_bootstrap > 0:
        boot, dropped, corr, method_note = _bootstrap_summary(vin, tc, e, mass, kv, kb0, theta, s_tc, s_cor,
                                                              kb0_source, n_bootstrap, seed, messages)
        method += method_note
    return BallFit(
        mass_kg=float(np.mean(mass)), n_impacts=n,
        kb0_N_m=float(kb0), kb0_lo=lo_hi["kb0"][0], kb0_hi=lo_hi["kb0"][1], kb0_source=kb0_source,
        ak=ak, ak_lo=lo_hi["ak"][0], ak_hi=lo_hi["ak"][1],
        a=a, a_lo=lo_hi["a"][0], a_hi=lo_hi["a"][1],
        ac=ac, ac_lo=lo_hi["ac"][0], ac_hi=lo_hi["ac"][1],
        ak_a_correlation=corr,
        contact_time_rmse_pct=_rmse_pct((tc_m - tc) / tc), cor_rmse_pct=_rmse_pct((cor_m - e) / e),
        interval_method=method, messages=messages, result=main["result"], bootstrap=boot,
        kb_10mm_N_m=float(kb0 + ak * 0.010**a), kb_10mm_lo=lo_hi["kb_10mm"][0], kb_10mm_hi=lo_hi["kb_10mm"][1],
        kb_20mm_N_m=float(kb0 + ak * 0.020**a), kb_20mm_lo=lo_hi["kb_20mm"][0], kb_20mm_hi=lo_hi["kb_20mm"][1],
        contact_time_scatter=s_tc, cor_scatter=s_cor, scatter_dof=float(min(main["dof_tc"], main["dof_cor"])),
        bootstrap_dropped=int(dropped), used=used, outlier_notes=list(outlier_notes), outlier_steps=list(steps),
        kb0_linear_N_m=line[0][0] if line else float("nan"),
        kb0_quadratic_N_m=line[1][0] if line else float("nan"),
        free_kb0_intervals=({k: ((float(lo), float(hi)) if k == "a" else (float(np.exp(lo)), float(np.exp(hi))))
                             for k, (lo, hi, _) in free["intervals"].items()}
                            if kb0_source == "extrapolated" and intervals else {}),
    )


def _fit_inputs(vin_m_s, contact_time_s, cor, mass_kg, kb0_N_m, kv_stiffness_N_m, n_bootstrap, confidence):
    """The checked inputs of :func:`fit_ball_model`: (vin [m/s], TC [s], COR [-], mass [kg],
    Kelvin-Voigt stiffness [N/m] or None) as 1-D arrays of one length."""
    vin = _as_1d("vin_m_s", vin_m_s)
    n_all = vin.size
    tc = _as_1d("contact_time_s", contact_time_s, n_all)
    e = _as_1d("cor", cor, n_all)
    mass = _as_1d("mass_kg", mass_kg, n_all)
    if np.any(tc <= 0) or np.any(e <= 0) or np.any(vin <= 0) or np.any(mass <= 0):
        raise ValueError("vin_m_s, contact_time_s, cor and mass_kg must be positive")
    if n_all < 3:
        raise FitError(f"fitting AK, a and AC needs at least 3 good impacts, got {n_all}")
    if n_bootstrap < 0:
        raise ValueError(f"n_bootstrap must be non-negative, got {n_bootstrap}")
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    if kb0_N_m is not None and (not np.isfinite(kb0_N_m) or kb0_N_m < 0):
        raise ValueError(f"kb0_N_m must be non-negative, got {kb0_N_m!r}")
    kv_all = None
    if kv_stiffness_N_m is not None:
        kv_all = _as_1d("kv_stiffness_N_m", kv_stiffness_N_m, n_all)
    return vin, tc, e, mass, kv_all


def _outlier_search(vin, tc, e, mass, kb0_N_m, detect, level, max_share):
    """Step 1 of :func:`fit_ball_model`: (used mask, outlier notes, robust start or None,
    search steps, messages); everything used when ``detect`` is false."""
    if not detect:
        return np.ones(vin.size, dtype=bool), [""] * vin.size, None, [], []
    found = detect_fit_outliers(vin, tc, e, mass, kb0_N_m=kb0_N_m, level=level, max_share=max_share)
    messages = list(found.messages)
    if (~found.used).any():
        messages.append(f"{int((~found.used).sum())} fit outlier(s) left out")
    return found.used, found.notes, found.start, found.steps, messages


def _kb0_choice(vin, kv, kb0_N_m, confidence):
    """kB(0) [N/m] to start from, its source ("config", "fitted" or "extrapolated"), the
    straight-line :class:`Kb0Fit` (None from the config) and :func:`_kb0_lines` (None)."""
    if kb0_N_m is not None:
        return float(kb0_N_m), "config", None, None
    kb0_fit = fit_kb0(vin, kv, confidence=confidence)
    line = _kb0_lines(vin, kv, confidence)
    source = "fitted" if np.min(vin) < LOW_SPEED_M_S else "extrapolated"
    return kb0_fit.kb0_N_m, source, kb0_fit, line


def _joint_fits(vin, tc, e, mass, kb0, kb0_source, confidence, robust_start, intervals=True):
    """The joint fit with kB(0) fixed, and with kB(0) free unless it comes from the config:
    (the one the parameters come from, the free one or None). Without ``intervals`` the
    free fit of an extrapolated kB(0) (only there for the intervals' hull) is not made."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        cond = _joint_fit(vin, tc, e, mass, kb0, None, confidence, robust_start=robust_start, intervals=intervals)
        free = None
        if kb0_source == "fitted" or (kb0_source != "config" and intervals):
            free = _joint_fit(vin, tc, e, mass, kb0, cond, confidence, intervals=intervals)
    return (free if kb0_source == "fitted" else cond), free


def _interval_ends(main, free, kb0_source, kb0_fit, messages):
    """Interval ends of each parameter in SI (``a`` [-], the others [N/m...]): the profile
    intervals of ``main``, the hull with ``free`` and the straight line's when kB(0) is
    extrapolated, NaN for kB(0) from the config. Appends a message per open interval."""
    iv = dict(main["intervals"])
    if kb0_source == "extrapolated":
        for key, (lo, hi, closed) in free["intervals"].items():
            if key in iv:
                lo0, hi0, closed0 = iv[key]
                iv[key] = (min(lo, lo0), max(hi, hi0), closed and closed0)
        lo_k, hi_k, closed_k = free["intervals"]["kb0"]
        iv["kb0"] = (np.log(max(min(np.exp(lo_k), kb0_fit.kb0_lo), 1.0)),
                     np.log(max(np.exp(hi_k), kb0_fit.kb0_hi)), closed_k)
    lo_hi = {}
    for key, (lo, hi, closed) in iv.items():
        lo_hi[key] = (float(lo), float(hi)) if key == "a" else (float(np.exp(lo)), float(np.exp(hi)))
        if not closed:
            messages.append(f"the {key} interval reaches the end of its profile grid: the data barely constrain it")
    if kb0_source == "config":
        lo_hi["kb0"] = (float("nan"), float("nan"))
    return lo_hi


def _bootstrap_summary(vin, tc, e, mass, kv, kb0, theta, s_tc, s_cor, kb0_source, n_bootstrap, seed, messages):
    """:func:`_bootstrap` and what follows from it: (resamples, dropped count, AK-a correlation
    [-] (NaN with fewer than 10 resamples), the note for the interval method). Appends a
    message when more than a fifth of the refits did not converge."""
    boot, dropped = _bootstrap(vin, tc, e, mass, kv, kb0, theta, s_tc, s_cor, kb0_source, n_bootstrap, seed)
    if dropped > 0.2 * n_bootstrap:
        messages.append(f"only {boot.shape[0]} of {n_bootstrap} bootstrap refits converged; bands unreliable")
    corr, note = float("nan"), ""
    if boot.shape[0] >= 10:
        corr = float(np.corrcoef(np.log(boot[:, 1]), boot[:, 2])[0, 1])
        note = (f"; AK-a correlation and curve bands from {boot.shape[0]} bootstrap resamples over impacts "
                f"({dropped} unconverged dropped)")
    return boot, dropped, corr, note


def _interval_method(kb0_source):
    """How the intervals were found, for ``BallFit.interval_method``."""
    method = ("profile likelihood, critical value calibrated by a parametric bootstrap of the fit "
              f"({CALIBRATION_SESSIONS} simulated sessions, linearised, TC and COR scatter re-estimated), "
              "residuals weighted by the unbiased TC and COR scatter")
    if CALIBRATION_SESSIONS < 100:
        method = ("profile likelihood, F(1, Satterthwaite dof) critical value, residuals weighted by "
                  "the unbiased TC and COR scatter")
    if kb0_source == "extrapolated":
        method += ("; kB(0) extrapolated by the paper's straight line, intervals the hull with kB(0) fixed "
                   "there and with kB(0) fitted (extrapolation-model uncertainty)")
    elif kb0_source == "config":
        method += "; conditional on kB(0) from the config"
    return method


def _joint_fit(vin, tc, e, mass, kb0, start, confidence, robust_start=None, intervals=True):
    """Joint fit of AK, a, AC (start None: kB(0) fixed) or of AK, a, AC, kB(0) (start: the
    fixed-kB(0) result, kB(0) then free from its value), weights re-estimated to the
    unbiased scatter of each kind, then the profile intervals. ``robust_start`` (theta,
    sigma_tc, sigma_cor) of :func:`detect_fit_outliers` replaces the stage fits."""
    if start is None and robust_start is not None:
        theta, s_tc, s_cor = robust_start
        theta = np.asarray(theta, dtype=float).copy()
    elif start is None:
        stage1 = fit_contact_time(vin, tc, mass, kb0)
        stage2 = fit_restitution(vin, e, mass, kb0, stage1.ak, stage1.a)
        theta = _to_theta(stage2.ak, stage2.a, stage2.ac)
        s_tc = max(stage1.rmse_pct / 100.0, 1e-4)
        s_cor = max(stage2.rmse_pct / 100.0, 1e-4)
    else:
        theta = np.append(start["theta"], np.log(max(kb0, KB0_BOUNDS_N_M[0] * 1.01)))
        s_tc, s_cor = start["sigma_tc"], start["sigma_cor"]
    n = vin.size
    res = None
    what = "joint fit (AK, a, AC" + (", kB(0))" if theta.size == 4 else ")")
    for _ in range(4):
        res = _fit_weighted(vin, tc, e, mass, kb0, theta, s_tc, s_cor, what)
        theta = res.x
        tc_m, cor_m = _simulate(theta, vin, mass, kb0)
        new_tc, new_cor, dof_tc, dof_cor, _ = _block_scatter(res.jac, (tc_m - tc) / tc, (cor_m - e) / e, n)
        # the weights are the scatter of each kind at the weights' own optimum (iterated
        # until they change by < 2 %; the fit is insensitive to smaller changes)
        done = abs(new_tc / s_tc - 1) < 0.02 and abs(new_cor / s_cor - 1) < 0.02
        s_tc, s_cor = new_tc, new_cor
        if done:
            break
    if not intervals:  # point estimates only (fit_ball_model(intervals=False))
        return {"theta": theta, "sigma_tc": s_tc, "sigma_cor": s_cor, "dof_tc": dof_tc, "dof_cor": dof_cor,
                "intervals": None, "result": res}
    crit = _calibrated_critical_values(vin, tc, e, mass, kb0, theta, s_tc, s_cor, confidence)
    iv = _profile_intervals(vin, tc, e, mass, kb0, s_tc, s_cor, dof_tc, dof_cor, theta, confidence, critical=crit)
    return {"theta": theta, "sigma_tc": s_tc, "sigma_cor": s_cor, "dof_tc": dof_tc, "dof_cor": dof_cor,
            "intervals": iv, "result": res}


def _bootstrap(vin, tc, e, mass, kv, kb0, theta, s_tc, s_cor, kb0_source, n_bootstrap, seed):
    """Case-resampling bootstrap: (resamples (B, 4): kB(0) [N/m], AK, a, AC SI; dropped count)."""
    n = vin.size
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(n_bootstrap, n))
    weights = np.stack([np.bincount(row, minlength=n) for row in idx]).astype(float)
    kb0_b = np.full(n_bootstrap, kb0)
    if kb0_source == "extrapolated":
        from scipy import stats

        for i, row in enumerate(idx):
            if np.ptp(vin[row]) > 0:
                reg = stats.linregress(vin[row], kv[row])
                kb0_b[i] = reg.intercept if reg.intercept > 0 else np.nan
            else:
                kb0_b[i] = np.nan
    ok = np.isfinite(kb0_b)
    dropped = int((~ok).sum())
    kb0_b, weights = kb0_b[ok], weights[ok]
    sqrt_w = np.sqrt(np.hstack([weights, weights]))
    lo_b, hi_b = _full_bounds(theta.size)

    def resid(pts, rows):
        return _residuals(pts, vin, tc, e, mass, kb0_b[rows], s_tc, s_cor) * sqrt_w[rows]

    th_b, conv = _batched_lm(resid, np.repeat(theta[None], kb0_b.size, axis=0), lo_b, hi_b)
    dropped += int((~conv).sum())
    ak_b, a_b, ac_b = _from_theta(th_b[:, :3])
    if theta.size == 4:
        kb0_b = np.exp(th_b[:, 3])
    return np.column_stack([kb0_b, ak_b, a_b, ac_b])[conv], dropped


def model_curves(fit: BallFit, speeds_m_s, *, confidence=0.95, max_band_samples=200):
    """Model TC, COR and peak force against inbound speed, with confidence and prediction bands.

    The curves are Eqs. (4)-(16) of Goodwill & Haake 2004 at the fitted parameters.
    Confidence band (where the curve lies): percentiles of the curves of the bootstrap
    parameter sets. Prediction band (where the next impact of this ball type will
    fall): the confidence band's half-width and the impacts' own relative scatter
    (``contact_time_scatter``, ``cor_scatter`` times the Student t quantile with the
    fit's residual degrees of freedom) added in quadrature about the curve.

    Parameters
    ----------
    fit : BallFit
        A fitted ball.
    speeds_m_s : array_like
        Inbound speeds [m/s].
    confidence : float
        Band level [-].
    max_band_samples : int
        Bootstrap parameter sets used for the band.

    Returns
    -------
    dict
        ``contact_time_s`` [s], ``cor`` [-], ``peak_force_N`` [N] (each (n_speed,)),
        confidence bands ``contact_time_s_lo/_hi``, ``cor_lo/_hi`` and prediction bands
        ``contact_time_s_pred_lo/_hi``, ``cor_pred_lo/_hi`` (NaN when unavailable).
    """
    v = _as_1d("speeds_m_s", speeds_m_s)
    sim = simulate_impact(v, fit.mass_kg, fit.kb0_N_m, fit.ak, fit.a, fit.ac)
    out = {
        "contact_time_s": sim.contact_time_s,
        "cor": sim.cor,
        "peak_force_N": sim.peak_force_N,
    }
    nan = np.full(v.size, np.nan)
    out.update(contact_time_s_lo=nan, contact_time_s_hi=nan, cor_lo=nan, cor_hi=nan,
               contact_time_s_pred_lo=nan, contact_time_s_pred_hi=nan, cor_pred_lo=nan, cor_pred_hi=nan)
    boot = fit.bootstrap
    half = {"contact_time_s": np.zeros(v.size), "cor": np.zeros(v.size)}
    if boot is not None and boot.shape[0] >= 10:
        b = boot[: max_band_samples]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            s = simulate_impact(v[None, :], fit.mass_kg, b[:, 0:1], b[:, 1:2], b[:, 2:3], b[:, 3:4])
        q = 100 * np.array([0.5 - confidence / 2, 0.5 + confidence / 2])
        out["contact_time_s_lo"], out["contact_time_s_hi"] = np.nanpercentile(s.contact_time_s, q, axis=0)
        out["cor_lo"], out["cor_hi"] = np.nanpercentile(s.cor, q, axis=0)
        for key in half:
            half[key] = np.maximum(out[key] - out[f"{key}_lo"], out[f"{key}_hi"] - out[key])
    scatter = {"contact_time_s": getattr(fit, "contact_time_scatter", np.nan),
               "cor": getattr(fit, "cor_scatter", np.nan)}
    dof = getattr(fit, "scatter_dof", np.nan)
    if np.isfinite(dof) and dof > 0:
        t = _t_ppf(0.5 + confidence / 2, dof)
        for key in half:
            if np.isfinite(scatter[key]):
                w = np.sqrt(half[key] ** 2 + (t * scatter[key] * out[key]) ** 2)
                out[f"{key}_pred_lo"], out[f"{key}_pred_hi"] = out[key] - w, out[key] + w
    return out
