"""Hinge fits of the contact's ends: the foot, the start and end at sub-sample precision and their uncertainties."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .noise import MIN_NOISE_SAMPLES, THRESHOLD_SIGMA

__all__ = ["hinge_se", "unbroken_run", "find_hinges", "contact_ends", "end_spreads"]

EDGE_BAND = (0.03, 0.20)  # fractions of the peak between which edges are fitted by a line [-]
FOOT_SIGMA = 4.0  # the walk from the peak stops at this many noise standard deviations [-]
FOOT_MIN_SAMPLES = 2  # fewest rising samples in the hinge fit [samples]
FOOT_MAX_S = 0.2e-3  # longest stretch of rising samples in the hinge fit [s]
FOOT_PRE_S = 0.15e-3  # stretch before the first sample above the noise in the hinge fit [s]
FOOT_PRE_SAMPLES = 4  # ... but at least this many samples [samples]
FOOT_MAX_WIDENINGS = 8  # a slow foot's pre window may grow to this many more FOOT_PRE_S [-]
KINK_SIGMA = 4.0  # a bend of the rise lowering the residual sum of squares by this many noise deviations squared [-]
FOOT_RESIDUAL_SIGMA = 3.0  # a rising sample predicted worse than this (standard errors) ends the foot [-]
SPREAD_FACTOR = 2.0  # the ends are fitted again from samples above this many times the noise thresholds [-]
CURVE_CHI2 = 9.0  # its uncertainty: half the ends within this many noise variances of the least, over its root [-]
HINGE_SE_STEP = 0.1  # the hinge's corner profiled on a grid this fine for the ends' uncertainties [samples]
BENT_STEP = 0.02  # the end's bent hinge profiled on a grid this fine, then its least refined [samples]
BENT_REFINE_LEVELS = 3  # ... its least refined on this many finer grids [-]
BENT_REFINE_POINTS = 41  # ... of this many corners each [-]
BEND_CHI2 = 0.0  # ... and taken where its bend lowers the least residual sum of squares by more than this many
#                   noise variances (none: a price selects the straight hinge's late corner where noise hides
#                   the bend) [-]
JUMP_SIGMA = 3.0  # the first rising sample's step beats the next rise by this many standard errors: a jump [-]
STEP_FRACTION = 0.03  # the first sample out of the noise above this fraction of the peak: the force stepped up to it [-]
STEP_SIGMA = 1.0  # ... where the start's line predicts the last quiet sample within this many noise deviations [-]
RING_GAP_S = 0.1e-3  # the ringing check starts this long after the end [s]
RING_WINDOW_S = 1.0e-3  # ... and lasts this long [s]
RING_SIGMA = 2.0  # rms after the end above this many noise deviations = ringing [-]


def _line_zero(u: np.ndarray, y: np.ndarray) -> float:
    """Zero crossing of the least-squares line y = a + b u (NaN when flat)."""
    if u.size < 2:
        return math.nan
    um, ym = u.mean(), y.mean()
    suu = np.sum((u - um) ** 2)
    if suu <= 0:
        return math.nan
    b = np.sum((u - um) * (y - ym)) / suu
    if not math.isfinite(b) or b == 0:
        return math.nan
    return float(um - ym / b)


def _hinge_fits(u: np.ndarray, y: np.ndarray, lower: float, upper: float, first: int):
    """Exact least-squares hinges y = b * max(u - ts, 0), b >= 0, ts in [lower, upper], of the windows
    ``u[:e + 1]`` for every e from ``first`` on: arrays (ts, b, sse), one entry per window.

    Between two sample times the samples right of the corner are fixed, so the
    hinge is the straight line through them and the optimum there is that
    line's zero crossing when it falls inside the interval; otherwise it is at
    a sample time or a bound. All candidates of all windows are evaluated at
    once (running sums along the window), and the residual sum of squares of
    each window's best hinge is summed directly. Every sample before
    ``upper`` must be inside the first window (the corner's candidates are then
    the same for every window).
    """
    shift = float(u[0])
    u = np.asarray(u, dtype=float) - shift
    y = np.asarray(y, dtype=float)
    lower, upper = lower - shift, upper - shift
    n = u.size
    m = int(np.count_nonzero(u < upper))  # samples left of the upper bound: the lines' intervals
    if not m <= first + 1 <= n:
        raise ValueError(f"first window must hold every sample before the upper bound, got first={first}")
    ends = np.arange(first, n)
    # running sums of 1, u, u^2, y, u y and y^2 from the window's start (a leading zero: sums over k .. e are
    # p[:, e + 1] - p[:, k])
    p = np.zeros((6, n + 1))
    np.cumsum(np.stack([np.ones(n), u, u * u, y, u * y, y * y]), axis=1, out=p[:, 1:])
    yy = p[5, first + 1:]
    # corners at the bounds and at the sample times
    cand = np.concatenate([[lower, upper], u[(u > lower) & (u < upper)]])
    g = np.maximum(u[None, :] - cand[:, None], 0.0)
    gy = np.maximum(np.cumsum(g * y, axis=1)[:, first:], 0.0)
    gg = np.cumsum(g * g, axis=1)[:, first:]
    ok = gg > 0
    b = np.where(ok, gy / np.where(ok, gg, 1.0), 0.0)
    sse = yy - b * gy
    ts = np.broadcast_to(cand[:, None], b.shape)
    # corners inside the interval before sample k (k = 0 .. m; before the first, any time from lower on):
    # the line through the samples k .. e
    k = np.arange(0, m + 1)
    left = np.concatenate([[-np.inf], u])[k]
    s0, s1, s2, sy, suy, syy = p[:, None, ends + 1] - p[:, k, None]
    den = s0 * s2 - s1 * s1
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = (s0 * suy - s1 * sy) / den
        alpha = (sy - beta * s1) / s0
        ts_line = -alpha / beta
        sse_line = (yy[None, :] - syy) + (syy - alpha * sy - beta * suy)
    inside = (s0 >= 2) & (den > 0) & (beta > 0) & (ts_line >= lower) & (ts_line <= upper)
    inside &= (ts_line > left[:, None]) & (ts_line < u[np.minimum(k, n - 1), None])
    ts = np.concatenate([ts, np.where(inside, ts_line, 0.0)])
    b = np.concatenate([b, np.where(inside, beta, 0.0)])
    sse = np.concatenate([sse, np.where(inside, sse_line, np.inf)])
    best = np.argmin(sse, axis=0)
    cols = np.arange(ends.size)
    ts, b = ts[best, cols], b[best, cols]
    resid = (y[None, :] - b[:, None] * np.maximum(u[None, :] - ts[:, None], 0.0)) ** 2
    sse = np.cumsum(resid, axis=1)[cols, ends]
    return ts + shift, b, sse


def _edge_zero(xs: np.ndarray, peak_index: int, lo: float, hi: float):
    """Zero crossing of the line through the lowest part of the rising edge between lo and hi.

    Returns (u, fallback): u in samples; fallback True when fewer than two
    samples were in the band and the two samples around the lo crossing were used.
    """
    below = np.flatnonzero(xs[:peak_index] < lo)
    j_lo = int(below[-1]) if below.size else -1
    if j_lo < 0:
        return 0.0, False
    seg = xs[j_lo + 1:peak_index + 1]
    over = np.flatnonzero(seg > hi)
    n_band = int(over[0]) if over.size else seg.size
    u = np.arange(j_lo, j_lo + 1 + max(n_band, 1), dtype=float)
    fallback = n_band < 2
    zero = _line_zero(u[:2], xs[j_lo:j_lo + 2]) if fallback else _line_zero(u[1:], xs[j_lo + 1:j_lo + 1 + n_band])
    if not math.isfinite(zero):
        zero = float(j_lo)
    return min(max(zero, j_lo - max(n_band, 2), 0.0), float(j_lo + 1)), fallback


def _foot_start(xs: np.ndarray, peak_index: int, sigma: float, fs: float, split: bool = True, window=None,
                step=None):
    """Where the force leaves zero before the peak [samples] and whether it jumps there; (None, False) when never zero.

    A jump: the force is at zero on one sample and on the next already higher
    than the rise to the sample after it (the line through the two
    extrapolates to zero before the quiet sample). Then the force left zero
    somewhere between the two samples and nothing in the samples says where:
    the start is the middle of that interval, uncertain by half a sample either
    way (the contact's ``*_jump`` flags). The model's force jumps at 2 mm of
    compression (section 3.2 in Goodwill & Haake 2004), and any steep rise looks
    like a jump at a low sample rate.

    Walks back from the peak to the first sample above FOOT_SIGMA noise
    deviations (i0), then fits the hinge ``b * max(u - ts, 0)`` to a window
    holding FOOT_PRE_S of samples before i0 (so foot samples hidden in the noise
    are still used) and the rising samples from i0 on, for as long as adding
    the next one raises the residual sum of squares by less than
    (FOOT_RESIDUAL_SIGMA sigma)**2, i.e. while the hinge predicts it within
    FOOT_RESIDUAL_SIGMA standard errors (the steep rise after a cloth ramp
    departs from the ramp). Applied to the reversed trace it gives the end.
    A list ``window`` receives the first and last sample of the hinge's fit and the first sample above
    FOOT_SIGMA noise deviations (the hinge's corner is not after it).

    A list ``step`` (the start only: a ball's force may jump up from zero, it
    never drops to zero by a jump in restitution, Eq. (14) in Goodwill &
    Haake 2004) asks for the step the hinge cannot see. The model's force
    steps up from zero at 2 mm of compression (section 3.2.4: no cloth force
    before, kB = kCONST after; about 5-40 % of the peak), and a step at t0
    followed by a ramp puts every sample from i0 on the line through them,
    which meets zero before t0: the hinge's corner ts is early by the step
    over the slope, and its fit is as good for a step at any t0 in [ts, i0]
    as long as the samples between stay at zero. Where the first sample out
    of the noise already holds STEP_FRACTION of the peak (the contact
    threshold's fraction: the force rose from the noise to it within one
    sample; a cloth foot, as ``synth``'s 0.7 % of the peak, or a smooth rise
    sampled at 20 kHz or faster stays below it) and the line predicts the last
    quiet sample within STEP_SIGMA noise deviations of zero (nothing there
    tells a ramp from a step after it), the start is the middle of [ts, i0]
    and ``step`` receives the interval's width [samples] (a uniform's standard
    deviation, width / sqrt(12), goes into the start's uncertainty): where
    the force stepped up, the hinge's own start is early by a third of a
    sample or more on average, its uncertainty far smaller, while the truth
    lies inside [ts, i0] (bench/ideal_plate_map.py measures it).
    """
    return _foot_from_hinge(xs, peak_index, sigma, _foot_hinge(xs, peak_index, sigma, fs, split), window, step)


def _foot_hinge(xs: np.ndarray, peak_index: int, sigma: float, fs: float, split: bool = True):
    """The hinge of :func:`_foot_start`: (ts [samples], i0, its window [wl, wr, i0]); None when never zero."""
    quiet = np.flatnonzero(xs[:peak_index + 1] <= FOOT_SIGMA * sigma)
    if not quiet.size:
        return None
    i0 = int(quiet[-1]) + 1
    w: list = []
    return _hinge_start(xs, peak_index, sigma, fs, i0, split, w), i0, w


def _foot_from_hinge(xs: np.ndarray, peak_index: int, sigma: float, hinge, window=None, step=None):
    """:func:`_foot_start` from its hinge (:func:`_foot_hinge`): the jump and the step judged on it."""
    if hinge is None:
        return None, False
    ts, i0, w = hinge
    if window is not None:
        window[:] = w
    if i0 + 1 <= peak_index and abs(ts - (i0 - 1)) < 0.5:
        jump, rise = xs[i0] - xs[i0 - 1], xs[i0 + 1] - xs[i0]
        if jump - rise > JUMP_SIGMA * math.sqrt(5.0) * sigma:
            return i0 - 0.5, True
    if step is not None and ts < i0 and len(w) == 3 and xs[i0] >= STEP_FRACTION * xs[peak_index]:
        wl, wr = int(w[0]), int(w[1])
        g = np.maximum(np.arange(wl, wr + 1, dtype=float) - ts, 0.0)
        gg = float(g @ g)
        b = float(g @ xs[wl:wr + 1]) / gg if gg > 0 else 0.0
        if b * max(i0 - 1 - ts, 0.0) <= STEP_SIGMA * sigma:
            step.append(float(i0 - ts))
            return 0.5 * (ts + i0), False
    return ts, False


def _hinge_start(xs: np.ndarray, peak_index: int, sigma: float, fs: float, i0: int, split: bool = True,
                 window=None) -> float:
    """The hinge-fit start of :func:`_foot_start` [samples]; i0 is the first sample above FOOT_SIGMA noise;
    ``split``: the start from the hinge's first straight segment where the rise bends (:func:`_first_segment`);
    a list ``window`` receives the first and last sample of the fit that gave it and i0."""
    n_pre = max(FOOT_PRE_SAMPLES, int(math.ceil(FOOT_PRE_S * fs)))
    k_max = max(FOOT_MIN_SAMPLES + 1, int(math.ceil(FOOT_MAX_S * fs)))
    # no foot reaches back to a lone sample above the contact threshold between quiet ones: that is a
    # spike (switching equipment), no force on the ball, and it must not pull the hinge
    # (looked for only as far back as the widest window reaches: one before it holds no window's corner back; the
    # slice starts a sample earlier, so that its first sample is judged with both neighbours)
    reach = max(i0 - n_pre * (1 + FOOT_MAX_WIDENINGS) - 2, 0)
    lone = np.flatnonzero(_lone_samples(xs[reach:max(i0, 0)], sigma))
    floor = reach + int(lone[-1]) + 1 if lone.size else 0
    wl = max(i0 - n_pre, floor)
    last = min(i0 + k_max - 1, peak_index)
    wr = min(i0 + FOOT_MIN_SAMPLES - 1, last)

    def fits_from(left: int):
        # the hinges of every window from left to an end from i0 (or wr, when the window cannot reach i0)
        # to last, fitted at once; index e - min(i0, wr)
        return _hinge_fits(np.arange(left, last + 1, dtype=float), xs[left:last + 1], float(left), float(i0),
                           min(i0, wr) - left)

    fits = fits_from(wl)
    # Slow foot (a gentle rise at low SNR, e.g. an 8 ms half-sine only 50x above the
    # noise takes > FOOT_PRE_S to reach FOOT_SIGMA): the pre window then holds no quiet
    # samples and the corner sticks to its first sample, giving a late start (TC up to
    # 4 % short). Widen the window back, a pre window at a time, until the corner is
    # free of it. A steep rise never sticks, so it is fitted exactly as before.
    n_widen = 0
    while fits[0][wr - min(i0, wr)] < wl + 1.0 and wl > floor and n_widen < FOOT_MAX_WIDENINGS:
        wl = max(wl - n_pre, floor)
        n_widen += 1
        fits = fits_from(wl)
    if last < i0:  # the peak itself is within FOOT_SIGMA noise: nothing rises to grow the window with
        if window is not None:
            window[:] = [wl, wr, i0]
        return float(fits[0][0])
    uw, yw = np.arange(wl, last + 1, dtype=float), xs[wl:last + 1]
    ts, b, sse = (float(v[wr - i0]) for v in fits)
    limit = (FOOT_RESIDUAL_SIGMA * sigma) ** 2
    if wr > i0:
        # Is the second rising sample already on the steep rise after a faint
        # foot? Then the hinge through it misses the sub-threshold foot samples
        # that the hinge through the first rising sample alone explains.
        sse2 = _hinge_sse(uw[:i0 - wl + 1], yw[:i0 - wl + 1], ts, b)
        if sse2 - fits[2][0] > limit:
            if window is not None:
                window[:] = [wl, i0, i0]
            return float(fits[0][0])
    # grow the window while the hinge predicts the next rising sample within FOOT_RESIDUAL_SIGMA
    while wr < last and fits[2][wr + 1 - i0] - sse <= limit:
        wr += 1
        ts, sse = float(fits[0][wr - i0]), float(fits[2][wr - i0])
    if window is not None:
        window[:] = [wl, wr, i0]
    return _first_segment(uw, yw, wl, wr, i0, fits, sigma, window) if split else ts


def _first_segment(uw, yw, wl: int, wr: int, i0: int, fits, sigma: float, window=None) -> float:
    """The hinge's start again from its first straight segment when the rise bends [samples].

    The growth of the hinge window stops at the first sample the hinge predicts
    worse than FOOT_RESIDUAL_SIGMA standard errors, but a rise that flattens
    gradually (read from the end: a low plateau ending in a steep drop) is
    followed sample by sample and the single line through it meets zero after
    the drop's foot. The window is split at every rising sample into the hinge
    before and a free, flatter line after; when the best such split lowers the
    residual sum of squares by more than KINK_SIGMA**2 noise variances, the
    start is that split's hinge. A rise that steepens (a cloth foot, a force
    smoothed by a low-pass) keeps the single line: its foot is what the hinge
    and the spread check were built for.

    ``uw``, ``yw``: sample times [samples] and values from wl on; ``fits``: the
    hinges (ts, b, sse) of the windows from wl to every end from i0 on
    (:func:`_hinge_fits`).
    """
    ts_all, b_all, sse_all = fits
    ts, sse = float(ts_all[wr - i0]), float(sse_all[wr - i0])
    ks = np.arange(i0 + FOOT_MIN_SAMPLES - 1, wr - 1)  # the hinge's last sample; the line takes k+1 .. wr
    if not ks.size:
        return ts
    tail_u, tail_y = uw[ks[0] + 1 - wl:wr + 1 - wl], yw[ks[0] + 1 - wl:wr + 1 - wl]
    on = tail_u[None, :] > ks[:, None]
    count = on.sum(axis=1)
    du = np.where(on, tail_u[None, :] - (on * tail_u).sum(axis=1, keepdims=True) / count[:, None], 0.0)
    dy = np.where(on, tail_y[None, :] - (on * tail_y).sum(axis=1, keepdims=True) / count[:, None], 0.0)
    suu = np.sum(du * du, axis=1)
    slope = np.where(suu > 0, np.sum(du * dy, axis=1) / np.where(suu > 0, suu, 1.0), 0.0)
    sse_k = sse_all[ks - i0] + np.sum((dy - slope[:, None] * du) ** 2, axis=1)
    # the rise flattens after the split (a drop from a low plateau), and the split fits better
    better = (sse_k < sse) & (b_all[ks - i0] > slope)
    if not better.any():
        return ts
    j = int(np.argmin(np.where(better, sse_k, np.inf)))
    if sse - float(sse_k[j]) > (KINK_SIGMA * sigma) ** 2:
        if window is not None:
            window[:] = [wl, int(ks[j]), i0]
        return float(ts_all[ks[j] - i0])
    return ts


def _hinge_sse(u, y, ts, b) -> float:
    return float(np.sum((y - b * np.maximum(u - ts, 0.0)) ** 2))


def _bent_corner(y, window, noise: float, ts_line: float) -> tuple[float, float]:
    """The corner of a bent hinge ``max(u - ts, 0) * (b + c * max(u - ts, 0))``, b > 0, least squares over the
    hinge's window (wl, wr, i0) of y [samples], and its standard uncertainty [samples]; (ts_line, NaN) where it
    cannot be fitted (fewer than 4 samples from i0 to wr, or b <= 0 at every corner).

    Read from the contact's end, the ball's force rises from its corner with a slope that eases (c <= 0; where
    the least squares bend it the other way the straight hinge is taken at that corner): it falls
    faster the nearer it is to its end, as the model's force (Eq. (14) in Goodwill & Haake 2004) does for
    the four balls of Table 2 at 12 and 30 m/s (tests/zoo.py model_force, looked at). A
    straight hinge through such a rise lies above it at the corner and meets zero after the end: TC long by
    +0.2 to +0.6 % of TC on the model's ends at noise of 0.1-0.3 % of the peak, more the more samples the
    noise lets the window take, and more still when fitted again from twice the threshold (the spread check).
    The bent hinge takes the curvature: the corners are profiled on a BENT_STEP grid between wl and i0
    (b and c solved exactly at each, :func:`_bent_sse`), the least refined between its neighbours on finer
    grids (BENT_REFINE_LEVELS of BENT_REFINE_POINTS corners, to 2.5e-6 samples). The bend is taken wherever it
    lowers the least residual sum of squares (BEND_CHI2 = 0); else the straight corner stands. A price for the
    bend (AIC's 2 noise variances, until issue 9's twenty-fourth round) keeps the straight corner exactly where the
    noise hides the bend, and that corner is late: at noise of 0.2-0.3 % of the peak the end was then +0.11 to
    +0.23 samples late on average on a nearly straight fall, its z (error over uncertainty) of mean +0.5 to +0.8
    and RMS up to 1.5; taken always, +0.04 to +0.10 samples, z of mean +0.14 to +0.35 and RMS 1.02-1.13
    (tests/test_contact.py, ``test_end_unbiased_with_an_honest_uncertainty_at_moderate_noise``). The
    uncertainty is :func:`hinge_se`'s rule on this profile: half the width of the corners within CURVE_CHI2 noise
    variances of the least over its root (inf when that reaches wl), or a uniform's over those within one.
    """
    wl, wr, i0 = (int(v) for v in window[:3])
    if not (noise > 0) or wr - i0 < 3:  # a bend is read from 4 rising samples at least
        return ts_line, math.nan
    u = np.arange(wl, wr + 1, dtype=float)
    yw = np.asarray(y[wl:wr + 1], dtype=float)
    grid = np.arange(float(wl), float(min(i0, wr - 3)) + 0.5 * BENT_STEP, BENT_STEP)
    if grid.size < 3:
        return ts_line, math.nan
    sse, straight = _bent_sse(u, yw, grid)
    k = int(np.argmin(sse))
    # the bend must lower the least residual (a few noisy samples bend a parabola as they like, but a price for
    # the bend biases the end late; the uncertainty below, never less than the straight hinge's, judges the bend)
    if not float(sse[k]) < float(np.min(straight)) - BEND_CHI2 * noise * noise:
        return ts_line, math.nan
    # refined between its neighbours: BENT_REFINE_LEVELS finer grids of BENT_REFINE_POINTS, each between the
    # neighbours of the last one's least (to BENT_STEP * (2 / (BENT_REFINE_POINTS - 1))**BENT_REFINE_LEVELS)
    lo, hi = float(grid[max(k - 1, 0)]), float(grid[min(k + 1, grid.size - 1)])
    ts, least = float(grid[k]), float(sse[k])
    for _ in range(BENT_REFINE_LEVELS):
        fine = np.linspace(lo, hi, BENT_REFINE_POINTS)
        fine_sse = _bent_sse(u, yw, fine)[0]
        j = int(np.argmin(fine_sse))
        if fine_sse[j] <= least:
            ts, least = float(fine[j]), float(fine_sse[j])
        lo, hi = float(fine[max(j - 1, 0)]), float(fine[min(j + 1, fine.size - 1)])
    level = float(sse[k]) + CURVE_CHI2 * noise * noise
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0:
        return ts, math.inf
    half = 0.5 * float(grid[inside[-1]] - grid[inside[0]]) / math.sqrt(CURVE_CHI2)
    flat = grid[sse <= float(sse[k]) + noise * noise]
    return ts, max(half, float(flat[-1] - flat[0]) / math.sqrt(12.0))


def _bent_sse(u: np.ndarray, yw: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual sums of squares of the bent hinge (:func:`_bent_corner`) at each corner, b and c solved exactly,
    c <= 0 (else the straight hinge's), and of the straight hinge; inf where b <= 0 or fewer than 3 samples are
    right of the corner."""
    g = np.maximum(u[None, :] - corners[:, None], 0.0)
    g2 = g * g
    s2, s3, s4 = np.sum(g2, axis=1), np.sum(g2 * g, axis=1), np.sum(g2 * g2, axis=1)
    y1, y2 = g @ yw, g2 @ yw
    det = s2 * s4 - s3 * s3
    ok = (np.count_nonzero(g, axis=1) >= 3) & (det > 1e-12 * np.maximum(s2 * s4, 1e-300))
    safe = np.where(ok, det, 1.0)
    b = np.where(ok, (s4 * y1 - s3 * y2) / safe, 0.0)
    c = np.where(ok, (s2 * y2 - s3 * y1) / safe, 0.0)
    yy = float(yw @ yw)
    sse = np.where(ok & (b > 0), yy - b * y1 - c * y2, np.inf)
    # a slope that eases only (c <= 0): a bend the other way is a fade into the end, the straight hinge's (the
    # curve's end and the spread judge it), and with it a tangent corner anywhere left of the rise would fit
    line = np.where(ok & (y1 > 0), yy - np.maximum(y1, 0.0) ** 2 / np.where(s2 > 0, s2, 1.0), np.inf)
    return np.where(c > 0, line, sse), line


def hinge_se(y, ts: float, window, jump: bool) -> float:
    """Standard uncertainty [samples] of the corner ts of the hinge ``b * max(u - ts, 0)`` fitted to y[wl:wr + 1]
    (``window`` = (wl, wr, i0, noise), y read from the end concerned): the half-width of the corners between wl and
    i0 (the first sample above FOOT_SIGMA noise deviations holds force: no corner after it, as in the fit) whose
    residual sum of squares, b fitted again (b >= 0), is within CURVE_CHI2 noise variances of the least, over its
    root, or a uniform's over those within one noise variance where larger (a residual flat across them); inf when
    that reaches wl (the quiet samples do not bound it), half a sample at a jump, NaN without a
    window."""
    if jump:
        return 0.5
    if window is None:
        return math.nan
    wl, wr, i0, noise = window
    if wr - wl < 2 or i0 - wl < 1 or not noise > 0:
        return math.nan
    u = np.arange(wl, wr + 1, dtype=float)
    yw = np.asarray(y[wl:wr + 1], dtype=float)
    grid = np.arange(float(wl), float(min(i0, wr)) + 0.5 * HINGE_SE_STEP, HINGE_SE_STEP)
    g = np.maximum(u[None, :] - grid[:, None], 0.0)
    gy, gg = np.maximum(g @ yw, 0.0), np.sum(g * g, axis=1)
    sse = float(yw @ yw) - np.where(gg > 0, gy * gy / np.where(gg > 0, gg, 1.0), 0.0)
    level = float(np.min(sse)) + CURVE_CHI2 * noise * noise
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0:
        return math.inf
    i, j = int(inside[0]), int(inside[-1])
    lo = grid[i] - HINGE_SE_STEP * float(level - sse[i]) / float(sse[i - 1] - sse[i])
    hi = grid[j] if j == grid.size - 1 else grid[j] + HINGE_SE_STEP * float(level - sse[j]) / float(
        sse[j + 1] - sse[j])
    # at least a uniform's over the corners within one noise variance: a residual flat across them (a corner
    # anywhere between two samples)
    flat = grid[sse <= float(np.min(sse)) + noise * noise]
    return max(0.5 * float(hi - lo) / math.sqrt(CURVE_CHI2), float(flat[-1] - flat[0]) / math.sqrt(12.0))


def _lone_samples(xs, sigma: float, threshold: float | None = None) -> np.ndarray:
    """Samples above the contact threshold (default THRESHOLD_SIGMA noise) whose two neighbours are quiet (FOOT_SIGMA).

    A force on the ball cannot rise from zero and fall back to it within two
    sample intervals at any sample rate of raw-format v1.1: such a sample is a
    spike, not a foot or a tail.
    """
    xs = np.asarray(xs, dtype=float)
    loud = THRESHOLD_SIGMA * sigma if threshold is None else threshold
    out = np.zeros(xs.size, dtype=bool)
    if xs.size >= 3:
        quiet = xs <= FOOT_SIGMA * sigma
        out[1:-1] = (xs[1:-1] > loud) & quiet[:-2] & quiet[2:]
    return out


def unbroken_run(xs, peak_index: int, sigma: float, thr: float, run_a: int, run_b: int) -> tuple[int, int]:
    """The run [run_a, run_b] above thr (merged across short gaps) without the lone samples at its ends (spikes)."""
    lone = _lone_samples(xs, sigma, thr)
    above = xs > thr
    while run_a < peak_index and lone[run_a]:
        run_a += int(np.flatnonzero(above[run_a + 1:peak_index + 1])[0]) + 1  # the peak is above: found
    while run_b > peak_index and lone[run_b]:
        run_b = peak_index + int(np.flatnonzero(above[peak_index:run_b])[-1])
    return run_a, run_b


@dataclass(frozen=True)
class _Hinges:
    """What :func:`contact_ends` finds that no option changes: the edges, the start's hinge before the step is
    judged, and the end's hinge (see there)."""

    start_hinge: tuple | None  # :func:`_foot_hinge` of the start
    u_edge_start: float
    u_edge_end: float
    edge_fallback: bool
    u_end: float | None  # on the reversed trace [samples]; None when the force never returns to zero
    jump_end: bool
    w_end: list
    sigma_end: float
    ringing: bool
    end_se: float
    u_line: float | None  # the straight hinge's end, on the reversed trace [samples]


def find_hinges(xs, peak_index, peak, sigma, fs) -> _Hinges:
    """The steep edges' zero crossings, the start's hinge and the end's (straight, then bent) of
    :func:`contact_ends`."""
    n = xs.size
    lo = max(EDGE_BAND[0] * peak, min(FOOT_SIGMA * sigma, 0.5 * EDGE_BAND[1] * peak))
    hi = EDGE_BAND[1] * peak
    rev = xs[::-1]
    # steep edges: line through the lowest part of each edge, extrapolated to zero
    u_edge_start, fallback_start = _edge_zero(xs, peak_index, lo, hi)
    u_edge_end, fallback_end = _edge_zero(rev, n - 1 - peak_index, lo, hi)
    u_edge_end = n - 1 - u_edge_end
    # foot: the hinge fit where the force returns to zero
    w_end: list = []
    u_end, jump_end = _foot_start(rev, n - 1 - peak_index, sigma, fs, window=w_end)
    sigma_end = sigma
    ringing = False
    if u_end is not None:
        # Plate ringing that outlasts the contact would pass for force: measure
        # the disturbance just after the end and, when it is well above the
        # noise, find the end again with it as the noise level.
        a = int(math.ceil(n - 1 - u_end + RING_GAP_S * fs))
        b = min(a + int(round(RING_WINDOW_S * fs)), n)
        if b - a >= MIN_NOISE_SAMPLES:
            ring = float(np.sqrt(np.mean(xs[a:b] ** 2)))
            if ring > RING_SIGMA * sigma:
                ringing = True
                w_ring: list = []
                u_ring, jump_ring = _foot_start(rev, n - 1 - peak_index, ring, fs, window=w_ring)
                if u_ring is not None:
                    u_end, jump_end, w_end, sigma_end = u_ring, jump_ring, w_ring, ring
    end_se, u_line = math.nan, u_end
    if u_end is not None and not jump_end and len(w_end) == 3:
        u_end, end_se = _bent_corner(rev, w_end, sigma_end, u_end)
    return _Hinges(_foot_hinge(xs, peak_index, sigma, fs), u_edge_start, u_edge_end, fallback_start or fallback_end,
                   u_end, jump_end, w_end, sigma_end, ringing, end_se, u_line)


def contact_ends(xs, peak_index, sigma, fs, hinges: _Hinges, flags, windows, step=False):
    """Start and end of the contact and of its steep edges [samples] from the trace's :func:`find_hinges` (the same
    trace, peak and noise), adding the flags of what was seen; the dict ``windows`` receives, for "start" and "end",
    the first and last sample of each hinge's fit (on the trace read from that end), the first sample above
    FOOT_SIGMA noise deviations and the noise it was fitted with."""
    n = xs.size
    if hinges.edge_fallback:
        flags.append("edge_fallback")
    if hinges.ringing:
        flags.append("ringing_after_contact")
    # foot: the hinge fit where the force leaves zero
    w_start, step_start = [], []
    u_start, jump_start = _foot_from_hinge(xs, peak_index, sigma, hinges.start_hinge, window=w_start,
                                           step=step_start if step else None)
    u_end, jump_end, u_line = hinges.u_end, hinges.jump_end, hinges.u_line
    windows.update(start=(*w_start, sigma) if len(w_start) == 3 else None,
                   end=(*hinges.w_end, hinges.sigma_end) if len(hinges.w_end) == 3 else None,
                   start_step=step_start[0] if step_start and u_start is not None else 0.0, end_se=hinges.end_se,
                   line_end=n - 1 - u_line if u_line is not None else math.nan)
    if step_start and u_start is not None:
        flags.append("start_step")
    if jump_start and u_start is not None:
        flags.append("start_jump")
    if jump_end and u_end is not None:
        flags.append("end_jump")
    if u_start is None:
        flags.append("contact_at_trace_start")
        u_start = 0.0
    elif u_start < hinges.u_edge_start - 1.0:
        flags.append("cloth_foot")
    if u_end is None:
        flags.append("contact_at_trace_end")
        u_end = float(n - 1)
    else:
        u_end = n - 1 - u_end
        if u_end > hinges.u_edge_end + 1.0:
            flags.append("end_tail")
    return u_start, u_end, hinges.u_edge_start, hinges.u_edge_end


def end_spreads(xs, peak_index, sigma, fs, u_start, u_end, step=False) -> tuple[float, float]:
    """How far each end moves when fitted from the samples above SPREAD_FACTOR times the thresholds [s]."""
    n = xs.size
    spreads = [math.nan, math.nan]
    # one line through each foot, never split where it bends: the spread then also measures how far the end
    # depends on the model of the foot (a bent tail may be the plate's lag, not the ball's force)
    u2, _ = _foot_start(xs, peak_index, SPREAD_FACTOR * sigma, fs, split=False, step=[] if step else None)
    e2, _ = _foot_start(xs[::-1], n - 1 - peak_index, SPREAD_FACTOR * sigma, fs, split=False)
    if u2 is not None:
        spreads[0] = (u2 - u_start) / fs
    if e2 is not None:
        spreads[1] = (n - 1 - e2 - u_end) / fs
    return spreads[0], spreads[1]
