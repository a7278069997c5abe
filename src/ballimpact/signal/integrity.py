"""Checks of the corrected signal away from the contact: level, baseline steps and bends, hum, edge events."""

from __future__ import annotations

import math

import numpy as np

from ..problems import Problem, ProblemKind
from .baseline import BaselineFit, MIN_PRE_SAMPLES, MIN_QUIET_SAMPLES, POST_GUARD_S, ROBUST_SIGMA
from .contact import ContactResult
from .noise import contact_threshold, robust_noise
from .window import event_threshold

__all__ = [
    "baseline_bend_problems",
    "edge_event_problems",
    "end_event_problems",
    "level_problems",
    "baseline_step_problems",
    "mains_problems",
    "short_record_hum",
]

MAINS_AMBIGUOUS_FRACTION = 1.0e-3  # ... and matter when their hum differs by more under the contact [-]
BASELINE_BEND_FRACTION = 0.1  # the fitted baseline departing from the line between its values at the contact's ends
#                                by more than this fraction of the peak under the contact is not known there [-]
EDGE_EVENT_MIN_S = 0.05e-3  # such an event from the record's first sample on for this long is a cut-off impact
#                             (at least 3 samples) [s]
FLAT_WINDOW_S = 2.0e-3  # stretches of the corrected signal checked for a level off zero [s]
FLAT_FRACTION = 2.0e-3  # a level above this fraction of the peak ... [-]
FLAT_SIGMA = 5.0  # ... and this many standard errors is a problem [-]
BASELINE_STEP_WINDOWS_S = (1.0e-3, 4.0e-3, 16.0e-3)  # a line and a step fitted to this long of quiet samples on
#                                                    either side of every candidate instant ... [s]
BASELINE_STEP_GRID_S = 0.25e-3  # ... the candidates this far apart (and the first quiet sample after each gap) [s]
BASELINE_STEP_SIGMA = 7.0  # ... a step of this many standard errors (a scan of many instants) ... [-]
BASELINE_STEP_FRACTION = 5.0e-4  # ... and this fraction of the peak is a step in the baseline [-]
BASELINE_STEP_ACROSS_SIGMA = 4.5  # across the contact, with every quiet sample on either side: one test, not a scan [-]


def baseline_bend_problems(fit: BaselineFit, peak, s_u, e_u, scale) -> list[Problem]:
    """A fitted baseline that bends under the contact by more than BASELINE_BEND_FRACTION of the peak.

    Under the contact the baseline (offset, drift and hum) is the fit's extrapolation from the quiet samples
    around it; the mains hum's bend over a few ms of contact is a few per cent of the hum, itself a few per cent of
    the peak at most on any rig of raw-format v1.1 (tens of mV). A bend of a tenth of the peak is a fit the quiet
    samples did not pin, and TC and kCAL read on it can be off by any amount. peak in [V / scale] (scale [V]); s_u,
    e_u: the contact's ends [samples].
    """
    b = fit.baseline
    a, e = max(int(math.ceil(s_u)), 0), min(int(math.floor(e_u)), b.size - 1)
    if e - a < 2 or not peak > 0:
        return []
    chord = np.interp(np.arange(a, e + 1), [a, e], [b[a], b[e]])
    bend = float(np.max(np.abs(b[a:e + 1] - chord)))
    if bend <= BASELINE_BEND_FRACTION * peak:
        return []
    amps = fit.hum_amplitudes
    hum = f" (a hum of {sum(amps) * scale * 1e3:.3g} mV fitted)" if amps else ""
    return [Problem(ProblemKind.MAINS_UNRESOLVED,
                    f"mains hum not resolved: the fitted baseline bends by {bend * scale * 1e3:.3g} mV "
                    f"({100 * bend / peak:.2g} % of the peak) under the contact{hum}; the quiet samples do not pin it "
                    "there (record longer pre- or post-trigger, or give daq.mains_hz)")]


def _edge_event_samples(fs) -> int:
    """The fewest samples an event at the record's start or end must hold: EDGE_EVENT_MIN_S at ``fs`` [Hz], and at
    least 3."""
    return max(3, int(round(EDGE_EVENT_MIN_S * fs)))


def edge_event_problems(x, fs, noise, peak, s_u, scale) -> list[Problem]:
    """Force at the record's first samples, before the contact: an impact the record cut off.

    The corrected signal stands out of the noise as an event does (EVENT_SIGMA noise deviations and
    EVENT_FRACTION of the peak) from the record's first sample on, for EDGE_EVENT_MIN_S at least, before the
    contact's start. Such an event is a pulse whose size and length the record does not show: below the contact
    threshold it is not counted as another impact, and the baseline fit leaves it out as an event. But a contact
    cut off by a late trigger (the fall of a first impact at the record's start, a second one measured in its
    place) is exactly that, and the gates' speeds then belong to the impact not measured (TC and kCAL off by
    tens of per cent). Only the start: before the contact the decay's correction adds
    nothing, while after it it integrates the baseline's small errors, and a record of seconds wanders away from
    zero by its end (looked at the same way, the end excluded right traces); an impact after the measured one does not change what the gates timed, and one that reaches the
    contact threshold is counted by :func:`ballimpact.signal.contact.detect_contact`. At the end, only force still
    rising at the last sample is taken for another impact (:func:`end_event_problems`). x and noise in
    [V / scale] (scale [V]), peak likewise; s_u: the contact's start [samples].
    """
    thr = event_threshold(noise, peak)
    need = _edge_event_samples(fs)
    seg = x[:max(int(math.floor(s_u)), 0)]
    quiet = np.flatnonzero(seg <= thr)
    run = int(quiet[0]) if quiet.size else seg.size  # samples above thr from the record's first on
    if run < need:
        return []
    top = float(np.max(seg[:run]))
    return [Problem(ProblemKind.MULTIPLE_IMPACTS,
                    f"more than one impact in the trace: force at the record's start, {run / fs * 1e3:.2g} ms of it "
                    f"before the contact, up to {top * scale * 1e3:.3g} mV ({100 * top / peak:.2g} % of the peak, "
                    f"{top / noise:.3g} noise deviations): an impact the record truncated (trigger earlier)")]


def end_event_problems(x, fs, noise, peak, e_u, tc_u, scale, post_guard_s=POST_GUARD_S) -> list[Problem]:
    """Force rising to the record's last sample, after the contact: another impact the record cut off.

    The mirror of :func:`edge_event_problems`, narrowed to what a contact's start looks like, for the end of a
    record wanders (the decay's correction integrates the baseline's small errors) and a plate rings after the
    contact: the corrected signal stands out as an event does (EVENT_SIGMA noise deviations and EVENT_FRACTION of
    the peak) over the record's last samples, for EDGE_EVENT_MIN_S at least and for no longer than the contact
    (a wander lasts longer), starting ``post_guard_s`` [s] or more after the contact's end, and its largest sample
    is the record's last, at the contact threshold (:func:`ballimpact.signal.noise.contact_threshold`) or above: a
    contact rising when the record stops, whose height the record does not show
    (:func:`ballimpact.signal.contact.detect_contact` counts a run at the record's end from 5 % of the peak). Below the
    contact threshold, an end rising a per cent or two of the peak is a right trace's (a long record's
    decay-corrected end, a record ending soon after the contact) as often as a faulty one's. x and noise in [V / scale] (scale [V]), peak
    likewise; e_u the contact's end and tc_u its length [samples].
    """
    thr = event_threshold(noise, peak)
    need = _edge_event_samples(fs)
    first = int(math.ceil(e_u + post_guard_s * fs))
    seg = x[max(first, 0):]
    if seg.size < need or not seg[-1] > thr:
        return []
    quiet = np.flatnonzero(seg <= thr)
    if not quiet.size:
        return []  # no quiet sample between the contact and the record's end: the end checks judge that
    run = seg.size - 1 - int(quiet[-1])  # samples above thr up to the record's last
    if not need <= run <= tc_u or not seg[-1] >= np.max(seg[-run:]) \
            or seg[-1] < contact_threshold(noise, peak):
        return []
    top = float(seg[-1])
    return [Problem(ProblemKind.MULTIPLE_IMPACTS,
                    f"more than one impact in the trace: force rising at the record's end, {run / fs * 1e3:.2g} ms "
                    f"of it, to {top * scale * 1e3:.3g} mV ({100 * top / peak:.2g} % of the peak, {top / noise:.3g} "
                    "noise deviations) at the last sample: another impact the record cut off (record longer after "
                    "the trigger)")]


def level_problems(x, fs, fit: BaselineFit, peak, scale, end_u, post_guard_s=POST_GUARD_S):
    """The corrected signal off zero before or after the contact, or a quiet residual that is not white noise.

    After the contact the stretch of the baseline fit is checked; when the record
    after the contact was too short for the fit (the baseline then extrapolated
    from before the contact), the samples from post_guard_s after the contact end
    to the end of the record, when there are MIN_PRE_SAMPLES of them.
    """
    out = []
    w = max(int(round(FLAT_WINDOW_S * fs)), MIN_QUIET_SAMPLES)
    pre_idx = np.flatnonzero(fit.pre)
    post_idx = np.flatnonzero(fit.post)
    stretches = []
    if pre_idx.size >= MIN_PRE_SAMPLES:
        stretches.append(("before", pre_idx[-w:]))
    if post_idx.size >= 2 * MIN_QUIET_SAMPLES:
        stretches.append(("just after", post_idx[:w]))
        if post_idx.size > 2 * w:
            stretches.append(("later after", post_idx[-w:]))
    else:
        tail = np.arange(int(math.ceil(end_u + post_guard_s * fs)), x.size)
        if tail.size >= MIN_PRE_SAMPLES:
            stretches.append(("after", tail[:w]))
    for where, sel in stretches:
        level = float(np.mean(x[sel]))
        se = fit.noise / math.sqrt(sel.size)
        if abs(level) > FLAT_FRACTION * peak and abs(level) > FLAT_SIGMA * se:
            out.append(Problem(ProblemKind.BASELINE_OFF_ZERO,
                               f"corrected signal {where} the contact is {level * scale * 1e3:.3g} mV off zero "
                               f"({100 * abs(level) / peak:.2g} % of the peak): baseline or amplifier decay not removed"))
    # the residual of the quiet samples must be white noise: compare its rms with the noise of
    # sample-to-sample differences (blind to hum and drift)
    qi = np.flatnonzero(fit.quiet)
    if qi.size >= 2 * MIN_QUIET_SAMPLES:
        y = x[qi]
        pairs = np.flatnonzero(np.diff(qi) == 1)
        if pairs.size >= MIN_QUIET_SAMPLES:
            white = robust_noise(y[pairs + 1] - y[pairs]) / math.sqrt(2.0)
            resid = y - np.median(y)
            clipped = np.clip(resid, -ROBUST_SIGMA * white, ROBUST_SIGMA * white) if white > 0 else resid
            excess = math.sqrt(max(float(np.mean(clipped ** 2)) - white ** 2, 0.0))
            if excess > FLAT_FRACTION * peak and excess > white:
                out.append(Problem(ProblemKind.BASELINE_RESIDUAL,
                                   f"quiet baseline not explained by offset, drift, hum and decay: "
                                   f"{excess * scale * 1e3:.3g} mV rms above the white noise "
                                   f"({100 * excess / peak:.2g} % of the peak; "
                                   f"{_residual_where(y, fit.pre[qi], fit.post[qi], white, peak)})"))
    return out


def baseline_step_problems(x, fs, fit: BaselineFit, contact: ContactResult, t0_s, scale,
                            tau_given: bool) -> list[Problem]:
    """A step in the level of the quiet baseline, which offset, drift, hum and decay cannot explain.

    A DAQ's or an amplifier's offset can shift within the record (a relay or a light gate switching near the
    wiring, a range change). The baseline fit then spreads the shift over the record as drift, and the corrected
    signal sits a fraction of it off zero at the contact's ends: on a slow fade a shift of 0.1-0.4 % of the peak
    moved the end by 1-2.4 % of TC with every level check passed (``python bench/step_map.py``). On the fit's quiet
    samples (the contact and the events left out), clipped at ROBUST_SIGMA noise deviations so that a burst or a
    spike weighs little, a line and a step are fitted to BASELINE_STEP_WINDOWS_S on either side of candidate
    instants BASELINE_STEP_GRID_S apart (the line takes up what the global fit's drift made of the step); a step of
    BASELINE_STEP_SIGMA standard errors and BASELINE_STEP_FRACTION of the peak that still holds, half its size and
    3 standard errors, when fitted over four times as long (a small second contact below the event mask's
    EVENT_FRACTION of the peak is a hump, not a step) is a problem. At the contact the two sides are every quiet
    sample before and after it, one test at BASELINE_STEP_ACROSS_SIGMA: a step within the contact when
    ``plate.time_constant_s`` is given. With the decay estimated, kappa takes up a shift within the contact, which
    is then taken for the amplifier's undershoot: only the given time constant tells them apart."""
    peak = float(contact.peak_V)
    qi = np.flatnonzero(fit.quiet)
    if not (peak > 0 and fit.noise > 0) or qi.size < 2 * MIN_QUIET_SAMPLES:
        return []
    lim = ROBUST_SIGMA * fit.noise
    y = np.clip(x[qi], -lim, lim)
    t = qi / fs
    # prefix sums: every window's line-and-step fit in O(1)
    c = [np.concatenate([[0.0], np.cumsum(q)]) for q in (np.ones(qi.size), t, t * t, y, t * y)]
    grid = np.unique(np.concatenate([
        np.searchsorted(t, np.arange(t[0], t[-1], BASELINE_STEP_GRID_S)),
        np.flatnonzero(np.diff(qi) > 1) + 1]))  # and the first sample after every gap (the contact's, an event's)
    grid = grid[(grid > 0) & (grid < qi.size)]
    pre_n = int(np.count_nonzero(fit.pre[qi]))

    def steps(w, j):
        """(step [V / scale], standard errors) of the line-and-step fit over w quiet samples either side of j."""
        lo, hi = np.maximum(j - w, 0), np.minimum(j + w, qi.size)
        sides = []
        for a, b in ((lo, j), (j, hi)):
            n, st, stt, sy, sty = (ck[b] - ck[a] for ck in c)
            with np.errstate(invalid="ignore", divide="ignore"):
                sides.append((n, st / n, sy / n, stt - st * st / n, sty - st * sy / n))
        (nl, tl, yl, sxx_l, sxy_l), (nr, tr, yr, sxx_r, sxy_r) = sides
        sxx = sxx_l + sxx_r
        with np.errstate(invalid="ignore", divide="ignore"):
            h = (yr - yl) - (sxy_l + sxy_r) / sxx * (tr - tl)
            z = np.abs(h) / (fit.noise * np.sqrt(1.0 / nl + 1.0 / nr + (tr - tl) ** 2 / sxx))
        z[~((nl >= MIN_QUIET_SAMPLES) & (nr >= MIN_QUIET_SAMPLES) & (sxx > 0))] = 0.0
        return h, np.nan_to_num(z)

    widths = [max(int(round(w * fs)), MIN_QUIET_SAMPLES) for w in BASELINE_STEP_WINDOWS_S]
    best = None  # (standard errors, step [V / scale], last sample before, first after)
    for i, w in enumerate(widths):
        h, z = steps(w, grid)
        z[np.abs(h) < BASELINE_STEP_FRACTION * peak] = 0.0
        for k in np.argsort(z)[::-1][:8]:  # the largest few: a hump (a small second contact) is not a step
            if z[k] < BASELINE_STEP_SIGMA or (best is not None and z[k] <= best[0]):
                break
            wider = [steps(4 * w2, grid[k:k + 1]) for w2 in widths[i:]]  # the shift must hold further out
            if all(hw[0] * h[k] > 0 and abs(hw[0]) >= 0.5 * abs(h[k]) and zw[0] >= 3.0 for hw, zw in wider):
                best = (float(z[k]), float(h[k]), int(qi[grid[k] - 1]), int(qi[grid[k]]))
                break
    if tau_given and 0 < pre_n < qi.size and np.all(fit.post[qi[pre_n:]]):
        h, z = steps(qi.size, np.array([pre_n]))
        if z[0] >= BASELINE_STEP_ACROSS_SIGMA and abs(h[0]) >= BASELINE_STEP_FRACTION * peak \
                and (best is None or z[0] > best[0]):
            best = (float(z[0]), float(h[0]), int(qi[pre_n - 1]), int(qi[pre_n]))
    if best is None:
        return []
    z, d, before, after = best
    return [Problem(ProblemKind.BASELINE_STEP,
                    f"step in the baseline: the corrected signal's level shifts by {d * scale * 1e3:.3g} mV "
                    f"({100 * abs(d) / peak:.2g} % of the peak, {z:.3g} standard errors) between "
                    f"{1e3 * (before / fs + t0_s):.4g} and {1e3 * (after / fs + t0_s):.4g} ms, which offset, drift, "
                    "hum and decay do not explain; the baseline under the contact is uncertain",
                    data={"level_V": abs(d) * scale, "decay_given": bool(tau_given)})]


def _residual_where(y, pre, post, white, peak) -> str:
    """Where a quiet residual that is more than white noise is: after the contact only, or not (for its reason)."""
    def excess(sel):
        r = y[sel] - np.median(y[sel])
        r = np.clip(r, -ROBUST_SIGMA * white, ROBUST_SIGMA * white) if white > 0 else r
        e = math.sqrt(max(float(np.mean(r ** 2)) - white ** 2, 0.0))
        return e > FLAT_FRACTION * peak and e > white

    if np.count_nonzero(pre) >= MIN_QUIET_SAMPLES and np.count_nonzero(post) >= MIN_QUIET_SAMPLES \
            and excess(post) and not excess(pre):
        return "after the contact only: plate ringing that outlasts the guard, or a decay not resolved?"
    return "hum or drift not resolved?"


def mains_problems(x, fs, fit: BaselineFit, peak, scale, ambiguous, start_u, end_u):
    """50 and 60 Hz hum that fit the quiet samples alike but differ under the contact."""
    out = []
    if ambiguous is not None:
        mains, other, other_baseline = ambiguous
        a, b = max(int(math.floor(start_u)), 0), min(int(math.ceil(end_u)) + 1, x.size)
        hum = float(np.sum(fit.hum_amplitudes))
        if other_baseline is None and hum > MAINS_AMBIGUOUS_FRACTION * peak:
            tq = np.flatnonzero(fit.quiet) / fs
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains frequency not resolved: the quiet baseline spans {1e3 * (tq[-1] - tq[0]):.3g} "
                               f"ms, too short to tell {mains:g} from {other:g} Hz hum of {hum * scale * 1e3:.3g} mV "
                               "(give daq.mains_hz)"))
        diff = float(np.max(np.abs(other_baseline[a:b] - fit.baseline[a:b]))) if b > a and other_baseline is not None \
            else 0.0
        if other_baseline is not None and diff > MAINS_AMBIGUOUS_FRACTION * peak:
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains frequency not resolved: {mains:g} and {other:g} Hz hum fit the quiet baseline "
                               f"equally well and differ by {diff * scale * 1e3:.3g} mV under the contact "
                               "(give daq.mains_hz)"))
    return out


def short_record_hum(x, fs, fit: BaselineFit, mains_hz: tuple, peak: float, scale: float):
    """Mains hum in quiet samples that span less than one period of it: not removed, and it matters.

    The baseline fit leaves hum out when the quiet samples do not span a full
    period of the fundamental (it cannot be told from the offset and drift
    there). What it leaves is tested here: the corrected quiet samples are
    fitted with a line and the fundamental of each mains frequency in
    question; a hum of more than FLAT_FRACTION of the peak and FLAT_SIGMA
    standard errors is a problem, since under the contact it bends the
    baseline by an unknown part of itself.
    """
    if fit.coef["hum_frequencies_hz"] or not mains_hz or not peak > 0:
        return []
    qi = np.flatnonzero(fit.quiet)
    if qi.size < 2 * MIN_QUIET_SAMPLES:
        return []
    t = qi / fs
    span = float(t[-1] - t[0])
    t = t - 0.5 * (t[0] + t[-1])
    out = []
    for f in mains_hz:
        if span * f >= 1.0:
            continue
        w = 2.0 * math.pi * f * t
        a = np.column_stack([np.ones(t.size), t, np.cos(w), np.sin(w)])
        coef, *_ = np.linalg.lstsq(a, x[qi], rcond=None)
        resid = x[qi] - a @ coef
        s2 = float(resid @ resid) / max(t.size - 4, 1)
        cov = s2 * np.linalg.pinv(a.T @ a)
        amp = float(math.hypot(coef[2], coef[3]))
        se = math.sqrt(max((coef[2] ** 2 * cov[2, 2] + coef[3] ** 2 * cov[3, 3] + 2 * coef[2] * coef[3] * cov[2, 3])
                           / max(amp * amp, 1e-300), 0.0))
        if amp > FLAT_FRACTION * peak and amp > FLAT_SIGMA * se:
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains hum not resolved: the quiet samples span {1e3 * span:.3g} ms, less than a period "
                               f"of {f:g} Hz, and hold a hum of about {amp * scale * 1e3:.3g} mV "
                               f"({100 * amp / peak:.2g} % of the peak) that bends the baseline under the contact "
                               "(record longer pre- or post-trigger)"))
            break
    return out
