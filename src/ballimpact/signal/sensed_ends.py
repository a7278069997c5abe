"""A contact's ends fitted in the sensed force through a known plate, where the noise is white."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._checks import finite_samples, positive_scalar
from .front import front_responses, steady_responses

__all__ = ["SENSED_INSIDE_FRACTION", "SENSED_INSIDE_SHORT", "SENSED_MIN_INSIDE", "SENSED_OUTSIDE_PERIODS",
           "SENSED_START_PERIODS", "SENSED_MIN_START", "SENSED_START_TERMS", "SENSED_BEFORE", "SENSED_REACH_PERIODS",
           "SENSED_MAX_RESIDUAL", "SENSED_MAX_START_RESIDUAL", "SENSED_MAX_MOVE", "SENSED_MIN_JUMP",
           "SENSED_FN_UNCERTAINTY", "SENSED_ZETA_UNCERTAINTY", "SensedEnd", "SensedContact", "sensed_end",
           "sensed_contact"]

#: Each end's window reaches this fraction of TC into the contact ... [-]
SENSED_INSIDE_FRACTION = 0.10
#: ... and is fitted again reaching this fraction: how far the end moves is the force's shape the line and the
#: parabola miss, charged to TC [-]
SENSED_INSIDE_SHORT = 0.05
#: ... both at least this many samples [samples]
SENSED_MIN_INSIDE = 6
#: The start's window reaches this fraction of the plate's period past the jump (at least SENSED_MIN_START samples,
#: at most SENSED_INSIDE_FRACTION of TC): the plate's first rise pins the jump, and beyond it lies the pre-buckling
#: spike, which no parabola follows [-]; fitted again reaching three quarters as far (at least 3 samples)
SENSED_START_PERIODS = 0.2
SENSED_MIN_START = 4
#: The force after the jump is fitted as the jump, a line and (3) a parabola [-]
SENSED_START_TERMS = 3
#: The end's window reaches this many of the plate's periods after it (its free ringing) [-]
SENSED_OUTSIDE_PERIODS = 1.5
#: The start's window begins this many samples before the jump, or within the cloth's phase where that is shorter
#: (three quarters of it less 2 samples, at least 2): the force there is the cloth's line [samples]
SENSED_BEFORE = 8
#: Candidates reach this many of the plate's periods either side of the end found on the sensed force (at least 4
#: samples): a plate's swing moves the crossings read there by up to about half a period [-]
SENSED_REACH_PERIODS = 0.5
#: An end's fit whose rms residual exceeds this many noise deviations is no line and parabola falling to zero
#: through the plate (the free ringing and a smooth force leave about one) [-] ...
SENSED_MAX_RESIDUAL = 4.0
#: ... a start's, this many (the pre-buckling spike beyond the jump's window leaves up to tens; what the force's
#: shape does to the start is charged as the windows' difference) [-]
SENSED_MAX_START_RESIDUAL = 30.0
#: The fitted TC this fraction or more from the contact found on the sensed force: another contact's ends [-]
SENSED_MAX_MOVE = 0.05
#: A start whose fitted jump is below this fraction of the sensed peak is no ball's jump (a fit to the noise before
#: a start found early) [-]
SENSED_MIN_JUMP = 0.05
#: The plate's resonance and damping ratio are known to about these fractions: how far TC moves with them either
#: way is charged to TC [-]
SENSED_FN_UNCERTAINTY = 0.01
SENSED_ZETA_UNCERTAINTY = 0.25
_COARSE, _FINE = 0.25, 0.02  # grids of the candidates [samples]
_ITERATIONS = 10  # the window re-anchored on the best at most this many times


class SensedEnd(NamedTuple):
    """An end of a contact fitted by :func:`sensed_end`."""

    index: float  #: the end [samples, fractional index]
    se: float  #: its standard uncertainty from the white noise (or the fit's residual, the larger) [samples]
    residual: float  #: rms residual of the fit [unit of the signal]
    first: int  #: first sample of the fit's window [-]
    last: int  #: last sample of the fit's window [-]
    jump: float = math.nan  #: the start's fitted jump [unit of the signal] (NaN at an end)


class SensedContact(NamedTuple):
    """A contact's ends fitted by :func:`sensed_contact` [samples, fractional indices]."""

    start: float  #: the first contact [samples]: the force's jump less the cloth's phase
    end: float  #: the end [samples]
    start_se: float  #: the start's standard uncertainty [samples]
    end_se: float  #: the end's standard uncertainty [samples]
    bias: float  #: how far TC moves with the window and with the plate off by its uncertainty, a bound [samples]
    residual: float  #: the larger of the two fits' rms residuals over the noise [-]


def _start_design(n, ts, wn, zeta, lo):
    """The plate's responses [n, 2 + SENSED_START_TERMS] to a level and a line from the window's first sample ``lo``
    (the cloth's light load before the jump, steady) and to a jump, a line and a parabola from ``ts``. (A cloth's
    ramp tied to the first contact ``ts - phase`` trades with the jump, giving a second least two to three samples
    late; with no term for the cloth's load the jump is drawn early onto it.)"""
    ramp, _ = steady_responses(n - lo, wn, zeta)
    return np.column_stack([np.ones_like(n), ramp, front_responses(n - ts, wn, zeta, 0.0)[:, :SENSED_START_TERMS]])


def _end_design(n, te, wn, zeta, lo):
    """The plate's free ringing from ``lo`` and its responses [n, 4] to a line and a parabola falling to zero at
    ``te`` (the force before it; zero after): the steady responses to the line and parabola less those of the same
    terms started at ``te`` (:func:`ballimpact.signal.front.front_responses`)."""
    u = n - te
    resp = front_responses(u, wn, zeta, 0.0)
    ramp, parabola = steady_responses(u, wn, zeta)
    wd, v = wn * math.sqrt(1.0 - zeta * zeta), n - lo
    decay = np.exp(-zeta * wn * v)
    return np.stack([decay * np.cos(wd * v), decay * np.sin(wd * v), -ramp + resp[:, 1], parabola - resp[:, 2]],
                    axis=1)


def _window(centre, side, inside, outside, phase, reach):
    """First and last sample of the window for candidates within ``reach`` of ``centre`` [samples]."""
    if side == "start":  # from within the cloth's phase, where the force before the jump is a line (the cloth's)
        before = SENSED_BEFORE if phase <= 0 else min(max(int(0.75 * phase) - 2, 2), SENSED_BEFORE)
        return int(math.floor(centre - reach)) - before, int(math.ceil(centre + reach + inside))
    return int(math.floor(centre - reach - inside)), int(math.ceil(centre + reach + outside))


def _fits(y, lo, hi, grid, side, wn, zeta):
    """The residual sum of squares [unit^2] and coefficients of the fit at every candidate of ``grid``."""
    n = np.arange(lo, hi + 1, dtype=float)
    design = np.stack([_start_design(n, g, wn, zeta, lo) if side == "start" else _end_design(n, g, wn, zeta, lo)
                       for g in grid])
    gram = np.einsum("gmp,gmq->gpq", design, design)
    ridge = 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(gram.shape[-1])
    coef = np.linalg.solve(gram + ridge + 1e-300, np.einsum("gmp,m->gp", design, y[lo:hi + 1])[..., None])[..., 0]
    r = y[lo:hi + 1][None] - np.einsum("gmp,gp->gm", design, coef)
    return np.einsum("gm,gm->g", r, r), coef, design


def sensed_end(x, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, index: float, side: str, *,
               inside_samples: int, noise_rms: float, cloth_phase_samples: float = 0.0,
               reach_samples: float | None = None) -> SensedEnd | None:
    """Where a contact starts (or ends), fitted in the sensed force through a known second-order plate.

    The plate (raw-format v1.2: resonance fn, damping ratio zeta, unit static gain) is causal and at rest
    before the contact: near the start the sensed force is its response to the ball's jump, line and parabola
    from ``ts`` on (the damping term at first contact: ``a + b (t - ts) + q (t - ts)^2``), zero before; the
    first contact is ``cloth_phase_samples`` before the jump (the cloth's light load, section 3.2.4).
    Near the end it is the plate's free ringing from the window's first sample plus its response to a line and
    a parabola falling to zero at ``te`` (a ball's force falls to zero continuously as it leaves). For each
    candidate the model is linear in its amplitudes (the responses are analytic:
    :func:`ballimpact.signal.front.front_responses`); the candidate of least residual wins, on a grid of a
    quarter of a sample within ``reach_samples`` of ``index``, then within 2 samples of the best with the window
    re-anchored on it (until it stays within a sample), then of 0.02 sample within one. The sensed noise is white,
    so no low-pass is needed and none spreads the ends (:func:`ballimpact.signal.undone_end.undone_end` fits
    through the undoing and a low-pass instead). Not in the paper; see docs/signal-processing.md, "Plate
    resonance".

    Parameters
    ----------
    x : array_like
        The conditioned (baseline-corrected) sensed voltage, proportional to the plate's output [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The plate's resonance [Hz] and damping ratio [-].
    index : float
        The end found on the sensed force [samples, fractional index]: the guess (for the start, the jump's).
    side : str
        ``"start"`` or ``"end"``.
    inside_samples : int
        Samples of the window inside the contact beyond the candidates [samples].
    noise_rms : float
        Standard deviation of the sensed white noise [V].
    cloth_phase_samples : float
        The cloth's phase before the jump [samples] (0: none fitted); the start returned is the jump's less it.
    reach_samples : float, optional
        Candidates this far either side of ``index`` [samples] (default SENSED_REACH_PERIODS of the plate's
        period, at least 4 samples).

    Returns
    -------
    SensedEnd or None
        None when the window leaves the record or the best end stays at the edge of the candidates.

    Raises
    ------
    ValueError
        For a non-positive sample rate, a resonance that is not positive, a damping ratio outside [0, 1), a side
        other than "start" or "end", or non-finite samples.
    """
    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not (frequency_hz > 0 and 0 <= damping_ratio < 1):
        raise ValueError(f"need frequency_hz > 0 and 0 <= damping_ratio < 1, got {frequency_hz!r}, {damping_ratio!r}")
    if side not in ("start", "end"):
        raise ValueError(f"side must be 'start' or 'end', got {side!r}")
    y = finite_samples("x", x)
    if not math.isfinite(index):
        return None
    wn, zeta = 2.0 * math.pi * frequency_hz / fs, float(damping_ratio)
    period = fs / frequency_hz
    reach = max(SENSED_REACH_PERIODS * period, 4.0) if reach_samples is None else float(reach_samples)
    outside = max(SENSED_OUTSIDE_PERIODS * period, 8.0)
    phase = max(float(cloth_phase_samples), 0.0)
    inside = max(int(inside_samples), 2)
    centre = float(index) + (phase if side == "start" else 0.0)  # the start's guess is the first contact's
    for it in range(_ITERATIONS):
        lo, hi = _window(centre, side, inside, outside, phase, reach)
        if lo < 0 or hi >= y.size:
            return None
        grid = np.arange(centre - reach, centre + reach + 1e-9, _COARSE)
        sse, _, _ = _fits(y, lo, hi, grid, side, wn, zeta)
        k = int(np.argmin(sse))
        best = float(grid[k])
        moved = abs(best - centre)
        centre = best
        if it > 0 and moved <= 1.0:
            break
        if k not in (0, grid.size - 1):  # inside the candidates: the window follows the best, and the force
            reach = min(reach, 2.0)  # beyond ``inside`` stays out of it
    else:
        return None  # still moving: no least the window settles on
    for _ in range(_ITERATIONS):  # the window's anchor moves the least by a fraction of a sample: follow it
        lo, hi = _window(centre, side, inside, outside, phase, 1.0)
        if lo < 0 or hi >= y.size:
            return None
        fine = np.arange(centre - 1.0, centre + 1.0 + 1e-9, _FINE)
        sse, coef, design = _fits(y, lo, hi, fine, side, wn, zeta)
        k = int(np.argmin(sse))
        if k not in (0, fine.size - 1):
            break
        centre = float(fine[k])
    else:
        return None
    m = hi - lo + 1
    resid2 = float(sse[k]) / max(m - design.shape[-1] - 1, 1)
    # the model's change with the end, its amplitudes held (central differences on the fine grid), beside its
    # linear columns: the end's variance in white noise of the larger of the sensed noise and the fit's residual
    d_end = (design[k + 1] - design[k - 1]) @ coef[k] / (2.0 * _FINE)
    jac = np.column_stack([d_end, design[k]])
    scale = np.sqrt(np.sum(jac * jac, axis=0))
    if not np.all(scale > 0):
        return None
    jn = jac / scale
    try:
        inv = np.linalg.inv(jn.T @ jn)
    except np.linalg.LinAlgError:
        return None
    sigma2 = max(float(noise_rms) ** 2, resid2)
    se = math.sqrt(max(sigma2 * float(inv[0, 0]), 0.0)) / float(scale[0])
    at = float(fine[k]) - (phase if side == "start" else 0.0)
    jump = float(coef[k][2]) if side == "start" else math.nan
    return SensedEnd(at, se, math.sqrt(resid2), int(lo), int(hi), jump)


def sensed_contact(x, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, start_u: float,
                   end_u: float, *, noise_rms: float, cloth_phase_samples: float = 0.0,
                   fn_uncertainty: float = SENSED_FN_UNCERTAINTY,
                   zeta_uncertainty: float = SENSED_ZETA_UNCERTAINTY) -> SensedContact | str:
    """A contact's ends fitted through a known plate in the sensed force (:func:`sensed_end`), with TC's bounds.

    Each end is fitted with its window reaching SENSED_INSIDE_FRACTION of TC into the contact; fitted again
    reaching SENSED_INSIDE_SHORT, and with the plate's resonance and damping ratio off by ``fn_uncertainty``
    and ``zeta_uncertainty`` either way, TC moves: the largest move is a bound on what the model leaves out
    (the force's shape beyond a parabola, the plate known only so well). An end's fit whose rms residual
    exceeds SENSED_MAX_RESIDUAL noise deviations, or a start's SENSED_MAX_START_RESIDUAL, is refused: the sensed
    force is then not that plate's response to such a force (another mode, a baseline wrong there, a second
    contact); so is a start whose jump is under SENSED_MIN_JUMP of the peak, and a TC SENSED_MAX_MOVE or more
    from the contact found.

    Parameters
    ----------
    x : array_like
        The conditioned sensed voltage [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The plate's resonance [Hz] and damping ratio [-].
    start_u, end_u : float
        The contact's start (the first contact) and end found on the sensed force [samples, fractional indices].
    noise_rms : float
        Standard deviation of the sensed white noise [V].
    cloth_phase_samples : float
        The cloth's phase before the ball's jump [samples] (0: none).
    fn_uncertainty, zeta_uncertainty : float
        Relative uncertainties of the resonance and the damping ratio [-].

    Returns
    -------
    SensedContact or str
        The ends and TC's bounds [samples]; else why not, in words.
    """
    tc = end_u - start_u
    if not (tc > 0 and noise_rms > 0):
        return "no contact of positive length, or no noise level, to fit its ends by"
    fits = {}
    period = sample_rate_hz / frequency_hz
    start_in = min(max(SENSED_START_PERIODS * period, SENSED_MIN_START), max(SENSED_INSIDE_FRACTION * tc,
                                                                                SENSED_MIN_START))
    windows = {"": (int(round(start_in)), max(int(round(SENSED_INSIDE_FRACTION * tc)), SENSED_MIN_INSIDE)),
               "short": (max(int(round(0.75 * start_in)), 3), max(int(round(SENSED_INSIDE_SHORT * tc)),
                                                                 SENSED_MIN_INSIDE))}
    variants = {name: (frequency_hz, damping_ratio, w) for name, w in windows.items()}
    for sign in (-1.0, 1.0):
        variants[f"fn{sign:+.0f}"] = (frequency_hz * (1.0 + sign * fn_uncertainty), damping_ratio, windows[""])
        variants[f"zeta{sign:+.0f}"] = (frequency_hz, min(damping_ratio * (1.0 + sign * zeta_uncertainty), 0.99),
                                        windows[""])
    for name, (fn, zeta, (inside_start, inside_end)) in variants.items():
        guess = (start_u, end_u) if not name else (fits[""][0].index, fits[""][1].index)
        reach = None if not name else 2.0
        pair = (sensed_end(x, sample_rate_hz, fn, zeta, guess[0], "start", inside_samples=inside_start,
                           noise_rms=noise_rms, cloth_phase_samples=cloth_phase_samples, reach_samples=reach),
                sensed_end(x, sample_rate_hz, fn, zeta, guess[1], "end", inside_samples=inside_end,
                           noise_rms=noise_rms, reach_samples=reach))
        if pair[0] is None or pair[1] is None:
            return (f"the {'start' if pair[0] is None else 'end'} fits no jump (or line) through the plate in the "
                    "sensed force" + (f" ({name})" if name else ""))
        fits[name] = pair
    start, end = fits[""]
    peak = float(np.max(np.asarray(x, dtype=float)[max(int(start_u), 0):max(int(end_u) + 1, 1)], initial=0.0))
    if not start.jump >= SENSED_MIN_JUMP * peak:
        return (f"its start fitted through the plate jumps by {100 * start.jump / peak:.2g} % of the peak only (less "
                f"than {100 * SENSED_MIN_JUMP:g} %): no ball's jump there")
    for side, fit, limit in (("start", start, SENSED_MAX_START_RESIDUAL), ("end", end, SENSED_MAX_RESIDUAL)):
        if fit.residual > limit * noise_rms:
            return (f"its {side}'s fit through the plate leaves {fit.residual / noise_rms:.2g} noise deviations rms "
                    f"(more than {limit:g}): the sensed force is not that plate's response to the force there")
    residual = max(start.residual, end.residual) / noise_rms
    tc_fit = end.index - start.index
    if not abs(tc_fit / tc - 1.0) < SENSED_MAX_MOVE:
        return (f"its ends fitted through the plate give a TC {100 * (tc_fit / tc - 1.0):+.2g} % from the contact "
                f"found on the sensed force (at most {100 * SENSED_MAX_MOVE:g} %)")
    bias = max(abs((e.index - s.index) - tc_fit) for s, e in fits.values())
    return SensedContact(start.index, end.index, start.se, end.se, float(bias), float(residual))
