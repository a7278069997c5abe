"""The baseline under a plate voltage: offset, drift, mains hum and the amplifier's decay, fitted on quiet samples.

The model and its fit are described in :mod:`ballimpact.signal.conditioning`: every quiet sample is
``V = B`` (offset, linear drift, sin/cos at the mains frequency and its harmonics), every quiet sample after the
contact ``V + kappa * I_V = sum_j theta_j (phi_j + kappa * I_phi_j)`` with ``kappa = 1 / tau`` [1/s]; linear in
theta for a given kappa, kappa found on a grid and refined. :func:`choose_tau` decides whether the estimated
time constant is used.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from ..problems import Problem, ProblemKind
from .noise import finite_median, robust_noise

__all__ = [
    "BaselineFit",
    "fit_baseline",
    "rough_trend",
    "integral_start",
    "running_integral",
    "decay_correct",
    "integral_to",
    "mains_frequencies",
    "choose_tau",
    "baseline_integral_se",
]

PRE_GUARD_S = 0.5e-3  # quiet pre-trigger ends this long before the contact start [s]
POST_GUARD_S = 2.0e-3  # quiet post stretch begins this long after the contact end (plate ringing) [s]
PRE_WINDOW_S = 0.1  # longest pre-contact stretch used for the baseline fit [s]
POST_WINDOW_S = 0.05  # longest post-contact stretch used for the baseline fit [s]
MIN_QUIET_SAMPLES = 20  # fewest samples for a pre or post baseline [samples]
MIN_PRE_SAMPLES = 8  # fewest pre-contact samples for an offset at all [samples]
MIN_POST_S = 2.0e-3  # shortest post-contact stretch for the decay [s]
SHORT_POST_GUARD_S = 0.5e-3  # a record too short for MIN_POST_S after POST_GUARD_S: the post stretch from this on ... [s]
SHORT_MIN_POST_S = 0.5e-3  # ... when it is at least this long (the decay's standard error then decides) [s]
UNDERSHOOT_SIGNIFICANCE = 5.0  # kappa must exceed this many standard errors [-]
TAU_BOUNDS_S = (0.005, 1.0e4)  # plausible charge-amplifier time constants [s]
KAPPA_CORRELATION_S = 2e-3  # kappa's standard error allows for residuals correlated over this long [s]
KAPPA_REFINE_ITERATIONS = 100  # most Newton or bisection steps refining kappa between two grid points [-]
BIAS_WARN_FRACTION = 1.0e-3  # warn when an uncorrected decay could bias the impulse by more [-]
BIAS_EXCLUDE_FRACTION = 3.0e-3  # exclude when it could bias the impulse by more [-]
NYQUIST_MARGIN = 0.45  # harmonics above this fraction of the sample rate are skipped [-]
MAINS_CANDIDATES_HZ = (50.0, 60.0)  # mains frequencies tried when not given [Hz]
HUM_PRIOR_SCALE = 3.0  # the hum's coefficients' prior standard deviation, in half ranges of the quiet samples [-]
ROBUST_SIGMA = 5.0  # quiet samples off the first fit by more noise deviations are dropped [-]


@dataclass
class BaselineFit:
    """A fit of the baseline model to the quiet samples of a record (:func:`fit_baseline`), in the record's unit."""

    baseline: np.ndarray  # offset + hum at every sample [V]
    coef: dict
    kappa: float  # 1 / tau [1/s] (the given one, or the estimate; NaN when not estimable)
    kappa_se: float  # its standard error [1/s]
    has_post: bool  # kappa could be estimated
    noise: float  # robust noise of the quiet residuals [V]
    hum_amplitudes: tuple[float, ...]
    bic: float  # Bayesian information criterion of the fit [-]
    quiet: np.ndarray  # samples used [bool]
    pre: np.ndarray  # pre-contact quiet samples [bool]
    post: np.ndarray  # post-contact quiet samples [bool]
    no_post: str = ""  # why kappa could not be estimated (what the record lacks), "" when it could
    cov: np.ndarray | None = None  # covariance of offset, drift and hum coefficients at the fitted kappa [unit^2]
    t_mid: float = 0.0  # the time the drift is counted from [s, from the first sample]


def _regions(n, fs, start_u, end_u, pre_guard, post_guard, mask):
    idx = np.arange(n)
    pre = (idx < start_u - pre_guard) & (idx >= start_u - pre_guard - PRE_WINDOW_S * fs)
    if np.count_nonzero(pre & ~mask) < MIN_PRE_SAMPLES and math.isfinite(start_u):
        # a short pre-trigger: come closer to the contact (the cloth foot is < 0.2 ms)
        pre = (idx < start_u - min(pre_guard, 0.2e-3 * fs)) & (idx >= start_u - PRE_WINDOW_S * fs)
    post = (idx > end_u + post_guard) & (idx <= end_u + post_guard + POST_WINDOW_S * fs)
    return pre & ~mask, post & ~mask


def fit_baseline(v, fs, frequencies, start_u, end_u, pre_guard, post_guard, mask=None, with_decay=False,
                  kappa_given=None, reduce=True, noise_floor=0.0, cache: dict | None = None) -> BaselineFit:
    """Robust least squares of the baseline model on the quiet samples (see the module docstring).

    Pre-contact quiet samples: ``v = B`` with ``B = sum_j theta_j phi_j`` (offset,
    drift, hum). Post-contact quiet samples: ``y + kappa * integral y = 0`` with
    ``y = v - B`` integrated from the contact start, i.e.
    ``v + kappa * Iv = sum_j theta_j (phi_j + kappa * Phi_j)`` (``Iv``, ``Phi_j``
    the running integrals of v and phi_j). For a given kappa this is linear in
    theta; kappa (when not given) minimises the residual sum of squares, found
    on a grid and refined, with normal equations built once (quadratic in kappa).

    When kappa comes out too uncertain for the impulse (a decay hidden in its
    standard error could bias it by more than BIAS_EXCLUDE_FRACTION, see
    choose_tau) and ``reduce``, the fits with fewer hum harmonics (down to
    none) are tried too: the harmonics can take up the undershoot's step in a
    short record, and the fit of least BIC is returned.

    A dict ``cache`` (one per record ``v``) holds the fits made: the window
    enters the fit only through its quiet samples and the sample its running
    integrals start from, so a window that moved by less than that (the
    iteration's last steps) gets the same fit back without refitting it.
    """
    n = v.size
    if mask is None:
        mask = np.zeros(n, dtype=bool)
    regions = _quiet_regions(n, fs, start_u, end_u, pre_guard, post_guard, mask, with_decay, kappa_given)
    if cache is not None:
        pre, post, quiet, has_post, use_post, no_post = regions
        key = (tuple(frequencies), kappa_given, noise_floor, pre.tobytes(), post.tobytes(), quiet.tobytes(),
               has_post, use_post, no_post, integral_start(start_u) if use_post else None)
        fit = cache.get(key)
        if fit is None:
            fit = cache[key] = _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor)
    else:
        fit = _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor)
    hidden = UNDERSHOOT_SIGNIFICANCE * fit.kappa_se
    if (reduce and fit.hum_amplitudes and regions[4] and kappa_given is None and hidden > abs(fit.kappa)
            and (end_u - start_u) / fs * hidden / 2.0 > BIAS_EXCLUDE_FRACTION):
        for k in range(len(fit.hum_amplitudes)):  # the harmonics fitted are all of ``frequencies``
            alt = fit_baseline(v, fs, list(frequencies)[:k], start_u, end_u, pre_guard, post_guard, mask, with_decay,
                                kappa_given, reduce=False, noise_floor=noise_floor, cache=cache)
            if alt.bic < fit.bic:
                fit = alt
    return fit


def _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor) -> BaselineFit:
    """The fit of :func:`fit_baseline` on its quiet samples ``regions`` (:func:`_quiet_regions`), before the
    fits with fewer harmonics are tried."""
    n = v.size
    pre, post, quiet, has_post, use_post, no_post = regions
    t = np.arange(n) / fs
    qi = np.flatnonzero(quiet)
    tq = t[qi]
    span = tq[-1] - tq[0] if tq.size else 0.0
    # a full period of the fundamental is needed, or no hum is fitted at all
    freqs = list(frequencies) if frequencies and span * min(frequencies) >= 1.0 else []
    t_mid = 0.5 * (tq[0] + tq[-1]) if tq.size else 0.0
    trig = _trig(n, fs, tuple(freqs))
    phi, norms, big_phi, iv = _design(v, fs, t, t_mid, trig, tuple(freqs), qi, post[qi], start_u, use_post)
    y = v[qi]
    p = phi.shape[1]
    keep = np.ones(qi.size, dtype=bool)
    ridge = _hum_prior(y, pre[qi], post[qi], norms, HUM_PRIOR_SCALE)
    for _ in range(2):
        ne = _normal_equations(phi, big_phi, y, iv, keep, ridge)
        kappa, curv = _best_kappa(ne, kappa_given, use_post)
        rss, theta = _solve_kappa(ne, kappa)
        columns = phi + kappa * big_phi  # the model's columns at this kappa
        resid = (y + kappa * iv) - columns @ theta
        s = robust_noise(resid[keep])
        new_keep = np.abs(resid) <= ROBUST_SIGMA * max(s, 1e-300)
        if np.count_nonzero(new_keep) < max(0.8 * qi.size, p + 3) or np.array_equal(new_keep, keep):
            break
        keep = new_keep
    n_par = p + (1 if (use_post and kappa_given is None) else 0)
    n_keep = int(np.count_nonzero(keep))
    s2 = rss / max(n_keep - n_par, 1)
    coef = theta / norms
    baseline = coef[0] + coef[1] * (t - t_mid) + trig @ coef[2:]
    try:  # the coefficients' covariance (with the hum's prior: its posterior), at the kappa found
        cov = s2 * np.linalg.inv(ne[0] + kappa * ne[1] + kappa * kappa * ne[2]) / np.outer(norms, norms)
    except np.linalg.LinAlgError:
        cov = None
    if use_post and kappa_given is None:
        kappa_se = math.sqrt(2.0 * s2 / curv) if curv > 0 else math.inf
        if math.isfinite(kappa_se):
            # residuals that are not white (hum over less than a period, left to the drift and the decay) carry
            # less information on kappa than their number says
            kept = slice(None) if keep.all() else keep  # a view where nothing was dropped
            kappa_se *= math.sqrt(_correlation_factor(columns[kept], (iv - big_phi @ theta)[kept], resid[kept],
                                                      max(1, int(round(KAPPA_CORRELATION_S * fs)))))
    elif kappa_given is not None:
        kappa, kappa_se = float(kappa_given), 0.0
    else:
        kappa, kappa_se = math.nan, math.nan
    pre_q = pre[qi]
    noise_sel = pre_q & keep if np.count_nonzero(pre_q & keep) >= MIN_QUIET_SAMPLES else keep
    noise = max(robust_noise(resid[noise_sel]), noise_floor)  # no less than the ADC's step / sqrt(12)
    bic = n_keep * math.log(max(rss, 1e-300) / n_keep) + n_par * math.log(n_keep) if n_keep else math.inf
    amps = tuple(float(math.hypot(coef[2 + 2 * i], coef[3 + 2 * i])) for i in range(len(freqs)))
    return BaselineFit(baseline, _coefficients(coef, freqs, float(t[0] - t_mid), kappa, kappa_se), float(kappa),
                       float(kappa_se), has_post or kappa_given is not None, noise, amps, bic, quiet, pre, post,
                       no_post, cov, float(t_mid))


def _coefficients(coef, freqs, t0_from_mid, kappa, kappa_se) -> dict:
    """The fitted model as :attr:`BaselineFit.coef` holds it (the offset at the first sample, ``t0_from_mid`` [s]
    from the drift's origin)."""
    return {
        "offset_V": float(coef[0] + coef[1] * t0_from_mid),
        "drift_V_per_s": float(coef[1]),
        "hum_frequencies_hz": tuple(float(f) for f in freqs),
        "hum_cos_V": tuple(float(coef[2 + 2 * i]) for i in range(len(freqs))),
        "hum_sin_V": tuple(float(coef[3 + 2 * i]) for i in range(len(freqs))),
        "kappa_per_s": float(kappa),
        "kappa_se_per_s": float(kappa_se),
    }


def _quiet_regions(n, fs, start_u, end_u, pre_guard, post_guard, mask, with_decay, kappa_given):
    """Quiet samples of the baseline fit: (pre, post, quiet, has_post, use_post, no_post).

    Boolean masks and flags; ``no_post`` says what the record lacks when the
    decay cannot be measured ("" when it can). The post stretch starts
    post_guard after the contact; when that leaves fewer than MIN_POST_S of
    it (a short post-trigger), it starts SHORT_POST_GUARD_S after the contact
    and needs SHORT_MIN_POST_S only: the standard error of kappa then says in
    choose_tau whether a decay hidden in the noise could bias the impulse.
    """
    pre, post = _regions(n, fs, start_u, end_u, pre_guard, post_guard, mask)
    min_post = max(MIN_QUIET_SAMPLES, int(round(MIN_POST_S * fs)))
    if with_decay and np.count_nonzero(post) < min_post and post_guard > SHORT_POST_GUARD_S * fs:
        short = _regions(n, fs, start_u, end_u, pre_guard, SHORT_POST_GUARD_S * fs, mask)[1]
        min_short = max(MIN_QUIET_SAMPLES, int(round(SHORT_MIN_POST_S * fs)))
        if np.count_nonzero(short) >= np.count_nonzero(post):
            post, min_post = short, min_short
    has_pre = np.count_nonzero(pre) >= MIN_PRE_SAMPLES
    has_post = has_pre and with_decay and np.count_nonzero(post) >= min_post
    no_post = ""
    if with_decay and not has_pre:
        no_post = (f"only {np.count_nonzero(pre)} quiet samples before the contact (at least {MIN_PRE_SAMPLES} "
                   "needed) to measure the undershoot against")
    elif with_decay and not has_post:
        no_post = (f"only {1e3 * np.count_nonzero(post) / fs:.2g} ms of quiet record after the contact (at least "
                   f"{1e3 * min_post / fs:.2g} ms from {1e3 * min(post_guard / fs, SHORT_POST_GUARD_S):.2g} ms after "
                   "its end needed) to measure the undershoot")
    if not with_decay or not has_pre:
        post = post & False if has_pre else post
    quiet = pre | post
    if np.count_nonzero(quiet) < MIN_PRE_SAMPLES:
        # no quiet stretch at all: a median offset is the best there is
        quiet = ~mask if np.count_nonzero(~mask) >= 3 else np.ones(n, dtype=bool)
        pre, post = quiet, np.zeros(n, dtype=bool)
        has_post = False
    use_post = has_post and (kappa_given is None or kappa_given > 0)
    if not has_post and has_pre and with_decay:
        quiet = pre  # the post stretch alone cannot tell an offset from the undershoot
        post = np.zeros(n, dtype=bool)
    return pre, post, quiet, has_post, use_post, no_post


def _design(v, fs, t, t_mid, trig, freqs, qi, post_q, start_u, use_post):
    """Normalised model columns at the quiet samples and, after the contact, their running integrals and v's.

    Returns (phi, norms, big_phi, iv): columns offset, drift, cos/sin per hum
    frequency (``trig``'s columns, of ``freqs`` [Hz]), scaled to unit norm
    (``norms``); their trapezoid integrals from the contact start and that of v
    at the post-contact quiet samples (zero elsewhere). The columns' integrals
    are the trapezoid rule's sums in closed form: exact for the offset and the
    drift, and for cos and sin of w t at step h, (h / 2) cot(w h / 2) times the
    change of sin (and minus that of cos) from the start, as the sum of the
    trapezoids telescopes; v's is summed.
    """
    phi = np.empty((qi.size, 2 + trig.shape[1]))
    phi[:, 0] = 1.0
    np.subtract(t[qi], t_mid, out=phi[:, 1])
    phi[:, 2:] = trig[qi]
    norms = np.sqrt(np.sum(phi * phi, axis=0))
    norms[norms == 0] = 1.0
    phi /= norms
    big_phi = np.zeros_like(phi)
    iv = np.zeros(qi.size)
    if use_post and post_q.any():
        i0 = integral_start(start_u)
        first = int(np.argmax(post_q))
        if post_q[first:].all():  # the post stretch follows the pre one: a slice, not a mask
            post_q = slice(first, None)
        j = qi[post_q]
        h = 1.0 / fs
        cols = [t[j] - t[i0], 0.5 * ((t[j] - t_mid) ** 2 - (t[i0] - t_mid) ** 2)]
        for i, f in enumerate(freqs):
            half = math.pi * f * h
            k = 0.5 * h * math.cos(half) / math.sin(half)
            cols.append(k * (trig[j, 2 * i + 1] - trig[i0, 2 * i + 1]))
            cols.append(-k * (trig[j, 2 * i] - trig[i0, 2 * i]))
        big_phi[post_q] = np.column_stack(cols) / norms
        iv[post_q] = cumulative_trapezoid(v[i0:int(j[-1]) + 1], dx=h, initial=0.0)[j - i0]
    return phi, norms, big_phi, iv


def _normal_equations(phi, big_phi, y, iv, keep, ridge=None):
    """Coefficients of the normal equations, quadratic in kappa, of the kept samples; ``ridge`` (one per column,
    or None) is added to the diagonal of the constant term: the prior's precision, in the columns' scale."""
    a, b_, y_, i_ = (phi, big_phi, y, iv) if keep.all() else (phi[keep], big_phi[keep], y[keep], iv[keep])
    p0 = a.T @ a
    if ridge is not None:
        p0[np.diag_indices_from(p0)] += ridge
    return (p0, a.T @ b_ + b_.T @ a, b_.T @ b_, a.T @ y_, a.T @ i_ + b_.T @ y_, b_.T @ i_,
            float(y_ @ y_), 2.0 * float(y_ @ i_), float(i_ @ i_))


def _hum_prior(y, pre_q, post_q, norms, scale):
    """The precision of the hum's prior on each normalised column [1/V^2 times the noise variance]: None when there
    is no hum column. Each cos and sin coefficient is given a prior of mean 0 and standard deviation ``scale``
    times the largest half range (1st to 99th percentile) of a quiet stretch about its median [V]: a stationary hum
    shows its size on the quiet samples, and a combination of harmonics that nearly cancels on them (a record of
    about a mains period) cannot grow under the contact beyond it."""
    if norms.size <= 2 or not math.isfinite(scale):
        return None
    half = 0.0
    for sel in (pre_q, post_q):
        if np.count_nonzero(sel) >= MIN_QUIET_SAMPLES:
            lo, hi = np.percentile(y[sel], [1.0, 99.0])
            half = max(half, 0.5 * (hi - lo))
    d = np.diff(y[pre_q]) if np.count_nonzero(pre_q) > 3 else np.diff(y)
    sigma2 = robust_noise(d) ** 2 / 2.0
    if not (half > 0 and sigma2 > 0):
        return None
    ridge = np.zeros(norms.size)
    ridge[2:] = sigma2 / (scale * half * norms[2:]) ** 2
    return ridge


def _solve_kappa(ne, k):
    """Residual sum of squares and coefficients for kappa = k (a scalar or an array of them)."""
    p0, p1, p2, q0, q1, q2, r0, r1, r2 = ne
    k = np.atleast_1d(np.asarray(k, dtype=float))[:, None, None]
    a = p0 + k * p1 + k * k * p2
    q = (q0 + k[:, :, 0] * q1 + k[:, :, 0] ** 2 * q2)[:, :, None]
    try:
        theta = np.linalg.solve(a, q)[:, :, 0]
    except np.linalg.LinAlgError:
        theta = (np.linalg.pinv(a, rcond=1e-12, hermitian=True) @ q)[:, :, 0]
    kk = k[:, 0, 0]
    rss = np.maximum(r0 + kk * r1 + kk * kk * r2 - np.sum(q[:, :, 0] * theta, axis=1), 0.0)
    return (float(rss[0]), theta[0]) if rss.size == 1 else (rss, theta)


def _correlation_factor(x: np.ndarray, d: np.ndarray, r: np.ndarray, lag: int) -> float:
    """How much correlated residuals widen kappa's variance [-]: at least 1.

    kappa's least-squares estimate moves with the sum of its scores ``r * w``,
    the residuals r [V] times w, the residual's derivative in kappa ``d`` [V s]
    with the other columns ``x`` projected out. Its variance is the scores'
    long-run variance, estimated with a Bartlett window of ``lag`` samples
    (Newey & West 1987) over the quiet samples in their order; the fit's own
    standard error takes the scores' variance at lag 0 (white residuals). The
    factor is their ratio, never below 1.
    """
    if r.size < 3:
        return 1.0
    try:
        w = d - x @ np.linalg.solve(x.T @ x, x.T @ d)
    except np.linalg.LinAlgError:
        w = d - x @ np.linalg.lstsq(x, d, rcond=None)[0]
    scores = r * w
    n = scores.size
    n_fft = 1 << (2 * n - 1).bit_length()  # zero-padded to a power of two: no wrap-around, and a fast transform
    acov = np.fft.irfft(np.abs(np.fft.rfft(scores, n_fft)) ** 2, n_fft)[:min(lag, n)]
    if not acov[0] > 0:
        return 1.0
    window = 1.0 - np.arange(acov.size) / (lag + 1.0)
    long_run = acov[0] + 2.0 * float(np.sum(window[1:] * acov[1:]))
    return max(1.0, long_run / float(acov[0]))


def _rss_slope(ne, k: float) -> tuple[float, float]:
    """First and second derivative of the residual sum of squares in kappa at kappa = k [V^2 s, V^2 s^2].

    With A(k) = p0 + k p1 + k^2 p2, q(k) = q0 + k q1 + k^2 q2, r(k) = r0 + k r1 + k^2 r2 and
    theta = A^-1 q, rss = r - q.theta, so rss' = r' - 2 q'.theta + theta.A'.theta, and with
    theta' = A^-1 (q' - A' theta), rss'' = r'' - 2 q''.theta - 2 q'.theta' + 2 theta'.A'.theta + theta.A''.theta.
    """
    p0, p1, p2, q0, q1, q2, r0, r1, r2 = ne
    a, a1 = p0 + k * p1 + k * k * p2, p1 + 2.0 * k * p2
    q, dq = q0 + k * q1 + k * k * q2, q1 + 2.0 * k * q2
    try:
        theta = np.linalg.solve(a, q)
        dtheta = np.linalg.solve(a, dq - a1 @ theta)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(a, rcond=1e-12, hermitian=True)
        theta = inv @ q
        dtheta = inv @ (dq - a1 @ theta)
    a1_theta = a1 @ theta
    d1 = r1 + 2.0 * k * r2 - 2.0 * float(dq @ theta) + float(theta @ a1_theta)
    d2 = (2.0 * r2 - 4.0 * float(q2 @ theta) - 2.0 * float(dq @ dtheta) + 2.0 * float(dtheta @ a1_theta)
          + 2.0 * float(theta @ p2 @ theta))
    return d1, d2


def _refine_kappa(ne, lo: float, hi: float, k0: float, xatol: float) -> float:
    """The least residual sum of squares in kappa between lo and hi [1/s], from k0: Newton's steps on its slope
    (:func:`_rss_slope`), kept inside the bracket the slope's sign narrows, bisecting where a step would leave it
    or not shrink it fast enough (``rtsafe``, Press et al., Numerical Recipes, section 9.4), to xatol [1/s]; the
    bound where the slope does not change sign between them."""
    f_lo, f_hi = _rss_slope(ne, lo)[0], _rss_slope(ne, hi)[0]
    if not f_lo < 0.0:
        return lo
    if not f_hi > 0.0:
        return hi
    k = min(max(k0, lo), hi)
    dx_old = dx = hi - lo
    for _ in range(KAPPA_REFINE_ITERATIONS):
        f, df = _rss_slope(ne, k)
        if f == 0.0:
            return k
        if f < 0.0:
            lo = k
        else:
            hi = k
        if not df > 0.0 or not lo < k - f / df < hi or abs(2.0 * f) > abs(dx_old * df):
            dx_old, dx = dx, 0.5 * (hi - lo)
            k = lo + dx
        else:
            dx_old, dx = dx, f / df
            k -= dx
        if abs(dx) < xatol or hi - lo < xatol:
            break
    return k


def _best_kappa(ne, kappa_given, use_post):
    """kappa = 1 / tau [1/s] of least residual (grid, then Newton's refinement) and the residual's second
    derivative there [V^2 s^2]."""
    if kappa_given is not None or not use_post:
        return (kappa_given if use_post else 0.0), math.nan
    k_max = 2.0 / TAU_BOUNDS_S[0]
    pos = np.geomspace(1e-4, k_max, 48)
    grid = np.concatenate([-pos[::-1], [0.0], pos])
    rss = _solve_kappa(ne, grid)[0]
    j = int(np.argmin(rss))
    lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
    k = _refine_kappa(ne, float(lo), float(hi), float(grid[j]), 1e-9 * max(abs(grid[j]), 1e-3))
    if not _solve_kappa(ne, k)[0] <= rss[j]:
        k = float(grid[j])
    # the curvature from the analytic second derivative: a central difference of the residual (steps of 1e-3 of
    # kappa) subtracts sums that agree to 1e-13 where the residual is flat, and can come out tens of per cent high,
    # kappa's standard error as much too small
    return k, _rss_slope(ne, k)[1]


@functools.lru_cache(maxsize=4)
def _trig(n, fs, freqs):
    """cos and sin of each frequency at the n sample times, one column each [-]."""
    t = np.arange(n) / fs
    out = np.empty((n, 2 * len(freqs)))
    for i, f in enumerate(freqs):
        out[:, 2 * i] = np.cos(2 * np.pi * f * t)
        out[:, 2 * i + 1] = np.sin(2 * np.pi * f * t)
    out.flags.writeable = False
    return out


def rough_trend(v, n_blocks=20):
    """A robust straight line through the record (Theil-Sen on block medians) [V]."""
    n = v.size
    if n < 4 * n_blocks:
        return np.full(n, finite_median(v))
    edges = np.linspace(0, n, n_blocks + 1).astype(int)
    centres = 0.5 * (edges[:-1] + edges[1:] - 1)
    meds = np.array([finite_median(v[a:b]) for a, b in zip(edges[:-1], edges[1:])])
    i, j = np.triu_indices(n_blocks, 1)
    slope = finite_median((meds[j] - meds[i]) / (centres[j] - centres[i]))
    icpt = finite_median(meds - slope * centres)
    return icpt + slope * np.arange(n)


def integral_start(start_u: float) -> int:
    """The sample the running integrals of the baseline fit and the decay's correction start from: the one before
    the contact's start ``start_u`` [samples], or the first."""
    return max(int(math.floor(start_u)) - 1, 0)


def running_integral(y, fs, start_u):
    """Trapezium integral of y from the sample before start, 0 before it [V s]."""
    i0 = integral_start(start_u)
    out = np.zeros(y.size)
    if i0 < y.size - 1:
        out[i0:] = cumulative_trapezoid(y[i0:], dx=1.0 / fs, initial=0.0)
    return out


def decay_correct(y, running, tau):
    """Inverse first-order high-pass from the contact start: y + cumulative integral / tau; ``running`` is y's
    :func:`running_integral` [V s], tau in [s]."""
    x = y.copy()
    if math.isfinite(tau):
        x += running / tau
    return x


def integral_to(running, start_u, end_u) -> float:
    """Trapezium integral of y from the sample before start to the sub-sample end [V s], from y's
    :func:`running_integral` ``running`` [V s] from the same start."""
    i0 = integral_start(start_u)
    c = running[i0:]
    return float(np.interp(end_u - i0, np.arange(c.size), c))


def mains_frequencies(mains_hz, n_harmonics, fs):
    """The mains frequency and its harmonics up to ``n_harmonics`` times it, below NYQUIST_MARGIN of the sample rate
    ``fs`` [Hz]."""
    return [k * mains_hz for k in range(1, n_harmonics + 1) if k * mains_hz < NYQUIST_MARGIN * fs]


def baseline_integral_se(coef: dict, fs: float, start_u: float, end_u: float) -> float:
    """Standard error [V s] of the fitted baseline's integral from ``start_u`` to ``end_u`` [samples, fractional
    indices]: the covariance of the offset, drift and hum coefficients (``coef["coef_cov"]`` [V^2 ...], their scatter
    in the quiet samples' noise at the kappa found; drift counted from ``coef["t_mid_s"]``, hum at
    ``coef["hum_frequencies_hz"]``) carried through the columns' integrals over the window. Where the quiet samples
    leave the hum across the contact loose (a record of about one mains period), the baseline under the contact,
    and the impulse over it, are known only so well. NaN where not known."""
    cov, freqs = coef.get("coef_cov"), coef.get("hum_frequencies_hz", ())
    if cov is None or np.shape(cov) != (2 + 2 * len(freqs),) * 2 or not end_u > start_u:
        return math.nan
    a, b, t_mid = start_u / fs, end_u / fs, float(coef.get("t_mid_s", 0.0))
    g = [b - a, 0.5 * ((b - t_mid) ** 2 - (a - t_mid) ** 2)]
    for f in freqs:
        w = 2.0 * math.pi * f
        g += [(math.sin(w * b) - math.sin(w * a)) / w, (math.cos(w * a) - math.cos(w * b)) / w]
    g = np.asarray(g)
    return math.sqrt(max(float(g @ np.asarray(cov) @ g), 0.0))


def choose_tau(tau_s, fit: BaselineFit, integral: float, duration_s: float, scale: float):
    """Time constant for the decay correction, its source, the warnings to give and the problems found.

    A significant positive kappa gives tau = 1 / kappa (applying a noisy tau is
    unbiased; skipping it is not). A kappa that is not measurable is applied as
    found when positive (0 otherwise); the impact is a problem when the decay
    hidden in the noise could bias the impulse by more than
    BIAS_EXCLUDE_FRACTION, and a warning is given above BIAS_WARN_FRACTION.
    """
    if tau_s is not None:
        return float(tau_s), "given", [], []
    if not fit.has_post:
        msg = f"charge-amplifier decay not corrected: {fit.no_post or 'no quiet baseline to measure the undershoot'}"
        return math.inf, "none", [msg], [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg + " (give plate.time_constant_s)")]
    kappa, se = fit.kappa, fit.kappa_se
    undershoot = kappa * integral
    messages, problems = [], []
    if kappa < -UNDERSHOOT_SIGNIFICANCE * se:
        msg = (f"charge-amplifier decay not corrected: the baseline after the contact is "
               f"{-undershoot * scale * 1e3:.3g} mV above the one before it (expected an undershoot)")
        return math.inf, "none", [msg], [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg)]
    if integral > 0 and UNDERSHOOT_SIGNIFICANCE * se > abs(kappa):
        # how much could a decay hidden in the noise change the impulse?
        bias = duration_s * UNDERSHOOT_SIGNIFICANCE * se / 2.0
        if bias > BIAS_WARN_FRACTION:
            msg = (f"charge-amplifier undershoot not measurable ({undershoot * scale * 1e3:.3g} "
                   f"+/- {se * integral * scale * 1e3:.2g} mV): "
                   f"the impulse may be off by up to {bias * 100:.2g} %")
            messages.append(msg)
            if bias > BIAS_EXCLUDE_FRACTION:
                problems.append(Problem(ProblemKind.UNDERSHOOT_NOT_MEASURABLE, msg))
    if not (integral > 0 and kappa > 0):
        return math.inf, "none", messages, problems
    tau = 1.0 / kappa
    if tau > TAU_BOUNDS_S[1]:
        return math.inf, "none", messages, problems  # DC-coupled in effect: the correction is negligible
    if tau < TAU_BOUNDS_S[0]:
        msg = (f"charge-amplifier decay not corrected: estimated time constant {tau:.3g} s is below "
               f"the plausible {TAU_BOUNDS_S[0]:g} s (a baseline shift that is not the amplifier's decay?)")
        return math.inf, "none", messages + [msg], problems + [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg)]
    return tau, "estimated", messages, problems
