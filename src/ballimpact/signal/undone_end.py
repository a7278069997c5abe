"""A contact end fitted through the plate's undoing and the low-pass: a jump, a line and a parabola from zero."""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from .._checks import finite_samples, positive_scalar
from .front import front_responses, steady_responses
from .undo import lowpass_kernel, undo_rows, undone_impulse_response

__all__ = ["UndoneEnd", "undone_end"]

END_TERMS = 3  # an end fitted as a jump, a line and (3) a parabola from it [-]
END_GRID_SAMPLES = 0.05  # an end fitted through the plate's undoing and the low-pass is found on this grid [samples]
NOISE_RESPONSE_HALF = 64  # the inverse's impulse response kept this far each side for the noise's covariance: its zeros
#                           (about -0.27 and -1.3 to -3.7) leave less than 1e-7 of it there [samples]


class UndoneEnd(NamedTuple):
    """An end of a contact fitted by :func:`undone_end`."""

    index: float  #: the end [samples, fractional index]
    slope: float  #: the force's slope b there [unit of the force per sample], positive into the contact
    jump: float  #: its jump a there [unit of the force] (0 at an end)
    residual: float  #: rms residual of the fit [unit of the force]
    uncertainty: float  #: standard uncertainty of the end from the fit's profile [samples]
    first: int  #: first sample of the fit's window [-]
    correction: np.ndarray  #: the fitted force less what the chain made of it, over the window [unit of the force]
    noise_se: float = math.nan  #: its standard uncertainty from the chain's coloured noise [samples] (NaN: not asked)


def _end_columns(frequency_hz: float, damping_ratio: float, fs: float, taps: np.ndarray, step: float, span: int):
    """The low-passed undone plate responses to a unit step, ramp and parabola starting at ``frac`` samples.

    For each fraction ``frac`` of a sample on a grid of ``step``: the arrays
    ``K * undo(P f(n - frac))`` for f = H(t), t H(t), t^2 H(t) and, last, the
    parabola t^2 for all t (P the plate's continuous response, analytic: :func:`front_responses`;
    undo :func:`undo_plate_resonance`; K the low-pass taps) over
    ``n = -span .. span``; an array of shape (fractions, 4, 2 span + 1) [-].
    """
    pad = 40 + taps.size  # the undo's backward pass starts from rest this far beyond the window: 0.27^40
    n = np.arange(-span - pad, span + pad + 1, dtype=float)
    wn = 2.0 * math.pi * frequency_hz / fs  # [rad / sample]
    zeta = damping_ratio
    t = n[None, :] - np.arange(0.0, 1.0 - 1e-9, step)[:, None]  # [frac, n]
    _, steady_q = steady_responses(t, wn, zeta)  # the parabola's steady response
    responses = np.concatenate([np.moveaxis(front_responses(t, wn, zeta, 0.0), -1, 1), steady_q[:, None, :]],
                               axis=1)  # [frac, response, n]: step, ramp, parabola (analytic), the steady parabola
    u = undo_rows(responses, fs, frequency_hz, damping_ratio)
    if taps.size > 1:
        from scipy.ndimage import convolve1d

        u = convolve1d(u, taps, axis=-1, mode="constant")
    return u[..., pad:-pad]


def undone_end(force, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, cutoff_hz: float,
               index: float, side: str, *, inside_samples: int = 4, reach_samples: int = 2,
               noise_rms: float | None = None):
    """Where a force that starts (or ends) as a line, seen through the plate, its undoing and a low-pass, starts (ends).

    Near a contact's start the force is zero before ts and about
    ``a + b (t - ts) + q (t - ts)^2`` after it (a > 0: a jump from zero, as
    the model's force at its start); near its end it falls to zero at ts
    as ``b (ts - t) + q (ts - t)^2``, with no jump (a ball leaves the plate
    when its force has fallen to zero). Undone (:func:`undo_plate_resonance`), the force
    is returned exactly where it is linear between samples, and the interval
    that holds the end leaves a transient (the undo assumes a line between
    samples); :func:`lowpass_zero_phase` then spreads it by up to the
    kernel's half-width W. So the end is fitted through that chain: for ts on
    a grid of END_GRID_SAMPLES, the plate's continuous step and ramp
    responses from ts, undone and low-passed, are fitted (a and b) to the
    force by least squares over a window from W + 3 samples outside the
    earliest candidate to W + ``inside_samples`` inside the latest; the ts
    of the least residual wins. An end is a start of the force ``L - a H(t -
    ts) + b (t - ts)+`` with L the line ``a + b (ts - t)``, so both sides use the
    same responses. Not in the paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        The undone (and low-passed) force (any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The resonance undone [Hz] and its damping ratio [-].
    cutoff_hz : float
        The low-pass's half-amplitude frequency [Hz]; ``inf`` for none.
    index : float
        The end found on the force (e.g. by ``detect_contact``) [samples]:
        candidates from W + ``reach_samples`` samples before it (start) to
        2 W + ``reach_samples`` after it (mirrored at an end).
    side : str
        ``"start"`` or ``"end"``.
    inside_samples : int
        Samples of the line fitted beyond the kernel's reach [samples], at least 2.
    reach_samples : int
        Candidates reach this many samples (and the kernel's W, 2 W inside)
        beyond ``index`` on each side [samples], at least 1: more where the
        end found on the force may be several samples off (a foot in the
        amplified noise of an exact undone force).
    noise_rms : float, optional
        Standard deviation of the sensed trace's white noise, in the unit of
        ``force`` [V]. When given, the end's standard uncertainty from that
        noise as the chain colours it is returned too (``noise_se``; see
        :func:`_end_noise_se`).

    Returns
    -------
    UndoneEnd or None
        The end [samples, fractional index], the line's slope b at it, its
        jump a at it, the rms residual of the fit [unit of the force per
        sample, unit of the force, unit of the force], the end's standard
        uncertainty [samples] (the farthest end whose fit leaves at most one
        residual variance more per independent sample of the low-passed
        noise, correlated over about ``1 / sum(K^2)`` samples) and, from the
        window's first sample on, the fitted force less what the undoing and
        the kernel made of it (added to the force, it restores the end's
        jump and the impulse the kernel spread outside it); None
        when the window leaves the record or the best end is at the edge of
        the candidates (no end inside them).

    Raises
    ------
    ValueError
        For a non-positive sample rate or cutoff, a side other than "start"
        or "end", inside_samples below 2, reach_samples below 1 or non-finite samples.
    """
    fs = _checked_end_arguments(sample_rate_hz, frequency_hz, damping_ratio, cutoff_hz, side, inside_samples,
                                reach_samples)
    y = finite_samples("force", force)
    if not math.isfinite(index):
        return None
    taps = np.ones(1) if math.isinf(cutoff_hz) else lowpass_kernel(fs, cutoff_hz)
    w = taps.size // 2
    sign = 1 if side == "start" else -1
    k_lo, k_hi, lo, hi = _end_window(index, w, side, int(inside_samples), int(reach_samples))
    if lo < 0 or hi >= y.size:
        return None
    span = 32 * ((hi - lo + 2) // 32 + 1)  # the columns' half-length, shared by windows of similar length
    cols = _end_columns_cached(float(frequency_hz), float(damping_ratio), fs, float(cutoff_hz), END_GRID_SAMPLES, span)
    data = y[lo:hi + 1]
    n = np.arange(lo, hi + 1, dtype=float)
    design, ts_all = _end_designs(cols, span, lo, k_lo, k_hi, n, sign)
    gram = np.swapaxes(design, 1, 2) @ design
    rhs = np.swapaxes(design, 1, 2) @ data
    ridge = 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(gram.shape[-1])  # never singular
    coef = np.linalg.solve(gram + ridge + 1e-300, rhs[..., None])[..., 0]
    sse_all = np.sum((data[None, :] - (design @ coef[..., None])[..., 0]) ** 2, axis=1)
    i_best = int(np.argmin(sse_all))
    best = np.concatenate([[0.0], coef[i_best]]) if sign < 0 else coef[i_best]
    sse, end, a, b = float(sse_all[i_best]), float(ts_all[i_best]), float(best[0]), float(best[1])
    if not (k_lo < end < k_hi):  # at the edge of the candidates: no end inside them
        return None
    resid2 = sse / max(data.size - design.shape[-1] - 1, 1)
    # the ends whose fit is worse by less than one residual variance per independent sample of the
    # low-passed noise (correlated over about 1 / sum(taps^2) samples): a standard uncertainty
    rise = resid2 / float(np.sum(taps ** 2))
    spread = float(np.max(np.abs(ts_all[sse_all <= sse + rise] - end)))
    # the force the fit says is there, less what the chain made of it: the kernel's spread and the undoing's
    # transient at the end, to be added back to the low-passed force over the window
    q = float(best[2]) if best.size > 2 else 0.0
    u = (n - end) * sign
    model = np.where(u >= 0, a + b * u + q * u * u, 0.0)
    correction = model - design[i_best] @ coef[i_best]
    noise_se = math.nan
    if noise_rms is not None:
        # the model's change with the end, its linear terms held: central differences on the grid (the best end is
        # inside the candidates, so both neighbours are on it)
        d_end = (design[i_best + 1] - design[i_best - 1]) @ coef[i_best] / (2.0 * END_GRID_SAMPLES)
        noise_se = _end_noise_se(np.column_stack([d_end, design[i_best]]), sse,
                                 _undone_noise_autocorrelation(float(frequency_hz), float(damping_ratio), fs,
                                                               float(cutoff_hz)), float(noise_rms))
    return UndoneEnd(float(end), float(b), float(a), math.sqrt(resid2), float(spread), int(lo), correction,
                     float(noise_se))


def _checked_end_arguments(sample_rate_hz, frequency_hz, damping_ratio, cutoff_hz, side, inside_samples,
                           reach_samples) -> float:
    """The arguments of :func:`undone_end` checked (ValueError naming the bad one); the sample rate [Hz]."""
    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not cutoff_hz > 0:
        raise ValueError(f"cutoff_hz must be positive, got {cutoff_hz!r}")
    if not (frequency_hz > 0 and 0 <= damping_ratio < 1):
        raise ValueError(f"need frequency_hz > 0 and 0 <= damping_ratio < 1, got {frequency_hz!r}, {damping_ratio!r}")
    if side not in ("start", "end"):
        raise ValueError(f"side must be 'start' or 'end', got {side!r}")
    if int(inside_samples) < 2:
        raise ValueError(f"inside_samples must be at least 2, got {inside_samples!r}")
    if int(reach_samples) < 1:
        raise ValueError(f"reach_samples must be at least 1, got {reach_samples!r}")
    return fs


def _end_window(index, w, side, inside, reach):
    """The candidates ts from k_lo to k_hi (the start's side) and the window fitted from lo to hi [samples], for the
    end found at ``index`` and a kernel of half-width ``w`` [samples]."""
    if side == "start":
        k_lo, k_hi = int(math.floor(index)) - w - reach, int(math.ceil(index)) + 2 * w + reach
        return k_lo, k_hi, k_lo - w - 3, k_hi + w + inside
    k_lo, k_hi = int(math.floor(index)) - 2 * w - reach, int(math.ceil(index)) + w + reach
    return k_lo, k_hi, k_lo - w - inside, k_hi + w + 3


def _end_designs(cols, span, lo, k_lo, k_hi, n, sign):
    """The design of every candidate ts = k + frac at once (jump, line, parabola through the chain; for an end
    ``sign`` < 0 its line and parabola only) [ts, n, term], and the candidates [samples]."""
    fracs = np.arange(0.0, 1.0 - 1e-9, END_GRID_SAMPLES)
    ks = np.arange(k_lo, k_hi + 1)
    idx = (lo - ks + span)[:, None] + np.arange(n.size)[None, :]  # column index of sample n for each k
    design = np.stack([cols[:, i, :][:, idx] for i in range(3)], axis=-1)  # [frac, k, n, term]
    design = np.swapaxes(design, 0, 1).reshape(-1, n.size, 3)  # ts = k + frac, k-major
    ts_all = (ks[:, None] + fracs[None, :]).ravel()
    if sign < 0:  # an end: Q(t) (1 - H(t - ts)), Q = a - b (t - ts) + q (t - ts)^2 for all t
        parabola = np.swapaxes(cols[:, 3, :][:, idx], 0, 1).reshape(-1, n.size)
        design = np.stack([1.0 - design[..., 0], (ts_all[:, None] - n[None, :]) + design[..., 1],
                           parabola - design[..., 2]], axis=-1)
        return design[..., 1:END_TERMS], ts_all  # a ball's force falls to zero continuously as it leaves: no jump
    return design[..., :END_TERMS], ts_all


def _end_noise_se(jac: np.ndarray, sse: float, autocorrelation: np.ndarray, noise_rms: float) -> float:
    """Standard uncertainty of an end fitted by least squares in noise the plate's undoing has coloured [samples].

    ``jac`` [n, 1 + terms] holds the fitted force's derivative with respect
    to the end [unit of the force per sample] and the fit's linear columns
    [-, samples, samples^2] over the window's n samples. The undone (and
    low-passed) force's noise is the sensed white noise ``noise_rms`` passed
    through the chain, so its covariance is ``noise_rms^2 R`` with R the
    Toeplitz matrix of the chain's impulse response's ``autocorrelation``
    (lag 0 first): strongly correlated (the inverse amplifies the noise near
    and above the resonance by up to ``(fs / 2 fn)^2``, the low-pass keeps
    what lies below its cutoff), which no residual over the window shows
    (a whole stretch of samples moves together). The ordinary least squares'
    covariance is then the sandwich ``A^-1 J^T C J A^-1`` (A = J^T J,
    linearised at the fit: ordinary least squares in correlated noise), and its
    first diagonal element the end's variance. The noise variance is raised by
    the residual sum of squares ``sse`` over what that noise alone leaves
    (``noise_rms^2 tr((I - P) R)``, P the fit's hat matrix) where larger: a
    force the model does not fit: the fit's residual alone can allow half a
    sample for an end that is two samples off.
    """
    n = jac.shape[0]
    if autocorrelation.size < n:
        autocorrelation = np.concatenate([autocorrelation, np.zeros(n - autocorrelation.size)])
    lag = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    cov = autocorrelation[lag]  # [n, n], in units of the sensed noise's variance
    gram = jac.T @ jac
    scale = np.sqrt(np.diag(gram))
    if not np.all(scale > 0) or not np.all(np.isfinite(scale)):
        return math.inf
    jn = jac / scale  # columns of unit norm: the solve is well conditioned whatever the terms' units
    try:
        inv = np.linalg.inv(jn.T @ jn)
    except np.linalg.LinAlgError:
        return math.inf
    meat = jn.T @ cov @ jn
    sandwich = inv @ meat @ inv
    expected = float(np.trace(cov) - np.trace(inv @ meat))  # tr((I - P) R): the residual noise alone leaves
    variance = noise_rms * noise_rms * max(1.0, sse / (noise_rms * noise_rms * expected)) \
        if noise_rms > 0 and expected > 0 else sse / max(expected, 1e-300)
    se2 = variance * float(sandwich[0, 0]) / float(scale[0] ** 2)
    return math.sqrt(se2) if se2 >= 0 and math.isfinite(se2) else math.inf


@functools.lru_cache(maxsize=16)
def _undone_noise_autocorrelation(frequency_hz: float, damping_ratio: float, fs: float, cutoff_hz: float) -> np.ndarray:
    """Autocorrelation of the impulse response of the plate's inverse and the low-pass, lag 0 first [-]: the
    undone force's noise covariance over the sensed white noise's variance, at each lag [samples]."""
    half = NOISE_RESPONSE_HALF + (0 if math.isinf(cutoff_hz) else int(math.ceil(0.5 * fs / cutoff_hz)))
    h = undone_impulse_response(fs, frequency_hz, damping_ratio, half, cutoff_hz)
    full = np.correlate(h, h, mode="full")
    return full[h.size - 1:].copy()


@functools.lru_cache(maxsize=16)
def _end_columns_cached(frequency_hz: float, damping_ratio: float, fs: float, cutoff_hz: float, step: float,
                        span: int):
    """:func:`_end_columns` for one plate [Hz, -], sample rate and cutoff [Hz], grid and span, kept for reuse."""
    taps = np.ones(1) if math.isinf(cutoff_hz) else lowpass_kernel(fs, cutoff_hz)
    return _end_columns(frequency_hz, damping_ratio, fs, taps, step, span)
