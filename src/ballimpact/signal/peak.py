"""Checks of the contact's peak: on the plate's ringing or first overshoot, between samples, after a front's dip."""

from __future__ import annotations

import math

import numpy as np

from ..calibration import force_top
from ..model import BUCKLING_TIME_S
from ..problems import Problem, ProblemKind
from .end_checks import MIN_CONTACT_SAMPLES
from .front import fit_front
from .spikes import SPIKE_END_IMPULSE
from .window import EVENT_SIGMA

__all__ = [
    "turning_points",
    "peak_on_ringing",
    "peak_between_samples",
    "peak_on_front_ringing",
    "peak_on_first_overshoot",
    "ideal_front_beyond_noise",
    "front_dip",
]

TURN_FRACTION = 0.02  # a turning point of the contact force is left by more than this fraction of the peak ... [-]
TURN_SIGMA = 8.0  # ... and this many noise deviations [-]
TURN_MIN_OSCILLATION = 3  # fewest turning points of an oscillation [-]
TURN_REGULARITY = 1.5  # spacings of an oscillation's turning points within this factor of each other [-]
TURN_FAST_RUN = 4  # ... or this many before the peak within one sample of each other, at most 3 apart [-]
PEAK_ON_RINGING_FRACTION = 0.015  # averaged over one period of it, the peak drops by more: not the ball's [-]
PEAK_SAMPLING_FRACTION = 0.10  # the force may rise above the largest sample by more: the peak is not known to 5 % [-]
PEAK_RAMP_FLOOR = 0.5  # ... judged on the rises from samples above this fraction of the peak (a ramp, no jump) [-]
PEAK_JUMP_FRACTION = 0.1  # the largest sample straight after one below this fraction of it: at the jump [-]
FRONT_DIP_JUMPED = 0.2  # once a sample of the front is above this fraction of the peak, ... [-]
FRONT_DIP_ZERO = 0.02  # ... a sample below this fraction of it before BUCKLING_TIME_S and FRONT_DIP_AFTER_SAMPLES
#                        more is a swing as large as the jump: no ball's force [-]
FRONT_DIP_AFTER_SAMPLES = 2  # [samples]
PEAK_ALONE_FRACTION = 0.015  # the largest sample, risen from one below PEAK_RAMP_FLOOR of it, above every other
#                              sample by more than this fraction of it: a single-sample top (the ball's spike or an
#                              electrical one), not known; half the 3 % tolerance of the peak [-]
FRONT_PHASE_S = 0.2e-3  # a largest sample this soon (and a sample) after the contact start is checked ... [s]
FRONT_MIN_SAMPLES = 8  # ... when the contact holds this many samples up to it ... [samples]
FRONT_PRE_SAMPLES = 3  # ... by a fit from this many samples before the start to it ... [samples]
FRONT_JUMP_FRACTION = 0.05  # ... when the force is above this fraction of the peak as many samples after the start [-]
FRONT_SIGNIFICANCE = 25.0  # ... through a plate better than through an ideal one by this many variances ... [-]
FRONT_LIFT_FRACTION = 0.03  # ... whose ringing lifts the largest sample above the force by more: not the ball's [-]
OVERSHOOT_MAX_SAMPLES = 4.5  # a largest sample at most this long after the start (half a period of 2-6 samples) ... [samples]
OVERSHOOT_AFTER_SAMPLES = 10  # fewer samples up to it: fitted on this many after it, with a drop at buckling [samples]
OVERSHOOT_MAX_DAMPING = 0.35  # ... through a plate damped at most this much (more: a smoother, no ringing) [-]
OVERSHOOT_MIN_PERIOD = 2.5  # a plate fitted with fewer samples per period may be an alias: not evidence [samples]
OVERSHOOT_RISE_MAX = 1.0  # ... the jumps rising over at most this many samples (the model's: 10 us) [samples]


def _alike(a: float, b: float) -> bool:
    """Two spacings of turning points within a factor TURN_REGULARITY of each other."""
    return max(a, b) <= TURN_REGULARITY * min(a, b)


def turning_points(y, h) -> list[int]:
    """Indices of the turning points of y, each left by more than h (a hysteresis; noise below h makes none)."""
    out: list[int] = []
    direction, i_ext = 0, 0
    for i in range(1, y.size):
        v = y[i]
        if direction == 0:
            if abs(v - y[0]) > h:
                direction, i_ext = (1 if v > y[0] else -1), i
        elif direction * (v - y[i_ext]) > 0:
            i_ext = i
        elif direction * (y[i_ext] - v) > h:
            out.append(i_ext)
            direction, i_ext = -direction, i
    return out


def peak_on_ringing(xc, fs, noise, peak):
    """The peak force riding on plate ringing: the largest value is one of the plate's swings.

    Turning points of the contact force are the places it leaves by more than
    TURN_FRACTION of the peak and TURN_SIGMA noise deviations (a hysteresis:
    noise makes none). The force jumps from zero at the start (and drops at
    buckling), and a plate resonance rings after each jump. The peak is one of
    the plate's swings when it is the jump's overshoot (within one period of
    the oscillation of the start, with the oscillation going on after it) or
    when the last two or three turning points before it are spaced like the one after
    it (a ringing that began before the peak). Half a period of the
    oscillation is the spacing of the peak to the next turning point; two
    spacings are alike within a factor TURN_REGULARITY. A ringing of 2-6
    samples per period (a resonance near the Nyquist frequency) has turning
    points located to a sample only, its half-periods read 1 and 2 (or 2 and
    3) samples: the TURN_FAST_RUN spacings before the peak and the one after
    it, each at most 3 and within a sample of each other, are such a ringing,
    of half-period their mean. The ball's own spike
    before buckling comes later, after a rise with no regular turns. It
    matters when, averaged over one period of the oscillation, the peak drops
    by more than PEAK_ON_RINGING_FRACTION of the peak.
    """
    if xc.size < MIN_CONTACT_SAMPLES:
        return []
    turns = turning_points(xc, max(TURN_FRACTION * peak, TURN_SIGMA * noise))
    i_peak = int(np.argmax(xc))
    if i_peak not in turns or len(turns) < TURN_MIN_OSCILLATION:
        return []
    j = turns.index(i_peak)
    spacing = np.diff(turns).astype(float)
    if j >= spacing.size:
        return []
    after = float(spacing[j])  # half a period of the oscillation [samples]
    # the jump's overshoot: the peak within one period of the start, an oscillation after it
    overshoot = i_peak <= 2.0 * after and spacing.size - j >= 2 and _alike(spacing[j + 1], after)
    # a peak inside a ringing that began before it: the two or three turning points before it at its spacing
    inside = j >= 2 and all(_alike(float(d), after) for d in spacing[max(j - TURN_MIN_OSCILLATION, 0):j])
    # ringing of 2-6 samples per period: its turning points are located to a sample, so its half-periods
    # read 1 and 2 (or 2 and 3) samples; a longer run of them before the peak, each within a sample
    fast = spacing[max(j - TURN_FAST_RUN, 0):j + 1]
    near_nyquist = (j >= TURN_FAST_RUN and float(np.max(fast)) <= 3.0
                    and float(np.max(fast) - np.min(fast)) <= 1.0)
    if not (overshoot or inside or near_nyquist):
        return []
    period = 2.0 * (float(np.mean(fast)) if near_nyquist and not (overshoot or inside) else after)
    k = max(int(round(period)), 1)
    averaged = np.convolve(xc, np.ones(k) / k, mode="same")
    drop = float(np.max(xc) - np.max(averaged))
    if drop > PEAK_ON_RINGING_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_ON_RINGING,
                        f"peak force on plate ringing: the force oscillates at about {fs / period / 1e3:.3g} kHz during "
                        f"the contact and its peak is one of the swings (averaged over one period it is "
                        f"{100 * drop / peak:.2g} % lower); the peak is not the ball's")]
    return []


def _alone_top(xc, fs, i, peak):
    """The largest sample ``xc[i]`` (``peak``), risen from one below PEAK_RAMP_FLOOR of it and standing more than
    PEAK_ALONE_FRACTION of it above every other sample: a single-sample top (PEAK_BETWEEN_SAMPLES), and were it
    electrical, an impulse it moves by more than SPIKE_END_IMPULSE (IMPULSE_UNRESOLVED); empty otherwise."""
    if i + 1 < xc.size and xc[i - 1] < PEAK_RAMP_FLOOR * peak:
        below = float(np.max(np.delete(xc, i)))
        if peak - below > PEAK_ALONE_FRACTION * peak:
            seen = (f"{1e3 * (i - 1) / fs:.2g} ms into the contact, it rises from a sample at "
                    f"{100 * xc[i - 1] / peak:.2g} % of it and stands {100 * (peak - below) / peak:.2g} % of it above "
                    "every other sample: a single-sample top, the ball's spike with its ramp unsampled or an "
                    "electrical spike where the force's curve breaks, which the samples cannot tell apart")
            out = [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                           f"peak force between samples: the largest sample stands alone: {seen} (sample faster)")]
            # were it electrical, its excess over its neighbours' mean is in the impulse too (as a sample kept at
            # a contact end: spikes_at_ends)
            excess, impulse = float(xc[i] - 0.5 * (xc[i - 1] + xc[i + 1])), float(np.sum(xc[1:]))
            if impulse > 0 and excess > SPIKE_END_IMPULSE * impulse:
                out.append(Problem(ProblemKind.IMPULSE_UNRESOLVED,
                                   f"impulse not known to {100 * SPIKE_END_IMPULSE:.2g} %: were the largest sample an "
                                   f"electrical spike, the impulse would be {100 * excess / impulse:.2g} % off"))
            return out
    return []


def peak_between_samples(xc, fs, noise, lifted=True):
    """A peak force the samples do not pin down: the force may rise above the largest sample.

    Between the largest sample and the next one the force may go on rising
    before it drops: the ball's pre-buckling spike is a steep ramp ending in a
    sudden drop (section 3.2 in Goodwill & Haake 2004). It can rise by at most
    the rise over one sample: the larger of the last two rises before the
    largest sample (a plate that smooths the ramp slows the last one), less two
    noise deviations of the difference. Only rises from a sample already above
    PEAK_RAMP_FLOOR of the peak count: the force's jump from zero (at 2 mm of
    compression in the model) is no ramp and goes on nowhere. Where in the
    interval the force drops is not known (any instant alike), so the largest
    sample misses the top by half that rise on average and by all of it at
    worst. When that rise is more than PEAK_SAMPLING_FRACTION (10 %) of the
    peak, the peak is not known to 5 % (the zoo's tolerance for the spike):
    sample faster. Nor is it
    known when the largest sample is the first of the contact (the one before
    it below PEAK_JUMP_FRACTION of it): a ball's force rises as it compresses,
    so that sample is the top of the force's jump from zero, a plate's
    overshoot of the jump, or a spike whose top fell within the first sample
    interval.
    Nor when it rises from a sample below PEAK_RAMP_FLOOR of it (no ramp
    before it) and stands more than PEAK_ALONE_FRACTION of it above every
    other sample: a single-sample top, either the ball's spike with none of
    its ramp sampled or an electrical spike riding on the force where its
    curve breaks (the jump, the drop at buckling), whose second differences
    there do not have an isolated spike's shape (:func:`remove_spikes`): taken
    for the peak, such a spike makes it tens of per cent high. Were it electrical,
    its excess over its neighbours' mean is in the impulse as well: above
    SPIKE_END_IMPULSE of the impulse that is a problem too
    (IMPULSE_UNRESOLVED, as for a sample kept at a contact end), so that a
    withheld peak never passes a kCAL that a spike moved.

    The same holds at every lower local maximum of the samples that follows
    two rises from samples above PEAK_JUMP_FRACTION of the peak (a spike's
    ramp), or the jump from zero to a sample above PEAK_RAMP_FLOOR of it and
    one rise (the jump's sample on the ramp at low rates, about 25 kHz),
    judged by its expected top (half the larger
    rise above it) against the largest sample: a spike whose top fell
    between the samples so wholly that the largest sample is on the smooth
    part of the contact is such a
    maximum, and its top may exceed the largest sample.
    At the largest sample the rule is the one above (half a rise against half
    of PEAK_SAMPLING_FRACTION). A jump from zero (one rise from a sample near
    zero) or a swing of ringing (a fall before the rise) hides no top above
    it; a jump smoothed over two or three samples cannot be told from a
    spike's ramp and is judged as one.

    With ``lifted`` (the sensed force, whose peak
    :func:`ballimpact.calibration.force_top` reads), where force_top lifts the
    largest sample to the middle of the range a ramp cut by a drop can take,
    the reported top is off by up to half that range (half the last rise),
    which must also be within PEAK_SAMPLING_FRACTION / 2 of the peak. Where a
    sample is kept (the largest one when force_top does not lift it, a lower
    maximum, an undone force: ``lifted`` False) the top may be up to a whole
    rise above it, but it is judged by half a rise, on average: judging the
    whole rise there excluded many more right traces, and good impacts of the
    synthetic sessions.
    """
    if xc.size < 3:
        return []
    i = int(np.argmax(xc))
    if i == 0:
        return []
    peak = float(xc[i])
    if peak > 0 and xc[i - 1] < PEAK_JUMP_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                        f"peak force between samples: the largest sample is the first of the contact (the one "
                        f"before it at {100 * xc[i - 1] / peak:.2g} % of it): the top of the force's jump from zero "
                        "or the plate's overshoot of it, not a measured maximum (sample faster)")]
    if not peak > 0:
        return []
    alone = _alone_top(xc, fs, i, peak)
    if alone:
        return alone
    # every sampled maximum (the largest sample and each lower local maximum, e.g. a spike whose top
    # fell between the samples while the smooth part of the contact later holds the largest sample)
    # may hide a top up to one rise above it: a ramp's rises only. At the largest sample, the rises
    # from a sample already at PEAK_RAMP_FLOOR of the peak (not the jump from zero); at a lower
    # maximum, a spike's ramp starts low: a maximum after two rises, both from samples off zero
    # (PEAK_JUMP_FRACTION of the peak), or after the jump from zero to a sample already at PEAK_RAMP_FLOOR of
    # the peak and one rise from it (at about 25 kHz the jump's sample is on the spike's ramp; a jump from zero
    # spread over two samples, the first of them low, is no ramp: counting any sample off zero excluded right
    # traces); a jump from zero alone (one rise from a sample near zero) or a swing of ringing
    # (a fall before its rise) hides no top above it
    jump_floor = PEAK_JUMP_FRACTION * peak
    maxima = [k for k in range(2, xc.size - 1)
              if xc[k - 2] < xc[k - 1] <= xc[k] and xc[k] > xc[k + 1] and k != i
              and xc[k - 1] >= (jump_floor if xc[k - 2] >= jump_floor else PEAK_RAMP_FLOOR * peak)]
    # force_top's half range at the largest sample where it lifts it (0 where it keeps the sample)
    half = force_top(np.arange(xc.size) / fs, xc, noise)[2] if lifted else 0.0
    for k in (i, *maxima):
        floor = PEAK_RAMP_FLOOR * peak if k == i else jump_floor
        rises = [float(xc[j] - xc[j - 1]) for j in (k, k - 1) if j >= 1 and xc[j - 1] >= floor]
        rise = max(rises, default=0.0) - 2.0 * math.sqrt(2.0) * noise
        # the top there: half a rise above the sample on average (the drop anywhere in the interval);
        # at the largest sample this is the rise against PEAK_SAMPLING_FRACTION; where force_top lifts
        # it, also the half range of the top it reports
        lift = k == i and half > 0.0
        miss = float(xc[k]) + 0.5 * rise - peak
        if lift:
            miss = max(miss, half)
        if miss > 0.5 * PEAK_SAMPLING_FRACTION * peak:
            where = ("the largest sample" if k == i else
                     f"a sampled maximum of {100 * xc[k] / peak:.3g} % of the largest sample, "
                     f"{1e3 * (k - i) / fs:+.3g} ms from it,")
            return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                            f"peak force between samples: the force rises by {100 * rise / peak:.2g} % of the peak in "
                            f"the {1e6 / fs:.3g} us before {where} and may go on rising before it drops: "
                            f"the largest sample may miss the peak by {100 * miss / peak:.2g} % on average "
                            "(sample faster)")]
    return []


def peak_on_front_ringing(x, fs, noise, peak, s_u, e_u):
    """The peak force lifted by the plate's ringing from the force's jump: a later swing of it, not the ball's.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake 2004)
    the force jumps from zero and rises smoothly to the spike, which ends in
    the drop at buckling. A plate rings from the jump; when the spike's top
    lands on a later maximum of that ringing (the first overshoot is
    :func:`peak_on_step_response`'s too) the largest sample is lifted
    above the ball's force with nothing in the contact to show it (the peak
    a few per cent high and ok). So when the contact's largest sample is within FRONT_PHASE_S
    (and a sample) of its start and FRONT_MIN_SAMPLES of the contact reach
    it, the samples from FRONT_PRE_SAMPLES before the start to it are fitted
    with a jump, a ramp and a parabola (:func:`ballimpact.signal.front.fit_front`),
    once through a plate (fn and zeta free, at most 0.45 fs, at least one
    period over the window) and once through an ideal plate. When the plate
    fits better by more than FRONT_SIGNIFICANCE residual variances (the
    larger of the noise's and the plate fit's own, per sample) and the
    largest sample stands more than FRONT_LIFT_FRACTION of the peak above
    the force the plate's fit finds under it, the peak is the plate's (also
    when the ball's top comes later, hidden in a trough of the ringing: the
    peak is then not measured either).

    The fit looks for the force's jump from FRONT_PRE_SAMPLES samples before
    the first contact sample to that sample: a front still below
    FRONT_JUMP_FRACTION of the peak FRONT_PRE_SAMPLES samples after it (a
    cloth's foot before the jump, as the synthetic chain's) is not the
    model's, and is not judged.
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not peak > 0 or k1 - k0 < MIN_CONTACT_SAMPLES or k0 - FRONT_PRE_SAMPLES < 0 or k1 >= x.size:
        return []
    i = k0 + int(np.argmax(x[k0:k1 + 1]))
    if i - s_u > FRONT_PHASE_S * fs + 1.0 or i - k0 + 1 < FRONT_MIN_SAMPLES:
        return []
    if x[k0 + FRONT_PRE_SAMPLES] < FRONT_JUMP_FRACTION * peak:
        return []  # no jump where the fit looks for one: a slower front (a cloth's foot) is not fitted
    plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, i, s_u)
    if plate is None:
        return []
    ideal = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, i, s_u, resonance=False)
    variance = max(noise * noise, plate.rss / max(plate.n_samples - 7, 1))
    gain = (ideal.rss - plate.rss) / variance if variance > 0 else math.inf
    lift = float(x[i] - plate.force(i))
    if gain > FRONT_SIGNIFICANCE and lift > FRONT_LIFT_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_ON_RINGING,
                        f"peak force on the plate's ringing: from the contact start to its largest sample "
                        f"({1e3 * (i - s_u) / fs:.2g} ms in) the force is a jump and a ramp through a plate of about "
                        f"{plate.frequency_hz / 1e3:.3g} kHz (damping ratio {plate.damping_ratio:.2g}), with "
                        f"{ideal.rss / max(plate.rss, 1e-300):.2g} times less residual than through an ideal plate, "
                        f"whose ringing from the jump lifts the largest sample {100 * lift / peak:.2g} % of the peak "
                        "above the force; the peak is not the ball's")]
    return []


def peak_on_first_overshoot(x, fs, noise, peak, s_u, e_u):
    """The peak force on the plate's first overshoot of the force's jump, sampled a few times per period.

    A lightly damped plate sampled 2-5 times per period answers the force's
    jump (section 3.2.4 in Goodwill & Haake 2004: zero below 2 mm of
    compression, then kCONST) with a first overshoot that lands on the
    contact's first samples and stands 5-25 % above the ball's peak (8.5 kHz
    and damping 0.11 at 25.5 kHz: +22 %). Its ringing is gone after a
    period or two, so neither :func:`peak_on_ringing` nor
    :func:`peak_on_step_response` sees an oscillation, and
    :func:`peak_on_front_ringing` needs FRONT_MIN_SAMPLES up to the largest
    sample. So when the largest sample is within FRONT_PHASE_S (and a
    sample) of the start with fewer than FRONT_MIN_SAMPLES up to it, the
    window runs on to OVERSHOOT_AFTER_SAMPLES after it, past the pre-buckling
    spike: from FRONT_PRE_SAMPLES before the start it is fitted with the
    model's front and its drop at buckling (:func:`ballimpact.signal.front.fit_front`
    with ``drop``: a jump, a ramp that rises by at most the jump, a drop at a
    free instant and a new ramp and parabola after it; the jumps rising over
    at most OVERSHOOT_RISE_MAX samples), once through a plate (fn and zeta
    free, zeta up to plate.FRONT_DROP_MAX_DAMPING) and once through an ideal
    plate. When the plate fits better by more than FRONT_SIGNIFICANCE
    residual variances (the larger of the noise's and the plate fit's own,
    per sample), its damping is at most OVERSHOOT_MAX_DAMPING (a fit at the
    bound smooths the force's shape; it is no ringing) and the largest
    sample stands more than FRONT_LIFT_FRACTION of the peak above the force
    it finds under it, the peak is the plate's: evidence of the plate
    (PEAK_ON_RINGING), whose resonance is then identified and undone where
    that passes every check, unless the plate fitted rings with fewer than
    OVERSHOOT_MIN_PERIOD samples per period: a resonance above fs / 2 is
    sampled as its alias below it, and undone as that alias its force is
    wrong (the peak off by several per cent), so the peak is then named as not resolved by the
    samples (PEAK_BETWEEN_SAMPLES), which is no evidence. A ball's front
    through an ideal plate, its spike's top and its drop sampled anywhere,
    needs no plate (tests/test_conditioning.py). Not run when the checks
    before it found evidence of the plate already (its undoing is tried
    then whatever this check finds): a few ms of fits saved.

    An electrical spike on the ringing after the largest sample (added
    after the plate; :func:`remove_spikes` cannot tell it from the
    ringing's swings) raises the plate fit's own residual, which then sets
    the significance, and the plate's gain over the ideal plate, counted in
    its own residual variances, is then too small to be evidence. So where the plate
    fits better than the ideal plate by more than FRONT_SIGNIFICANCE noise
    variances but not by its own residual, both are fitted again with a
    free spike on one sample after the largest (``fit_front``'s
    ``spike``), and the plate's is evidence when its spike stands
    EVENT_SIGMA noise deviations out and, with it, the plate's fit leaves
    at most FRONT_SIGNIFICANCE noise variances: the spike must explain the
    whole misfit (a free sample also absorbs the model's misfit of a
    ball's front, where the fit with it still leaves more).
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not peak > 0 or k1 - k0 < MIN_CONTACT_SAMPLES or k0 - FRONT_PRE_SAMPLES < 0 or k1 >= x.size:
        return []
    i = k0 + int(np.argmax(x[k0:k1 + 1]))
    if i - s_u > min(FRONT_PHASE_S * fs + 1.0, OVERSHOOT_MAX_SAMPLES) or i - k0 + 1 >= FRONT_MIN_SAMPLES:
        return []  # a later peak, or one :func:`peak_on_front_ringing` judges
    if x[k0 + FRONT_PRE_SAMPLES] < FRONT_JUMP_FRACTION * peak:
        return []
    last = min(i + OVERSHOOT_AFTER_SAMPLES, k1)
    ideal = ideal_front_beyond_noise(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, noise, drop=True,
                                      rise_max=OVERSHOOT_RISE_MAX)
    if ideal is None:
        return []  # the ball's front through an ideal plate leaves too little for a plate to explain
    plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, drop=True, rise_max=OVERSHOOT_RISE_MAX)
    if plate is None:
        return []

    def evident(ideal, plate, n_params):  # the plate's evidence: its fit's gain, the lift; None when not evident
        variance = max(noise * noise, plate.rss / max(plate.n_samples - n_params, 1))
        gain = (ideal.rss - plate.rss) / variance if variance > 0 else math.inf
        lift = float(x[i] - plate.force(i))
        ok = gain > FRONT_SIGNIFICANCE and lift > FRONT_LIFT_FRACTION * peak and \
            plate.damping_ratio <= OVERSHOOT_MAX_DAMPING
        return lift if ok else None

    lift, spike = evident(ideal, plate, 10), ""
    if lift is None and plate.rss > FRONT_SIGNIFICANCE * noise * noise \
            and ideal.rss - plate.rss > FRONT_SIGNIFICANCE * noise * noise:
        # the plate explains the front better than the ideal plate by more than the noise, but its fit's own residual
        # (not the noise) refused the evidence: an electrical spike on the ringing after the peak (added after the
        # plate, where remove_spikes cannot tell it from the ringing's swings) may be that residual; fitted with one
        others = list(range(i + 1, last + 1))
        ideal = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, resonance=False, drop=True,
                          rise_max=OVERSHOOT_RISE_MAX, spike=others)
        if ideal is None or not ideal.rss > FRONT_SIGNIFICANCE * noise * noise:
            return []
        plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                          spike=others)
        if plate is None or not abs(plate.spike) > EVENT_SIGMA * noise \
                or not plate.rss <= FRONT_SIGNIFICANCE * noise * noise:
            return []  # no spike out of the noise, or one that does not leave the plate's fit at the noise
        lift = evident(ideal, plate, 11)
        spike = (f", less a single-sample spike of {plate.spike / noise:.3g} noise deviations "
                 f"{plate.spike_index - s_u:+.2g} samples from the start (an electrical one, not through the plate)")
    if lift is None:
        return []
    return _overshoot_problems(fs, ideal, plate, i, s_u, last, lift, peak, spike)


def _overshoot_problems(fs, ideal, plate, i, s_u, last, lift, peak, spike):
    """The problem of a largest sample ``i`` that a plate's first overshoot of the force's jump lifts by ``lift``
    [V] above the force (:func:`peak_on_first_overshoot`): on its ringing (PEAK_ON_RINGING), or between samples
    (PEAK_BETWEEN_SAMPLES, no evidence) for a plate of fewer than OVERSHOOT_MIN_PERIOD samples per period."""
    seen = (f"the contact's front (to {last - i} samples after it) is a jump and a ramp through a plate of about "
            f"{plate.frequency_hz / 1e3:.3g} kHz (damping ratio {plate.damping_ratio:.2g}, "
            f"{fs / plate.frequency_hz:.2g} samples per period), with {ideal.rss / max(plate.rss, 1e-300):.2g} times "
            f"less residual than through an ideal plate{spike}, whose overshoot lifts the largest sample "
            f"{100 * lift / peak:.2g} % of the peak above the force")
    if fs / plate.frequency_hz < OVERSHOOT_MIN_PERIOD:  # near fs / 2: a resonance above it looks the same
        return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                        f"peak force between samples: the largest sample, {1e3 * (i - s_u) / fs:.2g} ms after the "
                        f"contact start, is a plate's first overshoot of the force's jump, ringing near half the "
                        f"sample rate (or above it, seen through its alias): {seen}; the peak is not the ball's "
                        "(sample faster)")]
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on plate ringing: the largest sample, {1e3 * (i - s_u) / fs:.2g} ms after the contact "
                    f"start, is the plate's first overshoot of the force's jump: {seen}; the peak is not the ball's")]


def ideal_front_beyond_noise(x, fs, first, last, start, noise, **options):
    """The front's fit through an ideal plate (:func:`ballimpact.signal.front.fit_front` with ``resonance=False`` and
    ``options``), or None when it leaves at most FRONT_SIGNIFICANCE noise variances: nothing for a plate or a
    low-pass to explain. The starting grid's fit is tried first (fast): when it leaves that little, the refined
    one, whose residual is no larger, does too."""
    for refine in (False, True):
        ideal = fit_front(x, fs, first, last, start, resonance=False, refine=refine, **options)
        if ideal is None or ideal.rss <= FRONT_SIGNIFICANCE * noise * noise:
            return None
    return ideal


def front_dip(x, fs, peak, s_u, e_u):
    """A sample of the contact's front back near zero after the force's jump: the start not determined.

    The ball's force, once it has jumped from zero (section 3.2.4 in Goodwill & Haake 2004), does not return to zero
    before the ball leaves: at buckling it drops by about half (section 3.2). A sample of the front (from
    FRONT_PRE_SAMPLES before the start found, which may come after such a dip, to BUCKLING_TIME_S and
    FRONT_DIP_AFTER_SAMPLES after it) below FRONT_DIP_ZERO of the peak after one above
    FRONT_DIP_JUMPED of it is a swing as large as the jump: a negative electrical spike where the force's curve
    breaks (which :func:`remove_spikes` cannot tell from the jump) or a plate's swing, and the samples do not say
    which of the samples around it the force starts at (tests/test_robustness.py). :func:`_start_on_fast_ringing`
    names the plate's swing where it sees its ringing; this check runs where it did not.
    """
    k0, k1 = int(math.ceil(s_u)), int(math.floor(e_u))
    a = max(k0 - FRONT_PRE_SAMPLES, 0)  # and the samples just before it: the start may be found after such a dip
    b = min(k0 + int(math.ceil(BUCKLING_TIME_S * fs)) + FRONT_DIP_AFTER_SAMPLES, k1, x.size - 1)
    if not peak > 0 or k0 < 0 or b <= k0:
        return []
    front = x[a:b + 1]
    jumped = np.flatnonzero(front > FRONT_DIP_JUMPED * peak)
    if not jumped.size:
        return []
    j = int(jumped[0]) + int(np.argmin(front[jumped[0]:]))
    if not front[j] < FRONT_DIP_ZERO * peak:
        return []
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact start not determined: {1e3 * (a + j - s_u) / fs:+.2g} ms from it a sample falls back to "
                    f"{100 * front[j] / peak:.2g} % of the peak after one at {100 * front[jumped[0]] / peak:.2g} % "
                    "(no ball's force returns to zero before it leaves): a negative electrical spike or a plate's "
                    "swing, and the force may start on either side of it")]
