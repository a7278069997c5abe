"""Fitting the ball model to measured contact times and COR (section 3.4 of Goodwill & Haake 2004).

Method (our reading of section 3.4, made a proper least-squares problem):

* kB(0) is fixed from session.yaml when given; otherwise it is the zero-speed
  intercept of a straight line through the per-impact Kelvin-Voigt stiffness
  (Eq. (2)) against inbound speed (:func:`fit_kb0`).
* Stage one (:func:`fit_contact_time`): AK and a so that the model's TC matches
  the measured TC of every impact (the paper used Goal Seek on a trend line; we
  use least squares on the impacts themselves).
* Stage two (:func:`fit_restitution`): AC so that the model's COR matches the
  measured COR, AK and a fixed.
* Joint refinement (:func:`fit_ball_model`): AK, a and AC on both TC and COR,
  each residual relative and weighted by the scatter of its own kind, then 95 %
  intervals by a case-resampling bootstrap over impacts (kB(0) re-extrapolated in
  every resample when it was extrapolated).

Internally the stiffness law is parametrised by the stiffness increment at a
reference displacement, kR = AK xR^a with xR = 20 mm, instead of AK: AK and a
trade off strongly (a slightly larger a with a much larger AK gives nearly the
same kB over the displacements reached), and the (log kR, a) pair is far better
conditioned. Results are reported as AK, a as in Table 2, together with the
correlation between AK and a.

The objective is smooth in the parameters because the model's end of contact is
interpolated between time steps (see :mod:`ballimpact.model`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from .model import kelvin_voigt_parameters, simulate_impact

__all__ = [
    "REFERENCE_DISPLACEMENT_M",
    "PARAMETER_BOUNDS",
    "Kb0Fit",
    "StageFit",
    "BallFit",
    "FitError",
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
        "config" or "extrapolated".
    ak, ak_lo, ak_hi : float
        AK and its 95 % interval [N/m^(1+a)].
    a, a_lo, a_hi : float
        Exponent a and its 95 % interval [-].
    ac, ac_lo, ac_hi : float
        AC and its 95 % interval [N s/m^3].
    ak_a_correlation : float
        Correlation between AK and a over the bootstrap resamples [-].
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
    reg = stats.linregress(vin, kv)
    t = stats.t.ppf(0.5 + confidence / 2, vin.size - 2)
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
    """TC [s] and COR for parameter sets theta (..., 3) at every impact: shape (..., n)."""
    ak, a, ac = _from_theta(theta)
    sim = simulate_impact(
        vin, mass, np.asarray(kb0)[..., None] if np.ndim(kb0) else kb0,
        ak[..., None], a[..., None], ac[..., None],
    )
    return sim.contact_time_s, sim.cor


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


def _batched_lm(resid, p0, lo, hi, max_iter=10):
    """Levenberg-Marquardt on many independent problems at once.

    resid : callable mapping points (..., B, k) to residuals (..., B, m); it is
        called with the current points and their forward-difference neighbours
        stacked, so every iteration is one batched model simulation.
    p0 : (B, k) starting points; lo, hi : bounds, (k,) or (B, k).
    Returns the points (B, k) and a converged flag (B,).
    """
    p = np.array(p0, dtype=float)
    b, k = p.shape
    lo = np.broadcast_to(np.asarray(lo, dtype=float), p.shape)
    hi = np.broadcast_to(np.asarray(hi, dtype=float), p.shape)
    lam = np.full(b, 1e-3)
    converged = np.zeros(b, dtype=bool)
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
        for _ in range(max_iter):
            act = np.flatnonzero(~converged)
            if not act.size:
                break
            ja, ra = jac[act], r0[act]
            jtj = np.einsum("bij,bik->bjk", ja, ja)
            jtr = np.einsum("bij,bi->bj", ja, ra)
            diag = np.einsum("bjj->bj", jtj)
            a_mat = jtj + lam[act][:, None, None] * eye * diag[:, None, :] + 1e-12 * eye
            step = -np.linalg.solve(a_mat, jtr[..., None])[..., 0]
            new = np.clip(p[act] + step, lo[act], hi[act])
            # One call per iteration: the trial point comes with its Jacobian, used
            # at once when the trial is accepted (LM rejects rarely near the optimum).
            r_new, jac_new = with_jacobian(new, act)
            c0 = np.sum(ra**2, axis=-1)
            c1 = np.sum(r_new**2, axis=-1)
            better = c1 < c0
            acc = act[better]
            p[acc], r0[acc], jac[acc] = new[better], r_new[better], jac_new[better]
            lam[acc] *= 0.3
            lam[act[~better]] *= 10.0
            # converged: the step moves no parameter by more than 1e-5 (log scale: a
            # relative 1e-5) or no longer lowers the cost by a relative 1e-7
            tiny = np.max(np.abs(step), axis=-1) < 1e-5
            conv = (better & ((c0 - c1) <= 1e-7 * np.maximum(c0, 1e-30))) | tiny | (lam[act] > 1e8)
            converged[act[conv]] = True
    return p, converged


def _weighted_resid(vin, tc, cor, mass, sigma_tc, sigma_cor, kb0, sqrt_w, to_theta):
    """Residual function for :func:`_batched_lm`: free points -> weighted relative residuals."""

    def resid(pts, rows):
        tc_m, cor_m = _simulate(to_theta(pts, rows), vin, mass, kb0[rows])
        r = np.concatenate([(tc_m - tc) / tc / sigma_tc, (cor_m - cor) / cor / sigma_cor], axis=-1)
        return np.where(np.isfinite(r), r, 1.0e3) * sqrt_w[rows]

    return resid


def _profile_intervals(vin, tc, cor, mass, kb0, sigma_tc, sigma_cor, theta, jac, confidence, n_grid=25):
    """Profile-likelihood intervals of log AK, a and log AC (Bates & Watts 1988, ch. 6).

    For each parameter psi on a grid about its estimate, the other two are refitted;
    the interval is where (S(psi) - S_min) / s^2 stays below the F(1, N - P) quantile,
    s^2 = S_min / (N - P) (N residuals, P = 3 parameters). Follows the curved AK-a
    ridge instead of assuming an ellipse.
    """
    lo_b, hi_b = _theta_bounds()
    r_opt = _weighted_resid(vin, tc, cor, mass, sigma_tc, sigma_cor, np.array([kb0]), np.ones((1, 2 * vin.size)),
                            lambda pts, rows: pts)(theta[None, None], np.array([0]))[0, 0]
    n_res, n_par = r_opt.size, 3
    s_min = float(np.sum(r_opt**2))
    s2 = max(s_min / max(n_res - n_par, 1), 1e-12)
    f_crit = stats.f.ppf(confidence, 1, max(n_res - n_par, 1))
    # Wald standard errors in the profiled coordinates (log AK, a, log AC) set the grid.
    log_xr = np.log(REFERENCE_DISPLACEMENT_M)
    phi_hat = np.array([theta[0] - theta[1] * log_xr, theta[1], theta[2]])
    dtheta_dphi = np.array([[1.0, log_xr, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    j_phi = jac @ dtheta_dphi
    try:
        cov = s2 * np.linalg.inv(j_phi.T @ j_phi)
        se = np.sqrt(np.clip(np.diag(cov), 1e-12, None))
    except np.linalg.LinAlgError:
        se = np.array([1.0, 0.3, 0.2])
    offsets = np.concatenate([-np.geomspace(12, 0.25, n_grid // 2), [0.0], np.geomspace(0.25, 12, n_grid // 2)])
    g = offsets.size
    # All three profiles in one batch: row r profiles parameter r // g at grid point r % g.
    prof_of = np.repeat(np.arange(3), g)
    # grid points outside the search bounds of a and AC are clipped onto them
    # log AK = log kR - a log xR, bounded by the kR and a bounds
    lo_phi = np.array([lo_b[0] - lo_b[1] * log_xr, lo_b[1], lo_b[2]])
    hi_phi = np.array([hi_b[0] - hi_b[1] * log_xr, hi_b[1], hi_b[2]])
    psi = np.clip(phi_hat[:, None] + offsets[None, :] * se[:, None], lo_phi[:, None], hi_phi[:, None]).ravel()
    free_idx = np.array([[i for i in range(3) if i != j] for j in range(3)])[prof_of]  # (3g, 2)

    def to_theta(pts, rows):
        phi = np.empty(pts.shape[:-1] + (3,))
        idx = np.broadcast_to(free_idx[rows], pts.shape)
        np.put_along_axis(phi, idx, pts, axis=-1)
        fixed = np.broadcast_to(prof_of[rows][:, None], pts.shape[:-1] + (1,))
        np.put_along_axis(phi, fixed, np.broadcast_to(psi[rows][:, None], pts.shape[:-1] + (1,)), axis=-1)
        return np.stack([phi[..., 0] + phi[..., 1] * log_xr, phi[..., 1], phi[..., 2]], axis=-1)

    resid = _weighted_resid(vin, tc, cor, mass, sigma_tc, sigma_cor, np.full(3 * g, kb0),
                            np.ones((3 * g, 2 * vin.size)), to_theta)
    p0 = phi_hat[free_idx]
    pts, _ = _batched_lm(resid, p0, lo_phi[free_idx], hi_phi[free_idx], max_iter=12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = resid(pts[None], np.arange(3 * g))[0]
    dev_all = ((np.sum(r**2, axis=-1) - s_min) / s2).reshape(3, g)
    psi = psi.reshape(3, g)
    centre = int(np.flatnonzero(offsets == 0)[0])
    intervals = []
    for j in range(3):
        dev = dev_all[j]
        dev[centre] = 0.0
        ends = []
        for step in (-1, 1):
            prev, end, closed = centre, psi[j, 0 if step < 0 else g - 1], False
            for i in range(centre + step, -1 if step < 0 else g, step):
                if dev[i] > f_crit:
                    w = (f_crit - dev[prev]) / (dev[i] - dev[prev])
                    end, closed = psi[j, prev] + w * (psi[j, i] - psi[j, prev]), True
                    break
                prev = i
            ends.append((end, closed))
        intervals.append((ends[0][0], ends[1][0], ends[0][1] and ends[1][1]))
    return intervals


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
) -> BallFit:
    """Fit kB(0), AK, a and AC of one ball type to its impacts, with 95 % intervals.

    kB(0) from the argument (source "config") or by :func:`fit_kb0` from the
    Kelvin-Voigt stiffness (Eq. (2)) when ``kb0_N_m`` is None ("extrapolated");
    stage one :func:`fit_contact_time`; stage two :func:`fit_restitution`; then
    a joint least-squares refinement of AK, a, AC on the relative TC and COR
    residuals, each kind weighted by its own RMS from the stages (so neither
    dominates by its scale). Intervals: BCa bootstrap over impacts
    (``n_bootstrap`` resamples refitted from the joint optimum, jackknife for
    the acceleration; kB(0) re-extrapolated in each when extrapolated), widened
    by sqrt(n / (n - p)) for the small-sample shrinkage of case resampling. The model is Eqs. (4)-(16) of
    Goodwill & Haake 2004.

    Parameters
    ----------
    vin_m_s, contact_time_s, cor, mass_kg : array_like
        Inbound speed [m/s], contact time [s], COR [-] and mass [kg] of each good impact.
    kb0_N_m : float, optional
        Fixed kB(0) [N/m].
    kv_stiffness_N_m : array_like, optional
        Kelvin-Voigt stiffness per impact [N/m]; computed from TC and COR when omitted.
    n_bootstrap : int
        Bootstrap resamples (0 disables the intervals).
    seed : int
        Seed of the resampling.
    confidence : float
        Interval level [-].

    Returns
    -------
    BallFit

    Raises
    ------
    FitError
        Too few impacts, or an optimiser that did not succeed.
    """
    vin = _as_1d("vin_m_s", vin_m_s)
    n = vin.size
    tc = _as_1d("contact_time_s", contact_time_s, n)
    e = _as_1d("cor", cor, n)
    mass = _as_1d("mass_kg", mass_kg, n)
    if np.any(tc <= 0) or np.any(e <= 0) or np.any(vin <= 0) or np.any(mass <= 0):
        raise ValueError("vin_m_s, contact_time_s, cor and mass_kg must be positive")
    if n < 3:
        raise FitError(f"fitting AK, a and AC needs at least 3 good impacts, got {n}")
    if n_bootstrap < 0:
        raise ValueError(f"n_bootstrap must be non-negative, got {n_bootstrap}")
    messages = []
    if n < 6:
        messages.append(f"only {n} impacts: the intervals are rough")
    if kv_stiffness_N_m is None:
        kv_stiffness_N_m, _ = kelvin_voigt_parameters(mass, tc, e)
    kv = _as_1d("kv_stiffness_N_m", kv_stiffness_N_m, n)

    if kb0_N_m is None:
        kb0_fit = fit_kb0(vin, kv, confidence=confidence)
        kb0, kb0_source = kb0_fit.kb0_N_m, "extrapolated"
    else:
        if not np.isfinite(kb0_N_m) or kb0_N_m < 0:
            raise ValueError(f"kb0_N_m must be non-negative, got {kb0_N_m!r}")
        kb0, kb0_source, kb0_fit = float(kb0_N_m), "config", None

    stage1 = fit_contact_time(vin, tc, mass, kb0)
    stage2 = fit_restitution(vin, e, mass, kb0, stage1.ak, stage1.a)
    # Weights: the scatter of each kind of residual in the stage fits (floored).
    sigma_tc = max(stage1.rmse_pct / 100.0, 1e-4)
    sigma_cor = max(stage2.rmse_pct / 100.0, 1e-4)
    joint = _Problem(vin, tc, e, mass, kb0, True, True, sigma_tc, sigma_cor)
    res = _least_squares(joint, _to_theta(stage2.ak, stage2.a, stage2.ac), "joint refinement (AK, a, AC)")
    # Re-weight once with the scatter of each kind left by the joint fit (so that both
    # blocks of weighted residuals have unit variance, as the F test of the intervals
    # assumes), then refine from there.
    tc_m, cor_m = _simulate(res.x, vin, mass, kb0)
    sigma_tc = max(float(np.sqrt(np.mean(((tc_m - tc) / tc) ** 2))), 1e-4)
    sigma_cor = max(float(np.sqrt(np.mean(((cor_m - e) / e) ** 2))), 1e-4)
    joint = _Problem(vin, tc, e, mass, kb0, True, True, sigma_tc, sigma_cor)
    res = _least_squares(joint, res.x, "joint refinement (AK, a, AC)")
    theta = res.x
    ak, a, ac = (float(v) for v in _from_theta(theta))
    messages += _bound_messages(theta)
    tc_m, cor_m = _simulate(theta, vin, mass, kb0)
    tc_rmse = _rmse_pct((tc_m - tc) / tc)
    cor_rmse = _rmse_pct((cor_m - e) / e)

    nan = float("nan")
    lo_hi = {k: (nan, nan) for k in ("kb0", "ak", "a", "ac")}
    if kb0_fit is not None:
        lo_hi["kb0"] = (kb0_fit.kb0_lo, kb0_fit.kb0_hi)
    # 95 % intervals of AK, a, AC: profile likelihood (kB(0) held at its value).
    prof = _profile_intervals(vin, tc, e, mass, kb0, sigma_tc, sigma_cor, theta, res.jac, confidence)
    for key, (lo, hi, closed) in zip(("ak", "a", "ac"), prof):
        lo_hi[key] = (float(np.exp(lo)), float(np.exp(hi))) if key != "a" else (float(lo), float(hi))
        if not closed:
            messages.append(f"the {key} interval reaches the end of the profile grid: the data barely constrain it")
    method = "profile likelihood (F test)"

    # Bootstrap over impacts: AK-a correlation, model-curve bands, and kB(0) propagation.
    corr = nan
    boot = np.empty((0, 4))
    if n_bootstrap > 0:
        rng = np.random.default_rng(seed)
        idx = rng.integers(0, n, size=(n_bootstrap, n))
        weights = np.stack([np.bincount(row, minlength=n) for row in idx]).astype(float)
        kb0_b = np.full(n_bootstrap, kb0)
        if kb0_fit is not None:
            for i, row in enumerate(idx):
                if np.ptp(vin[row]) > 0:
                    reg = stats.linregress(vin[row], kv[row])
                    kb0_b[i] = reg.intercept if reg.intercept > 0 else np.nan
                else:
                    kb0_b[i] = np.nan
        ok = np.isfinite(kb0_b)
        kb0_b, weights = kb0_b[ok], weights[ok]
        lo_b, hi_b = _theta_bounds()
        resid = _weighted_resid(vin, tc, e, mass, sigma_tc, sigma_cor, kb0_b, np.sqrt(np.hstack([weights, weights])),
                                lambda pts, rows: pts)
        th_b, conv = _batched_lm(resid, np.repeat(theta[None], kb0_b.size, axis=0), lo_b, hi_b)
        ak_b, a_b, ac_b = _from_theta(th_b)
        boot = np.column_stack([kb0_b, ak_b, a_b, ac_b])[conv]
        if boot.shape[0] < 0.8 * n_bootstrap:
            messages.append(
                f"only {boot.shape[0]} of {n_bootstrap} bootstrap refits converged; bands unreliable"
            )
        if boot.shape[0] >= 10:
            corr = float(np.corrcoef(boot[:, 1], boot[:, 2])[0, 1])
            method += f"; correlation and bands from {boot.shape[0]} bootstrap resamples over impacts"
            if kb0_fit is not None:
                # kB(0) was extrapolated: widen the intervals by the spread it adds, read off
                # the bootstrap (in which kB(0) is re-extrapolated every time).
                for j, key in ((1, "ak"), (2, "a"), (3, "ac")):
                    f = np.log if key != "a" else (lambda x: x)
                    q = np.percentile(f(boot[:, j]), 100 * np.array([0.5 - confidence / 2, 0.5 + confidence / 2]))
                    lo, hi = (f(v) for v in lo_hi[key])
                    lo, hi = min(lo, q[0]), max(hi, q[1])
                    lo_hi[key] = (float(np.exp(lo)), float(np.exp(hi))) if key != "a" else (float(lo), float(hi))
                method += " (union with bootstrap percentiles, kB(0) re-extrapolated in each)"

    return BallFit(
        mass_kg=float(np.mean(mass)),
        n_impacts=n,
        kb0_N_m=kb0,
        kb0_lo=lo_hi["kb0"][0],
        kb0_hi=lo_hi["kb0"][1],
        kb0_source=kb0_source,
        ak=ak, ak_lo=lo_hi["ak"][0], ak_hi=lo_hi["ak"][1],
        a=a, a_lo=lo_hi["a"][0], a_hi=lo_hi["a"][1],
        ac=ac, ac_lo=lo_hi["ac"][0], ac_hi=lo_hi["ac"][1],
        ak_a_correlation=corr,
        contact_time_rmse_pct=tc_rmse,
        cor_rmse_pct=cor_rmse,
        interval_method=method,
        messages=messages,
        result=res,
        bootstrap=boot,
    )


def model_curves(fit: BallFit, speeds_m_s, *, confidence=0.95, max_band_samples=200):
    """Model TC, COR and peak force against inbound speed, with bands from the bootstrap.

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
        ``contact_time_s``, ``cor``, ``peak_force_N`` (each (n_speed,)) and
        ``contact_time_s_lo/_hi``, ``cor_lo/_hi`` (NaN when there is no bootstrap).
    """
    v = _as_1d("speeds_m_s", speeds_m_s)
    sim = simulate_impact(v, fit.mass_kg, fit.kb0_N_m, fit.ak, fit.a, fit.ac)
    out = {
        "contact_time_s": sim.contact_time_s,
        "cor": sim.cor,
        "peak_force_N": sim.peak_force_N,
    }
    nan = np.full(v.size, np.nan)
    out.update(contact_time_s_lo=nan, contact_time_s_hi=nan, cor_lo=nan, cor_hi=nan)
    boot = fit.bootstrap
    if boot is not None and boot.shape[0] >= 10:
        b = boot[: max_band_samples]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            s = simulate_impact(v[None, :], fit.mass_kg, b[:, 0:1], b[:, 1:2], b[:, 2:3], b[:, 3:4])
        q = 100 * np.array([0.5 - confidence / 2, 0.5 + confidence / 2])
        out["contact_time_s_lo"], out["contact_time_s_hi"] = np.nanpercentile(s.contact_time_s, q, axis=0)
        out["cor_lo"], out["cor_hi"] = np.nanpercentile(s.cor, q, axis=0)
    return out
