"""The contact's front fitted through a second-order response: an ideal or a ringing plate, or a low-pass."""

from __future__ import annotations

import itertools
import math
from typing import NamedTuple

import numpy as np

from .._checks import finite_samples, positive_scalar

__all__ = ["FrontFit", "front_responses", "steady_responses", "fit_front"]

FRONT_RISE_MAX = 4.0  # the force's jump rises over at most this many samples (the model's 10 us step) [samples]
FRONT_START_SPAN = 3.0  # the force's start is looked for up to this many samples before the contact's first [samples]
FRONT_MAX_FREQUENCY = 0.45  # resonances fitted up to this fraction of the sample rate [-]
FRONT_GRID_FREQUENCIES = 16  # the starting grid: this many resonances, log-spaced ... [-]
FRONT_GRID_DAMPING = (0.03, 0.1, 0.2, 0.35)  # ... each with these damping ratios [-]
FRONT_MAX_EVALUATIONS = 60  # least-squares evaluations from the grid's best at most [-]
FRONT_DROP_MAX_DAMPING = 0.4  # with the drop at buckling, damping ratios fitted up to this [-]


class FrontFit(NamedTuple):
    """A contact's front fitted by :func:`fit_front`: a jump, a ramp and a parabola, through a plate or an ideal one."""

    frequency_hz: float  #: the plate's resonance [Hz] (inf: an ideal plate)
    damping_ratio: float  #: its damping ratio [-]
    start: float  #: where the force starts [samples, fractional index]
    rise: float  #: the samples over which its jump rises [samples]
    jump: float  #: the jump [unit of the force]
    slope: float  #: the ramp's slope after the start [unit of the force per sample]
    curvature: float  #: the parabola's coefficient [unit of the force per sample^2]
    rss: float  #: residual sum of squares over the window [unit of the force^2]
    n_samples: int  #: samples in the window [-]
    drop_start: float = math.inf  #: where a second jump (the drop at buckling) starts [samples] (inf: none fitted)
    drop: float = 0.0  #: that jump, rising over ``rise`` too (negative: a drop) [unit of the force]
    drop_slope: float = 0.0  #: the change of the ramp's slope from it [unit of the force per sample]
    drop_curvature: float = 0.0  #: ... and of the parabola's coefficient [unit of the force per sample^2]
    spike_index: int = -1  #: the sample a single-sample electrical spike was fitted on (-1: none) [-]
    spike: float = 0.0  #: that spike, added to the sensed force (not through the plate) [unit of the force]
    cubic: float = 0.0  #: a cubic's coefficient from the start (0 with a drop) [unit of the force per sample^3]
    drop_cubic: float = 0.0  #: ... and its change at the drop [unit of the force per sample^3]

    def force(self, index) -> np.ndarray:
        """The fitted applied force (not the sensed one) at fractional sample indices [unit of the force]."""
        def jump(u):
            ramp = np.clip(u / self.rise, 0.0, 1.0) if self.rise > 0 else (u >= 0).astype(float)
            return np.where(u >= 0, ramp, 0.0)

        u = np.asarray(index, dtype=float) - self.start
        out = np.where(u >= 0, self.jump * jump(u) + u * (self.slope + u * (self.curvature + u * self.cubic)), 0.0)
        if math.isfinite(self.drop_start):
            v = np.asarray(index, dtype=float) - self.drop_start
            out = out + self.drop * jump(v) + np.where(
                v >= 0, v * (self.drop_slope + v * (self.drop_curvature + v * self.drop_cubic)), 0.0)
        return out


def steady_responses(u, wn: float, zeta: float) -> tuple:
    """The plate's steady responses to the ramp u and the parabola u^2 applied for all u.

    For the continuous second-order plate of unit static gain: ``u - c`` with c = 2 zeta / wn, and
    ``u^2 + p1 u + p0`` with p1 = -4 zeta / wn and p0 = 2 (4 zeta^2 - 1) / wn^2 (the polynomials that solve the
    plate's equation; :func:`front_responses` is them less the oscillation that starts each at rest).

    Parameters
    ----------
    u : array_like
        Time [samples].
    wn : float
        The resonance's angular frequency [rad per sample], finite.
    zeta : float
        Its damping ratio [-].

    Returns
    -------
    tuple of numpy.ndarray
        The ramp's and the parabola's steady responses [samples, samples^2].
    """
    u = np.asarray(u, dtype=float)
    p0, p1 = 2.0 * (4.0 * zeta * zeta - 1.0) / (wn * wn), -4.0 * zeta / wn
    return u - 2.0 * zeta / wn, u * u + p1 * u + p0


def front_responses(u, wn, zeta, rise, *, cubic: bool = False):
    """The plate's response to a jump rising linearly over ``rise`` samples, a ramp and a parabola from u = 0.

    Analytic (the continuous second-order plate of unit static gain sampled
    at u): the step response ``1 - exp(-zeta wn u) (cos wd u + zeta wn / wd
    sin wd u)``, the ramp response ``u - c + exp(-zeta wn u) (c cos wd u + d
    sin wd u)`` (c = 2 zeta / wn, d = (2 zeta^2 - 1) / wd) and the
    parabola's; the jump rising over ``rise`` samples is the difference of
    two ramp responses over ``rise``. ``wn = inf`` is an ideal plate (the
    force itself). With ``cubic``, also the response to u^3: ``u^3 + A u^2 +
    B u + C - exp(-zeta wn u) (C cos wd u + (zeta wn C + B) / wd sin wd u)``
    with A = -6 zeta / wn, B = (24 zeta^2 - 6) / wn^2 and C = 24 zeta (1 -
    2 zeta^2) / wn^3 (the polynomial solves the plate's equation, the
    oscillation starts it at rest).

    Parameters
    ----------
    u : array_like
        Time since the force's start [samples], any shape (broadcast with the others).
    wn : array_like
        The resonance's angular frequency [rad per sample] (inf: no resonance).
    zeta : array_like
        Its damping ratio, 0 to 1 [-].
    rise : array_like
        The samples over which the jump rises [samples], >= 0 (0: a step).
    cubic : bool
        Also return the response to the cubic u^3.

    Returns
    -------
    numpy.ndarray
        Shape ``broadcast(...) + (3,)`` (``(4,)`` with ``cubic``): the
        responses to the unit jump, the unit ramp u, the parabola u^2 [-,
        samples, samples^2] (and the cubic u^3 [samples^3]), zero before u = 0.
    """
    u, wn, zeta, rise = (np.asarray(v, dtype=float) for v in (u, wn, zeta, rise))
    shape = np.broadcast_shapes(u.shape, wn.shape, zeta.shape, rise.shape)
    ideal = ~np.isfinite(wn)
    all_ideal, any_ideal = bool(np.all(ideal)), bool(np.any(ideal))
    if not all_ideal:  # the plate's constants, once per resonance (not per sample)
        w = np.where(ideal, 1.0, wn)
        z = np.where(ideal, 0.5, zeta)
        sigma, wd = z * w, w * np.sqrt(np.maximum(1.0 - z * z, 1e-12))
        c, d = 2.0 * z / w, (2.0 * z * z - 1.0) / wd
        p0, p1 = 2.0 * (4.0 * z * z - 1.0) / (w * w), -4.0 * z / w
        qb = (-sigma * p0 - p1) / wd
        c2, c1, c0 = -6.0 * z / w, (24.0 * z * z - 6.0) / (w * w), 24.0 * z * (1.0 - 2.0 * z * z) / w ** 3
        cb = (sigma * c0 + c1) / wd

    def responses(v, all_three=True):  # (step, ramp, parabola) responses at v, or the ramp's alone
        v = np.broadcast_to(v, shape)
        on = v >= 0
        t = np.where(on, v, 0.0)
        if all_ideal:
            ramp = t
        else:
            decay = np.exp(-sigma * t)
            cos, sin = np.cos(wd * t), np.sin(wd * t)
            ramp = np.where(ideal, t, t - c + decay * (c * cos + d * sin)) if any_ideal else \
                t - c + decay * (c * cos + d * sin)
        ramp = np.where(on, ramp, 0.0)
        if not all_three:
            return ramp
        if all_ideal:
            step, par = np.ones(shape), t * t
        else:
            step = 1.0 - decay * (cos + sigma / wd * sin)
            par = t * t + p1 * t + p0 + decay * (-p0 * cos + qb * sin)
            if any_ideal:
                step, par = np.where(ideal, 1.0, step), np.where(ideal, t * t, par)
        if not cubic:
            return np.where(on, step, 0.0), ramp, np.where(on, par, 0.0)
        if all_ideal:
            cub = t ** 3
        else:
            cub = t * (t * (t + c2) + c1) + c0 - decay * (c0 * cos + cb * sin)
            if any_ideal:
                cub = np.where(ideal, t ** 3, cub)
        return np.where(on, step, 0.0), ramp, np.where(on, par, 0.0), np.where(on, cub, 0.0)

    step, ramp, *higher = responses(u)
    spread = np.broadcast_to(rise > 1e-9, shape)
    jump = np.where(spread, (ramp - responses(u - rise, all_three=False)) / np.where(spread, rise, 1.0), step)
    return np.stack([jump, ramp, *higher], axis=-1)


def fit_front(force, sample_rate_hz: float, first: int, last: int, start: float, *, resonance: bool = True,
              drop: bool = False, rise_max: float = FRONT_RISE_MAX, refine: bool = True, spike=None,
              damping=None, drop_within=None, cubic: bool = False):
    """The front of a contact (a jump from zero, a ramp, a parabola) through a plate fitted to its samples.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake
    2004: the cloth carries no load below 2 mm of compression, kB = kCONST
    for the first 0.2 ms, Eq. (14) F = kB x + (cB + cM) x') the force jumps
    from zero and then rises smoothly to the spike: ``J r(t - ts) + b (t -
    ts) + q (t - ts)^2`` with r a rise from 0 to 1 over a few microseconds.
    A plate of resonance fn and damping zeta answers the jump with a rise
    over part of its period, an overshoot and a damped oscillation. The
    samples ``first .. last`` are fitted with that force through the plate
    (:func:`front_responses`; J, b, q linear, fn, zeta, ts and the rise by
    nonlinear least squares from a grid) or, with ``resonance=False``,
    through an ideal plate. Comparing the two says whether the samples need
    the plate's ringing, and the fit says how far the ringing lifts a sample
    above the force. Not in the paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        The sensed force (any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    first, last : int
        The window's first and last sample [-] (a few before the start, up to the peak).
    start : float
        The contact start found [samples, fractional index]: the force's start
        is looked for from FRONT_START_SPAN samples before its first sample
        to that sample.
    resonance : bool
        Fit through a plate (fn up to FRONT_MAX_FREQUENCY of the sample
        rate, and down to one period over the window) or an ideal one.
    drop : bool
        Also fit a second jump (rising over the same samples) and a change
        of the ramp's slope and of the parabola from anywhere in the window
        after the force's first sample: the model's drop at buckling
        (section 3.2.4: kB falls from kCONST to Eq. (4) 0.2 ms after first
        contact), for a window that runs on past the pre-buckling spike;
        the jump and the ramp before it then rise (>= 0) and the drop
        falls (<= 0), as the model's force does.
    rise_max : float
        The most samples the jumps may rise over [samples] (FRONT_RISE_MAX:
        the model's 10 us step at up to 400 kHz).
    refine : bool
        Refine the starting grid's best fit by least squares; False returns
        the grid's best (a residual no smaller than the refined one's; fast).
    spike : sequence of int, optional
        Samples (inside the window) where a single-sample electrical spike
        may be: the fit also takes a free value added to one of them (not
        through the plate: the spike is the amplifier's, after the plate):
        each candidate is fitted from the fit without a spike and from the
        starting grid's best with it, and the least residual of all is the
        fit (``spike_index``, ``spike``; about twice as many fits as
        candidates: with a free spike, spurious fits at a bound of the grid
        beat its rows near the true plate, and the fit from them stays
        there). A spike on the plate's ringing, which
        :func:`ballimpact.signal.spikes.remove_spikes` cannot tell from the
        ringing's own swings, otherwise raises the residual of the fit
        through the plate as much as the ideal one's.
    damping : (float, float), optional
        The damping ratios the plate's may take, (lowest, highest) within 0
        to 1 [-]; by default 0.005 to 0.9 (FRONT_DROP_MAX_DAMPING with ``drop``).
    drop_within : float, optional
        With ``drop``, the drop is looked for up to this many samples after the
        force's first sample [samples]; by default anywhere in the window.
    cubic : bool
        Also fit a cubic from the start (with ``drop``, a cubic from the drop,
        as the parabola): a force that starts smoothly (a half-sine's foot)
        curves more over a long window than a parabola can follow.

    Returns
    -------
    FrontFit or None
        The fit; None when the window holds fewer than 8 samples, leaves the
        record, or no resonance fits between one period over the window and
        FRONT_MAX_FREQUENCY of fs. With ``drop``, its ``drop_*`` fields hold
        the drop and the changes after it (``curvature`` is 0: no parabola
        before the drop).
        With ``spike``, ``spike_index`` and ``spike`` hold the spike's sample
        and value (-1 and 0 when no candidate is inside the window).

    Raises
    ------
    ValueError
        For a non-positive sample rate, a non-finite start, a negative or
        non-finite rise_max, or non-finite samples.
    """
    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    zeta_grid, zeta_lo, zeta_hi = _checked_front_arguments(start, rise_max, damping, drop, drop_within)
    x = finite_samples("force", force)
    first, last = int(first), int(last)
    if first < 0 or last >= x.size or last - first + 1 < 8:
        return None
    y = x[first:last + 1]
    k0 = float(math.ceil(start))
    t_lo, t_hi = k0 - FRONT_START_SPAN, k0
    drop_last = float(last) if drop_within is None else min(float(last), k0 + float(drop_within))
    w_hi = 2.0 * math.pi * FRONT_MAX_FREQUENCY
    w_lo = 2.0 * math.pi / max(last - start + 1.0, 1.0)  # at least one period over the window
    if resonance and w_lo >= w_hi:
        return None
    grid = _front_grid(resonance, w_lo, w_hi, zeta_grid, k0, t_lo, t_hi, rise_max, drop, drop_last)
    if grid.size == 0:
        return None
    candidates = sorted({int(k) - first for k in (spike or ()) if first <= int(k) <= last})
    if spike is not None and not candidates:  # no candidate inside the window: the fit without a spike
        return fit_front(x, fs, first, last, start, resonance=resonance, drop=drop, rise_max=rise_max, refine=refine,
                         damping=damping, drop_within=drop_within, cubic=cubic)
    # the free parameters: (wn, zeta, ts, rise) through a plate, (ts, rise) through an ideal one
    if resonance:
        lo, hi = np.array([0.8 * w_lo, zeta_lo, t_lo, 0.0]), np.array([w_hi, zeta_hi, t_hi, rise_max])
    else:
        lo, hi = np.array([t_lo, 0.0]), np.array([t_hi, rise_max])
    if drop:
        lo, hi = np.append(lo, k0), np.append(hi, drop_last)
    problem = _FrontProblem(y, np.arange(first, last + 1, dtype=float), drop, cubic, resonance, lo, hi, refine)
    if not candidates:
        p, solved = problem.fitted(grid[int(np.argmin(problem.solve(problem.design_of(grid))[0]))])
        return _front_fit(p, solved, drop, fs, y.size, cubic=cubic)
    # a free spike makes spurious fits on the grid (at a bound) beat the grid's rows near the true plate: each
    # candidate is also fitted from the fit without a spike, and the least residual of all is the fit
    plain = fit_front(x, fs, first, last, start, resonance=resonance, drop=drop, rise_max=rise_max, refine=refine,
                      damping=damping, drop_within=drop_within, cubic=cubic)
    if plain is None:
        return None
    starts = [np.array([2.0 * math.pi * plain.frequency_hz / fs, plain.damping_ratio, plain.start, plain.rise]
                       + ([plain.drop_start] if drop else []))]
    best = None
    for unit in np.eye(y.size)[candidates]:
        problem.spike_col = unit
        for p0 in starts + [grid[int(np.argmin(problem.solve(problem.design_of(grid))[0]))]]:
            p, solved = problem.fitted(p0)
            if best is None or solved[0][0] < best[0]:
                best = (float(solved[0][0]), p, solved, unit)
    return _front_fit(best[1], best[2], drop, fs, y.size, first, best[3], cubic=cubic)


def _checked_front_arguments(start, rise_max, damping, drop, drop_within):
    """The arguments of :func:`fit_front` checked (ValueError naming the bad one); the damping ratios of the
    starting grid and the lowest and highest fitted [-]."""
    if not math.isfinite(start):
        raise ValueError(f"start must be finite, got {start!r}")
    if not (rise_max >= 0 and math.isfinite(rise_max)):
        raise ValueError(f"rise_max must be finite and non-negative, got {rise_max!r}")
    if damping is None:
        zeta_grid, zeta_lo, zeta_hi = FRONT_GRID_DAMPING, 0.005, FRONT_DROP_MAX_DAMPING if drop else 0.9
    else:
        zeta_lo, zeta_hi = (float(v) for v in damping)
        if not 0.0 < zeta_lo < zeta_hi < 1.0:
            raise ValueError(f"damping must be (lowest, highest) with 0 < lowest < highest < 1, got {damping!r}")
        zeta_grid = tuple(np.geomspace(zeta_lo, zeta_hi, 4))
    if drop_within is not None and not (drop_within > 0 and math.isfinite(drop_within)):
        raise ValueError(f"drop_within must be positive and finite, got {drop_within!r}")
    return zeta_grid, zeta_lo, zeta_hi


def _front_grid(resonance, w_lo, w_hi, zeta_grid, k0, t_lo, t_hi, rise_max, drop, drop_last):
    """The starting grid of :func:`fit_front`: rows of (wn [rad/sample], zeta [-], ts [samples], rise [samples]
    [, the drop's start tb [samples]])."""
    if resonance:
        g = np.meshgrid(np.geomspace(w_lo, w_hi, FRONT_GRID_FREQUENCIES), zeta_grid,
                        (k0 - 2.0, k0 - 1.0), (0.5, 1.5), indexing="ij")
        grid = np.stack([v.ravel() for v in g], axis=1)  # wn, zeta, ts, rise
    else:
        # through an ideal plate a sample sees the jump's rise only where it falls: a fine grid, no local minimum
        g = np.meshgrid(np.arange(t_lo, t_hi + 1e-9, 0.125), np.arange(0.0, rise_max + 1e-9, 0.25),
                        indexing="ij")
        grid = np.stack([np.full(g[0].size, np.inf), np.zeros(g[0].size), g[0].ravel(), g[1].ravel()], axis=1)
    if drop:  # the drop's start on every half sample after the force's first contact sample
        tb = np.arange(k0 + 0.5, drop_last, 0.5)
        grid = np.column_stack([np.repeat(grid, tb.size, axis=0), np.tile(tb, grid.shape[0])])
    return grid


class _FrontProblem:
    """The least squares of :func:`fit_front` on the window's samples ``y`` at sample indices ``n``: the linear
    coefficients (J, b, q and the drop's) for given responses, and the free parameters between ``lo`` and ``hi``
    ((wn, zeta, ts, rise[, tb]) through a plate, (ts, rise[, tb]) through an ideal one) refined from a start."""

    def __init__(self, y, n, drop, cubic, resonance, lo, hi, refine):
        self.y, self.n, self.drop, self.cubic, self.resonance = y, n, drop, cubic, resonance
        self.lo, self.hi, self.refine = lo, hi, refine
        self.free = slice(None) if resonance else slice(2, None)
        self.spike_col = None  # the spike's column (a unit at its sample), once chosen

    def full(self, q):
        """Rows of (wn, zeta, ts, rise[, tb]) from rows of the free parameters (an ideal plate: wn inf, zeta 0)."""
        if self.resonance:
            return np.atleast_2d(q)
        q = np.atleast_2d(q)
        return np.column_stack([np.full(q.shape[0], np.inf), np.zeros(q.shape[0]), q])

    def unconstrained(self, design):
        """Least squares of J, b, q (and the drop's) for each design [..., n, 3 or 5]: (rss, coef, resid)."""
        y = self.y
        gram = np.swapaxes(design, -1, -2) @ design
        rhs = np.swapaxes(design, -1, -2) @ y
        ridge = 1e-12 * (np.trace(gram, axis1=-2, axis2=-1)[..., None, None] + 1e-300) * np.eye(design.shape[-1])
        coef = np.linalg.solve(gram + ridge, rhs[..., None])[..., 0]
        resid = y - (design @ coef[..., None])[..., 0]
        return np.sum(resid * resid, axis=-1), coef, resid

    def solve(self, design):
        """(rss, coef, resid); with the drop, J >= 0, b >= 0 and the drop <= 0."""
        if not self.drop:
            return self.unconstrained(design)
        y = self.y
        gram = np.swapaxes(design, -1, -2) @ design
        rhs = (np.swapaxes(design, -1, -2) @ y)[..., None]
        m = design.shape[-1]  # 5, or 6 with a spike's column
        ridge = 1e-12 * (np.trace(gram, axis1=-2, axis2=-1)[..., None, None] + 1e-300) * np.eye(m)
        best_rss, best_coef = None, None
        for off in itertools.product((False, True), repeat=3):  # each sign-constrained column free or held at 0
            keep = np.array([not off[0], not off[1], not off[2]] + [True] * (m - 3), dtype=float)
            coef = np.linalg.solve(gram * np.outer(keep, keep) + ridge, rhs * keep[:, None])[..., 0]
            rss = float(y @ y) - 2.0 * np.sum(coef * rhs[..., 0], axis=-1) \
                + np.einsum("...i,...ij,...j->...", coef, gram, coef)
            sign = coef[..., :3] * np.array([1.0, 1.0, -1.0])
            rss = np.where(np.all(sign >= -1e-12 * (1.0 + np.abs(coef[..., :3])), axis=-1), rss, np.inf)
            if best_rss is None:
                best_rss, best_coef = rss, coef
            else:
                better = rss < best_rss
                best_rss, best_coef = np.where(better, rss, best_rss), np.where(better[..., None], coef, best_coef)
        resid = y - (design @ best_coef[..., None])[..., 0]
        return np.sum(resid * resid, axis=-1), best_coef, resid

    def design_of(self, rows):
        """The responses of each row of (wn, zeta, ts, rise[, tb]) [rows, n, 3 or 5, +1 with a spike]."""
        n, drop, cubic = self.n, self.drop, self.cubic
        cols = front_responses(n[None, :] - rows[:, 2:3], rows[:, 0:1], rows[:, 1:2], rows[:, 3:4],
                               cubic=cubic and not drop)
        if drop:
            later = front_responses(n[None, :] - rows[:, 4:5], rows[:, 0:1], rows[:, 1:2], rows[:, 3:4], cubic=cubic)
            # no parabola before the drop, and the ramp up to it rises by at most the jump: J = a + b L, a, b >= 0
            span = np.maximum(rows[:, 4:5] - rows[:, 2:3], 0.0)[..., None]  # L, from the start to the drop [samples]
            cols = np.concatenate([cols[..., :1], cols[..., 1:2] + span * cols[..., :1], later], axis=-1)
        if self.spike_col is None:
            return cols
        return np.concatenate([cols, np.broadcast_to(self.spike_col, cols.shape[:-1])[..., None]], axis=-1)

    def residuals(self, rows):
        """The residuals of each row of free parameters, all at once [rows, n]."""
        return self.solve(self.design_of(self.full(rows)))[2]

    def jacobian(self, q, *_):
        """Forward differences (backward at an upper bound), in one batch."""
        step = 1e-6 * np.maximum(np.abs(q), 1e-2) * np.where(q < self.hi - 1e-9, 1.0, -1.0)
        r = self.residuals(np.vstack([q, q + np.diag(step)]))
        return ((r[1:] - r[0]) / step[:, None]).T

    def fitted(self, p0):
        """The parameters from p0 (refined when asked) and their linear least squares."""
        from scipy.optimize import least_squares

        if self.refine:
            q = least_squares(lambda v: self.residuals(v)[0], np.clip(p0[self.free], self.lo, self.hi),
                              jac=self.jacobian, bounds=(self.lo, self.hi), x_scale="jac",
                              max_nfev=FRONT_MAX_EVALUATIONS).x
            p0 = self.full(q)[0]
        return p0, self.solve(self.design_of(p0[None, :]))


def _front_fit(p, solved, drop: bool, fs: float, n: int, first: int = 0, spike_col=None, *,
               cubic: bool = False) -> FrontFit:
    """The FrontFit of parameters p (wn, zeta, ts, rise[, tb]) and their linear least squares (rss, coef, resid);
    with ``spike_col`` (the spike's unit column, the window's first sample ``first``), the spike's sample and value
    from the last coefficient; with ``cubic``, the cubic's from the one before."""
    rss, coef = float(solved[0][0]), solved[1][0]
    spiked = ()
    if spike_col is not None:
        spiked, coef = (first + int(np.argmax(spike_col)), float(coef[-1])), coef[:-1]
    cubed = {}
    if cubic:
        cubed, coef = {"drop_cubic" if drop else "cubic": float(coef[-1])}, coef[:-1]
    if drop:  # (J - b L, b, D, the slope's and the parabola's change at the drop): no parabola before it
        span = max(float(p[4] - p[2]), 0.0)
        coef, extra = (np.array([coef[0] + coef[1] * span, coef[1], 0.0]),
                       (float(p[4]), float(coef[2]), float(coef[3]), float(coef[4])))
    else:
        extra = ()
    fit = FrontFit(float(p[0] * fs / (2.0 * math.pi)), float(p[1]), float(p[2]), float(p[3]), float(coef[0]),
                   float(coef[1]), float(coef[2]), float(rss), int(n), *extra, **cubed)
    return fit._replace(spike_index=spiked[0], spike=spiked[1]) if spiked else fit
