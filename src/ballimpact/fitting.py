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

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, special

from .model import kelvin_voigt_parameters, simulate_impact

# scipy.stats costs about 0.4 CPU-s to import, in every job that fits: the quantiles and
# tail probabilities of a fit are the special functions its distributions call (the same
# numbers), and scipy.stats is imported only where a regression needs it.


def _t_ppf(q, dof):
    """Quantile of Student's t [-], as scipy.stats.t.ppf(q, dof) (which calls this function)."""
    return special.stdtrit(dof, q)


def _t_sf(x, dof):
    """Upper tail probability of Student's t [-], as scipy.stats.t.sf(x, dof)."""
    return special.stdtr(dof, -x)


def _f_ppf(q, dof_num, dof_den):
    """Quantile of Fisher's F [-], as scipy.stats.f.ppf(q, dof_num, dof_den)."""
    return special.fdtri(dof_num, dof_den, q)


def _chi2_ppf(q, dof):
    """Quantile of chi-squared [-], as scipy.stats.chi2.ppf(q, dof)."""
    return 2 * special.gammaincinv(dof / 2, q)


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

#: Reference displacement for the internal stiffness parameter kR = AK xR^a [m].
REFERENCE_DISPLACEMENT_M = 0.020
#: Search bounds, SI: AK [N/m^(1+a)] via kR [N/m], a [-], AC [N s/m^3].
PARAMETER_BOUNDS = {
    "kr_N_m": (1.0e2, 1.0e6),
    "a": (0.3, 4.0),
    "ac": (1.0e1, 1.0e5),
}
#: Search bounds of kB(0) when it is fitted [N/m].
KB0_BOUNDS_N_M = (1.0e2, 2.0e5)
#: kB(0) is fitted with AK, a and AC when some impact is slower than this [m/s].
LOW_SPEED_M_S = 10.0
#: Family-wise level of the fit-outlier test per ball type [-].
OUTLIER_LEVEL = 0.005
#: Largest share of a ball type's impacts that may be removed as fit outliers [-].
OUTLIER_MAX_SHARE = 0.2
#: Relative offset (Bates & Watts 1981) below which a least-squares problem has converged [-]:
#: the parameters are then within about 1 % of a standard error of the optimum. (1e-3 is
#: below what the model's finite-difference Jacobian resolves at some optima.)
CONVERGENCE_OFFSET = 1.0e-2
#: Simulated sessions, fitted in the model linearised at the estimate, that calibrate the
#: critical value of the profile intervals (:func:`_calibrated_critical_values`) [-];
#: 0 gives the F(1, nu) quantile alone.
CALIBRATION_SESSIONS = 4000
#: Of those, sessions also refitted with the full model (batched Levenberg-Marquardt) to
#: correct the linearised quantile for the model's curvature [-]; 0: none (the default:
#: the correction is within its own sampling noise on Table 2 balls at 14-30 m/s).
CALIBRATION_REFITS = 0
_FD_STEP = 1.0e-4  # forward-difference step in the internal parameters (log kR, a, log AC)


class FitError(RuntimeError):
    """The optimiser did not converge, or the data cannot constrain the fit."""


@dataclass
class Kb0Fit:
    """Result of :func:`fit_kb0`.

    Attributes
    ----------
    kb0_N_m : float
        Zero-speed intercept kB(0) [N/m].
    kb0_lo, kb0_hi : float
        95 % confidence interval of the intercept [N/m].
    slope_N_s_m2 : float
        Slope of the Kelvin-Voigt stiffness against inbound speed [N s/m^2].
    n_impacts : int
        Impacts used.
    result : object
        The regression result (scipy.stats.linregress).
    """

    kb0_N_m: float
    kb0_lo: float
    kb0_hi: float
    slope_N_s_m2: float
    n_impacts: int
    result: object


@dataclass
class StageFit:
    """Result of one stage: fitted parameters (SI) and the optimiser result."""

    ak: float
    a: float
    ac: float
    rmse_pct: float
    result: optimize.OptimizeResult


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


def _as_1d(name, value, n=None):
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if n is not None and arr.size not in (1, n):
        raise ValueError(f"{name} must have {n} values (one per impact), got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr[~np.isfinite(arr)][0]!r}")
    return np.broadcast_to(arr, (n,)).copy() if n is not None else arr


def fit_kb0(vin_m_s, kv_stiffness_N_m, *, confidence=0.95) -> Kb0Fit:
    """Extrapolate the Kelvin-Voigt stiffness to zero inbound speed: kB(0) (section 3.4).

    A straight line kB_KV = kB(0) + s VB through the per-impact Kelvin-Voigt
    stiffness (Eq. (2) in Goodwill & Haake 2004) by ordinary least squares; the
    interval of the intercept from Student's t.

    Parameters
    ----------
    vin_m_s : array_like
        Inbound speeds [m/s].
    kv_stiffness_N_m : array_like
        Kelvin-Voigt stiffness of each impact [N/m].
    confidence : float
        Confidence level of the interval [-].

    Returns
    -------
    Kb0Fit

    Raises
    ------
    FitError
        Fewer than 3 impacts, all at one speed, or a non-positive intercept.
    """
    vin = _as_1d("vin_m_s", vin_m_s)
    kv = _as_1d("kv_stiffness_N_m", kv_stiffness_N_m, vin.size)
    if vin.size < 3:
        raise FitError(f"kB(0) extrapolation needs at least 3 impacts, got {vin.size}")
    if np.ptp(vin) <= 0:
        raise FitError("kB(0) extrapolation needs impacts at more than one inbound speed")
    from scipy import stats

    reg = stats.linregress(vin, kv)
    t = _t_ppf(0.5 + confidence / 2, vin.size - 2)
    lo, hi = reg.intercept - t * reg.intercept_stderr, reg.intercept + t * reg.intercept_stderr
    if not reg.intercept > 0:
        raise FitError(
            f"extrapolated kB(0) is not positive ({reg.intercept / 1e3:.1f} kN/m): the Kelvin-Voigt "
            "stiffness does not fall towards low speeds; give kb0_kN_m in session.yaml"
        )
    return Kb0Fit(float(reg.intercept), float(lo), float(hi), float(reg.slope), int(vin.size), reg)


# --- internal parameters: theta = (log kR, a, log AC) -------------------------------------


def _to_theta(ak, a, ac):
    kr = ak * REFERENCE_DISPLACEMENT_M**a
    return np.array([np.log(kr), a, np.log(ac)], dtype=float)


def _from_theta(theta):
    theta = np.asarray(theta, dtype=float)
    kr, a, ac = np.exp(theta[..., 0]), theta[..., 1], np.exp(theta[..., 2])
    return kr / REFERENCE_DISPLACEMENT_M**a, a, ac


def _theta_bounds():
    b = PARAMETER_BOUNDS
    lo = np.array([np.log(b["kr_N_m"][0]), b["a"][0], np.log(b["ac"][0])])
    hi = np.array([np.log(b["kr_N_m"][1]), b["a"][1], np.log(b["ac"][1])])
    return lo, hi


def _simulate(theta, vin, mass, kb0):
    """TC [s] and COR for parameter sets theta (..., 3) at every impact: shape (..., n).

    theta = (log kR, a, log AC), or (..., 4) with log kB(0) last (``kb0`` [N/m] is then
    ignored). Parameter sets that are not finite and positive give NaN.
    """
    theta = np.asarray(theta, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        ak, a, ac = _from_theta(theta[..., :3])
        kb0 = np.exp(theta[..., 3]) if theta.shape[-1] == 4 else np.asarray(kb0, dtype=float)
    ak, a, ac, kb0 = np.broadcast_arrays(ak, a, ac, kb0)
    good = (np.isfinite(ak) & (ak > 0) & np.isfinite(a) & (a > 0) & np.isfinite(ac) & (ac > 0)
            & np.isfinite(kb0) & (kb0 >= 0))
    if not np.all(good):
        ak, a, ac, kb0 = (np.where(good, x, d) for x, d in ((ak, 1e4), (a, 1.5), (ac, 3e3), (kb0, 2e4)))
    sim = simulate_impact(vin, mass, kb0[..., None], ak[..., None], a[..., None], ac[..., None])
    tc_m, cor_m = sim.contact_time_s, sim.cor
    if not np.all(good):
        tc_m = np.where(good[..., None], tc_m, np.nan)
        cor_m = np.where(good[..., None], cor_m, np.nan)
    return tc_m, cor_m


class _Problem:
    """Weighted relative residuals of TC and/or COR for one ball type."""

    def __init__(self, vin, tc, cor, mass, kb0, use_tc, use_cor, sigma_tc=1.0, sigma_cor=1.0,
                 fixed=None):
        self.vin, self.tc, self.cor, self.mass, self.kb0 = vin, tc, cor, mass, kb0
        self.use_tc, self.use_cor = use_tc, use_cor
        self.sigma_tc, self.sigma_cor = sigma_tc, sigma_cor
        self.fixed = fixed  # dict index -> value for parameters held fixed
        self.free = [i for i in range(3) if not fixed or i not in fixed]

    def full(self, p):
        p = np.asarray(p, dtype=float)
        theta = np.empty(p.shape[:-1] + (3,))
        theta[..., self.free] = p
        for i, v in (self.fixed or {}).items():
            theta[..., i] = v
        return theta

    def residuals_batch(self, p):
        tc_m, cor_m = _simulate(self.full(p), self.vin, self.mass, self.kb0)
        parts = []
        if self.use_tc:
            parts.append((tc_m - self.tc) / self.tc / self.sigma_tc)
        if self.use_cor:
            parts.append((cor_m - self.cor) / self.cor / self.sigma_cor)
        r = np.concatenate(parts, axis=-1)
        # an impact that did not end gets a large, finite residual so the optimiser backs off
        return np.where(np.isfinite(r), r, 1.0e3)

    def fun(self, p):
        # The residuals and all forward-difference points in one batched simulation;
        # the Jacobian is kept for the call of jac() that follows at the same point.
        p = np.asarray(p, dtype=float)
        pts = np.repeat(p[None, :], p.size + 1, axis=0)
        pts[1:] += np.eye(p.size) * _FD_STEP
        r = self.residuals_batch(pts)
        self._jac_cache = (p.copy(), ((r[1:] - r[0]) / _FD_STEP).T)
        return r[0]

    def jac(self, p):
        p = np.asarray(p, dtype=float)
        cache = getattr(self, "_jac_cache", None)
        if cache is None or not np.array_equal(cache[0], p):
            self.fun(p)
        return self._jac_cache[1]


def _least_squares(problem: _Problem, p0, what):
    lo, hi = _theta_bounds()
    free = problem.free
    p0 = np.clip(np.asarray(p0, dtype=float), lo[free] + 1e-9, hi[free] - 1e-9)
    res = optimize.least_squares(
        problem.fun, p0, jac=problem.jac, bounds=(lo[free], hi[free]), method="trf",
        x_scale=1.0, xtol=1e-8, ftol=1e-8, gtol=1e-8, max_nfev=200,
    )
    if not res.success:
        raise FitError(f"{what}: the optimiser did not converge ({res.message})")
    return res


def _bound_messages(theta, names=("AK (via kR)", "a", "AC")):
    lo, hi = _theta_bounds()
    msgs = []
    for i, name in enumerate(names):
        span = hi[i] - lo[i]
        if theta[i] - lo[i] < 1e-3 * span or hi[i] - theta[i] < 1e-3 * span:
            msgs.append(f"{name} sits on its search bound; the data do not constrain it, treat it with care")
    return msgs


def _rmse_pct(r):
    return float(100.0 * np.sqrt(np.mean(np.square(r))))


def _start_grid(vin, tc, mass, kb0, ac):
    """Coarse grid over (kR, a) for a robust start of stage one."""
    kr = np.geomspace(3e3, 1e5, 9)
    a = np.linspace(0.8, 2.6, 7)
    K, A = np.meshgrid(np.log(kr), a, indexing="ij")
    theta = np.stack([K.ravel(), A.ravel(), np.full(K.size, np.log(ac))], axis=-1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        tc_m, _ = _simulate(theta, vin, mass, kb0)
    cost = np.nansum(((tc_m - tc) / tc) ** 2, axis=-1) + 1e3 * np.isnan(tc_m).sum(axis=-1)
    return theta[int(np.argmin(cost))]


def fit_contact_time(vin_m_s, contact_time_s, mass_kg, kb0_N_m, *, ac=3.5e3, start=None) -> StageFit:
    """Stage one: AK and a so that the model's TC matches each measured TC (section 3.4.1).

    Least squares on the relative TC residuals of the impacts themselves, with
    kB(0) and AC held fixed (TC depends mainly on the stiffness, Eq. (4)).

    Parameters
    ----------
    vin_m_s : array_like
        Inbound speeds [m/s].
    contact_time_s : array_like
        Measured contact times [s].
    mass_kg : array_like
        Ball mass per impact [kg].
    kb0_N_m : float
        kB(0) [N/m].
    ac : float
        AC held fixed in this stage [N s/m^3].
    start : tuple of float, optional
        Starting (AK [N/m^(1+a)], a); default a coarse grid search.

    Returns
    -------
    StageFit

    Raises
    ------
    FitError
        When the optimiser does not converge or fewer than 2 impacts are given.
    """
    vin = _as_1d("vin_m_s", vin_m_s)
    n = vin.size
    tc = _as_1d("contact_time_s", contact_time_s, n)
    mass = _as_1d("mass_kg", mass_kg, n)
    if n < 2:
        raise FitError(f"stage one needs at least 2 impacts to fit AK and a, got {n}")
    theta0 = _start_grid(vin, tc, mass, kb0_N_m, ac) if start is None else _to_theta(start[0], start[1], ac)
    prob = _Problem(vin, tc, None, mass, kb0_N_m, True, False, fixed={2: np.log(ac)})
    res = _least_squares(prob, theta0[:2], "stage one (AK, a on contact time)")
    ak, a, _ = _from_theta(prob.full(res.x))
    return StageFit(float(ak), float(a), float(ac), _rmse_pct(res.fun), res)


def fit_restitution(vin_m_s, cor, mass_kg, kb0_N_m, ak, a, *, ac_start=3.5e3) -> StageFit:
    """Stage two: AC so that the model's COR matches each measured COR (section 3.4.2).

    Parameters
    ----------
    vin_m_s : array_like
        Inbound speeds [m/s].
    cor : array_like
        Measured coefficients of restitution [-].
    mass_kg : array_like
        Ball mass per impact [kg].
    kb0_N_m : float
        kB(0) [N/m].
    ak : float
        AK from stage one [N/m^(1+a)].
    a : float
        a from stage one [-].
    ac_start : float
        Starting AC [N s/m^3].

    Returns
    -------
    StageFit

    Raises
    ------
    FitError
        When the optimiser does not converge.
    """
    vin = _as_1d("vin_m_s", vin_m_s)
    n = vin.size
    e = _as_1d("cor", cor, n)
    mass = _as_1d("mass_kg", mass_kg, n)
    if n < 1:
        raise FitError("stage two needs at least one impact")
    th = _to_theta(ak, a, ac_start)
    prob = _Problem(vin, None, e, mass, kb0_N_m, False, True, fixed={0: th[0], 1: th[1]})
    res = _least_squares(prob, th[2:], "stage two (AC on COR)")
    return StageFit(float(ak), float(a), float(np.exp(res.x[0])), _rmse_pct(res.fun), res)


def _relative_offset(jac, r, p, lo, hi):
    """Bates & Watts (1981) relative offset of each batch row: how far the residual vector
    still has a component in the tangent plane of the model, relative to the residual
    scatter. Parameters held on a bound by the gradient are left out of the plane.

    jac (B, m, k), r (B, m), p/lo/hi (B, k) -> (B,) [-]; 0 when the residuals vanish.
    """
    g = np.einsum("bij,bi->bj", jac, r)
    at_bound = ((p <= lo + 1e-12) & (g > 0)) | ((p >= hi - 1e-12) & (g < 0))
    free = ~at_bound
    k = p.shape[-1]
    jtj = np.einsum("bij,bik->bjk", jac, jac)
    mask = free[:, :, None] & free[:, None, :]
    jtj = np.where(mask, jtj, 0.0) + np.eye(k) * (~free)[:, None, :]
    jtj = jtj + 1e-14 * np.eye(k) * np.maximum(np.einsum("bjj->b", jtj), 1e-300)[:, None, None]
    g = np.where(free, g, 0.0)
    proj2 = np.einsum("bj,bj->b", g, np.linalg.solve(jtj, g[..., None])[..., 0])
    rr = np.sum(r**2, axis=-1)
    m = np.count_nonzero(r, axis=-1)
    n_free = free.sum(axis=-1)
    den = np.maximum(rr - proj2, 0.0) / np.maximum(m - n_free, 1)
    num = np.maximum(proj2, 0.0) / np.maximum(n_free, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        off = np.sqrt(num / den)
    return np.where(rr < 1e-24, 0.0, np.where(np.isfinite(off), off, np.inf))


def _batched_lm(resid, p0, lo, hi, max_iter=100, offset_tol=CONVERGENCE_OFFSET):
    """Levenberg-Marquardt on many independent least-squares problems at once.

    resid : callable mapping points (..., B, k) and row indices (B,) to residuals
        (..., B, m); it is called with the current points and their forward-difference
        neighbours stacked, so every iteration is one batched model simulation.
    p0 : (B, k) starting points; lo, hi : bounds, (k,) or (B, k).

    Convergence is judged at the current point of each problem by the relative
    offset criterion of Bates & Watts (1981), i.e. by the gradient relative to the
    residual scatter: a problem has converged when the part of its residual vector
    in the model's tangent plane is below ``offset_tol`` of the residual scatter
    (the parameters are then within about ``offset_tol`` standard errors of the optimum). A problem
    started at its optimum is converged before the first step. ``max_iter`` is only
    a safety stop: a problem that reaches it, or whose damping grows without an
    accepted step, is reported as not converged.

    Returns the points (B, k) and a converged flag (B,).
    """
    p = np.array(p0, dtype=float)
    b, k = p.shape
    lo = np.broadcast_to(np.asarray(lo, dtype=float), p.shape)
    hi = np.broadcast_to(np.asarray(hi, dtype=float), p.shape)
    p = np.clip(p, lo, hi)
    lam = np.full(b, 1e-3)
    converged = np.zeros(b, dtype=bool)
    stuck = np.zeros(b, dtype=bool)
    eye = np.eye(k)

    def with_jacobian(points, rows):
        # the points and their forward-difference neighbours in one batched call
        pts = np.repeat(points[None], k + 1, axis=0)
        for j in range(k):
            pts[j + 1, :, j] += _FD_STEP
        r_all = resid(pts, rows)
        return r_all[0], np.moveaxis((r_all[1:] - r_all[0]) / _FD_STEP, 0, -1)  # (B, m), (B, m, k)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r0, jac = with_jacobian(p, np.arange(b))
        for _ in range(max_iter + 1):
            act = np.flatnonzero(~converged & ~stuck)
            if not act.size:
                break
            off = _relative_offset(jac[act], r0[act], p[act], lo[act], hi[act])
            converged[act[off < offset_tol]] = True
            stuck[act[lam[act] > 1e12]] = True
            act = np.flatnonzero(~converged & ~stuck)
            if not act.size or _ == max_iter:
                break
            ja, ra = jac[act], r0[act]
            jtj = np.einsum("bij,bik->bjk", ja, ja)
            jtr = np.einsum("bij,bi->bj", ja, ra)
            diag = np.einsum("bjj->bj", jtj)
            a_mat = jtj + lam[act][:, None, None] * eye * diag[:, None, :] + 1e-12 * eye
            step = -np.linalg.solve(a_mat, jtr[..., None])[..., 0]
            new = np.clip(p[act] + step, lo[act], hi[act])
            r_new, jac_new = with_jacobian(new, act)
            c0 = np.sum(ra**2, axis=-1)
            c1 = np.sum(r_new**2, axis=-1)
            better = c1 < c0
            acc = act[better]
            p[acc], r0[acc], jac[acc] = new[better], r_new[better], jac_new[better]
            lam[acc] = np.maximum(lam[acc] * 0.3, 1e-9)
            lam[act[~better]] *= 10.0
    return p, converged


def _residuals(theta, vin, tc, cor, mass, kb0, sigma_tc, sigma_cor):
    """Weighted relative residuals (model - measured) / measured / sigma, TC then COR: (..., 2n)."""
    tc_m, cor_m = _simulate(theta, vin, mass, kb0)
    r = np.concatenate([(tc_m - tc) / tc / sigma_tc, (cor_m - cor) / cor / sigma_cor], axis=-1)
    return np.where(np.isfinite(r), r, 1.0e3)


def _jacobian(fun, theta):
    """Forward-difference Jacobian of fun at theta (P,) -> (m, P), one batched call."""
    k = theta.size
    pts = np.repeat(theta[None], k + 1, axis=0)
    pts[1:] += np.eye(k) * _FD_STEP
    r = fun(pts)
    return ((r[1:] - r[0]) / _FD_STEP).T


def _full_bounds(n_par):
    lo, hi = _theta_bounds()
    if n_par == 4:
        lo = np.append(lo, np.log(KB0_BOUNDS_N_M[0]))
        hi = np.append(hi, np.log(KB0_BOUNDS_N_M[1]))
    return lo, hi


def _fit_weighted(vin, tc, cor, mass, kb0, theta0, sigma_tc, sigma_cor, what, loss="linear"):
    """Least squares of all free parameters (3, or 4 with log kB(0) last) at fixed weights."""
    n_par = theta0.size
    lo, hi = _full_bounds(n_par)

    def fun_batch(pts):
        return _residuals(pts, vin, tc, cor, mass, kb0, sigma_tc, sigma_cor)

    cache = {}

    def fun(p):
        pts = np.repeat(p[None], n_par + 1, axis=0)
        pts[1:] += np.eye(n_par) * _FD_STEP
        r = fun_batch(pts)
        cache["p"], cache["j"] = p.copy(), ((r[1:] - r[0]) / _FD_STEP).T
        return r[0]

    def jac(p):
        if "p" not in cache or not np.array_equal(cache["p"], p):
            fun(p)
        return cache["j"]

    p0 = np.clip(np.asarray(theta0, dtype=float), lo + 1e-9, hi - 1e-9)
    res = optimize.least_squares(fun, p0, jac=jac, bounds=(lo, hi), method="trf", loss=loss, f_scale=1.0,
                                 x_scale=1.0, xtol=1e-8, ftol=1e-9, gtol=1e-9, max_nfev=300)
    if res.status <= 0:
        raise FitError(f"{what}: the optimiser did not converge ({res.message})")
    return res


def _block_scatter(jac, r_raw_tc, r_raw_cor, n):
    """Unbiased relative scatter of the TC and COR residuals and their degrees of freedom.

    jac : (2n, P) Jacobian of the weighted residuals. The effective number of
    parameters each block uses is the trace of its part of the hat matrix
    (Hoaglin & Welsch 1978); sigma_b^2 = RSS_b / (n - p_b).
    """
    cov = np.linalg.pinv(jac.T @ jac)
    h = np.einsum("ij,jk,ik->i", jac, cov, jac)
    p_tc, p_cor = float(np.sum(h[:n])), float(np.sum(h[n:]))
    dof_tc, dof_cor = max(n - p_tc, 1.0), max(n - p_cor, 1.0)
    s_tc = max(float(np.sqrt(np.sum(r_raw_tc**2) / dof_tc)), 1e-5)
    s_cor = max(float(np.sqrt(np.sum(r_raw_cor**2) / dof_cor)), 1e-5)
    return s_tc, s_cor, dof_tc, dof_cor, h


def _satterthwaite_dof(grad, jac, n, dof_tc, dof_cor):
    """Degrees of freedom of the variance of a function of the parameters with gradient
    ``grad`` when the TC and COR scatter are estimated separately (Satterthwaite 1946)."""
    cov = np.linalg.pinv(jac.T @ jac)
    v = cov @ grad
    v_tc = float(np.sum((jac[:n] @ v) ** 2))
    v_cor = float(np.sum((jac[n:] @ v) ** 2))
    den = v_tc**2 / dof_tc + v_cor**2 / dof_cor
    return float((v_tc + v_cor) ** 2 / den) if den > 0 else float(min(dof_tc, dof_cor))


class _Quantity:
    """A profiled quantity q(theta) [log scale except a]; theta[drop] is solved from q."""

    def __init__(self, key, drop, fwd, inv):
        self.key, self.drop, self.fwd, self.inv = key, drop, fwd, inv


def _quantities(n_par, kb0_fixed):
    log_xr = np.log(REFERENCE_DISPLACEMENT_M)

    def kb0_of(th):
        return np.exp(th[..., 3]) if n_par == 4 else kb0_fixed

    def kb_x(x):
        lx = np.log(x / REFERENCE_DISPLACEMENT_M)

        def fwd(th):
            return np.log(kb0_of(th) + np.exp(th[..., 0] + th[..., 1] * lx))

        def inv(q, th):
            with np.errstate(invalid="ignore", divide="ignore"):
                return np.log(np.exp(q) - kb0_of(th)) - th[..., 1] * lx
        return fwd, inv

    qs = [
        _Quantity("ak", 0, lambda th: th[..., 0] - th[..., 1] * log_xr, lambda q, th: q + th[..., 1] * log_xr),
        _Quantity("a", 1, lambda th: th[..., 1], lambda q, th: q),
        _Quantity("ac", 2, lambda th: th[..., 2], lambda q, th: q),
        _Quantity("kb_10mm", 0, *kb_x(0.010)),
        _Quantity("kb_20mm", 0, *kb_x(0.020)),
    ]
    if n_par == 4:
        qs.append(_Quantity("kb0", 3, lambda th: th[..., 3], lambda q, th: q))
    return qs


def _profile_intervals(vin, tc, cor, mass, kb0, sigma_tc, sigma_cor, dof_tc, dof_cor, theta, confidence,
                       n_grid=17, critical=None):
    """Profile-likelihood intervals (Bates & Watts 1988, ch. 6) of every quantity of
    :func:`_quantities`, with the critical value calibrated for the estimated scatter.

    The residuals are weighted by the unbiased TC and COR scatter (``sigma_*``), so the
    profile deviance S(q) - S_min of a quantity q is compared with ``critical[key]``
    (from :func:`_calibrated_critical_values`), or when that is missing with the F(1, nu)
    quantile, nu the Satterthwaite degrees of freedom of q's variance (the TC and COR
    scatter are estimated separately, from nu_TC and nu_COR residual degrees of
    freedom; :func:`_satterthwaite_dof`). The profile grid's spacing still comes from
    the Wald standard error. The other parameters are refitted at every
    grid point (started from the Wald-linearised conditional optimum), so the interval
    follows the curved AK-a ridge.

    Returns {key: (lo, hi, closed)} on the quantity's scale (log for all but a).
    """
    n, n_par = vin.size, theta.size
    lo_b, hi_b = _full_bounds(n_par)

    def fun(pts):
        return _residuals(pts, vin, tc, cor, mass, kb0, sigma_tc, sigma_cor)

    r_opt = fun(theta[None])[0]
    s_min = float(np.sum(r_opt**2))
    jac = _jacobian(fun, theta)
    cov = np.linalg.pinv(jac.T @ jac)
    qs = _quantities(n_par, kb0)
    offsets = np.concatenate([-np.geomspace(10, 0.3, n_grid // 2), [0.0], np.geomspace(0.3, 10, n_grid // 2)])
    g = offsets.size
    q_hat, crit, starts, psi = [], [], [], []
    for spec in qs:
        qh, c, start, grid = _profile_grid(spec, theta, cov, jac, n, dof_tc, dof_cor, confidence, offsets,
                                           lo_b, hi_b)
        if critical is not None and np.isfinite(critical.get(spec.key, np.nan)):
            c = critical[spec.key]
        q_hat.append(qh)
        crit.append(c)
        starts.append(start)
        psi.append(grid)
    psi_all = np.concatenate(psi)
    q_of_row = np.repeat(np.arange(len(qs)), g)
    p0 = np.concatenate(starts)
    lo_rows = np.concatenate([np.broadcast_to(lo_b[[i for i in range(n_par) if i != s.drop]], (g, n_par - 1))
                              for s in qs])
    hi_rows = np.concatenate([np.broadcast_to(hi_b[[i for i in range(n_par) if i != s.drop]], (g, n_par - 1))
                              for s in qs])

    def to_theta(pts, rows):
        out = np.empty(pts.shape[:-1] + (n_par,))
        qi = q_of_row[rows]
        for j, spec in enumerate(qs):
            sel = np.flatnonzero(qi == j)
            if not sel.size:
                continue
            keep = [i for i in range(n_par) if i != spec.drop]
            th = np.zeros(pts.shape[:-1][:-1] + (sel.size, n_par))
            th[..., keep] = pts[..., sel, :]
            th[..., spec.drop] = spec.inv(psi_all[rows][sel], th)
            out[..., sel, :] = th
        return out

    def resid(pts, rows):
        with np.errstate(invalid="ignore", over="ignore"):
            return fun(to_theta(pts, rows))

    pts, _ = _batched_lm(resid, p0, lo_rows, hi_rows, max_iter=30)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = resid(pts[None], np.arange(pts.shape[0]))[0]
    dev_all = ((np.sum(r**2, axis=-1) - s_min)).reshape(len(qs), g)
    return {spec.key: _profile_ends(dev_all[j], psi[j], crit[j], q_hat[j]) for j, spec in enumerate(qs)}


def _profile_grid(spec, theta, cov, jac, n, dof_tc, dof_cor, confidence, offsets, lo_b, hi_b):
    """The profile grid of one quantity of :func:`_quantities`: (its estimate, the F(1, nu)
    critical value, the starts of the other parameters at each grid point, the grid)."""
    n_par = theta.size
    qh = float(spec.fwd(theta))
    grad = np.zeros(n_par)
    for j in range(n_par):
        th = theta.copy()
        th[j] += 1e-6
        grad[j] = (float(spec.fwd(th)) - qh) / 1e-6
    var = float(grad @ cov @ grad)
    se = np.sqrt(max(var, 1e-12))
    dof = _satterthwaite_dof(grad, jac, n, dof_tc, dof_cor)
    crit = _f_ppf(confidence, 1, max(dof, 1.0))
    grid = qh + offsets * se
    if spec.key == "a":
        grid = np.clip(grid, lo_b[1], hi_b[1])
    if spec.key == "ac":
        grid = np.clip(grid, lo_b[2], hi_b[2])
    if spec.key == "kb0":
        grid = np.clip(grid, lo_b[3], hi_b[3])
    # Wald-linearised conditional optimum of the other parameters at each grid point
    shift = (cov @ grad) / max(var, 1e-300)
    th_start = theta[None, :] + (grid - qh)[:, None] * shift[None, :]
    keep = [i for i in range(n_par) if i != spec.drop]
    return qh, crit, np.clip(th_start[:, keep], lo_b[keep], hi_b[keep]), grid


def _profile_ends(deviance, grid, crit, q_hat):
    """(lo, hi, closed) of one profile: where the deviance along ``grid`` first crosses
    ``crit`` on each side of the centre, else the grid's end (open).

    Between two grid points the root of the deviance is interpolated linearly: it is
    linear in q where the profile is quadratic (a linear model), so the crossing is then
    exact; interpolating the deviance itself would put it inside the true one (the
    deviance is convex), about 2.5 % narrow on this grid."""
    g = grid.size
    centre = g // 2
    dev = np.where(np.isfinite(deviance), deviance, np.inf)
    dev[centre] = 0.0
    ends = []
    for step in (-1, 1):
        prev, end, closed = centre, grid[0 if step < 0 else g - 1], False
        for i in range(centre + step, -1 if step < 0 else g, step):
            if dev[i] > crit:
                r_prev, r_i = math.sqrt(max(dev[prev], 0.0)), math.sqrt(max(dev[i], 0.0))
                w = (math.sqrt(crit) - r_prev) / (r_i - r_prev) if np.isfinite(dev[i]) else 0.0
                end, closed = grid[prev] + w * (grid[i] - grid[prev]), True
                break
            prev = i
        ends.append((end, closed))
    return float(min(ends[0][0], q_hat)), float(max(ends[1][0], q_hat)), ends[0][1] and ends[1][1]


def _quantity_gradient(spec, theta):
    """Forward-difference gradient of a quantity of :func:`_quantities` at theta: (P,)."""
    qh = float(spec.fwd(theta))
    grad = np.zeros(theta.size)
    for j in range(theta.size):
        th = theta.copy()
        th[j] += 1e-6
        grad[j] = (float(spec.fwd(th)) - qh) / 1e-6
    return grad


def _inverse(a):
    """Inverse of a stack of symmetric positive definite matrices; pseudo-inverse if one is singular."""
    try:
        return np.linalg.inv(a)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(a)


def _linear_sessions(jac_raw, r0, sigma_tc, sigma_cor, n, rounds=2):
    """The fit of :func:`_calibrated_critical_values` in the model linearised at the estimate.

    jac_raw (2n, P): Jacobian of the unweighted relative residuals (TC then COR); r0 (B, 2n):
    each session's relative residuals at the estimate. Weighted least squares with the
    scatter re-estimated from the residuals (RSS / (n - p_kind)) ``rounds`` times, like the
    nonlinear fit. Returns the parameter offsets (B, P) and their covariance (B, P, P) with
    each session's final scatter."""
    b = r0.shape[0]
    s = np.tile([float(sigma_tc), float(sigma_cor)], (b, 1))
    d = np.zeros((b, jac_raw.shape[1]))
    for _ in range(rounds + 1):
        w = np.repeat(1.0 / s**2, n, axis=1)
        jw = jac_raw[None] * w[:, :, None]  # (B, 2n, P)
        cov = _inverse(np.swapaxes(jw, 1, 2) @ jac_raw)
        if _ == rounds:
            break
        d = -(cov @ (np.swapaxes(jw, 1, 2) @ r0[:, :, None]))[:, :, 0]
        r = r0 + d @ jac_raw.T
        h = np.sum((jac_raw[None] @ cov) * jw, axis=2)  # leverages of the weighted fit
        dof = np.stack([np.maximum(n - h[:, :n].sum(axis=1), 1.0), np.maximum(n - h[:, n:].sum(axis=1), 1.0)], 1)
        rss = np.stack([np.sum(r[:, :n] ** 2, axis=1), np.sum(r[:, n:] ** 2, axis=1)], 1)
        s = np.maximum(np.sqrt(rss / dof), 1e-5)
    return d, cov


def _refit_sessions(vin, mass, kb0, theta, tc_b, cor_b, sigma_tc, sigma_cor, jac_raw):
    """Sessions (tc_b [s], cor_b [-], each (B, n)) fitted like the data, started at theta:
    batched Levenberg-Marquardt with weights 1 / sigma_* [-], the TC and COR scatter
    re-estimated from each session's residuals (RSS / (n - p_kind)) and the fit repeated.
    Returns the parameters (B, P), a converged flag (B,) and the linearised covariance
    (B_converged, P, P) with each session's scatter (jac_raw: unweighted relative
    residuals' Jacobian (2n, P) at theta)."""
    n, n_sim, n_par = vin.size, tc_b.shape[0], theta.size
    s_tc = np.full((n_sim, 1), float(sigma_tc))
    s_cor = np.full((n_sim, 1), float(sigma_cor))
    lo_b, hi_b = _full_bounds(n_par)

    def resid(pts, rows):
        return _residuals(pts, vin, tc_b[rows], cor_b[rows], mass, kb0, s_tc[rows], s_cor[rows])

    th_b = np.repeat(theta[None], n_sim, axis=0)
    conv = np.ones(n_sim, dtype=bool)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for _ in range(2):
            th_b, ok = _batched_lm(resid, th_b, lo_b, hi_b, max_iter=30)
            conv &= ok
            tcm, corm = _simulate(th_b, vin, mass, kb0)
            w = np.concatenate([np.repeat(1.0 / s_tc**2, n, axis=1), np.repeat(1.0 / s_cor**2, n, axis=1)], axis=1)
            cov = np.linalg.pinv(np.einsum("ip,bi,iq->bpq", jac_raw, w, jac_raw))
            h = np.einsum("ip,bpq,iq,bi->bi", jac_raw, cov, jac_raw, w)
            dof_tc = np.maximum(n - h[:, :n].sum(axis=1), 1.0)
            dof_cor = np.maximum(n - h[:, n:].sum(axis=1), 1.0)
            s_tc = np.maximum(np.sqrt(np.sum(((tcm - tc_b) / tc_b) ** 2, axis=1) / dof_tc), 1e-5)[:, None]
            s_cor = np.maximum(np.sqrt(np.sum(((corm - cor_b) / cor_b) ** 2, axis=1) / dof_cor), 1e-5)[:, None]
    w = np.concatenate([np.repeat(1.0 / s_tc**2, n, axis=1), np.repeat(1.0 / s_cor**2, n, axis=1)], axis=1)
    cov_nl = np.linalg.pinv(np.einsum("ip,bi,iq->bpq", jac_raw, w[conv], jac_raw))
    return th_b, conv, cov_nl


def _calibrated_critical_values(vin, tc, cor, mass, kb0, theta, sigma_tc, sigma_cor, confidence,
                                n_sim=None, n_linear=None, seed=0):
    """Critical values of the profile deviance, calibrated by a parametric bootstrap.

    Sessions are simulated from the fitted model at the impacts' own speeds, with the
    fitted relative scatter of TC and COR (``sigma_*`` [-], normal errors), and each is
    fitted like the data: weighted least squares from the estimate, the TC and COR
    scatter re-estimated from its residuals (RSS / (n - p_kind)) and the fit repeated
    with them. For every quantity q of :func:`_quantities` a session's statistic is
    (q_b - q_hat)^2 / var_b, var_b the linearised variance of q with that session's
    scatter (the profile deviance of a linear model), and the critical value is its
    ``confidence`` quantile. It takes the place of the F(1, nu) quantile: F(1, nu) with
    Satterthwaite's nu approximates the effect of two scatters estimated separately from
    few residuals; the simulation has it exactly (in the linearised model), together
    with what F(1, nu) leaves out: the estimated scatters set the weights, so they move
    the estimate too.

    ``n_linear`` sessions (default :data:`CALIBRATION_SESSIONS`) are fitted in the
    model linearised at the estimate (:func:`_linear_sessions`, plain linear algebra:
    milliseconds). Optionally ``n_sim`` of them (default :data:`CALIBRATION_REFITS`)
    are also refitted with the full model (one batched :func:`_batched_lm`) and the
    linearised quantile is multiplied by the ratio of the full refits' quantile to the
    linearised quantile of the same sessions (a control variate: both share the
    sampling noise of the same draws).

    Why the linearised sessions suffice: the intervals compare the profile deviance (a
    likelihood ratio), not this Wald form, with the critical value, and the two agree only
    in a linear model. At the bench's noise (10 impacts, TC 0.4 %, COR 0.003) the model is
    close enough to linear: on sessions simulated at known parameters and refitted with the
    full model, the profile deviance at the truth stays below this critical value in
    0.950-0.955 of them per quantity (``python bench/coverage.py --lr-check --seeds 8
    --sessions 500``).

    Returns {key: critical value [-]}; empty (the F(1, nu) quantile is then used) when
    ``n_linear`` < 100; without the refits' correction when fewer than half converged.
    """
    n_sim = CALIBRATION_REFITS if n_sim is None else n_sim
    n_linear = CALIBRATION_SESSIONS if n_linear is None else n_linear
    n, n_par = vin.size, theta.size
    if n_linear < 100:
        return {}
    rng = np.random.default_rng(seed)
    tc_m, cor_m = _simulate(theta, vin, mass, kb0)
    fun0 = lambda pts: _residuals(pts, vin, tc_m, cor_m, mass, kb0, 1.0, 1.0)  # noqa: E731
    jac_raw = _jacobian(fun0, theta)  # unweighted relative residuals at the estimate: (2n, P)

    def sessions(b):
        z = rng.standard_normal((2, b, n))
        tc_b, cor_b = tc_m * (1.0 + sigma_tc * z[0]), cor_m * (1.0 + sigma_cor * z[1])
        return tc_b, cor_b, np.concatenate([(tc_m - tc_b) / tc_b, (cor_m - cor_b) / cor_b], axis=1)

    d_lin, cov_lin = _linear_sessions(jac_raw, sessions(n_linear)[2], sigma_tc, sigma_cor, n)
    grads = {spec.key: _quantity_gradient(spec, theta) for spec in _quantities(n_par, kb0)}

    def stat(d, cov, grad):
        return (d @ grad) ** 2 / np.maximum(np.einsum("p,bpq,q->b", grad, cov, grad), 1e-300)

    out = {key: float(np.quantile(stat(d_lin, cov_lin, g), confidence)) for key, g in grads.items()}
    if n_sim < 20:
        return out
    tc_b, cor_b, r0 = sessions(n_sim)
    th_b, conv, cov_nl = _refit_sessions(vin, mass, kb0, theta, tc_b, cor_b, sigma_tc, sigma_cor, jac_raw)
    if conv.sum() < n_sim / 2:
        return out
    d_pair, cov_pair = _linear_sessions(jac_raw, r0[conv], sigma_tc, sigma_cor, n)
    for spec in _quantities(n_par, kb0):
        q_nl = spec.fwd(th_b[conv]) - float(spec.fwd(theta))
        stat_nl = q_nl**2 / np.maximum(np.einsum("p,bpq,q->b", grads[spec.key], cov_nl, grads[spec.key]), 1e-300)
        ratio = np.quantile(stat_nl, confidence) / max(np.quantile(stat(d_pair, cov_pair, grads[spec.key]),
                                                                   confidence), 1e-300)
        out[spec.key] *= float(ratio)
    return out


def _kb0_lines(vin, kv, confidence):
    """Linear (the paper's) and quadratic extrapolation of the Kelvin-Voigt stiffness to
    zero speed: ((kb0, lo, hi) linear, (kb0, lo, hi) quadratic) [N/m], t intervals."""
    out = []
    for deg in (1, 2):
        x = np.vander(vin, deg + 1, increasing=True)
        if vin.size <= deg + 1 or np.linalg.matrix_rank(x) < deg + 1:
            out.append((np.nan, np.nan, np.nan))
            continue
        coef, *_ = np.linalg.lstsq(x, kv, rcond=None)
        r = kv - x @ coef
        dof = vin.size - deg - 1
        s2 = float(r @ r) / dof
        se = float(np.sqrt(s2 * np.linalg.inv(x.T @ x)[0, 0]))
        t = _t_ppf(0.5 + confidence / 2, dof)
        out.append((float(coef[0]), float(coef[0] - t * se), float(coef[0] + t * se)))
    return out


@dataclass
class FitOutliers:
    """Result of :func:`detect_fit_outliers`.

    Attributes
    ----------
    used : numpy.ndarray of bool
        True for impacts to use in the fit, False for named fit outliers.
    notes : list of str
        Per impact: empty, or why it was left out (its residuals and the test).
    p_values : numpy.ndarray
        Bonferroni-adjusted-by-kind p value of each tested impact (NaN when not tested) [-].
    level : float
        Family-wise test level per ball type [-].
    max_removed : int
        Largest number of impacts that may be removed.
    messages : list of str
        Remarks (e.g. more outliers than the cap allows).
    start : tuple
        (theta, sigma_tc, sigma_cor) of the robust fit, a start for the final fit (None when not fitted).
    steps : list of (int, float)
        The generalised ESD steps in order: (impact index, p value) [-].
    """

    used: np.ndarray
    notes: list
    p_values: np.ndarray
    level: float
    max_removed: int
    messages: list = field(default_factory=list)
    start: tuple | None = None
    steps: list = field(default_factory=list)


def _robust_kb0(vin, kv):
    """Robust (Theil-Sen) straight-line intercept of the Kelvin-Voigt stiffness [N/m]."""
    if np.ptp(vin) <= 0:
        return float(np.median(kv))
    from scipy import stats

    slope, intercept, *_ = stats.theilslopes(kv, vin)
    return float(intercept) if intercept > 0 else float(np.median(kv) * 0.5)


def detect_fit_outliers(vin_m_s, contact_time_s, cor, mass_kg, *, kb0_N_m=None, level=OUTLIER_LEVEL,
                        max_share=OUTLIER_MAX_SHARE) -> FitOutliers:
    """Name the impacts of one ball type that sit implausibly far off their siblings' fit.

    1. Robust fit: AK, a, AC by least squares with the soft-L1 loss on the relative TC
       and COR residuals, each scaled by its median absolute deviation; kB(0) from the
       argument or a robust (Theil-Sen) line through the Kelvin-Voigt stiffness (Eq. (2)).
    2. Screen: when no impact's squared robust z-scores (TC and COR) sum above the
       0.99 quantile of chi-square(2), there is no outlier and the search stops.
    3. Generalised ESD (Rosner 1983), at most ``max(1, floor(max_share * n))`` steps:
       every kept impact is tested against the fit of the other kept impacts
       (leave-one-out refits; externally studentised with the leverage, t distribution
       with each kind's residual degrees of freedom) in three directions: TC alone,
       COR alone, and the direction in which an error of the inbound speed moves both
       (from the model's slopes dlog TC / dlog VB and dlog COR / dlog VB). Its p value
       is the smallest two-sided p of the three times 3. The impact with the smallest
       p is set aside and the step repeated. The outliers are the impacts of the steps
       up to the last one with p < ``level`` / (impacts kept at that step), so that
       one outlier cannot mask another; none when fewer than 6 impacts.

    Parameters
    ----------
    vin_m_s, contact_time_s, cor, mass_kg : array_like
        Inbound speed [m/s], contact time [s], COR [-] and mass [kg] of each impact.
    kb0_N_m : float, optional
        kB(0) [N/m] (from the config); robustly extrapolated when None.
    level : float
        Family-wise level of the test per ball type [-].
    max_share : float
        Largest share of the impacts that may be removed [-].

    Returns
    -------
    FitOutliers

    Raises
    ------
    ValueError
        Bad arguments.
    FitError
        When the robust fit fails.
    """
    vin = _as_1d("vin_m_s", vin_m_s)
    n = vin.size
    tc = _as_1d("contact_time_s", contact_time_s, n)
    e = _as_1d("cor", cor, n)
    mass = _as_1d("mass_kg", mass_kg, n)
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    if not 0 <= max_share < 1:
        raise ValueError(f"max_share must be in [0, 1), got {max_share!r}")
    cap = max(1, int(np.floor(max_share * n + 1e-9))) if max_share > 0 else 0
    used = np.ones(n, dtype=bool)
    notes = [""] * n
    pvals = np.full(n, np.nan)
    result = FitOutliers(used, notes, pvals, float(level), cap)
    if n < 6 or cap == 0:
        if n < 6:
            result.messages.append(f"only {n} impacts: no search for fit outliers")
        return result
    if kb0_N_m is None:
        kv, _ = kelvin_voigt_parameters(mass, tc, e)
        kb0 = _robust_kb0(vin, kv)
    else:
        kb0 = float(kb0_N_m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        theta, mad_tc, mad_cor, r_tc, r_cor = _robust_fit(vin, tc, e, mass, kb0)
        result.start = (theta.copy(), mad_tc, mad_cor)
        d2 = (r_tc / mad_tc) ** 2 + (r_cor / mad_cor) ** 2
        suspects = np.flatnonzero(d2 > _chi2_ppf(0.99, 2))
        suspects = suspects[np.argsort(-d2[suspects])][: max(n - 6, 0)]
        if not suspects.size:
            return result
        steps = _esd_steps(vin, tc, e, mass, kb0, theta, mad_tc, mad_cor, cap)
    result.steps = [(int(i), float(p)) for i, p, _ in steps]
    n_out = 0
    for k, (i, p, note) in enumerate(steps):
        pvals[i] = p
        if p < level / (n - k):
            n_out = k + 1
    for k, (i, p, note) in enumerate(steps[:n_out]):
        used[i] = False
        notes[i] = note + f"; p = {p:.1e} < {level:g}/{n - k} (Bonferroni, generalised ESD step {k + 1})"
    return result


def _robust_fit(vin, tc, e, mass, kb0):
    """Step 1 of :func:`detect_fit_outliers`: AK, a, AC (theta) by the soft-L1 loss from the
    stage fits, the robust scatter (1.4826 MAD, at least 1e-4) of the relative TC and COR
    residuals [-] and those residuals: (theta, mad_tc, mad_cor, r_tc, r_cor)."""
    s1 = fit_contact_time(vin, tc, mass, kb0)
    s2 = fit_restitution(vin, e, mass, kb0, s1.ak, s1.a)
    th0 = _to_theta(s2.ak, s2.a, s2.ac)
    tc_m, cor_m = _simulate(th0, vin, mass, kb0)
    mad_tc = max(1.4826 * float(np.median(np.abs((tc_m - tc) / tc))), 1e-4)
    mad_cor = max(1.4826 * float(np.median(np.abs((cor_m - e) / e))), 1e-4)
    res = _fit_weighted(vin, tc, e, mass, kb0, th0, mad_tc, mad_cor, "robust fit (soft-L1)", loss="soft_l1")
    tc_m, cor_m = _simulate(res.x, vin, mass, kb0)
    r_tc, r_cor = (tc_m - tc) / tc, (cor_m - e) / e
    mad_tc = max(1.4826 * float(np.median(np.abs(r_tc))), 1e-4)
    mad_cor = max(1.4826 * float(np.median(np.abs(r_cor))), 1e-4)
    return res.x, mad_tc, mad_cor, r_tc, r_cor


def _esd_steps(vin, tc, e, mass, kb0, theta, mad_tc, mad_cor, cap):
    """Generalised ESD (Rosner 1983): remove the most extreme impact, refit, repeat ``cap``
    times; the steps as (impact index, p value, note). Which of them are outliers is
    decided by the caller (the last significant step, so one outlier cannot mask another)."""
    keep = np.ones(vin.size, dtype=bool)
    steps = []
    for _ in range(cap):
        step = _most_extreme(vin, tc, e, mass, kb0, keep, theta, mad_tc, mad_cor)
        if step is None:
            break
        i, p, note, theta = step
        steps.append((i, p, note))
        keep[i] = False
    return steps


def _most_extreme(vin, tc, e, mass, kb0, keep, theta, s_tc, s_cor):
    """One step of the fit-outlier search: each kept impact against the fit of the other
    kept impacts (leave-one-out refits, batched). Returns (index, p, note, theta of the
    kept impacts' fit) of the impact with the smallest p, or None."""
    idx = np.flatnonzero(keep)
    m = idx.size
    if m < 6:
        return None
    v, t, c, ms = vin[idx], tc[idx], e[idx], mass[idx]
    fit_k = _fit_weighted(v, t, c, ms, kb0, theta, s_tc, s_cor, "fit of the kept impacts")
    theta_k = fit_k.x
    tcm, corm = _simulate(theta_k, v, ms, kb0)
    s_tc, s_cor, _, _, _ = _block_scatter(fit_k.jac, (tcm - t) / t, (corm - c) / c, m)
    fun = lambda pts: _residuals(pts, v, t, c, ms, kb0, s_tc, s_cor)  # noqa: E731
    jac = _jacobian(fun, theta_k)
    cov = np.linalg.pinv(jac.T @ jac)
    h_tc = np.einsum("ij,jk,ik->i", jac[:m], cov, jac[:m])
    h_cor = np.einsum("ij,jk,ik->i", jac[m:], cov, jac[m:])
    # leave-one-out refits, all at once: problem j has weight 0 on impact j
    w = 1.0 - np.eye(m)
    sqrt_w = np.hstack([w, w])
    lo_b, hi_b = _full_bounds(theta_k.size)

    def resid(pts, rows):
        return _residuals(pts, v, t, c, ms, kb0, s_tc, s_cor) * sqrt_w[rows]

    th_loo, _ = _batched_lm(resid, np.repeat(theta_k[None], m, axis=0), lo_b, hi_b, max_iter=30)
    tc_l, cor_l = _simulate(th_loo, v, ms, kb0)  # (m, m): row j = fit without j
    tc_p, cor_p = _simulate(th_loo, v * 1.001, ms, kb0)
    rows = np.arange(m)
    r_tc = np.log(t[None, :] / tc_l)  # log residual, measured over model
    r_cor = np.log(c[None, :] / cor_l)
    dof_tc, dof_cor = max(m - 1 - float(h_tc.sum()), 1.0), max(m - 1 - float(h_cor.sum()), 1.0)
    best = None
    for j in rows:
        others = rows != j
        sd_tc = np.sqrt(np.sum(r_tc[j, others] ** 2) / dof_tc)
        sd_cor = np.sqrt(np.sum(r_cor[j, others] ** 2) / dof_cor)
        # prediction of an impact left out: variance factor 1 / (1 - h) of the kept fit
        f_tc, f_cor = 1.0 / np.sqrt(max(1 - h_tc[j], 1e-3)), 1.0 / np.sqrt(max(1 - h_cor[j], 1e-3))
        z_tc = r_tc[j, j] / (sd_tc * f_tc)
        z_cor = r_cor[j, j] / (sd_cor * f_cor)
        # an inbound speed measured (1 + delta) too high: the model is read at (1 + delta) VB
        # and the measured COR is divided by (1 + delta): log residuals -delta (s_tc, 1 + s_cor)
        s_v_tc = np.log(tc_p[j, j] / tc_l[j, j]) / np.log(1.001)
        s_v_cor = np.log(cor_p[j, j] / cor_l[j, j]) / np.log(1.001)
        u = -np.array([s_v_tc / (sd_tc * f_tc), (1 + s_v_cor) / (sd_cor * f_cor)])
        z_v = float(u @ np.array([z_tc, z_cor]) / np.linalg.norm(u))
        tests = {
            "contact time": 2 * _t_sf(abs(z_tc), dof_tc),
            "COR": 2 * _t_sf(abs(z_cor), dof_cor),
            "inbound speed": 2 * _t_sf(abs(z_v), min(dof_tc, dof_cor)),
        }
        kind = min(tests, key=tests.get)
        p = min(1.0, 3 * tests[kind])
        if best is None or p < best[1]:
            extra = f", as if the inbound speed were {100 * z_v / np.linalg.norm(u):+.1f} % off" \
                if kind == "inbound speed" else ""
            note = (f"fit outlier ({kind}): TC {100 * np.expm1(r_tc[j, j]):+.1f} % ({z_tc:+.1f} sd), "
                    f"COR {100 * np.expm1(r_cor[j, j]):+.1f} % ({z_cor:+.1f} sd) off the fit of the other "
                    f"{m - 1} impacts{extra}")
            best = (int(idx[j]), p, note)
    return best + (theta_k,)


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
