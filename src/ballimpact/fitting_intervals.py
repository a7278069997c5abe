"""Intervals of the ball fit: profile likelihood with a critical value calibrated by a parametric bootstrap."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .fitting_core import (
    REFERENCE_DISPLACEMENT_M,
    _batched_lm,
    _f_ppf,
    _full_bounds,
    _jacobian,
    _residuals,
    _satterthwaite_dof,
    _simulate,
)

__all__ = ["CALIBRATION_SESSIONS", "CALIBRATION_REFITS"]


#: Simulated sessions, fitted in the model linearised at the estimate, that calibrate the
#: critical value of the profile intervals (:func:`_calibrated_critical_values`) [-];
#: 0 gives the F(1, nu) quantile alone.
CALIBRATION_SESSIONS = 4000
#: Of those, sessions also refitted with the full model (batched Levenberg-Marquardt) to
#: correct the linearised quantile for the model's curvature [-]; 0: none (the default:
#: the correction is within its own sampling noise on Table 2 balls at 14-30 m/s).
CALIBRATION_REFITS = 0


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
