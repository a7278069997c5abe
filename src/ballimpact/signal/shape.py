"""Checks of the force's shape: a second hump, a step response or slow fall at the peak, a low-passed front."""

from __future__ import annotations

import math

import numpy as np

from ..model import BUCKLING_TIME_S
from ..problems import Problem, ProblemKind
from .end_checks import MIN_CONTACT_SAMPLES
from .front import fit_front
from .peak import (FRONT_JUMP_FRACTION, FRONT_PRE_SAMPLES, FRONT_SIGNIFICANCE, OVERSHOOT_RISE_MAX,
                   ideal_front_beyond_noise, turning_points)

__all__ = ["second_hump", "peak_on_step_response", "peak_on_slow_fall", "front_lowpass"]

HUMP_SKIP_S = 0.3e-3  # a second hump is looked for this long after the contact start (the spike's phase) ... [s]
HUMP_SMOOTH_S = 0.1e-3  # ... in the force averaged over this long ... [s]
HUMP_DIP_FRACTION = 0.05  # ... a fall by more than this fraction of the peak after a maximum ... [-]
HUMP_RISE_FRACTION = 0.02  # ... then a rise by more than this fraction of it ... [-]
HUMP_SIGMA = 6.0  # ... each also this many noise deviations of the average: not the ball's force [-]
STEP_PHASE_S = 0.2e-3  # a peak this soon after the contact start (the spike's phase) is checked for ... [s]
STEP_WINDOW_S = 0.5e-3  # ... a fall, a second bump and a fall again within this long after it ... [s]
STEP_SMOOTH_S = 0.02e-3  # ... in the force averaged over this long (an odd number of samples) ... [s]
STEP_FRACTION = 5.0e-3  # ... each turn left by more than this fraction of the peak ... [-]
STEP_SIGMA = 6.0  # ... and this many noise deviations of the average ... [-]
STEP_FIRST_PERIOD = 1.0  # ... after a peak within this many of its periods of the start (the first overshoot) [-]
STEP_STEEPEST = 1.5  # a fall after the peak steeper than this times a swing's steepest is the force's own drop [-]
FALL_WINDOW_S = 0.15e-3  # a peak in the spike's phase (STEP_PHASE_S) is followed this long for its fall ... [s]
FALL_MIN_FRACTION = 0.05  # ... a fall by more than this fraction of the peak ... [-]
FALL_SIGMA = 20.0  # ... and this many noise deviations ... [-]
FALL_MAX_SAMPLES = 2  # ... spread from 10 to 90 % of it over more samples than this ... [samples]
FALL_MAX_S = 30.0e-6  # ... and longer than this: not the ball's sudden drop at buckling [s]
LOWPASS_RISE_S = 0.15e-3  # the force's rise from the contact start to this long after it (before buckling) ... [s]
LOWPASS_STEP_S = 10.0e-6  # ... and its largest rise in this long (the model's jump: its 0.01 ms step) and a sample:
LOWPASS_CONCENTRATION = 0.4  # ... less than this fraction of the rise, a jump spread: its front is fitted ... [-]
LOWPASS_WINDOW_S = 0.6e-3  # ... from the contact start to this long after it ... [s]
LOWPASS_MAX_SAMPLES = 80  # ... on every q-th sample, q the least that leaves at most this many in it (40 lost a
#: slow low-pass's evidence) [samples]
LOWPASS_DAMPING = (0.2, 0.98)  # the low-pass fitted: a second-order response of these damping ratios (one at the
#: lower bound is a plate that rings, for the plate's checks) ...
LOWPASS_DELAY_FRACTION = 2.0e-3  # ... whose delay 2 zeta / wn is more than this fraction of TC ... [-]
LOWPASS_DELAY_SAMPLES = 1.0  # ... and more than this many of the samples fitted (less: no trace in them) ... [samples]
LOWPASS_RESIDUAL = 4.0  # ... that leaves at most this many noise variances per sample (it explains the front) [-]


def second_hump(xc, fs, noise, peak):
    """A contact force that falls and rises again after its first maximum: not a ball's force.

    After the pre-buckling spike (its phase, HUMP_SKIP_S after the start), the ball's
    force of the model (Eq. (14) in Goodwill & Haake 2004: kB x + (cB + cM) x' with x
    rising then falling once) has one maximum. A fall of more than HUMP_DIP_FRACTION of
    the peak after a maximum and a rise of more than HUMP_RISE_FRACTION after it, in the
    force averaged over HUMP_SMOOTH_S (which quiets the noise and ringing of a plate
    above a few kHz, left to the other checks), is a plate resonance below the band the
    ringing checks look at (3 kHz; such a plate leaves TC and the peak tens of per cent off), or a second contact
    inside
    the first.
    """
    skip = int(round(HUMP_SKIP_S * fs))
    w = max(int(round(HUMP_SMOOTH_S * fs)), 1)
    if not peak > 0 or xc.size - skip < 3 * w:
        return []
    y = np.convolve(xc[skip:], np.full(w, 1.0 / w), mode="valid")
    tol = HUMP_SIGMA * noise / math.sqrt(w)
    dip_min = max(HUMP_DIP_FRACTION * peak, tol)
    rise_min = max(HUMP_RISE_FRACTION * peak, tol)
    top = low = float(y[0])  # the largest average so far, and the lowest since it
    for j in range(1, y.size):
        v = float(y[j])
        if top - low > dip_min and v - low > rise_min:
            t_top = 1e3 * (skip + int(np.argmax(y[:j])) + (w - 1) / 2) / fs
            return [Problem(ProblemKind.PLATE_RINGING,
                            f"force with two humps: after its maximum at {t_top:.2g} ms into the contact it falls by "
                            f"{100 * (top - low) / peak:.2g} % of the peak and rises again by "
                            f"{100 * (v - low) / peak:.2g} % (averaged over {HUMP_SMOOTH_S * 1e3:g} ms); a ball's "
                            "force has one: a plate resonance below 3 kHz, or a second contact inside the first")]
        if v > top:
            top = low = v
        elif v < low:
            low = v
    return []


def peak_on_step_response(xc, fs, noise, peak, lead=0.0):
    """The peak force on the plate's step response: its first overshoot of the force's jump, not the ball's.

    The ball's force jumps from zero (at 2 mm of compression in the model), rises
    to the pre-buckling spike, drops at buckling, and then rises once to its
    maximum and falls once (Eq. (14) in Goodwill & Haake 2004: kB x + (cB + cM) x'
    with x rising then falling once): after a peak in the spike's phase it has
    one minimum and no bump before the maximum that follows. A plate of a few kHz
    answers the jump with its step response: a rise over part of its period, an
    overshoot, then a damped oscillation. Heavily damped (zeta about 0.2), that one
    overshoot raises the peak by 5-20 % and the swings after it are too few and
    too unequal for :func:`peak_on_ringing` (plates of several kHz, ok with the peak
    5.6-10.4 % high).

    So, in the force averaged over STEP_SMOOTH_S, a peak within STEP_PHASE_S of
    the contact start that is followed within STEP_WINDOW_S by a fall, a rise (a
    second bump) and a fall again, each turn left by more than STEP_FRACTION of
    the peak and STEP_SIGMA noise deviations of the average (the rise after the
    last fall too, so that the fall after the ball's own maximum is none), is the
    plate's when it is its first overshoot: no turn before it, and within
    STEP_FIRST_PERIOD periods of the swing (the spacing of the two minima) of the
    contact start (``lead`` [samples]: from the start to the first sample of
    ``xc``). A fall after the peak steeper than STEP_STEEPEST times a swing's
    steepest (pi times the fall over the period, per sample; less two noise
    deviations of a difference) is the ball's own drop at buckling (sensed
    through a fast plate, or an undone one), whose ringing came after the peak.
    A peak on a later swing (a spike's top overshot by a plate that has rung
    since the jump) is not judged here.
    """
    w = 2 * int(round(0.5 * STEP_SMOOTH_S * fs)) + 1
    if not peak > 0 or xc.size < 4 * w:
        return []
    y = np.convolve(xc, np.full(w, 1.0 / w), mode="same") if w > 1 else xc
    i = int(np.argmax(y))
    if i > STEP_PHASE_S * fs:
        return []
    h = max(STEP_FRACTION * peak, STEP_SIGMA * noise / math.sqrt(w))
    seg = y[i:min(xc.size, i + int(round(STEP_WINDOW_S * fs)) + 1)]
    turns = turning_points(seg, h)  # from the peak: a minimum, a maximum, a minimum (each confirmed)
    if len(turns) < 3:
        return []
    low1, bump, low2 = turns[:3]
    period = float(low2 - low1)  # [samples]
    if i + lead > STEP_FIRST_PERIOD * period or turning_points(y[:i + 1], h):
        return []  # a peak later than the first overshoot, or not the first maximum
    fall = float(seg[0] - seg[low1])
    steepest = float(np.max(xc[i:i + low1] - xc[i + 1:i + low1 + 1])) - 2.0 * math.sqrt(2.0) * noise
    if steepest > STEP_STEEPEST * math.pi * fall / period:
        return []  # a swing of that period falls by at most pi fall / period a sample: the ball's force drops
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on the plate's step response: {1e3 * i / fs:.2g} ms into the contact the force "
                    f"peaks, falls by {100 * (seg[0] - seg[low1]) / peak:.2g} % of the peak, rises again by "
                    f"{100 * (seg[bump] - seg[low1]) / peak:.2g} % and falls by {100 * (seg[bump] - seg[low2]) / peak:.2g}"
                    f" % within {1e3 * low2 / fs:.2g} ms (a ball's force has no such bump): the plate's first "
                    f"overshoot of the force's jump, ringing at about {fs / (low2 - low1) / 1e3:.3g} kHz; the peak "
                    "is not the ball's")]


def peak_on_slow_fall(xc, fs, noise, peak, lead=0.0):
    """A peak in the spike's phase that the force leaves slowly: the chain's response to the jump, not the ball's.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake 2004)
    the force jumps from zero and rises until the wall buckles, when the
    stiffness falls at once from kCONST to kB(0) + AK x^a: a largest sample in
    that phase (within STEP_PHASE_S of the start; ``lead`` [samples] from the
    start to ``xc``'s first sample) is the spike's top, and the force drops
    from it suddenly, within a sample or two of any sample rate. A fall of
    more than FALL_MIN_FRACTION of the peak (and FALL_SIGMA noise
    deviations) within FALL_WINDOW_S after it, spread from 10 to 90 % of its
    depth over more than FALL_MAX_SAMPLES samples and FALL_MAX_S, is the
    sensing chain's: the overshoot of the force's jump by a plate the ringing
    checks do not recognise (a plate of two modes, the largest sample a few per
    cent to tens of per cent above the ball's peak), or a smoothing that spreads the
    spike. Either way the top is not the ball's: the ball's drop at buckling
    takes at most a couple of samples, such a fall several. Run last on the sensed
    force, on a trace nothing else excludes: after
    :func:`peak_on_first_overshoot` (a plate near fs / 2 it names as no
    evidence stays so) and after :func:`front_lowpass` (a low-pass slows
    the fall too, and its message names TC's error:
    tests/test_robustness.py's low-pass cases). Also run on an undone force
    that is not low-passed (a low-pass spreads the drop by its kernel), on a
    peak no other check judged: where one mode is identified and undone,
    the other's overshoot stays (5:243, 8.0 and 30.3 kHz, the second
    undone: +29 %).
    """
    if not peak > 0 or xc.size < 3:
        return []
    i = int(np.argmax(xc))
    if (i + lead) / fs > STEP_PHASE_S:
        return []
    seg = xc[i:min(xc.size, i + int(round(FALL_WINDOW_S * fs)) + 1)]
    m = int(np.argmin(seg))
    drop = float(seg[0] - seg[m])
    if drop <= max(FALL_MIN_FRACTION * peak, FALL_SIGMA * noise):
        return []
    k10 = int(np.argmax(seg[:m + 1] <= seg[0] - 0.1 * drop))
    k90 = int(np.argmax(seg[:m + 1] <= seg[0] - 0.9 * drop))
    spread = k90 - k10
    if spread <= FALL_MAX_SAMPLES or spread / fs <= FALL_MAX_S:
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on the plate's step response: {1e3 * (i + lead) / fs:.2g} ms into the contact the "
                    f"force peaks and falls by {100 * drop / peak:.2g} % of the peak over {spread} samples "
                    f"({1e6 * spread / fs:.3g} us from 10 to 90 % of the fall); a ball's force drops at once as its "
                    "wall buckles: the sensing chain's answer to the force's jump (a plate's overshoot, or a "
                    "smoothing), not the ball's peak")]


def front_lowpass(x, fs, noise, peak, s_u, e_u, tc):
    """The force's jump at the contact start spread by a low-pass in the chain: the end comes late, TC long.

    The model's force jumps from zero (section 3.2.4 in Goodwill & Haake
    2004: the cloth carries no load below 2 mm of compression, then kB =
    kCONST) to 30-57 % of its peak within its 0.01 ms step. A low-pass in the
    sensor chain (a charge amplifier's filter: a second-order Butterworth has
    damping 0.71, a Bessel 0.87; or a plate on damped mounts) spreads that
    jump over its rise and delays the rest of the force by its group delay,
    2 zeta / wn. The contact's start is found at the foot of the spread jump,
    its end where the delayed and rounded fade meets zero, about twice the
    delay late: TC comes out long, and nothing rings to show it.

    So when the force's largest rise in LOWPASS_STEP_S (at least a sample)
    within LOWPASS_RISE_S of the start is less than LOWPASS_CONCENTRATION of
    its whole rise there (a jump through an ideal plate puts more than a
    third of it into that step; the gate only spares the fits, about 0.1 s
    each, on most traces, and the fits decide), the samples from
    FRONT_PRE_SAMPLES before the start to LOWPASS_WINDOW_S after it (every
    q-th, at most LOWPASS_MAX_SAMPLES) are fitted with the model's front and
    its drop at buckling (:func:`ballimpact.signal.front.fit_front` with ``drop``),
    once through a second-order response (fn up to 0.45 of the rate fitted,
    damping within LOWPASS_DAMPING) and once through an ideal plate (the jump
    rising over at most OVERSHOOT_RISE_MAX samples) with a cubic as well. The
    cubic lets the ideal plate follow a force that starts smoothly, without
    a jump, whose curve over the window is more than a parabola's (a
    half-sine's foot: tests/test_conditioning.py
    ``test_an_end_that_jumps_is_no_convex_fade``, which the low-pass fit took
    for a low-pass against the ideal plate's ramp and parabola); the
    low-pass fit gets none (there, it trades against the damping, which it
    presses to the bound). The low-pass is
    seen, and TC is not known to 1 %, when its fit

    * beats the ideal one by more than FRONT_SIGNIFICANCE residual variances
      (the larger of the noise's and its own, per sample),
    * explains the front: it leaves at most LOWPASS_RESIDUAL noise variances
      per sample (an ideal plate's front that the model's shape misses by
      more than the noise is fitted better through a smoother, and leaves
      many more),
    * is damped: its damping ratio is off the lower bound, 0.2 (a plate
      damped less rings, and the plate's checks see it; a bound much higher
      leaves a plate between them, ringing too little for those checks and
      fitted here at the bound), and
    * delays by more than LOWPASS_DELAY_FRACTION of TC and LOWPASS_DELAY_SAMPLES.

    A low-pass whose delay is under a sample or two (at 20-40 kHz, near half
    the rate) leaves little trace in the samples and is not always seen (docs/robustness.md,
    "What remains"). Not in the paper.
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not (peak > 0 and tc > 0) or k1 - k0 < MIN_CONTACT_SAMPLES or k1 >= x.size:
        return []
    seg = x[max(k0 - 1, 0):k0 + min(max(int(round(LOWPASS_RISE_S * fs)), 3), k1 - k0) + 1]
    m = max(1, int(math.ceil(LOWPASS_STEP_S * fs)))
    rise = float(np.max(seg) - seg[0])
    steepest = float(np.max(seg[m:] - seg[:-m]))
    if not rise > FRONT_JUMP_FRACTION * peak or steepest >= LOWPASS_CONCENTRATION * rise:
        return []  # no rise to judge, or a jump within a step: no low-pass worth a sample
    w = min(max(int(round(LOWPASS_WINDOW_S * fs)), 3), k1 - k0)
    q = max(1, int(math.ceil(w / LOWPASS_MAX_SAMPLES)))  # every q-th sample: a slow front needs no more
    first = k0 - FRONT_PRE_SAMPLES * q
    if first < 0:
        return []
    xs, fq, start = x[first:k0 + w + 1:q], fs / q, (s_u - first) / q
    within = BUCKLING_TIME_S * fq + 1.0  # the drop at buckling within 0.2 ms (and a sample) of the first sample
    ideal = ideal_front_beyond_noise(xs, fq, 0, xs.size - 1, start, noise, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                                      drop_within=within, cubic=True)
    if ideal is None:
        return []  # the ideal plate leaves too little for a low-pass to explain
    lowpass = fit_front(xs, fq, 0, xs.size - 1, start, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                        damping=LOWPASS_DAMPING, drop_within=within)
    if lowpass is None:
        return []
    variance = max(noise * noise, lowpass.rss / max(lowpass.n_samples - 10, 1))
    gain = (ideal.rss - lowpass.rss) / variance if variance > 0 else math.inf
    delay = 2.0 * lowpass.damping_ratio / (2.0 * math.pi * lowpass.frequency_hz)  # [s]
    damped = lowpass.damping_ratio > 1.05 * LOWPASS_DAMPING[0]  # off the lower bound, not pressed against it
    explained = lowpass.rss <= LOWPASS_RESIDUAL * lowpass.n_samples * noise * noise
    if not (gain > FRONT_SIGNIFICANCE and damped and explained
            and delay > max(LOWPASS_DELAY_FRACTION * tc, LOWPASS_DELAY_SAMPLES / fq)):
        return []
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact end not determined to 1 %: the force's jump at the contact start is spread over "
                    f"several samples, as through a low-pass (an amplifier's filter or a damped plate): the front "
                    f"fits a jump through a second-order response of about {lowpass.frequency_hz / 1e3:.3g} kHz "
                    f"(damping ratio {lowpass.damping_ratio:.2g}) with {ideal.rss / max(lowpass.rss, 1e-300):.3g} "
                    f"times less residual than through an ideal plate; such a low-pass delays the force by about "
                    f"{delay * 1e6:.3g} us ({100 * delay / tc:.2g} % of TC), and the contact's end as much or more "
                    "than its start (record without the filter)")]
