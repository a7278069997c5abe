"""Checks for the plate's ringing: after the contact, as a spectral line in it, on its front, force below zero."""

from __future__ import annotations

import math

import numpy as np

from ..model import BUCKLING_TIME_S
from ..problems import Problem, ProblemKind
from .baseline import NYQUIST_MARGIN
from .end_checks import JUMP_MAX_FRACTION, MIN_CONTACT_SAMPLES
from .integrity import FLAT_SIGMA
from .peak import (FRONT_PRE_SAMPLES, OVERSHOOT_MIN_PERIOD, front_dip, peak_between_samples, peak_on_first_overshoot,
                   peak_on_front_ringing, peak_on_ringing)
from .shape import peak_on_slow_fall, peak_on_step_response, second_hump

__all__ = ["ringing_problems"]

RING_GAP_S = 0.1e-3  # the ringing check starts this long after the contact end [s]
RING_WINDOW_S = 1.0e-3  # ... and lasts this long [s]
RING_LINE_MIN_HZ = 3000.0  # plate resonances looked for in the contact above this [Hz]
RING_LINE_PROMINENCE = 3.8  # a spectral line this many times its neighbourhood is plate ringing [-]
RING_LINE_NOISE_FACTOR = 6.0  # ... and this many times the noise's amplitude in a bin [-]
RING_LINE_SIDE_BINS = 4  # a bump no more prominent over the median of the bins below it (at least this many) ... [-]
RING_LINE_EDGE_FRACTION = 3.0e-4  # ... and below this fraction of the peak is the force's own spectrum, no line [-]
RING_MAX_FRACTION = 0.02  # rms of the corrected signal there above this fraction of the peak: a problem [-]
FAST_RING_GAP_SAMPLES = 2  # the front's ringing is read from this long after buckling (BUCKLING_TIME_S in) ... [samples]
FAST_RING_WINDOW_S = 0.3e-3  # ... over this long (at least FAST_RING_MIN_SAMPLES), less a cubic (the force) ... [s]
FAST_RING_MIN_SAMPLES = 12  # ... [samples]
FAST_RING_SIGMA = 3.0  # ... whose residual's rms above this many noise deviations ... [-]
FAST_RING_FRACTION = 5.0e-3  # ... and this fraction of the peak ... [-]
FAST_RING_MAX_PERIOD = 3.6  # ... alternating with a period of at most this many samples: the ends are not known [samples]
FAST_RING_JUMPED = 0.2  # ... when the front, once above this fraction of the peak, ... [-]
FAST_RING_ZERO = 0.02  # ... swings back below this fraction of it, or half a sample exceeds JUMP_MAX_FRACTION of TC [-]
NEGATIVE_WINDOW_S = 3.0e-3  # the corrected signal this long after the contact must not go below zero ... [s]
NEGATIVE_SMOOTH_S = 0.05e-3  # ... averaged over this long (at least one sample) ... [s]
NEGATIVE_FRACTION = 5.0e-3  # ... by more than this fraction of the peak ... [-]
NEGATIVE_SIGMA = 6.0  # ... and this many standard errors of the average [-]
#: ... of which at least one must show the ringing itself.
PLATE_EVIDENCE = frozenset({ProblemKind.PLATE_RINGING, ProblemKind.PEAK_ON_RINGING, ProblemKind.NEGATIVE_FORCE})


def ringing_problems(x, fs, noise, peak, s_u, e_u, start_u, end_u, front=False, fall=False):
    """Plate ringing after the contact, force below zero, a peak on ringing, a spectral line in the contact; with
    ``front`` (the sensed force), also a peak lifted by the plate's ringing from the force's jump; with ``fall`` (an
    undone force, not low-passed: its drop at buckling as sudden as the ball's), a peak no other check judged that
    the force leaves slowly (on the sensed force :func:`condition_voltage` looks for that last)."""
    out = []
    a = int(math.ceil(e_u + RING_GAP_S * fs))
    b = min(a + max(int(round(RING_WINDOW_S * fs)), 3), x.size)
    if b - a >= 3:
        ring = float(np.sqrt(np.mean(x[a:b] ** 2)))
        if ring > RING_MAX_FRACTION * peak and ring > FLAT_SIGMA * noise:
            out.append(Problem(ProblemKind.PLATE_RINGING,
                               f"plate ringing outlasts the contact ({100 * ring / peak:.2g} % of the peak rms in the "
                               f"{RING_WINDOW_S * 1e3:g} ms after it): force and ringing not separable"))
    out.extend(_negative_force(x, fs, noise, peak, e_u))
    out.extend(peak_on_ringing(x[int(math.ceil(s_u)):int(math.floor(e_u)) + 1], fs, noise, peak))
    xc = x[max(int(math.ceil(s_u)), 0):int(math.floor(e_u)) + 1]
    # with the sample before the contact: a start inside the interval before the first sample (a jump's, a step's)
    # leaves it out of xc, and a largest sample that is the contact's first must still be judged against it
    out.extend(peak_between_samples(x[max(int(math.ceil(s_u)) - 1, 0):int(math.floor(e_u)) + 1], fs, noise,
                                     lifted=front))
    out.extend(second_hump(xc, fs, noise, peak))
    out.extend(peak_on_step_response(xc, fs, noise, peak, math.ceil(s_u) - s_u))
    out.extend(peak_on_front_ringing(x, fs, noise, peak, s_u, e_u) if front else [])
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:  # with evidence already the plate's undoing is tried
        out.extend(peak_on_first_overshoot(x, fs, noise, peak, s_u, e_u))
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:
        out.extend(_start_on_fast_ringing(x, fs, noise, peak, s_u, e_u))
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:
        out.extend(front_dip(x, fs, peak, s_u, e_u))
    if fall and not out:  # a peak no check above judged (without ``front`` they find only plate or peak kinds)
        out.extend(peak_on_slow_fall(xc, fs, noise, peak, math.ceil(s_u) - s_u))
    line = _ringing_line(x[max(int(math.ceil(start_u)), 0):min(int(math.floor(end_u)) + 1, x.size)], fs,
                         noise)
    if line is not None:
        f_line, amp_line, prominence = line
        out.append(Problem(ProblemKind.PLATE_RINGING,
                           f"plate ringing at {f_line / 1e3:.3g} kHz during the contact (a spectral line "
                           f"{prominence:.3g} times its neighbourhood, {100 * amp_line / peak:.2g} % of the peak): "
                           "force and plate ringing not separable",
                           data={"line_hz": f_line, "amplitude_fraction": amp_line / peak, "prominence": prominence}))
    return out


def _start_on_fast_ringing(x, fs, noise, peak, s_u, e_u):
    """The contact's ends read off a front that rings near half the sample rate: not known to 1 %.

    The force's jump (section 3.2.4 in Goodwill & Haake 2004: zero below
    2 mm of compression) sets a lightly damped plate ringing. Sampled 2-3.6
    times per period, the ringing alternates from sample to sample with a slow
    beat, and the samples of the front are the force plus a swing of up to the
    jump: the hinge through them puts the start up to 3 samples off (one of
    them swung down to zero reads as the last quiet sample, or the rise is
    sampled as a ramp), and TC 1.4-1.7 % off in bench/overshoot_map.py's
    plates at 2.2-3.5 samples a period, while the peak, later, is right and
    no other check sees the ringing: it dies before the contact's middle
    (where :func:`_ringing_line`'s window weighs the samples) and turns too
    fast for :func:`turning_points`. It is read after the drop at buckling
    (FAST_RING_GAP_SAMPLES after BUCKLING_TIME_S from the start, where the
    model's force is smooth) over FAST_RING_WINDOW_S: those samples less a
    cubic fitted to them leave more than FAST_RING_SIGMA noise deviations
    and FAST_RING_FRACTION of the peak in rms, ringing with a period of at
    most FAST_RING_MAX_PERIOD samples (its frequency w from ``y[n - 1] +
    y[n + 1] = 2 cos(w) y[n] + cubic(n)`` by least squares, the noise's
    power taken out of the normal equations; a decay reads cos(w) a little
    nearer -1, i.e. nearer fs / 2).
    Such ringing moves the start found by more than 1 % of TC when a sample
    of the front, once above FAST_RING_JUMPED of the peak, swings back below
    FAST_RING_ZERO of it (the ball's force never returns to zero after its
    jump: a swing as large as the jump), or when the contact holds so few
    samples that half a sample exceeds JUMP_MAX_FRACTION of TC (the rise
    sampled through the plate is its answer to a jump, located to half a
    sample at best, as :func:`end_problems` charges a jump); otherwise the
    start is left as found (tests/test_conditioning.py). At
    OVERSHOOT_MIN_PERIOD samples per period or more it is evidence of the
    plate (PLATE_RINGING: its undoing is tried); below, or above fs / 2 seen
    through its alias, the ringing is named and the start not determined
    (CONTACT_END_UNDETERMINED, no evidence: an alias undone is wrong). Not
    in the paper.
    """
    k0, k1 = int(math.ceil(s_u)), int(math.floor(e_u))
    a = k0 + int(math.ceil(BUCKLING_TIME_S * fs)) + FAST_RING_GAP_SAMPLES
    b = min(a + max(int(round(FAST_RING_WINDOW_S * fs)), FAST_RING_MIN_SAMPLES), k1 - FAST_RING_GAP_SAMPLES)
    if not (peak > 0 and noise > 0) or a < 0 or b - a < FAST_RING_MIN_SAMPLES or b > x.size:
        return []
    y = x[a:b]
    u = np.linspace(-1.0, 1.0, y.size)
    r = y - np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyfit(u, y, 3))
    power = float(np.mean(r * r))
    rms = math.sqrt(power)
    if not (rms > FAST_RING_SIGMA * noise and rms > FAST_RING_FRACTION * peak):
        return []
    # a sinusoid of w radians a sample obeys y[n - 1] + y[n + 1] = 2 cos(w) y[n], a cubic a cubic: fitted jointly
    # (the noise's power taken out of the normal equations: no bias towards cos(w) = 0)
    mid, um = y[1:-1], u[1:-1]
    design = np.column_stack([mid, np.ones(mid.size), um, um * um, um * um * um])
    gram = design.T @ design
    gram[0, 0] -= mid.size * noise * noise
    try:
        cos_w = 0.5 * float(np.linalg.solve(gram, design.T @ (y[:-2] + y[2:]))[0])
    except np.linalg.LinAlgError:
        return []
    if not cos_w < math.cos(2.0 * math.pi / FAST_RING_MAX_PERIOD):
        return []
    period = 2.0 * math.pi / math.acos(max(cos_w, -1.0))
    # the force, once jumped, never returns to zero: a front sample back at zero is a swing as large as the jump
    front = x[max(k0 - FRONT_PRE_SAMPLES, 0):min(a, x.size)]
    jumped = np.flatnonzero(front > FAST_RING_JUMPED * peak)
    dip = jumped.size and float(np.min(front[jumped[0]:])) < FAST_RING_ZERO * peak
    # else the rise is the plate's answer to a jump: the start located to half a sample at best, as a jump's
    if not dip and 0.5 <= JUMP_MAX_FRACTION * (e_u - s_u):
        return []
    why = (f"a sample of the front swings back below {100 * FAST_RING_ZERO:g} % of the peak after the force's jump "
           "(a swing as large as the jump)" if dip else
           f"the rise is the plate's answer to the force's jump, so the start is located to half a sample at best, "
           f"{100 * 0.5 / (e_u - s_u):.2g} % of TC ({e_u - s_u:.0f} samples)")
    seen = (f"the force {1e3 * (a - s_u) / fs:.2g}-{1e3 * (b - s_u) / fs:.2g} ms into the contact swings about a "
            f"smooth curve by {100 * rms / peak:.2g} % of the peak rms ({rms / noise:.3g} noise deviations), "
            f"alternating from sample to sample (about {period:.3g} samples a period, {fs / period / 1e3:.3g} kHz): "
            f"the plate rings from the force's jump, and {why}")
    if period >= OVERSHOOT_MIN_PERIOD:
        return [Problem(ProblemKind.PLATE_RINGING,
                        f"plate ringing near half the sample rate at the contact's front: {seen}; the start is not "
                        "known to 1 % of TC")]
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact start not determined to 1 %: {seen}; the plate rings near half the sample rate (or "
                    "above it, seen through its alias: not undone) (sample faster)")]


def _negative_force(x, fs, noise, peak, end_u):
    """A pull on the plate after the contact: the plate's own motion (or a wrong baseline), never the ball's force.

    A ball only pushes. After it has left, a plate with a resonance near the
    contact's frequencies swings back below zero (its free response; a heavily
    damped plate still undershoots once), and the same resonance has shaped the
    force during the contact, so neither TC nor the peak can be trusted. The
    corrected signal in the NEGATIVE_WINDOW_S after the contact end, averaged
    over NEGATIVE_SMOOTH_S, must not fall below zero by more than
    NEGATIVE_FRACTION of the peak and NEGATIVE_SIGMA standard errors.
    """
    k = max(int(round(NEGATIVE_SMOOTH_S * fs)), 1)
    a = int(math.ceil(end_u))
    b = min(a + int(round(NEGATIVE_WINDOW_S * fs)), x.size)
    if b - a < k:
        return []
    avg = np.convolve(x[a:b], np.ones(k) / k, mode="valid")
    i = int(np.argmin(avg))
    low = -float(avg[i])
    se = noise / math.sqrt(k)
    if low > NEGATIVE_FRACTION * peak and low > NEGATIVE_SIGMA * se:
        return [Problem(ProblemKind.NEGATIVE_FORCE,
                        f"force below zero after the contact: {100 * low / peak:.2g} % of the peak "
                        f"({low / se if se > 0 else math.inf:.3g} "
                        f"noise deviations) {1e3 * (i + (k - 1) / 2) / fs:.2g} ms after its end; the plate rings (or "
                        "the baseline is wrong) and TC and the peak cannot be trusted")]
    return []


def _ringing_line(xc, fs, noise):
    """A plate resonance in the contact: (frequency [Hz], amplitude [V], prominence [-]) or None.

    The contact less a quartic (its smooth shape) is Hann-windowed and
    zero-padded 4x; the largest spectral amplitude between RING_LINE_MIN_HZ
    and 0.45 fs is a line when it exceeds RING_LINE_PROMINENCE times the median
    amplitude within a factor 1.6 of its frequency (the smooth contact and the
    noise have no lines), and RING_LINE_NOISE_FACTOR times the amplitude white
    noise gives a bin (``1.73 noise / sqrt(n)`` with the Hann window). The
    force's own spectrum falls steeply with frequency (as f^-2 to f^-4): one
    of its side lobes just above RING_LINE_MIN_HZ stands out of the quieter
    frequencies above it only. A bump that does not stand out of the median
    below it alone and is below RING_LINE_EDGE_FRACTION of the peak is not
    taken for a line (the force's own spectrum there, a few hundredths of a
    per cent of the peak at most).
    """
    n = xc.size
    if n < MIN_CONTACT_SAMPLES:
        return None
    u = np.linspace(-1.0, 1.0, n)
    r = xc - np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyfit(u, xc, 4))
    w = np.hanning(n)
    nfft = 4 * n
    amp = 2.0 * np.abs(np.fft.rfft(r * w, nfft)) / w.sum()
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    band = np.flatnonzero((f > RING_LINE_MIN_HZ) & (f < NYQUIST_MARGIN * fs))
    if band.size < 10:
        return None
    k = int(band[np.argmax(amp[band])])
    lo, hi = np.searchsorted(f, [f[k] / 1.6, f[k] * 1.6])
    below, above = amp[lo:max(k - 12, lo)], amp[k + 12:hi]
    ref = np.concatenate([below, above])
    if ref.size < 8:
        return None
    prominence = float(amp[k] / max(np.median(ref), 1e-300))
    if prominence <= RING_LINE_PROMINENCE or amp[k] <= RING_LINE_NOISE_FACTOR * 1.73 * noise / math.sqrt(n):
        return None
    if below.size >= RING_LINE_SIDE_BINS and amp[k] <= RING_LINE_PROMINENCE * float(np.median(below)) \
            and amp[k] < RING_LINE_EDGE_FRACTION * float(np.max(xc)):
        return None  # a tiny bump on the force's own spectrum, which falls steeply above the band's edge
    return float(f[k]), float(amp[k]), prominence
