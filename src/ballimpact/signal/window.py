"""The contact window and the baseline fitted around it in turn, other events masked, until they stop moving."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..problems import Problem, ProblemKind
from .baseline import (UNDERSHOOT_SIGNIFICANCE, BaselineFit, choose_tau, decay_correct, fit_baseline, integral_start,
                       integral_to, running_integral)
from .contact import ContactResult, ContactSearch

__all__ = ["event_threshold", "iterate"]

MAX_ITERATIONS = 8  # contact window / baseline iterations [-]
CONVERGED_SAMPLES = 0.01  # window change that ends the iteration [samples]
UNSTABLE_SAMPLES = 0.5  # still moving by more after MAX_ITERATIONS: a problem [samples]
MAINS_AMBIGUOUS_BIC = 10.0  # 50 and 60 Hz fits closer than this in BIC are not told apart [-]
EVENT_SIGMA = 6.0  # an event stands this many noise deviations out of the corrected record [-]
#: ... and reaches this fraction of the main peak [-]: low enough for a second contact of about a per cent, half
#: taken up by the hum fitted over a short record, to stand out and be masked (left in, it bends that hum under the
#: contact). Not lower than about twice FLAT_FRACTION: an oscillation (ringing, hum not resolved) has its positive
#: swings taken for events, and the quiet residual's check must still see it.
EVENT_FRACTION = 0.005
EVENT_GUARD_BEFORE_S = 0.5e-3  # samples this long before an event are left out of the fit [s]
EVENT_GUARD_AFTER_S = 2.0e-3  # ... and this long after it (ringing) [s]
#: An event's samples run on, either side of where it stands out as one, while the corrected record stays this many
#: noise deviations above zero [-]: the shoulders of a second contact (its rise and fall out of the noise), left
#: in the fit, bend the hum fitted under the main contact as the whole of it does.
EVENT_SHOULDER_SIGMA = 3.0


def event_threshold(noise, peak) -> float:
    """The level an event of the corrected record stands above: EVENT_SIGMA noise deviations and EVENT_FRACTION of
    the main peak (``noise`` and ``peak`` in one unit, the threshold in it)."""
    return max(EVENT_SIGMA * noise, EVENT_FRACTION * peak)


def _event_mask(x, fs, noise, contact: ContactResult, pre_guard, post_guard):
    """Samples of every event other than the main contact (runs standing out of the noise), with guards."""
    n = x.size
    peak = max(float(x[contact.peak_index]), 0.0) if contact.found else float(np.max(x))
    thr = event_threshold(noise, peak)
    above = x > thr
    if contact.found:
        a = max(int(math.floor((contact.start_s - 0.0) * fs - pre_guard)), 0)
        b = min(int(math.ceil(contact.end_s * fs + post_guard)) + 1, n)
        above[a:b] = False
    mask = np.zeros(n, dtype=bool)
    if not above.any():
        return mask
    # each event with its shoulders: the run of samples above EVENT_SHOULDER_SIGMA noise around its core
    shoulder = x > EVENT_SHOULDER_SIGMA * noise
    if contact.found:
        shoulder[a:b] = False
    d = np.diff(np.concatenate([[0], shoulder.view(np.int8), [0]]))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    cores = np.flatnonzero(above)
    keep = np.unique(np.searchsorted(starts, cores, side="right") - 1)  # the shoulder run holding each core sample
    gb, ga = int(round(EVENT_GUARD_BEFORE_S * fs)), int(round(EVENT_GUARD_AFTER_S * fs))
    for s, e in zip(starts[keep], ends[keep]):
        mask[max(s - gb, 0):min(e + ga, n)] = True
    return mask


@dataclass
class _Iteration:
    """Where the window / baseline iteration of :func:`condition_voltage` ended."""

    x: np.ndarray  # decay-corrected signal [scaled V]
    fit: BaselineFit
    tau: float
    source: str
    pending: list
    tau_problems: list
    problems: list
    mains: float
    ambiguous: tuple | None
    start_u: float
    end_u: float
    n_iter: int
    contact_integral: float
    search: ContactSearch  # the contact's search on x (with fit's noise)
    never_measured: bool = False  # the decay's kappa was never significant on the way (or not fitted)


def _fit_candidates(v, fs, candidates, start_u, end_u, pre_guard, post_guard, mask, kappa_given, noise_floor,
                    cache=None):
    """The baseline fit of each mains candidate; the best by BIC, its frequency, and an ambiguity (or None)."""
    fits = {f: fit_baseline(v, fs, fr, start_u, end_u, pre_guard, post_guard, mask, True, kappa_given,
                             noise_floor=noise_floor, cache=cache)
            for f, fr in candidates.items()}
    mains = min(fits, key=lambda f: fits[f].bic)
    fit = fits[mains]
    hum = [f for f in fits if f > 0]
    ambiguous = None
    if mains > 0 and fits[mains].hum_amplitudes:
        other = [f for f in hum if f != mains][0]
        if not fits[other].hum_amplitudes:
            ambiguous = (mains, other, None)  # the quiet stretch is too short for the other frequency
        elif fits[other].bic - fit.bic < MAINS_AMBIGUOUS_BIC:
            ambiguous = (mains, other, fits[other].baseline)
    return fit, mains, ambiguous


def iterate(v, fs, candidates, rough, pre_guard, post_guard, tau_s, kappa_given, scale, noise_floor) -> _Iteration:
    """Contact window, event mask and baseline (with the decay) fitted in turn until they stop moving.

    Where they do not, and the decay was never measurable on the way (its kappa within UNDERSHOOT_SIGNIFICANCE
    standard errors of zero at every window: a record too short after the contact for the undershoot, whose
    insignificant kappa flips with the quiet samples each window leaves), they are fitted again with no decay,
    which a window does not move: the decay's effect on the impulse is charged as it was (the last window's
    undershoot not measurable).
    """
    it = _iterate(v, fs, candidates, rough, pre_guard, post_guard, tau_s, kappa_given, scale, noise_floor)
    if not (it.problems and it.never_measured and tau_s is None and kappa_given is None):
        return it
    still = _iterate(v, fs, candidates, rough, pre_guard, post_guard, tau_s, 0.0, scale, noise_floor)
    if still.problems:
        return it
    still.pending, still.tau_problems = it.pending, it.tau_problems
    still.fit = _measured(still.fit, it.fit)
    return still


def _measured(fit: BaselineFit, free: BaselineFit) -> BaselineFit:
    """``fit`` (without the decay) giving the undershoot ``free`` measured: its kappa and standard error [1/s]."""
    coef = {**fit.coef, "kappa_per_s": free.kappa, "kappa_se_per_s": free.kappa_se}
    return dataclasses.replace(fit, kappa=free.kappa, kappa_se=free.kappa_se, coef=coef)


def _less_baseline(v, fs, fit: BaselineFit, start_u, end_u):
    """The record less ``fit``'s baseline, its running integral from the contact's start and its integral over the
    contact [unit, unit s, unit s]."""
    y = v - fit.baseline
    running = running_integral(y, fs, start_u)
    return y, running, integral_to(running, start_u, end_u)


def _iterate(v, fs, candidates, rough, pre_guard, post_guard, tau_s, kappa_given, scale, noise_floor) -> _Iteration:
    """The iteration of :func:`iterate` (``kappa_given`` 0: no decay)."""
    start_u, end_u = rough.start_s * fs, rough.end_s * fs
    mask = np.zeros(v.size, dtype=bool)
    problems: list[Problem] = []
    mains = next(iter(candidates))
    ambiguous: tuple | None = None
    windows = [(start_u, end_u)]
    # the fits made, and the last corrected signal and its contact: a window that moved by a fraction of a sample
    # often gives the same fit and the same signal again, whose contact is then known
    cache: dict = {}
    made_from: tuple = ()  # the fit (its baseline), tau and the sample the decay's integral starts at of x and search
    never_measured = True  # no fit's kappa stood out of its standard errors
    for n_iter in range(1, MAX_ITERATIONS + 1):
        if len(candidates) > 1 and n_iter <= 3:
            fit, mains, ambiguous = _fit_candidates(v, fs, candidates, start_u, end_u, pre_guard, post_guard, mask,
                                                    kappa_given, noise_floor, cache)
        else:
            fit = fit_baseline(v, fs, candidates[mains], start_u, end_u, pre_guard, post_guard, mask, True,
                                kappa_given, noise_floor=noise_floor, cache=cache)
        base = fit  # the fit whose baseline x is made from
        y, running, contact_integral = _less_baseline(v, fs, base, start_u, end_u)
        tau, source, pending, tau_problems = choose_tau(tau_s, fit, contact_integral, (end_u - start_u) / fs,
                                                         scale)
        never_measured &= not abs(fit.kappa) > UNDERSHOOT_SIGNIFICANCE * fit.kappa_se
        if not math.isfinite(tau) and kappa_given is None and fit.kappa != 0 and math.isfinite(fit.kappa):
            # the decay is not corrected: the baseline must not carry the level the rejected kappa put after the
            # contact (a kappa below zero puts the quiet record after it above the baseline, where it reads as force)
            base = fit_baseline(v, fs, candidates[mains], start_u, end_u, pre_guard, post_guard, mask, True, 0.0,
                                noise_floor=noise_floor, cache=cache)
            fit = _measured(base, fit)
            y, running, contact_integral = _less_baseline(v, fs, base, start_u, end_u)
        i0 = integral_start(start_u) if math.isfinite(tau) else -1
        if not (made_from and made_from[0] is base and made_from[1:] == (tau, i0)):
            x = decay_correct(y, running, tau)
            search = ContactSearch(x, fs, noise_rms_V=base.noise)
            made_from = (base, tau, i0)
        c = search.result()
        if not c.found:
            break
        new_mask = _event_mask(x, fs, fit.noise, c, pre_guard, post_guard)
        new_start, new_end = c.start_s * fs, c.end_s * fs
        moved = max(abs(new_start - start_u), abs(new_end - end_u))
        same_mask = np.array_equal(new_mask, mask)
        start_u, end_u, mask = new_start, new_end, new_mask
        windows.append((start_u, end_u))
        if moved < CONVERGED_SAMPLES and same_mask and not (len(candidates) > 1 and n_iter < 2):
            break
    else:
        if c.found and moved > UNSTABLE_SAMPLES:
            (a0, b0), (a1, b1) = windows[-2], windows[-1]
            problems.append(Problem(ProblemKind.CONTACT_UNSTABLE,
                                    f"contact window not stable under the baseline fit: its ends still move by "
                                    f"{moved:.2g} samples after {MAX_ITERATIONS} iterations (last from "
                                    f"{1e3 * a0 / fs:.4g}-{1e3 * b0 / fs:.4g} ms to {1e3 * a1 / fs:.4g}-"
                                    f"{1e3 * b1 / fs:.4g} ms of the record: the decay, drift and hum fitted "
                                    "around each window move it)"))
    return _Iteration(x, fit, tau, source, pending, tau_problems, problems, mains, ambiguous, start_u, end_u, n_iter,
                      contact_integral, search, never_measured)
