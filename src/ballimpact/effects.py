"""Effects of what a check saw on TC, kCAL and the peak: first-order bounds from the conditioned signal."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["END_SLOPE_S", "LINE_FIT_S", "end_slopes", "line_amplitude_after", "ringing_effects"]

#: The force's slope at an end is read over this long inside it [s].
END_SLOPE_S = 0.1e-3
#: A line's amplitude at the contact's end is fitted over this long after it [s].
LINE_FIT_S = 1.0e-3


def end_slopes(x, fs: float, start_u: float, end_u: float, *, over_s: float = END_SLOPE_S) -> tuple[float, float]:
    """The force's slope at the contact's start and end [V/s], read over ``over_s`` inside each end.

    Parameters
    ----------
    x : array_like
        Conditioned voltage, proportional to the force [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's start and end in samples from ``x[0]`` [samples].
    over_s : float
        How far inside each end the slope is read [s].

    Returns
    -------
    (float, float)
        The absolute slope at the start and at the end [V/s]; NaN where the contact is too short or the end lies
        outside ``x``. At an end where the force jumps between samples the slope is that jump over one sample.
    """
    x = np.asarray(x, dtype=float)
    m = max(int(round(over_s * fs)), 1)
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    if not (0 <= i0 and i1 < x.size and i1 - i0 >= 2 * m):
        return math.nan, math.nan
    start = max(abs(float(x[i0 + m] - x[i0])) / m, abs(float(x[i0])) / max(i0 - start_u, 1.0)) * fs
    end = max(abs(float(x[i1 - m] - x[i1])) / m, abs(float(x[i1])) / max(end_u - i1, 1.0)) * fs
    return start, end


def line_amplitude_after(x, fs: float, end_u: float, line_hz: float, noise_V: float, *,
                         over_s: float = LINE_FIT_S) -> float:
    """Amplitude of a sinusoid at ``line_hz`` fitted to the signal just after the contact, plus two standard errors.

    After the contact the force is zero, so what stands there is the plate's ringing and noise: its amplitude at
    the line's frequency bounds the ringing at the contact's end.

    Parameters
    ----------
    x : array_like
        Conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    end_u : float
        The contact's end in samples from ``x[0]`` [samples].
    line_hz : float
        The line's frequency [Hz].
    noise_V : float
        Noise standard deviation [V].
    over_s : float
        How long after the end the fit runs [s].

    Returns
    -------
    float
        Fitted amplitude + 2 of its standard errors [V]; NaN when fewer than 8 samples follow the end.
    """
    x = np.asarray(x, dtype=float)
    a = int(math.ceil(end_u)) + 1
    b = min(a + max(int(round(over_s * fs)), 8), x.size)
    if b - a < 8 or not (line_hz > 0):
        return math.nan
    t = np.arange(a, b) / fs
    w = 2.0 * math.pi * line_hz
    basis = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(basis, x[a:b], rcond=None)
    se = (noise_V if math.isfinite(noise_V) else 0.0) * math.sqrt(2.0 / (b - a))
    return float(math.hypot(coef[0], coef[1]) + 2.0 * se)


def ringing_effects(x, fs: float, start_u: float, end_u: float, noise_V: float, line_hz: float,
                    line_amplitude_V: float) -> dict:
    """First-order bounds of what a spectral line of the plate does to TC, kCAL and the peak [-, relative].

    A line of amplitude A added to the force moves an end where the force falls with slope s by at most A / s;
    it moves the largest sample by at most A; its integral over any stretch is at most A / (pi f), against the
    contact's integral. A is the larger of the line's amplitude in the contact and the sinusoid fitted after the
    contact (:func:`line_amplitude_after`), so that a line still ringing at the end is counted at its size there.

    Parameters
    ----------
    x : array_like
        Conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's ends in samples from ``x[0]`` [samples].
    noise_V : float
        Noise standard deviation [V].
    line_hz, line_amplitude_V : float
        The line's frequency [Hz] and amplitude in the contact [V].

    Returns
    -------
    dict
        ``contact_time``, ``kcal``, ``peak``: bounds of the relative effects [-]; NaN (not known) where the contact
        or its slopes cannot be read.
    """
    x = np.asarray(x, dtype=float)
    nan = {"contact_time": math.nan, "kcal": math.nan, "peak": math.nan}
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    if not (0 <= i0 < i1 < x.size and line_hz > 0 and line_amplitude_V >= 0):
        return nan
    after = line_amplitude_after(x, fs, end_u, line_hz, noise_V)
    amp = max(line_amplitude_V, after) if math.isfinite(after) else math.nan
    s_start, s_end = end_slopes(x, fs, start_u, end_u)
    peak = float(np.max(x[i0:i1 + 1]))
    integral = float(np.sum(x[i0:i1 + 1])) / fs
    tc = (end_u - start_u) / fs
    if not (math.isfinite(amp) and peak > 0 and integral > 0 and tc > 0 and s_start > 0 and s_end > 0):
        return nan
    return {
        "contact_time": (line_amplitude_V / s_start + amp / s_end) / tc,
        "kcal": amp / (math.pi * line_hz) / integral,
        "peak": amp / peak,
    }


def finding_effects(problem, siblings, voltage_V, fs: float, start_u: float, end_u: float, noise_V: float):
    """``problem`` with the effects of what it saw estimated, where its check can estimate them.

    A spectral line of the plate (a PLATE_RINGING finding with ``line_hz`` and ``amplitude_fraction`` in its
    data) gets :func:`ringing_effects`. A plate identified but not undone (``undo_refused``) gets the effects of
    the line among ``siblings`` when that line is all the evidence of ringing (no ringing after the contact, no
    force below zero, no peak on ringing): what was not undone is then the line itself. Any other finding is
    returned as it is.

    Parameters
    ----------
    problem : ballimpact.problems.Problem
        The finding.
    siblings : sequence of ballimpact.problems.Problem
        Every finding of the same conditioned signal (``problem`` among them).
    voltage_V : array_like
        The conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's ends in samples from ``voltage_V[0]`` [samples].
    noise_V : float
        Noise standard deviation [V].

    Returns
    -------
    ballimpact.problems.Problem
    """
    from dataclasses import replace

    from .problems import ProblemKind

    def line_effects(p):
        x = np.asarray(voltage_V, dtype=float)
        i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
        if not (0 <= i0 < i1 < x.size):
            return {}
        amp = float(p.data["amplitude_fraction"]) * float(np.max(x[i0:i1 + 1]))
        return ringing_effects(x, fs, start_u, end_u, noise_V, float(p.data["line_hz"]), amp)

    if problem.kind is not ProblemKind.PLATE_RINGING or problem.effects:
        return problem
    if "line_hz" in problem.data:
        return replace(problem, effects=line_effects(problem))
    if "undo_refused" in problem.data:
        ringing = [p for p in siblings if p.kind in (ProblemKind.PLATE_RINGING, ProblemKind.NEGATIVE_FORCE,
                                                     ProblemKind.PEAK_ON_RINGING) and p is not problem]
        lines = [p for p in ringing if "line_hz" in p.data]
        if lines and len(lines) == len(ringing):
            effects = [line_effects(p) for p in lines]
            return replace(problem, effects={q: float(np.max([e.get(q, math.nan) for e in effects]))
                                             for q in ("contact_time", "kcal", "peak")})
    return problem
