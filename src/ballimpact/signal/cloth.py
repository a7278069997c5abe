"""The cloth's phase: the contact's first instant from the force's steep edge and the model's 2 mm (section 3.2.4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model import CLOTH_DISPLACEMENT_M

__all__ = ["STEEP_SLOPE_FRACTION", "STEEP_MIN_RISE", "STEEP_MIN_SIGMA", "STEEP_MAX_WIDTH", "SteepEdge", "steep_edge",
           "cloth_phase_s", "first_contact", "hidden_cloth_phase"]

#: The steep edge is the stretch about the force's steepest rise where its slope exceeds this fraction of it [-] ...
STEEP_SLOPE_FRACTION = 0.25
#: ... it is a jump of the force where it rises by at least this fraction of the peak across it ... [-]
STEEP_MIN_RISE = 0.10
#: ... and by at least this many noise deviations ... [-]
STEEP_MIN_SIGMA = 10.0
#: ... within at most this fraction of TC [-] (a half-sine's edge so defined lasts 42 % of it; the model's jump
#: through a 7.5 kHz anti-aliasing filter about 0.15 ms, 4 % of a 4 ms TC).
STEEP_MAX_WIDTH = 0.08


@dataclass(frozen=True)
class SteepEdge:
    """The force's jump at the start of the contact.

    Attributes
    ----------
    at_u : float
        Its instant: the steepest rise, interpolated [samples].
    se_u : float
        Standard uncertainty of ``at_u`` [samples].
    rise : float
        The force's rise across it [the signal's unit].
    width_u : float
        How long it lasts [samples].
    """

    at_u: float
    se_u: float
    rise: float
    width_u: float


def steep_edge(x, start_u: float, peak_index: int, noise: float, contact_samples: float) -> SteepEdge | None:
    """The jump with which the force of a ball starts, where the trace shows one [samples].

    The model's force steps from zero at 2 mm of compression (section 3.2.4 of Goodwill & Haake 2004; with a cloth,
    from its light load) by 30-60 % of its peak, then rises far more slowly. A band-limited record (an anti-aliasing
    filter, a plate undone within a band) rounds the step symmetrically about its instant, where the slope is
    steepest. The edge is the stretch about the steepest rise between the start and the peak where the slope exceeds
    STEEP_SLOPE_FRACTION of it; it is a jump when the force rises across it by STEEP_MIN_RISE of the peak and
    STEEP_MIN_SIGMA noise deviations within STEEP_MAX_WIDTH of TC, and stays below STEEP_MIN_RISE of the peak from
    the start to it. The steepest rise is sought up to where the force first reaches STEEP_MIN_RISE of the peak, and
    on up the slope while it steepens (a rounded jump crosses that level on its way up): a steeper rise later, an electrical spike's or a plate's swing (a plate of 27 kHz sampled at 97 kHz swings back
    up faster than the jump), is not the contact's jump. A smooth pulse (a half-sine, whose steepest rise is its
    start) has none.

    Parameters
    ----------
    x : array_like
        Conditioned force signal [any unit].
    start_u : float
        The contact's start as read [samples].
    peak_index : int
        Index of its largest sample [-].
    noise : float
        Noise standard deviation [the signal's unit].
    contact_samples : float
        TC as read [samples].

    Returns
    -------
    SteepEdge or None
        None where the force shows no jump.
    """
    x = np.asarray(x, dtype=float)
    i0 = max(int(math.floor(start_u)) - 2, 0)
    if not (0 <= i0 < peak_index < x.size and contact_samples > 0):
        return None
    d = np.diff(x[i0:peak_index + 1])  # d[j]: from sample i0 + j to i0 + j + 1
    # the jump is the steepest rise up to where the force first reaches STEEP_MIN_RISE of the peak: a steeper swing
    # later (a plate's, ringing at a few samples a period after the jump) is not the contact's jump
    s0 = max(int(math.ceil(start_u)), 0)
    above = np.flatnonzero(x[s0:peak_index + 1] >= STEEP_MIN_RISE * float(x[peak_index]))
    m = s0 + int(above[0]) - i0 if above.size else d.size  # d[m - 1]: the step into the first sample there
    if m < 1:
        return None
    while m < d.size and d[m] >= d[m - 1]:  # up the rounded jump's slope to its steepest
        m += 1
    k = int(np.argmax(d[:m]))
    if not d[k] > 0:
        return None
    a, b = k, k
    while a > 0 and d[a - 1] > STEEP_SLOPE_FRACTION * d[k]:
        a -= 1
    while b < d.size - 1 and d[b + 1] > STEEP_SLOPE_FRACTION * d[k]:
        b += 1
    if np.any(x[max(int(math.ceil(start_u)), 0):i0 + a] >= STEEP_MIN_RISE * float(x[peak_index])):
        return None  # the force had risen before it: not the contact's first jump (a spike, a plate's swing)
    rise = float(x[i0 + b + 1] - x[i0 + a])
    width = float(b - a + 1)
    if not (rise >= STEEP_MIN_RISE * float(x[peak_index]) and rise >= STEEP_MIN_SIGMA * noise
            and width <= STEEP_MAX_WIDTH * contact_samples):
        return None
    shift = 0.0
    if 0 < k < d.size - 1:  # the vertex of the parabola through the three slopes about the steepest
        den = d[k - 1] - 2.0 * d[k] + d[k + 1]
        if den < 0:
            shift = float(np.clip(0.5 * (d[k - 1] - d[k + 1]) / den, -0.5, 0.5))
    se = math.hypot(1.0 / math.sqrt(12.0), width * noise / rise) if width > 1 else 1.0 / math.sqrt(12.0)
    return SteepEdge(at_u=i0 + k + 0.5 + shift, se_u=se, rise=rise, width_u=width)


def cloth_phase_s(vin_m_s: float, cloth_displacement_m: float = CLOTH_DISPLACEMENT_M) -> float:
    """The cloth's phase: how long the ball takes to compress its cloth at the inbound speed [s] (section 3.2.4).

    Parameters
    ----------
    vin_m_s : float
        Inbound speed at the plate [m/s].
    cloth_displacement_m : float
        The cloth's compression before the ball's core loads [m].

    Returns
    -------
    float
        ``cloth_displacement_m / vin`` [s]; NaN where the speed is not known.
    """
    return cloth_displacement_m / vin_m_s if vin_m_s > 0 else math.nan


def first_contact(edge_u: float, fs: float, vin_m_s: float, *,
                  cloth_displacement_m: float = CLOTH_DISPLACEMENT_M) -> float:
    """The contact's first instant from the force's jump [samples]: the jump less the cloth's phase.

    The model's force is zero over the first ``cloth_displacement_m`` of compression and its TC counts them (section
    3.2.4), crossed at the inbound speed: the jump comes ``cloth_displacement_m / vin`` after the first contact. A
    real ball's cloth carries a light load there (the paper's Fig. 9), which noise, an undone plate or a filter's
    ringing can hide; the jump stands out of all of them.

    Parameters
    ----------
    edge_u : float
        The jump's instant (:func:`steep_edge`) [samples].
    fs : float
        Sample rate [Hz].
    vin_m_s : float
        Inbound speed at the plate [m/s].
    cloth_displacement_m : float
        The cloth's compression before the ball's core loads [m].

    Returns
    -------
    float
        [samples]; NaN where the speed is not known.
    """
    if not (vin_m_s > 0 and fs > 0):
        return math.nan
    return edge_u - cloth_phase_s(vin_m_s, cloth_displacement_m) * fs


def hidden_cloth_phase(vin_m_s: float, contact_time_s: float) -> float:
    """The relative shift of TC a cloth phase hidden by an undone plate may make: its length over TC [-].

    A ball's first 2 mm of compression load only its cloth, lightly (section 3.2.4 and Fig. 9 of Goodwill & Haake
    2004: the model's force is zero there, and its TC counts them), and TC runs from the first rise of that load.
    Undoing a plate amplifies the noise by far more than that load, so that a start read on the undone force where
    no jump completes it (:func:`first_contact`) may be late by up to the cloth's phase, 2 mm at the inbound speed
    (``ballimpact.model.CLOTH_DISPLACEMENT_M`` / vin). NaN where the speed or TC is not known.

    Parameters
    ----------
    vin_m_s : float
        Inbound speed at the plate [m/s].
    contact_time_s : float
        TC [s].
    """
    if not (vin_m_s > 0 and contact_time_s > 0):
        return math.nan
    return cloth_phase_s(vin_m_s) / contact_time_s
