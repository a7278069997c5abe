"""Single-sample electrical spikes: found by their second differences, replaced, or kept at a contact end."""

from __future__ import annotations

import math

import numpy as np

from ..problems import Problem, ProblemKind
from .contact import ContactResult
from .noise import robust_noise
from .window import EVENT_SIGMA

__all__ = ["remove_spikes", "replace_spikes", "second_differences", "spikes_at_ends", "low_spikes_at_ends"]

SPIKE_SIGMA = 12.0  # a spike's second difference exceeds this many noise deviations [-]
SPIKE_SHAPE_TOLERANCE = 0.15  # neighbours' second differences within this fraction of h of -h/2 (0 two and three away) [-]
SPIKE_END_SAMPLES = 4.0  # a spike replaced this close to a contact end may be the force's own at its jump [samples]
SPIKE_KINK_SIGMA = 5.0  # ... unless its neighbours continue one curve: their second differences, with it replaced,
#                         within this many noise deviations of the second difference (6.6 of their own noise) [-]
SPIKE_END_SIGMA = 6.0  # within SPIKE_END_WINDOW_S of a contact end a spike on one curve needs only this many [-]
SPIKE_END_WINDOW_S = 0.35e-3  # the samples the end's hinge is fitted to (contact.FOOT_MAX_S + FOOT_PRE_S) [s]
SPIKE_END_IMPULSE = 0.005  # a sample kept at a contact end, were it electrical, is this fraction of the impulse at
#                            most: half the 1 % tolerance of kCAL (the rest of the processing's kCAL error is
#                            within about a third of a per cent on almost every ok trace) [-]


def remove_spikes(voltage_V, noise_rms_V: float | None = None, keep=()):
    """Replace isolated single-sample spikes by the mean of their two neighbours.

    A spike of height h at sample k has second differences ``h`` at k, ``-h/2``
    at k-1 and k+1 and about 0 at k-2, k+2, k-3 and k+3; a contact, ringing or a step has
    not. Spikes are those with ``|h|`` above SPIKE_SIGMA noise deviations of the
    second difference and that shape.

    Parameters
    ----------
    voltage_V : array_like
        Voltage [V].
    noise_rms_V : float, optional
        Noise of the second difference [V]; robust estimate when omitted.
    keep : iterable of int
        Samples never replaced, whatever their shape [-] (a sample at a contact
        end that is the force's own, see :func:`spikes_at_ends`).

    Returns
    -------
    voltage_V : numpy.ndarray
        Copy with the spikes replaced [V].
    indices : numpy.ndarray
        Replaced samples [-].
    """
    v = np.array(voltage_V, dtype=float).ravel()
    d2, s = second_differences(v)
    if noise_rms_V is not None:
        s = float(noise_rms_V)
    return replace_spikes(v, d2, s, keep)


def replace_spikes(v, d2, s, keep=()):
    """:func:`remove_spikes` on v (replaced in place and returned) with its second differences d2 and their
    noise s [V] (:func:`second_differences`); a record of fewer than 7 samples is returned as it is."""
    if v.size < 7:
        return v, np.zeros(0, dtype=int)
    if not (s > 0):
        s = float(np.min(np.diff(np.unique(v)))) if np.unique(v).size > 1 else 0.0
        if not (s > 0):
            return v, np.zeros(0, dtype=int)
    cand = np.flatnonzero(np.abs(d2[3:-3]) > SPIKE_SIGMA * s) + 3
    cand = cand[~np.isin(cand, np.asarray(tuple(keep), dtype=int))]
    if cand.size == 0:
        return v, cand
    h = d2[cand]
    tol = SPIKE_SHAPE_TOLERANCE * np.abs(h)
    shape = (np.abs(d2[cand - 1] + 0.5 * h) < tol) & (np.abs(d2[cand + 1] + 0.5 * h) < tol)
    shape &= (np.abs(d2[cand - 2]) < tol) & (np.abs(d2[cand + 2]) < tol)
    shape &= (np.abs(d2[cand - 3]) < tol) & (np.abs(d2[cand + 3]) < tol)
    idx = cand[shape]
    v[idx] = 0.5 * (v[idx - 1] + v[idx + 1])
    return v, idx


def second_differences(v):
    """Second differences ``v[k] - (v[k-1] + v[k+1]) / 2`` (0 at both ends) [V] and their robust noise [V]."""
    d2 = np.zeros(v.size)
    d2[1:-1] = v[1:-1] - 0.5 * (v[:-2] + v[2:])
    return d2, robust_noise(d2[1:-1])


def _spike_kink(voltage_V, k: int) -> float:
    """How far sample k's neighbours are from continuing one curve through it [V].

    With sample k replaced by its neighbours' mean M, the second differences at
    k-1 and k+1 become ``v[k-1] - (v[k-2] + M) / 2`` and ``v[k+1] - (M + v[k+2]) / 2``;
    the larger magnitude is returned. An electrical spike riding on a smooth
    force (or on the baseline) leaves them at the noise and the force's own
    curvature; at the force's jump from zero (section 3.2.4 in Goodwill & Haake
    2004: no force below 2 mm of compression) the samples before k continue the
    baseline and those after it the force, and they stand about a quarter of the
    jump apart.

    Parameters
    ----------
    voltage_V : array_like
        Voltage [V].
    k : int
        Sample, 2 <= k < len - 2 [-].

    Returns
    -------
    float
        The larger corrected second difference at k-1 or k+1, in magnitude [V].
    """
    v = np.asarray(voltage_V, dtype=float)
    if not 2 <= k < v.size - 2:
        raise ValueError(f"_spike_kink needs two samples either side of sample {k} (record of {v.size})")
    m = 0.5 * (v[k - 1] + v[k + 1])
    return float(max(abs(v[k - 1] - 0.5 * (v[k - 2] + m)), abs(v[k + 1] - 0.5 * (m + v[k + 2]))))


def spikes_at_ends(v_spiky, d2_spiky, spikes, kept, contact: ContactResult, x, noise, fs, t0_s, scale):
    """Single-sample spikes within SPIKE_END_SAMPLES of a contact end: replaced, kept or the end not determined.

    :func:`remove_spikes` replaces a sample that stands alone above its
    neighbours by their mean. At a contact end the force jumps (from zero
    below 2 mm of compression, section 3.2.4 in Goodwill & Haake 2004), and
    the force's own samples there can have that shape: a lightly damped plate
    sampled about twice a period answers the jump with a one-sample overshoot
    (replacing it takes a per cent or so out of the impulse, and moves kCAL and
    TC as much: tests/test_robustness.py), and at 50 kHz the ball's pre-buckling
    spike, 0.03-0.04 ms long at 12 m/s, is one sample.

    They are told apart by whether the replaced sample's neighbours continue one
    curve (:func:`_spike_kink` at most SPIKE_KINK_SIGMA noise deviations of the
    second difference): an electrical spike on the force's smooth fade or on
    the baseline leaves them so, and its replacement is right; at the
    jump the neighbours before it continue the baseline and those after it the
    force (0:1635: 187, 1:1331: 66, 5:183: 16 noise deviations). Such samples
    are returned to be kept: the caller conditions the trace again without
    replacing them.

    A kept sample is the force's own or an electrical spike riding on the
    jump, and the samples cannot tell which. The end is not determined when
    the sample is the contact's outermost (its outer neighbour within
    EVENT_SIGMA noise deviations of zero: without it the contact might begin a
    sample later); otherwise the end rests on its neighbour, and the sample's
    excess over its neighbours' mean, were it all electrical, is charged to the
    impulse: above SPIKE_END_IMPULSE of it the end is not determined (the
    plate's overshoot of 5:183: 1.2 %; the ball's spike of 0:1635: 0.31 %).

    Parameters
    ----------
    v_spiky : numpy.ndarray
        Voltage before spike removal, in units of ``scale`` [-].
    d2_spiky : tuple
        Its second differences and their noise (:func:`second_differences`) [-].
    spikes : array_like of int
        Samples replaced [-].
    kept : tuple of int or None
        Samples kept at the caller's second pass (None at the first) [-].
    contact : ContactResult
        Contact found on the conditioned signal.
    x : numpy.ndarray
        Conditioned signal, in units of ``scale`` [-].
    noise : float
        Its noise, in units of ``scale`` [-].
    fs, t0_s, scale : float
        Sample rate [Hz], time of the first sample [s], volts per unit [V].

    Returns
    -------
    problems : list of Problem
    keep : tuple of int
        Samples to keep at a second pass (empty when there is none to make).
    """
    if not contact.found or not (len(spikes) or kept):
        return [], ()
    first, kept = kept is None, (() if kept is None else kept)
    ends = {"start": (contact.start_s - t0_s) * fs, "end": (contact.end_s - t0_s) * fs}
    s_d2 = d2_spiky[1]
    jumps = {}
    for where, u in ends.items():
        for k in (int(k) for k in spikes if abs(int(k) - u) <= SPIKE_END_SAMPLES):
            if 2 <= k < v_spiky.size - 2 and _spike_kink(v_spiky, k) <= SPIKE_KINK_SIGMA * s_d2:
                continue  # an electrical spike on one curve: replaced right
            jumps.setdefault(k, (where, u))
    if jumps and first:
        return [], tuple(sorted(jumps))
    for k, (where, u) in jumps.items():  # a second pass that replaced another sample at a jump
        return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                        f"contact {where} not determined: a single-sample spike was replaced {k - u:+.2g} "
                        f"samples from it ({1e3 * (k - u) / fs:+.2g} ms); at the force's jump a lightly damped "
                        "plate's overshoot has that shape, so the sample may be the force's and not known")], ()
    s_u, e_u = ends["start"], ends["end"]
    a, b = max(int(math.ceil(s_u)), 0), min(int(math.floor(e_u)) + 1, x.size)
    impulse = float(np.sum(x[a:b]))  # [unit samples]
    for k in kept:
        where, u = ("start", s_u) if abs(k - s_u) <= abs(k - e_u) else ("end", e_u)
        if not 1 <= k < x.size - 1:
            continue
        outer = x[k - 1] if where == "start" else x[k + 1]
        excess = float(x[k] - 0.5 * (x[k - 1] + x[k + 1]))
        what = (f"contact {where} not determined: the sample {k - u:+.2g} samples from it "
                f"({1e3 * (k - u) / fs:+.2g} ms) stands {excess * scale:+.3g} V off its neighbours' mean, a "
                "single-sample spike's shape, where the force's curve breaks; kept as the force's (the ball's "
                "pre-buckling spike after its jump, a plate's overshoot), it may also be an electrical spike")
        if not (s_u < k < e_u) or not (outer > EVENT_SIGMA * noise):
            return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                            f"{what}, and it is the contact's outermost sample (the next one out "
                            f"{outer * scale:.3g} V, noise {noise * scale:.2g} V): were it electrical, the contact "
                            f"would {'begin a sample later' if where == 'start' else 'end a sample earlier'}")], ()
        if abs(excess) > SPIKE_END_IMPULSE * abs(impulse):
            return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                            f"{what}, and were it electrical the impulse would be "
                            f"{100 * abs(excess) / abs(impulse):.2g} % off (more than "
                            f"{100 * SPIKE_END_IMPULSE:.2g} %)")], ()
    return [], ()


def low_spikes_at_ends(v_spiky, d2_spiky, spikes, contact: ContactResult, fs, t0_s) -> tuple:
    """Spikes below SPIKE_SIGMA near a contact end that bend the end's fit: samples to replace too [-].

    The end is a line through the force's last samples meeting zero (the
    hinge, ``ballimpact.signal.contact``); an electrical spike of 6-12 noise
    deviations of the second difference among them, which
    :func:`remove_spikes` leaves (its threshold is for the whole record), tilts
    the line, by up to 2 % of TC. Within SPIKE_END_WINDOW_S of each end a sample above
    SPIKE_END_SIGMA deviations with the spike's shape whose neighbours
    continue one curve (:func:`_spike_kink` within SPIKE_KINK_SIGMA) is
    electrical and is replaced as the others are (a spike whose neighbours
    miss the shape by the noise is left). The shape's tolerance is not widened for the noise: that
    lets the bend where the force meets zero (a second difference
    at one sample, none at its neighbours) pass with the noise's help, and moves TC.
    """
    if not contact.found:
        return ()
    v = np.asarray(v_spiky, dtype=float)
    d2, s = d2_spiky
    if not (s > 0):
        return ()
    w = max(int(math.ceil(SPIKE_END_WINDOW_S * fs)), int(SPIKE_END_SAMPLES))
    out = []
    for u in ((contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs):
        a, b = max(int(math.floor(u)) - w, 3), min(int(math.ceil(u)) + w + 1, v.size - 3)
        for k in (a + np.flatnonzero(np.abs(d2[a:b]) > SPIKE_END_SIGMA * s)).tolist() if b > a else ():
            h = d2[k]
            if k in out or np.isin(k, spikes):
                continue
            tol = SPIKE_SHAPE_TOLERANCE * abs(h)
            if (abs(d2[k - 1] + 0.5 * h) < tol and abs(d2[k + 1] + 0.5 * h) < tol and abs(d2[k - 2]) < tol
                    and abs(d2[k + 2]) < tol and abs(d2[k - 3]) < tol and abs(d2[k + 3]) < tol
                    and _spike_kink(v, k) <= SPIKE_KINK_SIGMA * s):
                out.append(k)
    return tuple(sorted(out))
