"""The contact's end read from the force's curve: a polynomial through the samples inside it, met with zero."""

from __future__ import annotations

import math

import numpy as np

from .ends import CURVE_CHI2, FOOT_PRE_S, FOOT_PRE_SAMPLES
from .noise import checked_arguments

__all__ = ["end_from_curve", "curve_end"]

CURVE_FITS = ((2, 0.03), (3, 0.05))  # the end's curve: polynomials of this degree over this fraction of TC [-]
CURVE_MIN_SAMPLES = 4  # ... but over at least this many samples inside the contact [samples]
CURVE_SEARCH = 3.0  # its zero is looked for within this many samples of the hinge's end ... [samples]
CURVE_STEP = 0.05  # ... on a grid this fine, the least's neighbours refined by a parabola [samples]
CURVE_MIN_SLOPE = 3.0  # ... pinned only where the force's slope there is this many noise deviations per sample [-]
CURVE_RATE_HZ = 50.0e3  # faster: the search and the slope per CURVE_RATE_HZ sample (noise averaged over it) [Hz]


def end_from_curve(force, sample_rate_hz: float, start_s: float, end_s: float, noise_rms: float, *,
                   t0_s: float = 0.0) -> tuple[float, float]:
    """The contact end from the force's curve before it, with its standard uncertainty.

    In restitution the model's force ``F = kB x + cB x'`` (Eq. (14) in
    Goodwill & Haake 2004, no momentum flux after the peak) reaches zero
    smoothly, with a finite slope and a curvature of either sign: the last
    samples of a punctured ball fall steeper and steeper (concave), others
    flatten into the end (convex). A straight line through them (the hinge
    of :func:`detect_contact`) then meets zero late or early, by an amount that
    depends on how many samples stand out of the noise. Here the force is
    fitted, by least squares, with ``a s + b s^2`` (s = end - t, zero after
    the end, a >= 0) over the last ``CURVE_FITS[0][1]`` of TC and the quiet
    samples after it, the end profiled on a grid of CURVE_STEP samples within
    CURVE_SEARCH samples of ``end_s`` (above CURVE_RATE_HZ, within the time of
    CURVE_SEARCH samples at CURVE_RATE_HZ: a faster rig's end is not known to
    fewer of its samples); its standard uncertainty is the
    half-width of the ends whose residual sum of squares is within CURVE_CHI2
    (9) noise variances of the least (chi-square with one degree of freedom),
    over 3: the three-sigma interval over three. Where the residual is not a
    parabola in the end (a steep fall with a few samples on it, one of them
    low in the noise, decides between two ends) the one-sigma interval is
    narrow while the end is not known; the wider interval sees the other end. The same
    fit with a cubic over ``CURVE_FITS[1][1]`` of TC tells how much the end
    depends on the curve's model; that difference is added in quadrature.

    Parameters
    ----------
    force : array_like
        Force (or a conditioned voltage proportional to it), zero baseline,
        one sample per 1/sample_rate_hz [N] (or [V]).
    sample_rate_hz : float
        Sample rate [Hz].
    start_s, end_s : float
        Contact start and end from another estimate (e.g. the hinge's) [s].
    noise_rms : float
        Noise standard deviation of the force, same unit as ``force``.
    t0_s : float
        Time of the first sample [s].

    Returns
    -------
    end_s : float
        End of the contact from the curve [s] (NaN when the samples do not
        allow the fit).
    se_s : float
        Its standard uncertainty [s]; inf when the end is not bounded within
        the search, or when the force's slope at the end is below
        CURVE_MIN_SLOPE noise deviations per sample (above CURVE_RATE_HZ: its
        rise over a sample at CURVE_RATE_HZ, against the noise averaged over
        that time) and the force may flatten into its end; NaN with a NaN end.

    Raises
    ------
    ValueError
        For non-finite samples, a non-positive sample rate, a contact not
        inside the trace or a noise that is not positive and finite.
    """
    fs, x = checked_arguments(force, sample_rate_hz, t0_s)
    if not (math.isfinite(start_s) and math.isfinite(end_s) and end_s > start_s):
        raise ValueError(f"need finite start_s < end_s, got start_s={start_s!r}, end_s={end_s!r}")
    u_start, u_end = (start_s - t0_s) * fs, (end_s - t0_s) * fs
    if u_start < 0 or u_end > x.size - 1:
        raise ValueError(f"contact [{start_s:.6g}, {end_s:.6g}] s lies outside the trace of {x.size} samples")
    if not (math.isfinite(noise_rms) and noise_rms > 0):
        raise ValueError(f"noise_rms must be positive and finite, got {noise_rms!r}")
    inside = x[int(math.ceil(u_start)):int(math.floor(u_end)) + 1]
    if inside.size < CURVE_MIN_SAMPLES:
        return math.nan, math.nan
    k = int(math.ceil(u_start)) + int(np.argmax(inside))
    u, se = curve_end(x, float(noise_rms), u_start, u_end, k, k, fs)
    return t0_s + u / fs, se / fs


def curve_end(xs, sigma: float, u_start: float, u_end: float, peak_index: int, floor_u: int,
               fs: float) -> tuple[float, float]:
    """The end from the force's curve and its standard uncertainty [samples] (see :func:`end_from_curve`); the
    fits start after the peak, and the end is not before floor_u (the last sample above the contact threshold)."""
    n_pre = max(FOOT_PRE_SAMPLES, int(math.ceil(FOOT_PRE_S * fs)))
    tc = u_end - u_start
    # above CURVE_RATE_HZ, in the time of one sample at it: the search's reach, and the slope over that time
    # against the noise averaged over it (faster sampling pins the same curve no worse)
    rate = max(fs / CURVE_RATE_HZ, 1.0)
    ends = []
    for degree, fraction in CURVE_FITS:
        lo = max(int(math.floor(u_end - max(fraction * tc, CURVE_MIN_SAMPLES))), peak_index, 0)
        hi = min(int(math.ceil(u_end)) + n_pre, xs.size - 1)
        ends.append(_profile_end(xs[lo:hi + 1], np.arange(lo, hi + 1, dtype=float), sigma, u_end, floor_u,
                                 degree, xs.size - 1, CURVE_SEARCH * rate))
    (u2, se2, slope), (u3, _, _) = ends
    if not (math.isfinite(u2) and math.isfinite(u3)):
        return u2, math.inf if math.isfinite(u2) else math.nan
    if not slope * rate ** 1.5 >= CURVE_MIN_SLOPE * sigma:
        return u2, math.inf  # a force that flattens into its end: where it meets zero is not in the samples
    return u2, math.hypot(se2, u2 - u3)


def _profile_end(y, u, sigma: float, u_end: float, floor_u: float, degree: int, last: float,
                 search: float = CURVE_SEARCH):
    """Least-squares end of ``sum_k c_k s^k`` (k = 1..degree, s = max(end - u, 0), c_1 >= 0) on a grid near
    u_end [samples], its standard uncertainty (half the width of the ends within CURVE_CHI2 noise variances of
    the least residual, over its square root; inf when that reaches the grid's edge) [samples] and the slope
    c_1 there [force per sample]; NaNs when the samples cannot tell."""
    grid = u_end + np.arange(-search, search + 0.5 * CURVE_STEP, CURVE_STEP)
    grid = grid[(grid >= floor_u) & (grid <= last)]
    if grid.size < 3 or y.size < degree + 2:
        return math.nan, math.nan, math.nan
    s = np.maximum(grid[:, None] - u[None, :], 0.0)

    def fit(s, powers):  # the residual sums of squares and the coefficients at each of the ends of s's rows
        a = np.stack([s ** p for p in powers], axis=-1)
        ata = np.einsum("gnk,gnl->gkl", a, a)
        aty = np.einsum("gnk,n->gk", a, y)
        ridge = 1e-12 * (1.0 + np.trace(ata, axis1=1, axis2=2))[:, None, None] * np.eye(len(powers))
        coef = np.linalg.solve(ata + ridge, aty[..., None])[..., 0]
        return np.sum((y[None, :] - np.einsum("gnk,gk->gn", a, coef)) ** 2, axis=1), coef

    sse, coef = fit(s, range(1, degree + 1))
    slope = np.maximum(coef[:, 0], 0.0)
    bent = np.flatnonzero(coef[:, 0] < 0)  # without the linear term where its slope is < 0 (only those ends)
    if bent.size:
        sse[bent] = fit(s[bent], range(2, degree + 1))[0]
    k = int(np.argmin(sse))
    level = sse[k] + CURVE_CHI2 * sigma * sigma
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0 or inside[-1] == grid.size - 1:
        return float(grid[k]), math.inf, float(slope[k])
    best = float(grid[k])
    curvature = sse[k - 1] - 2.0 * sse[k] + sse[k + 1]
    if 0 < k < grid.size - 1 and curvature > 0:  # the least between the grid's points, from a parabola
        best += 0.5 * CURVE_STEP * float(sse[k - 1] - sse[k + 1]) / float(curvature)
    i, j = int(inside[0]), int(inside[-1])  # the interval's edges between the grid's points, linearly
    lo = grid[i] - CURVE_STEP * float(level - sse[i]) / float(sse[i - 1] - sse[i])
    hi = grid[j] + CURVE_STEP * float(level - sse[j]) / float(sse[j + 1] - sse[j])
    return best, 0.5 * float(hi - lo) / math.sqrt(CURVE_CHI2), float(slope[k])
