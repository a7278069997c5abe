"""The model inversion of the ball fit: kB(0) extrapolated, the two stages and the joint weighted least squares."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

from .model import simulate_impact

__all__ = [
    "REFERENCE_DISPLACEMENT_M",
    "PARAMETER_BOUNDS",
    "Kb0Fit",
    "StageFit",
    "FitError",
    "CONVERGENCE_OFFSET",
    "fit_kb0",
    "fit_contact_time",
    "fit_restitution",
]


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


#: Relative offset (Bates & Watts 1981) below which a least-squares problem has converged [-]:
#: the parameters are then within about 1 % of a standard error of the optimum. (1e-3 is
#: below what the model's finite-difference Jacobian resolves at some optima.)
CONVERGENCE_OFFSET = 1.0e-2


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
