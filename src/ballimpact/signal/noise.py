"""Noise level, ADC step and the contact threshold of a plate voltage."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "MAD_TO_SIGMA",
    "robust_noise",
    "finite_median",
    "quantization_step",
    "contact_threshold",
    "smallest_step",
    "checked_arguments",
]

MAD_TO_SIGMA = 1.4826  # median absolute deviation -> standard deviation of a normal distribution [-]
THRESHOLD_SIGMA = 8.0  # contact threshold in noise standard deviations [-]
THRESHOLD_FRACTION = 0.03  # contact threshold as a fraction of the peak [-]
MIN_NOISE_SAMPLES = 20  # fewest quiet samples for a noise estimate [samples]
QUANTUM_MIN_STEPS = 20  # a grid of values is looked for only among at least this many distinct steps [-]
QUANTUM_ON_GRID = 0.95  # ... and found when this fraction of them are whole multiples of the least one ... [-]
QUANTUM_TOLERANCE = 0.02  # ... to within this fraction of it (a printed or float32 value's rounding) [-]


def robust_noise(values) -> float:
    """Noise standard deviation from the median absolute deviation.

    Parameters
    ----------
    values : array_like
        Quiet samples [V].

    Returns
    -------
    float
        1.4826 * median(|v - median(v)|) [V]; NaN for an empty input.
    """
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        return math.nan
    return float(MAD_TO_SIGMA * finite_median(np.abs(v - finite_median(v))))


def finite_median(values) -> float:
    """The median of finite values, as :func:`numpy.median` gives it, bit for bit, without its overhead.

    The conditioning takes about fifty medians of a few hundred to a few
    thousand samples per impact; numpy's wrapper (NaN check, axis handling)
    costs about as much as the partition itself there.

    Parameters
    ----------
    values : array_like
        Finite values, any unit; NaN is not checked for.

    Returns
    -------
    float
        The middle value, or the mean of the two middle ones for an even
        number of values [same unit]; NaN for an empty input.
    """
    v = np.asarray(values, dtype=float).ravel()
    n = v.size
    if n == 0:
        return math.nan
    k = n // 2
    if n % 2:
        return float(np.partition(v, k)[k])
    part = np.partition(v, (k - 1, k))
    return float((part[k - 1] + part[k]) / 2.0)


def quantization_step(values) -> float:
    """The step of the grid that a recorded trace's values lie on: the ADC's step [V], 0 when there is none.

    An ADC records whole multiples of its step (its range over 2^bits, plus
    an offset); a trace written as text keeps them to its printed digits. The
    least difference between distinct values is the step when nearly all the
    differences (QUANTUM_ON_GRID of them, at least QUANTUM_MIN_STEPS) are
    whole multiples of it, to within QUANTUM_TOLERANCE; values off any grid
    (a float simulation) give 0, and so does a single value off it (an
    interpolated sample: read the step on the samples as recorded). The step matters
    when the noise is smaller: undithered, the recorded trace moves in steps
    of it and its quiet stretches hold no noise to measure (the noise then
    estimated says nothing of what a step is), while the recording's error
    is up to half a step, with a standard deviation of step / sqrt(12) for a
    signal that crosses many steps. Not in the paper.

    Parameters
    ----------
    values : array_like
        The recorded samples [V] (before any correction: a corrected trace
        is off the grid).

    Returns
    -------
    float
        The step [V]; 0 when the values lie on no grid.
    """
    v = np.asarray(values, dtype=float).ravel()
    steps = np.diff(np.unique(v[np.isfinite(v)]))
    if steps.size < QUANTUM_MIN_STEPS:
        return 0.0
    q = float(steps.min())
    if not q > 0:
        return 0.0
    with np.errstate(over="ignore", invalid="ignore"):  # a least step near the smallest float: off any grid
        ratio = steps / q
        on_grid = np.abs(ratio - np.round(ratio)) <= QUANTUM_TOLERANCE
    return q if np.count_nonzero(on_grid) >= QUANTUM_ON_GRID * steps.size else 0.0


def contact_threshold(noise, peak) -> float:
    """The level a contact stands above: THRESHOLD_SIGMA noise deviations and THRESHOLD_FRACTION of the peak.

    Parameters
    ----------
    noise : float
        Noise standard deviation [V] (or any unit, the peak's).
    peak : float
        Largest value of the contact, in the noise's unit.

    Returns
    -------
    float
        The threshold, in that unit.
    """
    return max(THRESHOLD_SIGMA * noise, THRESHOLD_FRACTION * peak)


def smallest_step(xs: np.ndarray) -> float:
    """Smallest step between distinct sample values (the ADC step of a noise-free trace)."""
    steps = np.diff(np.unique(xs))
    return float(steps.min()) if steps.size else 0.0


def checked_arguments(voltage_V, sample_rate_hz, t0_s):
    """(sample rate [Hz], voltage as a float array [V]); ValueError naming a bad argument."""
    fs = float(sample_rate_hz)
    if not math.isfinite(fs) or fs <= 0:
        raise ValueError(f"sample_rate_hz must be positive and finite, got {sample_rate_hz!r}")
    x = np.asarray(voltage_V, dtype=float).ravel()
    if not np.all(np.isfinite(x)):
        bad = np.flatnonzero(~np.isfinite(x))
        raise ValueError(f"voltage_V holds {bad.size} non-finite samples (first at index {bad[0]})")
    if not math.isfinite(t0_s):
        raise ValueError(f"t0_s must be finite, got {t0_s!r}")
    return fs, x
