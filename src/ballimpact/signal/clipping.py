"""ADC clipping and saturated (flat-topped) contacts on a plate voltage."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["detect_clipping", "Saturation", "detect_saturation", "true_runs"]

SATURATION_TOP_SIGMA = 4.0  # the contact's top: samples within this many noise deviations of its 8th largest [-]
SATURATION_NEXT_SIGMA = 12.0  # ... the band below it reaches this many noise deviations under that sample [-]
SATURATION_MIN_SAMPLES = 8  # a flat top is judged from this many samples in the top band on [samples]
SATURATION_RATIO = 3.0  # ... and is a saturated one when the top band holds this many times the band below [-]


def detect_clipping(raw_voltage_V, adc_range_V, *, adc_bits: int = 16, tolerance_lsb: float = 1.5,
                    min_run: int = 2) -> bool:
    """Whether a raw trace touches an ADC rail.

    Clipping = at least ``min_run`` consecutive samples within ``tolerance_lsb``
    least significant bits of the same rail. Works on the voltage as recorded
    (polarity not applied).

    Parameters
    ----------
    raw_voltage_V : array_like
        Recorded voltage [V].
    adc_range_V : tuple of float
        (low, high) ADC input range [V].
    adc_bits : int
        ADC resolution [bit].
    tolerance_lsb : float
        Distance from a rail that counts as "at the rail" [LSB].
    min_run : int
        Consecutive samples at a rail that make a clip [samples].

    Returns
    -------
    bool
        True when the trace is clipped.
    """
    lo, hi = (float(r) for r in adc_range_V)
    if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
        raise ValueError(f"adc_range_V must be (low, high) with low < high, got {adc_range_V!r}")
    if adc_bits < 1:
        raise ValueError(f"adc_bits must be positive, got {adc_bits}")
    if min_run < 1:
        raise ValueError(f"min_run must be at least 1, got {min_run}")
    v = np.asarray(raw_voltage_V, dtype=float).ravel()
    lsb = (hi - lo) / 2**adc_bits
    for at_rail in (v >= hi - tolerance_lsb * lsb, v <= lo + tolerance_lsb * lsb):
        starts, ends = true_runs(at_rail)
        if starts.size and np.max(ends - starts + 1) >= min_run:
            return True
    return False


@dataclass(frozen=True)
class Saturation:
    """What :func:`detect_saturation` saw at the top of a contact.

    Attributes
    ----------
    saturated : bool
        The top is flat: the signal was cut at a level below the ADC's rails.
    level_V : float
        Median of the samples in the top band [V].
    n_top : int
        Samples within SATURATION_TOP_SIGMA noise deviations of the SATURATION_MIN_SAMPLES-th largest [-].
    n_below : int
        Samples in the band from there down to SATURATION_NEXT_SIGMA deviations [-].
    ratio : float
        n_top / max(n_below, 1) [-].
    flat : bool
        The SATURATION_MIN_SAMPLES largest samples lie within SATURATION_TOP_SIGMA noise deviations of one another.
    evidence : float
        n_top over the band below counted about two Poisson deviations high, n_below + 2 sqrt(n_below + 1) + 1
        [-]: a flat top with at least SATURATION_MIN_SAMPLES samples is saturated from SATURATION_RATIO on.
    """

    saturated: bool
    level_V: float
    n_top: int
    n_below: int
    ratio: float
    flat: bool = False
    evidence: float = math.nan


def detect_saturation(voltage_V, noise_rms_V: float) -> Saturation:
    """Whether the top of a contact is flat: a charge amplifier (or any stage before the ADC) saturated below the
    ADC's rails, which :func:`detect_clipping` cannot see. Not in the paper.

    A saturated stage holds its output at one level while the force goes on rising above it: the samples pile
    up at that level and the force reaches it, and leaves it, with its full slope. A smooth force's top holds
    few samples near its maximum for the samples just below it: where it is a parabola, the samples within
    ``d`` of the maximum go as ``sqrt(d)``, and the top band (0 to SATURATION_TOP_SIGMA noise deviations under
    the largest sample) holds about 1.4 times the band under it (down to SATURATION_NEXT_SIGMA deviations); a
    sharp peak, as the model's pre-buckling spike, holds fewer. A saturated top holds all its flat samples in
    the top band and only the few of its steep flanks in the band under it. The bands are counted from the
    SATURATION_MIN_SAMPLES-th largest sample, not the largest: over a flat top's hundreds of samples the
    largest is the noise's maximum. The top is called saturated when its SATURATION_MIN_SAMPLES largest
    samples lie within the top band's depth of one another (a peak's fall away from its largest), it holds at
    least SATURATION_MIN_SAMPLES samples, and SATURATION_RATIO times the band under it counted about two
    Poisson deviations high (``evidence``: a few samples in either band say little); the evidence of a top that is
    not saturated stays well below 2 (``python bench/saturation_map.py --margin`` measures it), and that map itself
    says how many saturated traces it finds.

    The voltage is the one recorded, polarity applied (positive force), over the contact: saturation flattens
    the amplifier's output, not the corrected signal (the amplifier's decay, undone, tilts it).

    Parameters
    ----------
    voltage_V : array_like
        Recorded voltage over the contact, polarity applied, offset (and, where it is added after the
        amplifier, hum) removed or not [V].
    noise_rms_V : float
        Noise standard deviation of the quiet baseline [V].

    Returns
    -------
    Saturation

    Raises
    ------
    ValueError
        If noise_rms_V is not positive and finite.
    """
    if not (math.isfinite(noise_rms_V) and noise_rms_V > 0):
        raise ValueError(f"noise_rms_V must be positive and finite, got {noise_rms_V!r}")
    x = np.asarray(voltage_V, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size == 0:
        return Saturation(False, math.nan, 0, 0, math.nan)
    # the reference: over a flat top's hundreds of samples the largest is the noise's maximum, 3 deviations above
    # the level, and a band from it misses the flat samples that the noise took below the level
    k = min(SATURATION_MIN_SAMPLES, x.size)
    top = float(np.partition(x, x.size - k)[x.size - k])
    in_top = x >= top - SATURATION_TOP_SIGMA * noise_rms_V
    n_top = int(np.count_nonzero(in_top))
    n_below = int(np.count_nonzero(~in_top & (x >= top - SATURATION_NEXT_SIGMA * noise_rms_V)))
    flat = float(np.max(x)) - top <= SATURATION_TOP_SIGMA * noise_rms_V
    # a smooth top's plain ratio scatters up to 5 over 10 and 2 samples
    evidence = n_top / (n_below + 2.0 * math.sqrt(n_below + 1.0) + 1.0)
    saturated = flat and n_top >= SATURATION_MIN_SAMPLES and evidence >= SATURATION_RATIO
    return Saturation(bool(saturated), float(np.median(x[in_top])), n_top, n_below, n_top / max(n_below, 1),
                      bool(flat), float(evidence))


def true_runs(mask: np.ndarray):
    """Start and end (inclusive) indices of the runs of True in a boolean array."""
    m = np.asarray(mask, dtype=bool)
    if m.size == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    d = np.diff(np.concatenate([[0], m.view(np.int8), [0]]))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1
