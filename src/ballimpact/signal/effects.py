"""Effects of what a check saw on TC, kCAL and the peak: first-order bounds from the conditioned signal."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..problems import ProblemKind
from .end_checks import PLATE_SLOPE_S
from .noise import robust_noise
from .ringing import RING_LINE_MIN_HZ

__all__ = ["END_SLOPE_S", "LINE_FIT_S", "RINGING_AFTER_S", "DEPARTURE_WINDOW_S", "DEPARTURE_SIGMA",
           "DEPARTURE_CHAIN_SIGMA", "DEPARTURE_GAP_S", "DEPARTURE_SKIP", "DEPARTURE_SWING", "end_slopes",
           "line_amplitude_after", "ringing_effects", "rounding_effects", "level_effects", "ringing_after",
           "finding_effects", "aliased_plate_effects", "window_effects", "departure_before_start"]

#: The force's slope at an end is read over this long inside it [s] (as the conditioning reads it).
END_SLOPE_S = PLATE_SLOPE_S
#: A line's amplitude at the contact's end is fitted over this long after it [s].
LINE_FIT_S = 1.0e-3
#: What stands after the contact's end is taken for ringing when a damped sinusoid and a level explain this long of
#: it [s] ...
RINGING_AFTER_S = 2.0e-3
#: ... to within this many times the noise's variance per sample, with the level under this many standard errors
RINGING_RESIDUAL = 1.5
RINGING_LEVEL_SIGMA = 3.0
#: ... and the line's frequency at or above this [Hz]
RINGING_MIN_HZ = 500.0
#: The signal this long before the contact's start is searched for where it departs from the noise ... [s]
DEPARTURE_WINDOW_S = 0.5e-3
#: ... a departure: a sample this many of the quiet signal's noise deviations from zero ... [-]
DEPARTURE_SIGMA = 4.5
#: ... reached from the start through samples beyond this many deviations ... [-]
DEPARTURE_CHAIN_SIGMA = 3.0
#: ... none further apart than this [s]; the samples this close to the start are not looked at (its sub-sample
#: place, and the transient an undone plate leaves in the sample interval of a jump) [samples]
DEPARTURE_GAP_S = 0.05e-3
DEPARTURE_SKIP = 2
#: A positive run before the start whose stretch to it swings below zero by this fraction of its height is ringing,
#: not a foot of force [-]
DEPARTURE_SWING = 0.5
#: A ringing that no identification finds out of the noise is at most this many noise deviations [-]
UNSEEN_RING_SIGMA = 3.0
#: An identified resonance is the line's when their frequencies agree to this fraction [-]
EXCITED_MATCH = 0.1
#: damping rates tried for the sinusoid [1/s]
_DECAY_RATES = (0.0, 250.0, 500.0, 1000.0, 2000.0, 4000.0, 8000.0)


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
        outside ``x``. The chord over ``over_s`` is never steeper than the force's edge at a jump, so that a
        bound divided by it is never too small.
    """
    x = np.asarray(x, dtype=float)
    m = max(int(round(over_s * fs)), 1)
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    if not (0 <= i0 and i1 < x.size and i1 - i0 >= 2 * m):
        return math.nan, math.nan
    return abs(float(x[i0 + m] - x[i0])) / m * fs, abs(float(x[i1 - m] - x[i1])) / m * fs


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

    A line of amplitude A added to the force moves an end where the force falls with slope s by at most A / s
    (s read as a chord over END_SLOPE_S, less the 2 A the line can add to that chord);
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
    # the line on the chord itself moves it by up to 2 A over END_SLOPE_S: the slopes' lower bounds
    return _amplitude_effects(x, fs, start_u, end_u, (line_amplitude_V, amp), 2.0 * amp,
                              amp / (math.pi * line_hz))


def _amplitude_effects(x, fs, start_u, end_u, at_ends, on_chord, area) -> dict:
    """Bounds of what a signal of amplitude ``at_ends`` (start, end) [V] added to the force does to TC (each over
    the force's slope there, read as a chord over END_SLOPE_S less the ``on_chord`` [V] it can add to it), kCAL (its
    ``area`` [V s] over the contact's integral) and the peak (the larger amplitude over it) [-]; NaN where the
    contact or its slopes cannot be read."""
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    s_start, s_end = (s - on_chord / END_SLOPE_S for s in end_slopes(x, fs, start_u, end_u))
    peak = float(np.max(x[i0:i1 + 1]))
    integral = float(np.sum(x[i0:i1 + 1])) / fs
    tc = (end_u - start_u) / fs
    if not (math.isfinite(on_chord) and peak > 0 and integral > 0 and tc > 0 and s_start > 0 and s_end > 0):
        return {"contact_time": math.nan, "kcal": math.nan, "peak": math.nan}
    return {"contact_time": (at_ends[0] / s_start + at_ends[1] / s_end) / tc, "kcal": area / integral,
            "peak": max(at_ends) / peak}


def rounding_effects(x, fs: float, start_u: float, end_u: float, rounding_s: float) -> dict:
    """First-order bounds of what a band limit that rounds the contact's jump does to TC and kCAL [-, relative].

    A band limit B (a filter's cut-off, a plate's resonance) spreads the force's jump at first contact over about
    half its period, ``rounding_s`` = 1 / (2 B), unseen by the checks of the ends where the front is all it
    rounded. Each end read off the rounded force may then move by up to that much: TC by at most
    ``rounding_s`` / TC (on an anti-aliasing filter at 9 kHz sampled at 21.5 kHz, rounding 1.7 % of TC, TC came
    out 1.5 % long: ``python bench/antialias_map.py``); the contact's integral by at most the force's area within
    ``rounding_s`` inside each end (the largest sample there times ``rounding_s``), against the whole integral.

    Parameters
    ----------
    x : array_like
        Conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's ends in samples from ``x[0]`` [samples].
    rounding_s : float
        How far the band limit spreads the jump [s].

    Returns
    -------
    dict
        ``contact_time`` and ``kcal``: bounds of the relative effects [-]; NaN (not known) where the contact cannot
        be read.
    """
    x = np.asarray(x, dtype=float)
    nan = {"contact_time": math.nan, "kcal": math.nan}
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    if not (0 <= i0 < i1 < x.size and fs > 0 and rounding_s >= 0):
        return nan
    tc = (end_u - start_u) / fs
    integral = float(np.sum(x[i0:i1 + 1])) / fs
    k = int(math.ceil(rounding_s * fs)) + 1
    inside = float(np.max(x[i0:min(i0 + k, i1 + 1)])) + float(np.max(x[max(i1 + 1 - k, i0):i1 + 1]))
    if not (tc > 0 and integral > 0):
        return nan
    return {"contact_time": rounding_s / tc, "kcal": max(inside, 0.0) * rounding_s / integral}


def level_effects(x, fs: float, start_u: float, end_u: float, level_V: float) -> dict:
    """First-order bounds of what a baseline uncertain by ``level_V`` under the contact does to TC, kCAL and the peak.

    A level L left under the force moves an end where the force falls with slope s by at most L / s (s read as a
    chord over END_SLOPE_S inside it, less the L the level can add to that chord); the largest sample by at most
    L; the contact's integral by at most L TC [-, relative].

    Parameters
    ----------
    x : array_like
        Conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's ends in samples from ``x[0]`` [samples].
    level_V : float
        The level's size [V].

    Returns
    -------
    dict
        ``contact_time``, ``kcal``, ``peak``: bounds of the relative effects [-]; NaN (not known) where the contact
        or its slopes cannot be read.
    """
    x = np.asarray(x, dtype=float)
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    level = abs(float(level_V))
    if not (0 <= i0 < i1 < x.size and math.isfinite(level)):
        return {"contact_time": math.nan, "kcal": math.nan, "peak": math.nan}
    return _amplitude_effects(x, fs, start_u, end_u, (level, level), level, level * (end_u - start_u) / fs)


def ringing_after(x, fs: float, end_u: float, noise_V: float, *, over_s: float = RINGING_AFTER_S):
    """A damped line that explains what stands after the contact's end: (frequency [Hz], amplitude at the end [V]).

    The signal over ``over_s`` after the end is fitted with a level and a sinusoid damped at each of a few rates, at
    the frequency of its largest spectral amplitude above RINGING_MIN_HZ. It is ringing, not force, when the best fit
    leaves at most RINGING_RESIDUAL noise variances per sample and its level is under RINGING_LEVEL_SIGMA standard
    errors: a force's tail is one-signed and has a level, a plate's ringing swings about zero.

    Parameters
    ----------
    x : array_like
        Conditioned voltage [V].
    fs : float
        Sample rate [Hz].
    end_u : float
        The contact's end in samples from ``x[0]`` [samples].
    noise_V : float
        Noise standard deviation [V].
    over_s : float
        How long after the end is fitted [s].

    Returns
    -------
    tuple of float or None
        None when it is not ringing, or there are too few samples to tell.
    """
    x = np.asarray(x, dtype=float)
    a = int(math.ceil(end_u)) + 1
    b = min(a + int(round(over_s * fs)), x.size)
    if b - a < 16 or not (noise_V > 0):
        return None
    seg = x[a:b]
    n = seg.size
    amp = np.abs(np.fft.rfft((seg - seg.mean()) * np.hanning(n), 8 * n))
    f = np.fft.rfftfreq(8 * n, 1.0 / fs)
    band = np.flatnonzero((f >= RINGING_MIN_HZ) & (f <= 0.45 * fs))
    if band.size == 0:
        return None
    line_hz = float(f[band[np.argmax(amp[band])]])
    t = np.arange(n) / fs + (a - end_u) / fs
    w = 2.0 * math.pi * line_hz
    best = None
    for rate in _DECAY_RATES:
        env = np.exp(-rate * t)
        basis = np.column_stack([env * np.sin(w * t), env * np.cos(w * t), np.ones(n)])
        coef, *_ = np.linalg.lstsq(basis, seg, rcond=None)
        rss = float(np.sum((seg - basis @ coef) ** 2))
        if best is None or rss < best[0]:
            cov = np.linalg.pinv(basis.T @ basis)
            best = (rss, coef, math.sqrt(max(cov[2, 2], 0.0)) * noise_V)
    rss, coef, level_se = best
    if rss > RINGING_RESIDUAL * (n - 3) * noise_V * noise_V or abs(coef[2]) > RINGING_LEVEL_SIGMA * level_se:
        return None
    return line_hz, float(math.hypot(coef[0], coef[1]))


def finding_effects(problem, siblings, voltage_V, fs: float, start_u: float, end_u: float, noise_V: float):
    """``problem`` with the effects of what it saw estimated, where its check can estimate them.

    A contact end not determined (CONTACT_END_UNDETERMINED) also gets its effect on kCAL where the span the end
    may move by is known (``span_s`` or ``departure_s`` in its data): :func:`window_effects`; where it is not, kCAL
    is withheld with TC. The rest, as follows.

    A spectral line of the plate (a PLATE_RINGING finding with ``line_hz`` and ``amplitude_fraction`` in its
    data) gets :func:`ringing_effects`; so does signal standing after the contact's end (a CONTACT_END_UNDETERMINED
    finding ``beyond`` the end) where :func:`ringing_after` shows it is a damped line, not force. A plate
    identified but not undone (``undo_refused``) gets the effects of the line among ``siblings`` (on the peak
    widened by :func:`_excited_peak_factor` where the resonance is the line's) when that line is all the evidence
    of ringing (no ringing after the contact, no
    force below zero, no peak on ringing) and the resonance identified, if any, lies in the band the line check
    looks in (above RING_LINE_MIN_HZ): what was not undone is then the line itself (a 0.59 kHz plate identified and
    refused beside a faint 3 kHz line left its peak 42 % high, ok: zoo 809:3210). Where a peak on ringing
    was all the evidence, or it and lines, and no resonance came out of the noise, each quantity gets the larger of
    the lines' effects and the bound of a ringing hidden in the noise at its end (:func:`_unseen_ringing_effects`:
    kCAL and the peak not known). A step in the baseline (a
    BASELINE_STEP finding with its ``level_V``) gets :func:`level_effects` of that level where the amplifier's decay
    was given (``decay_given``): an estimated decay takes up a step next to the contact, and the step found is then
    a smaller one elsewhere (``python bench/step_map.py --n 400 --seed 1`` trace 1:114: a step of 3.5 % of the peak
    just after the contact, 0.18 % found 10 ms later, TC 6 % long). Any other finding is returned as it is.

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
    out = _check_effects(problem, siblings, voltage_V, fs, start_u, end_u, noise_V)
    if out.kind is ProblemKind.CONTACT_END_UNDETERMINED and "kcal" not in out.effects:
        data = out.data
        span = float(data.get("span_s", data.get("departure_s", math.nan)))
        start = "departure_s" in data or "start" in (data.get("end"), data.get("beyond"))
        kcal = window_effects(voltage_V, fs, start_u, end_u, noise_V, span, at_start=start)
        out = replace(out, effects={**out.effects, "kcal": kcal})
    return out


def _check_effects(problem, siblings, voltage_V, fs: float, start_u: float, end_u: float, noise_V: float):
    """:func:`finding_effects` but for kCAL's of a contact end not determined."""
    def line_effects(p):
        x = np.asarray(voltage_V, dtype=float)
        i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
        if not (0 <= i0 < i1 < x.size):
            return {}
        amp = float(p.data["amplitude_fraction"]) * float(np.max(x[i0:i1 + 1]))
        return ringing_effects(x, fs, start_u, end_u, noise_V, float(p.data["line_hz"]), amp)

    if problem.effects:
        return problem
    if problem.kind is ProblemKind.BASELINE_STEP and problem.data.get("decay_given"):
        return replace(problem, effects=level_effects(voltage_V, fs, start_u, end_u, problem.data["level_V"]))
    if problem.kind is ProblemKind.CONTACT_END_UNDETERMINED and problem.data.get("beyond") == "end":
        found = ringing_after(voltage_V, fs, end_u, noise_V)
        if found is None:
            return problem
        return replace(problem, effects=ringing_effects(voltage_V, fs, start_u, end_u, noise_V, found[0], 0.0))
    if problem.kind is not ProblemKind.PLATE_RINGING:
        return problem
    if problem.data.get("aliases") and math.isfinite(float(problem.data.get("refused_hz", math.nan))):
        return replace(problem, effects=aliased_plate_effects(voltage_V, fs, start_u, end_u,
                                                              float(problem.data["refused_hz"]),
                                                              float(problem.data["refused_zeta"])))
    if "line_hz" in problem.data:
        return replace(problem, effects=line_effects(problem))
    if "undo_refused" in problem.data:
        ringing = [p for p in siblings if p.kind in (ProblemKind.PLATE_RINGING, ProblemKind.NEGATIVE_FORCE,
                                                     ProblemKind.PEAK_ON_RINGING) and p is not problem]
        lines = [p for p in ringing if "line_hz" in p.data]
        if float(problem.data.get("refused_hz", math.inf)) < RING_LINE_MIN_HZ:
            return problem  # a resonance below the band the line check looks in: no line can show what it does
        peaks = [p for p in ringing if p.kind is ProblemKind.PEAK_ON_RINGING]
        if peaks and "refused_hz" in problem.data:
            return problem  # a resonance the force excites, its swing on the peak: what it leaves at the end unknown
        tc_s = (end_u - start_u) / fs
        each = []
        for p in lines:
            e = dict(line_effects(p))
            e["peak"] = e.get("peak", math.nan) * _excited_peak_factor(problem.data, float(p.data["line_hz"]), tc_s)
            each.append(e)
        if peaks:  # no resonance out of the noise: a ringing at the end hidden in it, beside any line's
            each.append(_unseen_ringing_effects(voltage_V, fs, start_u, end_u, noise_V))
        if each and len(lines) + len(peaks) == len(ringing):
            return replace(problem, effects={q: float(np.max([e.get(q, math.nan) for e in each]))
                                             for q in ("contact_time", "kcal", "peak")})
    return problem


def window_effects(x, fs: float, start_u: float, end_u: float, noise_V: float, span_s: float, *,
                   at_start: bool = False) -> float:
    """A bound of what a contact end that may move by ``span_s`` does to kCAL [-, relative]: the contact's integral
    gains or loses the signal over that span.

    At the end, the larger magnitude of the signal's integral over ``span_s`` inside and outside it (the force's
    fade may end earlier, leaving non-force in the contact, or later); at the start, outside it only (the start is
    where the force jumps: what follows it is force). Each plus two standard errors of white noise ``noise_V``
    summed over the span, against the contact's integral (kCAL = m (vin + vout) / integral, section 2 of Goodwill
    & Haake 2004).

    Parameters
    ----------
    x : array_like
        Conditioned voltage, proportional to the force [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's start and end in samples from ``x[0]`` [samples].
    noise_V : float
        Noise standard deviation [V].
    span_s : float
        How far the end may move [s].
    at_start : bool
        The start, not the end.

    Returns
    -------
    float
        The bound [-]; NaN where the span is not finite or the contact's integral is not positive.
    """
    x = np.asarray(x, dtype=float)
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    if not (math.isfinite(span_s) and span_s >= 0 and 0 <= i0 < i1 < x.size):
        return math.nan
    integral = float(np.sum(x[i0:i1 + 1]))
    n = max(int(math.ceil(span_s * fs)), 1)
    sides = [x[max(i0 - n, 0):i0]] if at_start else [x[max(i1 - n + 1, i0):i1 + 1], x[i1 + 1:i1 + 1 + n]]
    moved = max(abs(float(np.sum(side))) for side in sides) + 2.0 * max(noise_V, 0.0) * math.sqrt(n)
    return moved / integral if integral > 0 else math.nan


def aliased_plate_effects(x, fs: float, start_u: float, end_u: float, frequency_hz: float,
                          damping_ratio: float) -> dict:
    """TC's bound from a known plate above what the samples resolve (its ringing aliases; it cannot be undone).

    Through a plate of unit static gain a smooth force is sensed as itself delayed by 2 zeta / wn, plus terms in
    its curvature over wn^2 (negligible for a resonance several times 1 / TC): both ends move alike, and TC not.
    What differs is the start, a jump, whose whole height the plate's response first reaches half its period
    after it, and what is left at the end of the ringing the jump excited, at most the peak times
    exp(-zeta wn TC), moving the end by that over the force's slope there (:func:`end_slopes`). TC's bound is
    their sum over TC [-]; kCAL and the peak: not known (NaN). Not in the paper.

    Parameters
    ----------
    x : array_like
        Conditioned voltage, proportional to the sensed force [V].
    fs : float
        Sample rate [Hz].
    start_u, end_u : float
        The contact's start and end in samples from ``x[0]`` [samples].
    frequency_hz, damping_ratio : float
        The plate's resonance [Hz] and damping ratio [-].

    Returns
    -------
    dict
        ``{"contact_time": bound, "kcal": nan, "peak": nan}`` [-]; the bound NaN where the slope at the end is
        not known.
    """
    x = np.asarray(x, dtype=float)
    tc = (end_u - start_u) / fs
    _, s_end = end_slopes(x, fs, start_u, end_u)
    i0, i1 = int(math.ceil(start_u)), int(math.floor(end_u))
    peak = float(np.max(x[i0:i1 + 1])) if 0 <= i0 < i1 < x.size else math.nan
    wn = 2.0 * math.pi * frequency_hz
    left = peak * math.exp(-damping_ratio * wn * tc) / s_end if s_end > 0 else math.nan
    bound = (0.5 / frequency_hz + left) / tc if tc > 0 else math.nan
    return {"contact_time": float(bound), "kcal": math.nan, "peak": math.nan}


def _unseen_ringing_effects(x, fs: float, start_u: float, end_u: float, noise_V: float) -> dict:
    """TC's bound where a peak on ringing was all the evidence of a plate and no decaying oscillation stands out of
    the noise in the contact and after it: a ringing at the end, which would ring on after it, is at most
    UNSEEN_RING_SIGMA noise deviations, and moves the end by at most that over the force's slope there (the start
    is the force's jump, which the ringing follows). kCAL and the peak: not known (NaN)."""
    _, s_end = end_slopes(x, fs, start_u, end_u)
    tc = (end_u - start_u) / fs
    bound = UNSEEN_RING_SIGMA * noise_V / s_end / tc if s_end > 0 and tc > 0 and noise_V >= 0 else math.nan
    return {"contact_time": float(bound), "kcal": math.nan, "peak": math.nan}


def _excited_peak_factor(data: dict, line_hz: float, contact_time_s: float) -> float:
    """How much more a resonance the force excites may ring at the peak than its line's amplitude over the contact.

    An identified resonance (``refused_hz`` [Hz], ``refused_zeta`` [-]) is excited by the force's jump and spike, near
    where the peak stands, and decays as exp(-zeta wn t): averaged over TC, its amplitude is about A0 / (zeta wn TC)
    of its amplitude A0 there. The line's effect on the peak is taken twice that ratio, at least 2; NaN (not known)
    without a damping ratio. 1 where no resonance was identified at the line (``line_hz`` [Hz], within
    EXCITED_MATCH of it): a line alone.
    """
    if "refused_hz" not in data or not abs(float(data["refused_hz"]) / line_hz - 1.0) <= EXCITED_MATCH:
        return 1.0
    decay = float(data.get("refused_zeta", math.nan)) * 2.0 * math.pi * float(data["refused_hz"]) * contact_time_s
    return 2.0 * max(decay, 1.0) if math.isfinite(decay) else math.nan


def departure_before_start(x, fs: float, start_u: float, *, window_s: float = DEPARTURE_WINDOW_S,
                           sigma: float = DEPARTURE_SIGMA, chain_sigma: float = DEPARTURE_CHAIN_SIGMA,
                           gap_s: float = DEPARTURE_GAP_S, force_only: bool = False) -> tuple[float, float]:
    """How long before the contact's start the signal already departs from its noise [s], and that noise [V].

    Before the force starts, the conditioned signal is noise. Signal standing out of it before the start found
    is force or what the chain spread of it: a linear-phase anti-aliasing filter rings ahead of the force's jump
    (Gibbs), over its half-length, and that ringing can hide a low foot of the force (the cloth's first
    compression), so that the start is read at the jump, late by up to the foot's length. The start is then known
    only to within the span from the earliest departure to the start found: a bound on its shift, whatever made
    the departure. The departure is walked back from DEPARTURE_SKIP samples before the start through samples
    beyond ``chain_sigma`` noise deviations, none more than ``gap_s`` apart; it counts when one of them stands
    beyond ``sigma``. The noise is the quiet signal's before the window (its median absolute deviation).

    Parameters
    ----------
    x : array_like
        The conditioned force signal (undone where a plate was) [V].
    fs : float
        Sample rate [Hz].
    start_u : float
        The contact's start in samples from ``x[0]`` [samples].
    force_only : bool
        Walk back through an unbroken run of samples above the noise only (a force presses: a foot of it is
        positive and does not swing), not through the swings either side of it a filter's ringing makes: for a
        start that no longer rests on the force's foot (:mod:`ballimpact.signal.cloth`), where only a foot longer
        than it can move it. A run from which the signal to the start swings below zero by DEPARTURE_SWING of its
        height or more is that ringing (a linear-phase filter's, alternating sample to sample ahead of the jump),
        no foot.

    Returns
    -------
    (float, float)
        The span from the earliest departure to the start [s] (0: none) and the quiet signal's noise [V]; (NaN,
        NaN) when the record before the window is too short to tell the noise.
    """
    x = np.asarray(x, dtype=float)
    n, gap = max(int(round(window_s * fs)), 2), 0 if force_only else max(int(round(gap_s * fs)), 1)
    last = int(math.ceil(start_u)) - 1 - DEPARTURE_SKIP  # the last sample looked at
    quiet = x[:max(last - n, 0)]
    if quiet.size < 20 or last < 0:
        return math.nan, math.nan
    noise = robust_noise(quiet)
    if not noise > 0:
        return math.nan, math.nan
    seg = x[last - n + 1:last + 1]
    z = (seg if force_only else np.abs(seg)) / noise  # z[-1] is the last sample before the start
    earliest, strong, since = None, False, 0
    for k in range(z.size - 1, -1, -1):
        if z[k] > chain_sigma:
            earliest, strong, since = k, strong or z[k] > sigma, 0
        else:
            since += 1
            if since > gap:
                break
    if earliest is None or not strong:
        return 0.0, noise
    to_start = x[last - n + 1 + earliest:int(math.ceil(start_u))]
    if force_only and -float(np.min(to_start)) >= DEPARTURE_SWING * float(np.max(to_start)):
        return 0.0, noise  # it swings below zero by as much: a filter's ringing ahead of the jump, no foot of force
    return (start_u - (last - n + 1 + earliest)) / fs, noise
