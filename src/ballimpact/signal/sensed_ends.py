"""A contact's ends fitted in the sensed force through a known plate, where the noise is white."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._checks import finite_samples, positive_scalar
from .contact import detect_contact
from .front import front_responses, steady_responses
from .plate import fit_trace_ringing
from .undo import lowpass_zero_phase, plate_undoable, undo_plate_resonance

__all__ = ["SENSED_INSIDE_FRACTION", "SENSED_INSIDE_SHORT", "SENSED_MIN_INSIDE", "SENSED_OUTSIDE_PERIODS",
           "SENSED_START_PERIODS", "SENSED_MIN_START", "SENSED_START_TERMS", "SENSED_BEFORE", "SENSED_REACH_PERIODS",
           "SENSED_MAX_RESIDUAL", "SENSED_MAX_START_RESIDUAL", "SENSED_MAX_MOVE", "SENSED_MIN_JUMP",
           "SENSED_FN_UNCERTAINTY", "SENSED_ZETA_UNCERTAINTY", "SENSED_OWN_FN_UNCERTAINTY",
           "SENSED_OWN_ZETA_UNCERTAINTY", "SENSED_RING_GAP", "SENSED_RING_PERIODS",
           "SENSED_RING_MAX_RESIDUAL", "SENSED_RING_COVERAGE", "SENSED_MIN_END_SIGMA", "SensedEnd", "SensedContact",
           "sensed_end", "sensed_contact", "resonance_lowpassed_contact"]

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
#: ... a start's, this fraction of its fitted jump (the pre-buckling spike beyond the jump's window leaves up to
#: hundreds of noise deviations where a plate's period spans a few samples, a fifth of the jump at most, the
#: start still within a sample; what the force's shape does to the start is charged as the windows' difference,
#: a window half as long again among them) [-]
SENSED_MAX_START_RESIDUAL = 0.25
#: A fitted start this fraction of TC or more from the one found on the sensed force, or (the plate not measured in
#: the trace) a fitted TC this far from the one found there: another contact's ends [-]
SENSED_MAX_MOVE = 0.05
#: A start whose fitted jump is below this fraction of the sensed peak is no ball's jump (a fit to the noise before
#: a start found early) [-]
SENSED_MIN_JUMP = 0.05
#: The plate's resonance and damping ratio are known to about these fractions: how far TC moves with them either
#: way is charged to TC [-]
SENSED_FN_UNCERTAINTY = 0.01
SENSED_ZETA_UNCERTAINTY = 0.25
#: A plate the trace identified itself, not measured again in its free ringing, is charged at these fractions: one
#: trace's identification, its resonance's and damping's errors where the ends' fits through it stand [-]
SENSED_OWN_FN_UNCERTAINTY = 0.10
SENSED_OWN_ZETA_UNCERTAINTY = 0.50
#: A known plate is measured in the trace's free ringing from this many samples after the fitted end [samples] ...
SENSED_RING_GAP = 2
#: ... over three of its decay times, at least the first and at most the second of these many periods [-] ...
SENSED_RING_PERIODS = (3.0, 10.0)
#: ... and used where its fit leaves at most this many noise deviations rms (one mode, no force there) [-] ...
SENSED_RING_MAX_RESIDUAL = 1.5
#: ... its fn and zeta then charged at this many of their standard uncertainties either way [-]
SENSED_RING_COVERAGE = 2.0
#: An end whose line and parabola stand below this many noise deviations at its window's inside edge holds no ball's
#: force there: the window lies after the contact (a ball's end stands tens to hundreds out of the noise) [-]
SENSED_MIN_END_SIGMA = 10.0
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
    level: float = math.nan  #: an end's fitted force at its window's inside edge [unit of the signal] (NaN at a start)


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
    se = _end_se(design, coef, k, max(float(noise_rms) ** 2, resid2))
    if se is None:
        return None
    at = float(fine[k]) - (phase if side == "start" else 0.0)
    jump, level = ((float(coef[k][2]), math.nan) if side == "start"  # the jump; an end's force inside its window
                   else (math.nan, float(coef[k][2] * inside + coef[k][3] * inside * inside)))
    return SensedEnd(at, se, math.sqrt(resid2), int(lo), int(hi), jump, level)


def _end_se(design, coef, k: int, sigma2: float) -> float | None:
    """The standard uncertainty of the end at fine candidate ``k`` [samples] in white noise of variance ``sigma2``:
    the model's change with the end, its amplitudes held (central differences on the fine grid), beside its linear
    columns; None where they do not determine it."""
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
    return math.sqrt(max(sigma2 * float(inv[0, 0]), 0.0)) / float(scale[0])


def sensed_contact(x, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, start_u: float,
                   end_u: float, *, noise_rms: float, cloth_phase_samples: float = 0.0,
                   fn_uncertainty: float = SENSED_FN_UNCERTAINTY,
                   zeta_uncertainty: float = SENSED_ZETA_UNCERTAINTY,
                   refine: bool = True) -> SensedContact | str:
    """A contact's ends fitted through a known plate in the sensed force (:func:`sensed_end`), with TC's bounds.

    Each end is fitted with its window reaching SENSED_INSIDE_FRACTION of TC into the contact (the end from
    ``end_u``, or where that fails from the end of the force undone and low-passed at the resonance: a swing of
    the plate can end the sensed force periods early). With ``refine``, the plate is then measured in this trace:
    fitted to the free ringing after the end (:func:`ballimpact.signal.plate.fit_trace_ringing`, from
    SENSED_RING_GAP samples after it over SENSED_RING_PERIODS of its periods, or three decay times), and where that
    fit leaves at most SENSED_RING_MAX_RESIDUAL noise deviations (one mode, no force) the ends are fitted again
    through it, its fn and zeta then uncertain by SENSED_RING_COVERAGE of their standard uncertainties instead of
    ``fn_uncertainty`` and ``zeta_uncertainty`` (twice, from the end fitted again). Fitted again with the window
    reaching SENSED_INSIDE_SHORT, with each end's half as long again, and with the plate off by its
    uncertainties either way, TC moves: the largest move is a bound on what the model leaves out (the force's
    shape beyond a parabola, the plate known only so well). Refused: an end's fit whose rms residual exceeds
    SENSED_MAX_RESIDUAL noise deviations, or a start's SENSED_MAX_START_RESIDUAL of its jump (the sensed force
    is then not that plate's response to such a force: another mode, a baseline wrong there, a second contact);
    a start whose jump is under SENSED_MIN_JUMP of the peak; an end whose line and parabola stand under
    SENSED_MIN_END_SIGMA noise deviations at the window's inside edge (a window after the contact); a start
    SENSED_MAX_MOVE of TC or more from ``start_u``; and, the plate not measured in the trace, a TC that far from
    the contact found (with it measured, the free ringing after the end shows no force there).
    Not in the paper; see docs/signal-processing.md, "Plate resonance".

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
        Relative uncertainties of the resonance and the damping ratio [-], where the trace does not measure them.
    refine : bool
        Measure the plate in the trace's free ringing after the end.

    Returns
    -------
    SensedContact or str
        The ends and TC's bounds [samples]; else why not, in words.
    """
    tc = end_u - start_u
    if not (tc > 0 and noise_rms > 0):
        return "no contact of positive length, or no noise level, to fit its ends by"
    x = np.asarray(x, dtype=float)
    plate, charged = (frequency_hz, damping_ratio), (fn_uncertainty, zeta_uncertainty)
    windows = _windows(sample_rate_hz / frequency_hz, tc)
    main = _fitted_pair(x, sample_rate_hz, plate, (start_u, end_u), windows[""], noise_rms, cloth_phase_samples)
    if main is None:
        main = _fitted_pair(x, sample_rate_hz, plate, (start_u, _undone_end(x, sample_rate_hz, plate)),
                            windows[""], noise_rms, cloth_phase_samples)
    if main is None:
        return "the start or the end fits no jump (or line) through the plate in the sensed force"
    measured = False
    for _ in range(2 if refine else 0):  # the plate measured in the free ringing after the end, twice
        ring = _free_ringing(x, sample_rate_hz, plate, main[1].index, noise_rms)
        again = None if ring is None else _fitted_pair(x, sample_rate_hz, ring[0], (main[0].index, main[1].index),
                                                       windows[""], noise_rms, cloth_phase_samples)
        if again is None:
            break
        (plate, charged), main, measured = ring, again, True
    fits = {"": main}
    for name, (fn, zeta, window) in _variants(plate, charged, windows).items():
        for reach in (2.0, None):  # near the main fit's ends, else as far as they were looked for
            pair = _fitted_pair(x, sample_rate_hz, (fn, zeta), (main[0].index, main[1].index), window, noise_rms,
                                cloth_phase_samples, reach=reach)
            if pair is not None:
                break
        if pair is None:
            return f"the start or the end fits no jump (or line) through the plate in the sensed force ({name})"
        fits[name] = pair
    refused = _refusal(x, main, start_u, end_u, noise_rms, measured)
    if refused:
        return refused
    start, end = main
    tc_fit = end.index - start.index
    bias = max(abs((e.index - s.index) - tc_fit) for s, e in fits.values())
    return SensedContact(start.index, end.index, start.se, end.se, float(bias),
                         max(start.residual, end.residual) / noise_rms)


def _windows(period: float, tc: float) -> dict:
    """Samples inside the contact of the start's and the end's windows: the main ones and the short ones."""
    start_in = min(max(SENSED_START_PERIODS * period, SENSED_MIN_START), max(SENSED_INSIDE_FRACTION * tc,
                                                                             SENSED_MIN_START))
    main = (int(round(start_in)), max(int(round(SENSED_INSIDE_FRACTION * tc)), SENSED_MIN_INSIDE))
    return {"": main,
            "short": (max(int(round(0.75 * start_in)), 3), max(int(round(SENSED_INSIDE_SHORT * tc)),
                                                              SENSED_MIN_INSIDE)),
            "long start": (int(round(1.5 * start_in)), main[1]),
            "long end": (main[0], int(round(1.5 * main[1])))}


def _variants(plate, charged, windows) -> dict:
    """The fits TC's bound is read from: the short windows, and the plate off by its uncertainties either way."""
    fn, zeta = plate
    out = {name: (fn, zeta, windows[name]) for name in ("short", "long start", "long end")}
    for sign in (-1.0, 1.0):
        out[f"fn{sign:+.0f}"] = (fn * (1.0 + sign * min(charged[0], 0.5)), zeta, windows[""])
        out[f"zeta{sign:+.0f}"] = (fn, min(zeta * (1.0 + sign * min(charged[1], 0.9)), 0.99), windows[""])
    return out


def _fitted_pair(x, fs, plate, guess, window, noise_rms, cloth_phase_samples, reach=None):
    """The start's and the end's :func:`sensed_end` through ``plate`` (fn [Hz], zeta [-]), or None."""
    if not math.isfinite(guess[1]):
        return None
    start = sensed_end(x, fs, plate[0], plate[1], guess[0], "start", inside_samples=window[0], noise_rms=noise_rms,
                       cloth_phase_samples=cloth_phase_samples, reach_samples=reach)
    end = sensed_end(x, fs, plate[0], plate[1], guess[1], "end", inside_samples=window[1], noise_rms=noise_rms,
                     reach_samples=reach)
    return None if start is None or end is None else (start, end)


def resonance_lowpassed_contact(x, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, *,
                                t0_s: float = 0.0):
    """The contact found on the force undone from a known plate and low-passed at its resonance.

    Its ringing gone and what is left of it above the resonance smoothed away, this force shows where the contact
    ends and whether it holds another (:func:`ballimpact.signal.contact.detect_contact`), though its ends are
    spread by the low-pass: the sensed force can end on a swing periods early, and a second contact can hide in
    a swing.

    Parameters
    ----------
    x : array_like
        The conditioned sensed voltage [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The plate's resonance [Hz] and damping ratio [-].
    t0_s : float
        Time of ``x[0]`` [s].

    Returns
    -------
    ballimpact.signal.contact.ContactResult

    Raises
    ------
    ValueError
        Where the sampled plate has no inverse (:func:`ballimpact.signal.undo.plate_undoable`).
    """
    y = lowpass_zero_phase(undo_plate_resonance(x, sample_rate_hz, frequency_hz, damping_ratio), sample_rate_hz,
                           frequency_hz)
    return detect_contact(y, sample_rate_hz, t0_s=t0_s)


def _undone_end(x, fs, plate) -> float:
    """The end of :func:`resonance_lowpassed_contact` [samples] (NaN: none, or a plate the samples cannot undo)."""
    if not plate_undoable(plate[0], plate[1], fs):
        return math.nan
    found = resonance_lowpassed_contact(x, fs, plate[0], plate[1])
    return found.end_s * fs if found.n_impacts >= 1 and math.isfinite(found.end_s) else math.nan


def _free_ringing(x, fs, plate, end, noise_rms):
    """The plate measured in the free ringing after ``end`` [samples]: ((fn, zeta), (their relative
    uncertainties)), or None where the stretch is too short, is not one mode's ringing, or measures the plate no
    better than a stated one is known (SENSED_FN_UNCERTAINTY, SENSED_ZETA_UNCERTAINTY)."""
    fn, zeta = plate
    period = fs / fn
    decay = 3.0 / (zeta * 2.0 * math.pi * fn / fs)  # three decay times [samples]
    first = int(math.ceil(end)) + SENSED_RING_GAP
    last = min(first + int(min(max(decay, SENSED_RING_PERIODS[0] * period), SENSED_RING_PERIODS[1] * period)),
               x.size)
    try:
        ring = fit_trace_ringing(x[first:last], fs, noise_rms, fn, zeta)
    except ValueError:
        return None
    if not ring.residual_rms <= SENSED_RING_MAX_RESIDUAL * noise_rms:
        return None
    charged = (SENSED_RING_COVERAGE * ring.frequency_se_hz / ring.frequency_hz,
               SENSED_RING_COVERAGE * ring.damping_se / ring.damping_ratio)
    if not (charged[0] <= SENSED_FN_UNCERTAINTY and charged[1] <= SENSED_ZETA_UNCERTAINTY):
        return None  # measured no better than a stated plate is known
    return (ring.frequency_hz, ring.damping_ratio), charged


def _refusal(x, main, start_u, end_u, noise_rms, measured) -> str:
    """Why the main fit cannot stand (see :func:`sensed_contact`), or ""."""
    start, end = main
    tc = end_u - start_u
    peak = float(np.max(x[max(int(start_u), 0):max(int(end_u) + 1, 1)], initial=0.0))
    if not start.jump >= SENSED_MIN_JUMP * peak:
        return (f"its start fitted through the plate jumps by {100 * start.jump / peak:.2g} % of the peak only (less "
                f"than {100 * SENSED_MIN_JUMP:g} %): no ball's jump there")
    if not end.level >= SENSED_MIN_END_SIGMA * noise_rms:
        return (f"its end fitted through the plate leaves {end.level / noise_rms:.2g} noise deviations of force inside "
                f"its window (less than {SENSED_MIN_END_SIGMA:g}): the window lies after the contact")
    if end.residual > SENSED_MAX_RESIDUAL * noise_rms:
        return (f"its end's fit through the plate leaves {end.residual / noise_rms:.2g} noise deviations rms (more "
                f"than {SENSED_MAX_RESIDUAL:g}): the sensed force is not that plate's response to the force there")
    if start.residual > SENSED_MAX_START_RESIDUAL * start.jump:
        return (f"its start's fit through the plate leaves {100 * start.residual / start.jump:.2g} % of its jump rms "
                f"(more than {100 * SENSED_MAX_START_RESIDUAL:g} %): the sensed force is not that plate's response "
                "to a jump there")
    if not abs(start.index - start_u) < SENSED_MAX_MOVE * tc:
        return (f"its start fitted through the plate lies {100 * (start.index - start_u) / tc:+.2g} % of TC from the "
                f"contact found on the sensed force (at most {100 * SENSED_MAX_MOVE:g} %)")
    tc_fit = end.index - start.index
    if not (measured or abs(tc_fit / tc - 1.0) < SENSED_MAX_MOVE):
        return (f"its ends fitted through the plate give a TC {100 * (tc_fit / tc - 1.0):+.2g} % from the contact "
                f"found on the sensed force (at most {100 * SENSED_MAX_MOVE:g} %)")
    return ""
