"""Contact start and end at sub-sample precision, impact counting and ADC clipping on a plate voltage.

Method (section 2 in Goodwill & Haake 2004: the contact time TC is the period
during which a force acts on the ball):

1. Noise: sigma = 1.4826 * median absolute deviation of the quiet pre-trigger
   (the samples before the first threshold crossing, less a 0.5 ms guard),
   unless the caller gives it.
2. Main contact: the run of samples above ``max(8 sigma, 3 % of peak)`` that
   holds the global maximum.
3. Start: walk back from the peak to the first sample above ``4 sigma``, then
   fit a hinge ``b * max(t - ts, 0)`` by least squares (exact, sub-sample ts)
   to the 0.15 ms before that sample and to the rising samples after it
   for as long as each added sample is predicted by the hinge within 3 standard
   errors. The samples before the crossing count as "zero force", so ts is
   where the force first becomes positive, not where it crosses a threshold;
   the low cloth ramp in front of the steep rise (about 1-2 % of the peak over
   0.1 ms) is included even when most of it is hidden in the noise, and the
   steep rise after it is left out of the fit. If the second rising sample is
   already on the steep rise (a faint foot with one sample above 4 sigma), the
   hinge through the first one alone is used.
4. End: the same on the reversed trace, which also includes a low force tail
   before the force returns to zero. If the rms in the 1 ms after the end is
   above 2 sigma (plate ringing outlasting the contact), the end is fitted
   again with that rms as the noise level so the ringing is not taken for
   force. The corner is then fitted again over the same samples with the
   hinge bent, ``g (b + c g)``, g = max(u - ts, 0), c <= 0: read from the
   end, the ball's force rises with a slope that eases, and the straight
   hinge through it meets zero late (+0.2 to +0.6 % of TC at noise of 0.1-0.3 %
   of the peak; ``line_end_s`` keeps its end).
5. Straight lines through the steep edges between 3 % and 20 % of the peak,
   extrapolated to zero (``edge_start_s``, ``edge_end_s``), are kept as
   diagnostics. They are not used for TC: plate ringing superposed on the rise
   makes the edge curved, and the line then crosses zero up to 3 samples early,
   and the line misses the cloth ramp and the force tail.
6. Other impacts: other runs above the threshold (runs separated by less than
   0.1 ms are merged) lasting more than 0.3 ms and reaching 5 % of the main peak
   above the record's level around them (the lower quartiles of 20 ms blocks):
   a pulse, not a slow wander.

On the test-suite's synthetic traces (half-sine with and without a 1-2 % cloth
ramp, peaks 2-8 V, 50 and 67 kHz, hum, decay, 1-3 mV noise, ringing) the
start and end are within about 0.3 samples (standard deviation), and TC is
within 1 % of the truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ContactResult",
    "detect_contact",
    "ContactSearch",
    "detect_clipping",
    "detect_saturation",
    "Saturation",
    "robust_noise",
    "finite_median",
    "quantization_step",
    "contact_threshold",
    "contact_samples",
    "end_from_curve",
    "end_standard_uncertainties",
    "MAD_TO_SIGMA",
]

MAD_TO_SIGMA = 1.4826  # median absolute deviation -> standard deviation of a normal distribution [-]

THRESHOLD_SIGMA = 8.0  # contact threshold in noise standard deviations [-]
THRESHOLD_FRACTION = 0.03  # contact threshold as a fraction of the peak [-]
EDGE_BAND = (0.03, 0.20)  # fractions of the peak between which edges are fitted by a line [-]
FOOT_SIGMA = 4.0  # the walk from the peak stops at this many noise standard deviations [-]
FOOT_MIN_SAMPLES = 2  # fewest rising samples in the hinge fit [samples]
FOOT_MAX_S = 0.2e-3  # longest stretch of rising samples in the hinge fit [s]
FOOT_PRE_S = 0.15e-3  # stretch before the first sample above the noise in the hinge fit [s]
FOOT_PRE_SAMPLES = 4  # ... but at least this many samples [samples]
FOOT_MAX_WIDENINGS = 8  # a slow foot's pre window may grow to this many more FOOT_PRE_S [-]
KINK_SIGMA = 4.0  # a bend of the rise lowering the residual sum of squares by this many noise deviations squared [-]
FOOT_RESIDUAL_SIGMA = 3.0  # a rising sample predicted worse than this (standard errors) ends the foot [-]
SPREAD_FACTOR = 2.0  # the ends are fitted again from samples above this many times the noise thresholds [-]
CURVE_FITS = ((2, 0.03), (3, 0.05))  # the end's curve: polynomials of this degree over this fraction of TC [-]
CURVE_MIN_SAMPLES = 4  # ... but over at least this many samples inside the contact [samples]
CURVE_SEARCH = 3.0  # its zero is looked for within this many samples of the hinge's end ... [samples]
CURVE_STEP = 0.05  # ... on a grid this fine, the least's neighbours refined by a parabola [samples]
CURVE_MIN_SLOPE = 3.0  # ... pinned only where the force's slope there is this many noise deviations per sample [-]
CURVE_RATE_HZ = 50.0e3  # faster: the search and the slope per CURVE_RATE_HZ sample (noise averaged over it) [Hz]
CURVE_CHI2 = 9.0  # its uncertainty: half the ends within this many noise variances of the least, over its root [-]
HINGE_SE_STEP = 0.1  # the hinge's corner profiled on a grid this fine for the ends' uncertainties [samples]
BENT_STEP = 0.02  # the end's bent hinge profiled on a grid this fine, then its least refined [samples]
BENT_REFINE_LEVELS = 3  # ... its least refined on this many finer grids [-]
BENT_REFINE_POINTS = 41  # ... of this many corners each [-]
BEND_CHI2 = 0.0  # ... and taken where its bend lowers the least residual sum of squares by more than this many
#                   noise variances (none: a price selects the straight hinge's late corner where noise hides
#                   the bend) [-]
JUMP_SIGMA = 3.0  # the first rising sample's step beats the next rise by this many standard errors: a jump [-]
STEP_FRACTION = 0.03  # the first sample out of the noise above this fraction of the peak: the force stepped up to it [-]
STEP_SIGMA = 1.0  # ... where the start's line predicts the last quiet sample within this many noise deviations [-]
RING_GAP_S = 0.1e-3  # the ringing check starts this long after the end [s]
RING_WINDOW_S = 1.0e-3  # ... and lasts this long [s]
RING_SIGMA = 2.0  # rms after the end above this many noise deviations = ringing [-]
SECOND_IMPACT_FRACTION = 0.05  # another impact reaches this fraction of the main peak [-]
SECOND_IMPACT_MIN_S = 0.3e-3  # ... and lasts longer than this [s]
SECOND_IMPACT_LOCAL_S = 20e-3  # ... above the level of the record in blocks this long around it [s]
MERGE_GAP_S = 0.1e-3  # runs above threshold closer than this are one run [s]
PRETRIGGER_GUARD_S = 0.5e-3  # gap between the noise window and the first crossing [s]
MIN_NOISE_SAMPLES = 20  # fewest quiet samples for a noise estimate [samples]
MIN_CONTACT_SAMPLES = 3  # fewest samples above threshold for a contact [samples]
NOISE_FLOOR_FRACTION = 1e-6  # lower bound of the noise estimate, fraction of the peak [-]
QUANTUM_MIN_STEPS = 20  # a grid of values is looked for only among at least this many distinct steps [-]
QUANTUM_ON_GRID = 0.95  # ... and found when this fraction of them are whole multiples of the least one ... [-]
QUANTUM_TOLERANCE = 0.02  # ... to within this fraction of it (a printed or float32 value's rounding) [-]
SATURATION_TOP_SIGMA = 4.0  # the contact's top: samples within this many noise deviations of its 8th largest [-]
SATURATION_NEXT_SIGMA = 12.0  # ... the band below it reaches this many noise deviations under that sample [-]
SATURATION_MIN_SAMPLES = 8  # a flat top is judged from this many samples in the top band on [samples]
SATURATION_RATIO = 3.0  # ... and is a saturated one when the top band holds this many times the band below [-]


@dataclass(frozen=True)
class ContactResult:
    """Where the contact is in a trace.

    Attributes
    ----------
    found : bool
        True when a contact was found; otherwise the times are NaN, the
        indices -1 (peak_index: the largest sample, -1 for an empty trace) and
        n_impacts 0.
    start_s, end_s : float
        Contact start and end on the trace's time axis ``t0_s + i / fs`` [s],
        sub-sample.
    edge_start_s, edge_end_s : float
        Zero crossings of the straight lines through the steep rising and
        falling edges (between 3 % and 20 % of the peak), diagnostics [s].
    start_index : int
        First sample at or after the start [-].
    end_index : int
        Last sample at or before the end [-].
    peak_index : int
        Index of the largest sample [-].
    peak_V : float
        Largest sample value [V].
    n_impacts : int
        Number of separate impacts in the trace (0 when none found) [-].
    noise_rms_V : float
        Noise standard deviation used for the thresholds [V]; at least the
        rms of the quantisation, (smallest step between sample values) / sqrt(12).
    threshold_V : float
        Threshold that defined the contact runs [V].
    clipped : bool
        True when the raw trace touches an ADC rail (only when the raw voltage
        and ADC range were given).
    flags : tuple of str
        Diagnostics: ``"no_contact"``, ``"multiple_impacts"``, ``"clipped"``,
        ``"contact_at_trace_start"``, ``"contact_at_trace_end"``,
        ``"short_pretrigger"``, ``"cloth_foot"`` (start more than a sample
        before the steep edge), ``"end_tail"`` (end more than a sample after
        it), ``"ringing_after_contact"``, ``"edge_fallback"``, ``"start_jump"``,
        ``"end_jump"`` (the force jumps from zero between two samples: that
        end is the middle of the interval, uncertain by half a sample),
        ``"start_step"`` (the line through the first samples predicts the last
        quiet one at zero: the force may step up anywhere between the hinge's
        corner and the first sample above the noise, and the start is the
        middle of that interval; see ``_foot_start``).
    other_impacts : tuple of (float, float)
        Every other impact counted in n_impacts: its start relative to the main
        contact's start [s] (negative before it) and its peak as a fraction of
        the main peak [-].
    start_spread_s, end_spread_s : float
        How far each end moves when it is fitted again from the samples above
        SPREAD_FACTOR times the noise threshold (only with ``spread=True``;
        NaN otherwise) [s]: a straight end hardly moves, a tail that fades
        into the noise does.
    curve_end_s, curve_end_se_s : float
        The end from the force's curve before it (only with ``curve=True``,
        not at a jump nor with ringing after the contact; NaN otherwise) and
        its standard uncertainty [s]: see :func:`end_from_curve`.
    start_se_s, end_se_s : float
        Standard uncertainty of each end from its hinge's fit (only with
        ``curve=True``; NaN otherwise) [s]: half the
        width of the corners whose residual sum of squares, with the hinge's
        slope fitted again, is within CURVE_CHI2 noise variances of the least,
        over its root (inf when that reaches the fit's window); half a sample
        at a jump; NaN without a fit. A force that fades into the noise with a
        slope of about a noise deviation per sample leaves its end known to a
        few samples only.
    line_end_s : float
        The end of the straight hinge through the last samples, before its
        bend is fitted (:func:`_bent_corner`; the same as ``end_s`` at a jump
        or without a bend) [s].
    """

    found: bool
    start_s: float
    end_s: float
    edge_start_s: float
    edge_end_s: float
    start_index: int
    end_index: int
    peak_index: int
    peak_V: float
    n_impacts: int
    noise_rms_V: float
    threshold_V: float
    clipped: bool
    flags: tuple[str, ...]
    other_impacts: tuple[tuple[float, float], ...] = ()
    start_spread_s: float = math.nan
    end_spread_s: float = math.nan
    curve_end_s: float = math.nan
    curve_end_se_s: float = math.nan
    start_se_s: float = math.nan
    end_se_s: float = math.nan
    line_end_s: float = math.nan

    @property
    def contact_time_s(self) -> float:
        """Contact time TC = end - start [s] (NaN when not found)."""
        return self.end_s - self.start_s if self.found else math.nan


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
        starts, ends = _runs(at_rail)
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
    Poisson deviations high (``evidence``: a few samples in either band say little). On the zoo's traces that
    are not faulty (tests/zoo.py, seeds 0-3, their true contacts) the evidence was at most 1.62
    (``python bench/saturation_map.py --margin --seed S --n 2000``); that map itself says how many saturated
    traces it finds.

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


def contact_samples(time_s, values, start_s: float, end_s: float, *, include_ends: bool = True,
                    start_jump: bool = False):
    """The samples of a signal inside a contact, with time from the contact start.

    Parameters
    ----------
    time_s : array_like
        Sample times, increasing [s].
    values : array_like
        Signal at those times (voltage [V], force [N], ...).
    start_s, end_s : float
        Contact start and end [s].
    include_ends : bool
        When True, the signal linearly interpolated at the start and the end
        is added as first and last point, so that trapezium sums cover exactly
        [start, end].
    start_jump : bool
        The force jumps from zero between the last quiet sample and the first
        one inside (the contact's ``start_jump`` flag; the start is the middle
        of that interval): with ``include_ends``, the first point holds the
        first inside sample's value instead of the line to zero. A jump
        anywhere in the interval, uniformly, holds that value over half a
        sample on average, and the trapezium sum then covers it so; the line
        from the quiet sample covers 3/8 of a sample, a bias of 1/8 of a
        sample times the jump (zoo traces at 20-25 kHz: kCAL +0.17 % on
        average over the ok ones, up to +0.8 % on a noiseless 20 kHz trace).
        The model's force jumps at 2 mm of compression (section 3.2.4 in
        Goodwill & Haake 2004).

    Returns
    -------
    t_rel_s : numpy.ndarray
        Time from the contact start [s] (0 first when include_ends).
    v : numpy.ndarray
        Signal values, same unit as ``values``.
    """
    t = np.asarray(time_s, dtype=float).ravel()
    v = np.asarray(values, dtype=float).ravel()
    if t.shape != v.shape:
        raise ValueError(f"time_s and values must have the same length, got {t.size} and {v.size}")
    if not (math.isfinite(start_s) and math.isfinite(end_s) and end_s > start_s):
        raise ValueError(f"need finite start_s < end_s, got start_s={start_s!r}, end_s={end_s!r}")
    if t.size < 2:
        raise ValueError(f"need at least 2 samples, got {t.size}")
    tol = 1e-6 * (t[-1] - t[0]) / (t.size - 1)  # rounding of the time axis [s]
    if start_s < t[0] - tol or end_s > t[-1] + tol:
        raise ValueError(f"contact [{start_s:.6g}, {end_s:.6g}] s lies outside the trace "
                         f"[{t[0]:.6g}, {t[-1]:.6g}] s")
    start_s, end_s = max(start_s, t[0]), min(end_s, t[-1])
    inside = (t > start_s) & (t < end_s)
    ts, vs = t[inside], v[inside]
    if include_ends:
        first = vs[0] if start_jump and vs.size else np.interp(start_s, t, v)
        ts = np.concatenate([[start_s], ts, [end_s]])
        vs = np.concatenate([[first], vs, [np.interp(end_s, t, v)]])
    return ts - start_s, vs


# --------------------------------------------------------------------------- internals


def _runs(mask: np.ndarray):
    """Start and end (inclusive) indices of the runs of True in a boolean array."""
    m = np.asarray(mask, dtype=bool)
    if m.size == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    d = np.diff(np.concatenate([[0], m.view(np.int8), [0]]))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1


def _merge_runs(starts, ends, max_gap: int):
    """Merge runs separated by fewer than max_gap samples below threshold."""
    if starts.size <= 1:
        return starts, ends
    gaps = starts[1:] - ends[:-1] - 1
    keep = np.concatenate([[True], gaps >= max_gap])
    new_starts = starts[keep]
    new_ends = ends[np.concatenate([keep[1:], [True]])]
    return new_starts, new_ends


def _line_zero(u: np.ndarray, y: np.ndarray) -> float:
    """Zero crossing of the least-squares line y = a + b u (NaN when flat)."""
    if u.size < 2:
        return math.nan
    um, ym = u.mean(), y.mean()
    suu = np.sum((u - um) ** 2)
    if suu <= 0:
        return math.nan
    b = np.sum((u - um) * (y - ym)) / suu
    if not math.isfinite(b) or b == 0:
        return math.nan
    return float(um - ym / b)


def _hinge_fits(u: np.ndarray, y: np.ndarray, lower: float, upper: float, first: int):
    """Exact least-squares hinges y = b * max(u - ts, 0), b >= 0, ts in [lower, upper], of the windows
    ``u[:e + 1]`` for every e from ``first`` on: arrays (ts, b, sse), one entry per window.

    Between two sample times the samples right of the corner are fixed, so the
    hinge is the straight line through them and the optimum there is that
    line's zero crossing when it falls inside the interval; otherwise it is at
    a sample time or a bound. All candidates of all windows are evaluated at
    once (running sums along the window), and the residual sum of squares of
    each window's best hinge is summed directly. Every sample before
    ``upper`` must be inside the first window (the corner's candidates are then
    the same for every window).
    """
    shift = float(u[0])
    u = np.asarray(u, dtype=float) - shift
    y = np.asarray(y, dtype=float)
    lower, upper = lower - shift, upper - shift
    n = u.size
    m = int(np.count_nonzero(u < upper))  # samples left of the upper bound: the lines' intervals
    if not m <= first + 1 <= n:
        raise ValueError(f"first window must hold every sample before the upper bound, got first={first}")
    ends = np.arange(first, n)
    # running sums of 1, u, u^2, y, u y and y^2 from the window's start (a leading zero: sums over k .. e are
    # p[:, e + 1] - p[:, k])
    p = np.zeros((6, n + 1))
    np.cumsum(np.stack([np.ones(n), u, u * u, y, u * y, y * y]), axis=1, out=p[:, 1:])
    yy = p[5, first + 1:]
    # corners at the bounds and at the sample times
    cand = np.concatenate([[lower, upper], u[(u > lower) & (u < upper)]])
    g = np.maximum(u[None, :] - cand[:, None], 0.0)
    gy = np.maximum(np.cumsum(g * y, axis=1)[:, first:], 0.0)
    gg = np.cumsum(g * g, axis=1)[:, first:]
    ok = gg > 0
    b = np.where(ok, gy / np.where(ok, gg, 1.0), 0.0)
    sse = yy - b * gy
    ts = np.broadcast_to(cand[:, None], b.shape)
    # corners inside the interval before sample k (k = 0 .. m; before the first, any time from lower on):
    # the line through the samples k .. e
    k = np.arange(0, m + 1)
    left = np.concatenate([[-np.inf], u])[k]
    s0, s1, s2, sy, suy, syy = p[:, None, ends + 1] - p[:, k, None]
    den = s0 * s2 - s1 * s1
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = (s0 * suy - s1 * sy) / den
        alpha = (sy - beta * s1) / s0
        ts_line = -alpha / beta
        sse_line = (yy[None, :] - syy) + (syy - alpha * sy - beta * suy)
    inside = (s0 >= 2) & (den > 0) & (beta > 0) & (ts_line >= lower) & (ts_line <= upper)
    inside &= (ts_line > left[:, None]) & (ts_line < u[np.minimum(k, n - 1), None])
    ts = np.concatenate([ts, np.where(inside, ts_line, 0.0)])
    b = np.concatenate([b, np.where(inside, beta, 0.0)])
    sse = np.concatenate([sse, np.where(inside, sse_line, np.inf)])
    best = np.argmin(sse, axis=0)
    cols = np.arange(ends.size)
    ts, b = ts[best, cols], b[best, cols]
    resid = (y[None, :] - b[:, None] * np.maximum(u[None, :] - ts[:, None], 0.0)) ** 2
    sse = np.cumsum(resid, axis=1)[cols, ends]
    return ts + shift, b, sse


def _edge_zero(xs: np.ndarray, peak_index: int, lo: float, hi: float):
    """Zero crossing of the line through the lowest part of the rising edge between lo and hi.

    Returns (u, fallback): u in samples; fallback True when fewer than two
    samples were in the band and the two samples around the lo crossing were used.
    """
    below = np.flatnonzero(xs[:peak_index] < lo)
    j_lo = int(below[-1]) if below.size else -1
    if j_lo < 0:
        return 0.0, False
    seg = xs[j_lo + 1:peak_index + 1]
    over = np.flatnonzero(seg > hi)
    n_band = int(over[0]) if over.size else seg.size
    u = np.arange(j_lo, j_lo + 1 + max(n_band, 1), dtype=float)
    fallback = n_band < 2
    zero = _line_zero(u[:2], xs[j_lo:j_lo + 2]) if fallback else _line_zero(u[1:], xs[j_lo + 1:j_lo + 1 + n_band])
    if not math.isfinite(zero):
        zero = float(j_lo)
    return min(max(zero, j_lo - max(n_band, 2), 0.0), float(j_lo + 1)), fallback


def _foot_start(xs: np.ndarray, peak_index: int, sigma: float, fs: float, split: bool = True, window=None,
                step=None):
    """Where the force leaves zero before the peak [samples] and whether it jumps there; (None, False) when never zero.

    A jump: the force is at zero on one sample and on the next already higher
    than the rise to the sample after it (the line through the two
    extrapolates to zero before the quiet sample). Then the force left zero
    somewhere between the two samples and nothing in the samples says where:
    the start is the middle of that interval, uncertain by half a sample either
    way (the contact's ``*_jump`` flags). The model's force jumps at 2 mm of
    compression (section 3.2 in Goodwill & Haake 2004), and any steep rise looks
    like a jump at a low sample rate.

    Walks back from the peak to the first sample above FOOT_SIGMA noise
    deviations (i0), then fits the hinge ``b * max(u - ts, 0)`` to a window
    holding FOOT_PRE_S of samples before i0 (so foot samples hidden in the noise
    are still used) and the rising samples from i0 on, for as long as adding
    the next one raises the residual sum of squares by less than
    (FOOT_RESIDUAL_SIGMA sigma)**2, i.e. while the hinge predicts it within
    FOOT_RESIDUAL_SIGMA standard errors (the steep rise after a cloth ramp
    departs from the ramp). Applied to the reversed trace it gives the end.
    A list ``window`` receives the first and last sample of the hinge's fit and the first sample above
    FOOT_SIGMA noise deviations (the hinge's corner is not after it).

    A list ``step`` (the start only: a ball's force may jump up from zero, it
    never drops to zero by a jump in restitution, Eq. (14) in Goodwill &
    Haake 2004) asks for the step the hinge cannot see. The model's force
    steps up from zero at 2 mm of compression (section 3.2.4: no cloth force
    before, kB = kCONST after; about 5-40 % of the peak), and a step at t0
    followed by a ramp puts every sample from i0 on the line through them,
    which meets zero before t0: the hinge's corner ts is early by the step
    over the slope, and its fit is as good for a step at any t0 in [ts, i0]
    as long as the samples between stay at zero. Where the first sample out
    of the noise already holds STEP_FRACTION of the peak (the contact
    threshold's fraction: the force rose from the noise to it within one
    sample; a cloth foot, as ``synth``'s 0.7 % of the peak, or a smooth rise
    sampled at 20 kHz or faster stays below it) and the line predicts the last
    quiet sample within STEP_SIGMA noise deviations of zero (nothing there
    tells a ramp from a step after it), the start is the middle of [ts, i0]
    and ``step`` receives the interval's width [samples] (a uniform's standard
    deviation, width / sqrt(12), goes into the start's uncertainty). On
    bench/ideal_plate_map.py (seed 1; 148 starts of 776 not flagged as jumps,
    141 of them with a first sample above 3 % of the peak) the hinge's start
    was early on every one, by 0.35 samples on average (up to 0.89), with a
    hinge uncertainty under 0.05 % of TC, the truth inside [ts, i0] on every
    one; on the 7 below 3 % it was off by 0.02 samples on average.
    """
    return _foot_from_hinge(xs, peak_index, sigma, _foot_hinge(xs, peak_index, sigma, fs, split), window, step)


def _foot_hinge(xs: np.ndarray, peak_index: int, sigma: float, fs: float, split: bool = True):
    """The hinge of :func:`_foot_start`: (ts [samples], i0, its window [wl, wr, i0]); None when never zero."""
    quiet = np.flatnonzero(xs[:peak_index + 1] <= FOOT_SIGMA * sigma)
    if not quiet.size:
        return None
    i0 = int(quiet[-1]) + 1
    w: list = []
    return _hinge_start(xs, peak_index, sigma, fs, i0, split, w), i0, w


def _foot_from_hinge(xs: np.ndarray, peak_index: int, sigma: float, hinge, window=None, step=None):
    """:func:`_foot_start` from its hinge (:func:`_foot_hinge`): the jump and the step judged on it."""
    if hinge is None:
        return None, False
    ts, i0, w = hinge
    if window is not None:
        window[:] = w
    if i0 + 1 <= peak_index and abs(ts - (i0 - 1)) < 0.5:
        jump, rise = xs[i0] - xs[i0 - 1], xs[i0 + 1] - xs[i0]
        if jump - rise > JUMP_SIGMA * math.sqrt(5.0) * sigma:
            return i0 - 0.5, True
    if step is not None and ts < i0 and len(w) == 3 and xs[i0] >= STEP_FRACTION * xs[peak_index]:
        wl, wr = int(w[0]), int(w[1])
        g = np.maximum(np.arange(wl, wr + 1, dtype=float) - ts, 0.0)
        gg = float(g @ g)
        b = float(g @ xs[wl:wr + 1]) / gg if gg > 0 else 0.0
        if b * max(i0 - 1 - ts, 0.0) <= STEP_SIGMA * sigma:
            step.append(float(i0 - ts))
            return 0.5 * (ts + i0), False
    return ts, False


def _hinge_start(xs: np.ndarray, peak_index: int, sigma: float, fs: float, i0: int, split: bool = True,
                 window=None) -> float:
    """The hinge-fit start of :func:`_foot_start` [samples]; i0 is the first sample above FOOT_SIGMA noise;
    ``split``: the start from the hinge's first straight segment where the rise bends (:func:`_first_segment`);
    a list ``window`` receives the first and last sample of the fit that gave it and i0."""
    n_pre = max(FOOT_PRE_SAMPLES, int(math.ceil(FOOT_PRE_S * fs)))
    k_max = max(FOOT_MIN_SAMPLES + 1, int(math.ceil(FOOT_MAX_S * fs)))
    # no foot reaches back to a lone sample above the contact threshold between quiet ones: that is a
    # spike (switching equipment), no force on the ball, and it must not pull the hinge
    # (looked for only as far back as the widest window reaches: one before it holds no window's corner back; the
    # slice starts a sample earlier, so that its first sample is judged with both neighbours)
    reach = max(i0 - n_pre * (1 + FOOT_MAX_WIDENINGS) - 2, 0)
    lone = np.flatnonzero(_lone_samples(xs[reach:max(i0, 0)], sigma))
    floor = reach + int(lone[-1]) + 1 if lone.size else 0
    wl = max(i0 - n_pre, floor)
    last = min(i0 + k_max - 1, peak_index)
    wr = min(i0 + FOOT_MIN_SAMPLES - 1, last)

    def fits_from(left: int):
        # the hinges of every window from left to an end from i0 (or wr, when the window cannot reach i0)
        # to last, fitted at once; index e - min(i0, wr)
        return _hinge_fits(np.arange(left, last + 1, dtype=float), xs[left:last + 1], float(left), float(i0),
                           min(i0, wr) - left)

    fits = fits_from(wl)
    # Slow foot (a gentle rise at low SNR, e.g. an 8 ms half-sine only 50x above the
    # noise takes > FOOT_PRE_S to reach FOOT_SIGMA): the pre window then holds no quiet
    # samples and the corner sticks to its first sample, giving a late start (TC up to
    # 4 % short). Widen the window back, a pre window at a time, until the corner is
    # free of it. A steep rise never sticks, so it is fitted exactly as before.
    n_widen = 0
    while fits[0][wr - min(i0, wr)] < wl + 1.0 and wl > floor and n_widen < FOOT_MAX_WIDENINGS:
        wl = max(wl - n_pre, floor)
        n_widen += 1
        fits = fits_from(wl)
    if last < i0:  # the peak itself is within FOOT_SIGMA noise: nothing rises to grow the window with
        if window is not None:
            window[:] = [wl, wr, i0]
        return float(fits[0][0])
    uw, yw = np.arange(wl, last + 1, dtype=float), xs[wl:last + 1]
    ts, b, sse = (float(v[wr - i0]) for v in fits)
    limit = (FOOT_RESIDUAL_SIGMA * sigma) ** 2
    if wr > i0:
        # Is the second rising sample already on the steep rise after a faint
        # foot? Then the hinge through it misses the sub-threshold foot samples
        # that the hinge through the first rising sample alone explains.
        sse2 = _hinge_sse(uw[:i0 - wl + 1], yw[:i0 - wl + 1], ts, b)
        if sse2 - fits[2][0] > limit:
            if window is not None:
                window[:] = [wl, i0, i0]
            return float(fits[0][0])
    # grow the window while the hinge predicts the next rising sample within FOOT_RESIDUAL_SIGMA
    while wr < last and fits[2][wr + 1 - i0] - sse <= limit:
        wr += 1
        ts, sse = float(fits[0][wr - i0]), float(fits[2][wr - i0])
    if window is not None:
        window[:] = [wl, wr, i0]
    return _first_segment(uw, yw, wl, wr, i0, fits, sigma, window) if split else ts


def _first_segment(uw, yw, wl: int, wr: int, i0: int, fits, sigma: float, window=None) -> float:
    """The hinge's start again from its first straight segment when the rise bends [samples].

    The growth of the hinge window stops at the first sample the hinge predicts
    worse than FOOT_RESIDUAL_SIGMA standard errors, but a rise that flattens
    gradually (read from the end: a low plateau ending in a steep drop) is
    followed sample by sample and the single line through it meets zero after
    the drop's foot. The window is split at every rising sample into the hinge
    before and a free, flatter line after; when the best such split lowers the
    residual sum of squares by more than KINK_SIGMA**2 noise variances, the
    start is that split's hinge. A rise that steepens (a cloth foot, a force
    smoothed by a low-pass) keeps the single line: its foot is what the hinge
    and the spread check were built for.

    ``uw``, ``yw``: sample times [samples] and values from wl on; ``fits``: the
    hinges (ts, b, sse) of the windows from wl to every end from i0 on
    (:func:`_hinge_fits`).
    """
    ts_all, b_all, sse_all = fits
    ts, sse = float(ts_all[wr - i0]), float(sse_all[wr - i0])
    ks = np.arange(i0 + FOOT_MIN_SAMPLES - 1, wr - 1)  # the hinge's last sample; the line takes k+1 .. wr
    if not ks.size:
        return ts
    tail_u, tail_y = uw[ks[0] + 1 - wl:wr + 1 - wl], yw[ks[0] + 1 - wl:wr + 1 - wl]
    on = tail_u[None, :] > ks[:, None]
    count = on.sum(axis=1)
    du = np.where(on, tail_u[None, :] - (on * tail_u).sum(axis=1, keepdims=True) / count[:, None], 0.0)
    dy = np.where(on, tail_y[None, :] - (on * tail_y).sum(axis=1, keepdims=True) / count[:, None], 0.0)
    suu = np.sum(du * du, axis=1)
    slope = np.where(suu > 0, np.sum(du * dy, axis=1) / np.where(suu > 0, suu, 1.0), 0.0)
    sse_k = sse_all[ks - i0] + np.sum((dy - slope[:, None] * du) ** 2, axis=1)
    # the rise flattens after the split (a drop from a low plateau), and the split fits better
    better = (sse_k < sse) & (b_all[ks - i0] > slope)
    if not better.any():
        return ts
    j = int(np.argmin(np.where(better, sse_k, np.inf)))
    if sse - float(sse_k[j]) > (KINK_SIGMA * sigma) ** 2:
        if window is not None:
            window[:] = [wl, int(ks[j]), i0]
        return float(ts_all[ks[j] - i0])
    return ts


def _hinge_sse(u, y, ts, b) -> float:
    return float(np.sum((y - b * np.maximum(u - ts, 0.0)) ** 2))


def _quantum(xs: np.ndarray) -> float:
    """Smallest step between distinct sample values (the ADC step of a noise-free trace)."""
    steps = np.diff(np.unique(xs))
    return float(steps.min()) if steps.size else 0.0


def _not_found(noise, threshold, peak_index, peak, clipped, flags) -> ContactResult:
    return ContactResult(
        found=False, start_s=math.nan, end_s=math.nan, edge_start_s=math.nan, edge_end_s=math.nan,
        start_index=-1, end_index=-1, peak_index=int(peak_index), peak_V=float(peak),
        n_impacts=0, noise_rms_V=float(noise), threshold_V=float(threshold),
        clipped=bool(clipped), flags=tuple(flags) + ("no_contact",),
    )


def _main_run(above: np.ndarray, peak_index: int, merge_gap: int):
    starts, ends = _merge_runs(*_runs(above), merge_gap)
    k = int(np.searchsorted(starts, peak_index, side="right")) - 1
    return starts, ends, k


def end_standard_uncertainties(contact: ContactResult, jump_s: float = 0.0) -> tuple[float, float]:
    """Standard uncertainties of the contact's start and end from their fits [s].

    Each end's hinge's (``start_se_s``, ``end_se_s``); the force's curve's where the end came from it
    (``end_curve``: ``curve_end_se_s``); ``jump_s`` where the force jumps from zero between two samples
    (``start_jump``, ``end_jump``). NaN where no fit was made.

    Parameters
    ----------
    contact : ContactResult
        The contact (found with ``curve=True`` for the fits' uncertainties).
    jump_s : float
        What an end at a jump counts [s]: 0 where its half sample is judged apart, 1 / (fs sqrt 12) for a
        uniform half sample.

    Returns
    -------
    (float, float)
        The start's and the end's standard uncertainty [s].
    """
    start = jump_s if "start_jump" in contact.flags else contact.start_se_s
    if "end_curve" in contact.flags:
        return start, contact.curve_end_se_s
    return start, jump_s if "end_jump" in contact.flags else contact.end_se_s


def detect_contact(voltage_V, sample_rate_hz: float, *, t0_s: float = 0.0, noise_rms_V: float | None = None,
                   raw_voltage_V=None, adc_range_V=None, adc_bits: int = 16, spread: bool = False,
                   curve: bool = False, step: bool = False) -> ContactResult:
    """Find the contact in a conditioned plate voltage.

    The voltage must have its offset, hum and decay removed and the polarity
    applied (see :func:`ballimpact.conditioning.condition_voltage`): the force
    is positive and the quiet baseline is zero. See the module docstring for
    the method. Never raises for a finite input of any shape and content;
    returns ``found=False`` with flag ``"no_contact"`` when nothing stands out of
    the noise. Contact time TC = end - start is the period during which a force
    acts on the ball (section 2 in Goodwill & Haake 2004).

    Parameters
    ----------
    voltage_V : array_like
        Conditioned voltage, one sample per 1/sample_rate_hz [V].
    sample_rate_hz : float
        Sample rate [Hz].
    t0_s : float
        Time of the first sample [s].
    noise_rms_V : float, optional
        Noise standard deviation [V]; estimated from the quiet pre-trigger when
        omitted.
    raw_voltage_V : array_like, optional
        Voltage as recorded [V], to check for clipping with ``adc_range_V``.
    adc_range_V : tuple of float, optional
        (low, high) ADC range [V].
    adc_bits : int
        ADC resolution [bit].
    spread : bool
        Also fit each end again from the samples above SPREAD_FACTOR times the
        noise threshold and report how far it moves (``start_spread_s``,
        ``end_spread_s``).
    curve : bool
        Also find the end from the force's curve before it
        (:func:`end_from_curve`; ``curve_end_s``, ``curve_end_se_s``).
    step : bool
        A start whose first sample out of the noise already holds
        STEP_FRACTION of the peak is the middle of the interval a step from
        zero may be in (flag ``start_step``; see ``_foot_start``): the model's
        force steps up at 2 mm of compression. False (default): the hinge's
        corner, as for a ramp.

    Returns
    -------
    ContactResult
        Start and end [s] (sub-sample), indices, peak [V], number of impacts,
        noise [V], threshold [V], clipping and flags.

    Raises
    ------
    ValueError
        If the voltage holds NaN or infinite values or the sample rate is not
        positive.
    """
    fs, x = _checked_arguments(voltage_V, sample_rate_hz, t0_s)
    return ContactSearch(x, fs, noise_rms_V=noise_rms_V, raw_voltage_V=raw_voltage_V, adc_range_V=adc_range_V,
                         adc_bits=adc_bits).result(t0_s=t0_s, spread=spread, curve=curve, step=step)


class ContactSearch:
    """The contact of one conditioned trace, found once and reported with any of :func:`detect_contact`'s options.

    ``ContactSearch(x, fs, noise_rms_V=s).result(t0_s=t, spread=True)`` is
    ``detect_contact(x, fs, t0_s=t, noise_rms_V=s, spread=True)``. The noise,
    the threshold, the main run, the other impacts, the edges and both ends'
    hinges do not depend on the options and are found once, when the search is
    made: the conditioning's last baseline iteration and its final report of
    the same signal share them.

    Parameters
    ----------
    voltage_V, sample_rate_hz, noise_rms_V, raw_voltage_V, adc_range_V, adc_bits
        As for :func:`detect_contact`: the conditioned voltage [V], its sample
        rate [Hz], its noise [V] (estimated when omitted), the recorded
        voltage [V] and the ADC's range [V] and resolution [bit].

    Raises
    ------
    ValueError
        If the voltage holds NaN or infinite values or the sample rate is not
        positive.
    """

    def __init__(self, voltage_V, sample_rate_hz: float, *, noise_rms_V: float | None = None, raw_voltage_V=None,
                 adc_range_V=None, adc_bits: int = 16):
        fs, x = _checked_arguments(voltage_V, sample_rate_hz, 0.0)
        self._fs = fs
        self._not_found = None
        flags: list[str] = []
        clipped = False
        if raw_voltage_V is not None and adc_range_V is not None:
            clipped = detect_clipping(raw_voltage_V, adc_range_V, adc_bits=adc_bits)
            if clipped:
                flags.append("clipped")
        self._clipped = clipped
        n = x.size
        if n < MIN_CONTACT_SAMPLES:
            self._not_found = _not_found(math.nan, math.nan, -1, math.nan, clipped, flags)
            return
        peak_index = int(np.argmax(x))
        scale = float(np.max(np.abs(x)))
        if scale == 0.0 or not math.isfinite(scale) or x[peak_index] <= 0:
            self._not_found = _not_found(math.nan, math.nan, peak_index, x[peak_index], clipped, flags)
            return
        xs = x / scale  # work in units of the largest magnitude: no overflow for any finite input
        peak = float(xs[peak_index])
        merge_gap = max(int(round(MERGE_GAP_S * fs)), 1)
        sigma = _noise_level(xs, peak, peak_index, fs, merge_gap, noise_rms_V, scale, flags)
        thr = contact_threshold(sigma, peak)
        if not peak > thr:
            self._not_found = _not_found(sigma * scale, thr * scale, peak_index, peak * scale, clipped, flags)
            return
        starts, ends, k = _main_run(xs > thr, peak_index, merge_gap)
        if k < 0 or ends[k] - starts[k] + 1 < MIN_CONTACT_SAMPLES:
            self._not_found = _not_found(sigma * scale, thr * scale, peak_index, peak * scale, clipped, flags)
            return
        others_found = _other_impacts(xs, starts, ends, k, peak, fs)
        if others_found:
            flags.append("multiple_impacts")
        self._xs, self._scale, self._peak_index, self._peak = xs, scale, peak_index, peak
        # consistency: the run above threshold lies inside the contact, start < end inside the trace. A spike
        # just before (after) the contact that the merging of runs joined to it is no force on the ball.
        self._sigma, self._thr = sigma, thr
        self._run = _unbroken_run(xs, peak_index, sigma, thr, int(starts[k]), int(ends[k]))
        self._others, self._flags = others_found, tuple(flags)
        self._hinges = _hinges(xs, peak_index, peak, sigma, fs)

    def result(self, *, t0_s: float = 0.0, spread: bool = False, curve: bool = False,
               step: bool = False) -> ContactResult:
        """The contact, as :func:`detect_contact` reports it with these options: the time of the first sample
        ``t0_s`` [s], ``spread``, ``curve`` and ``step`` (see there)."""
        if self._not_found is not None:
            return self._not_found
        fs, xs, peak_index, peak, sigma, scale = (self._fs, self._xs, self._peak_index, self._peak, self._sigma,
                                                  self._scale)
        n = xs.size
        flags = list(self._flags)
        others_found = self._others
        n_impacts = 1 + len(others_found)
        windows: dict = {}
        u_start, u_end, u_edge_start, u_edge_end = _contact_ends(xs, peak_index, sigma, fs, self._hinges, flags,
                                                                 windows, step)
        # the end's spread is the straight line's: how far its end depends on the samples near the noise (its
        # bend's corner moves less, and the checks on the spread were set on the line's)
        u_line = windows.get("line_end", math.nan)
        if not math.isfinite(u_line):
            u_line = u_end
        spreads = _spreads(xs, peak_index, sigma, fs, u_start, u_line, step) if spread else (math.nan, math.nan)
        run_a, run_b = self._run
        u_start = min(max(u_start, 0.0), float(run_a))
        u_end = max(min(u_end, n - 1.0), float(run_b))
        u_line = max(min(u_line, n - 1.0), float(run_b))
        u_edge_start = min(max(u_edge_start, u_start), float(run_a))
        u_edge_end = max(min(u_edge_end, u_end), float(run_b))
        ses = (math.nan, math.nan)
        if curve:  # the ends' uncertainties go with the curve's (what the conditioning's checks read)
            # a start in the middle of a step's interval: a uniform's deviation over it goes with the hinge's
            ses = (math.hypot(_hinge_se(xs, u_start, windows.get("start"), "start_jump" in flags),
                              windows.get("start_step", 0.0) / math.sqrt(12.0)),
                   # the bent hinge's (one more parameter) and never less than the straight one's: where no straight
                   # line pins the end, no bend does (zoo trace 1:1448, noise 0.6 % of the peak: TC -1.4 % with the
                   # bent hinge's own)
                   np.fmax(_hinge_se(xs[::-1], n - 1 - u_end, windows.get("end"), "end_jump" in flags),
                           windows.get("end_se", math.nan)))
        by_curve = (math.nan, math.nan)
        # also after an end flagged as a jump: a concave fade's last step out of low noise looks like one (zoo traces
        # 0:709, 1:763), and the curve's uncertainty tells whether its end is pinned
        if curve and not {"ringing_after_contact", "contact_at_trace_end"} & set(flags):
            by_curve = _curve_end(xs, sigma, u_start, u_line, peak_index, max(run_b, peak_index), fs)

        return ContactResult(
            found=True,
            start_s=t0_s + u_start / fs,
            end_s=t0_s + u_end / fs,
            edge_start_s=t0_s + u_edge_start / fs,
            edge_end_s=t0_s + u_edge_end / fs,
            start_index=int(math.ceil(u_start)),
            end_index=int(math.floor(u_end)),
            peak_index=peak_index,
            peak_V=peak * scale,
            n_impacts=n_impacts,
            noise_rms_V=sigma * scale,
            threshold_V=self._thr * scale,
            clipped=self._clipped,
            flags=tuple(flags),
            other_impacts=tuple(((j - u_start) / fs, frac) for j, frac in others_found),
            start_spread_s=spreads[0],
            end_spread_s=spreads[1],
            curve_end_s=t0_s + by_curve[0] / fs,
            curve_end_se_s=by_curve[1] / fs,
            start_se_s=ses[0] / fs,
            end_se_s=ses[1] / fs,
            line_end_s=t0_s + u_line / fs,
        )


def _bent_corner(y, window, noise: float, ts_line: float) -> tuple[float, float]:
    """The corner of a bent hinge ``max(u - ts, 0) * (b + c * max(u - ts, 0))``, b > 0, least squares over the
    hinge's window (wl, wr, i0) of y [samples], and its standard uncertainty [samples]; (ts_line, NaN) where it
    cannot be fitted (fewer than 4 samples from i0 to wr, or b <= 0 at every corner).

    Read from the contact's end, the ball's force rises from its corner with a slope that eases (c <= 0; where
    the least squares bend it the other way the straight hinge is taken at that corner): it falls
    faster the nearer it is to its end, as the model's force (Eq. (14) in Goodwill & Haake 2004) does for
    the four balls of Table 2 at 12 and 30 m/s (tests/zoo.py model_force, looked at). A
    straight hinge through such a rise lies above it at the corner and meets zero after the end: TC long by
    +0.2 to +0.6 % of TC on the model's ends at noise of 0.1-0.3 % of the peak, more the more samples the
    noise lets the window take, and more still when fitted again from twice the threshold (the spread check).
    The bent hinge takes the curvature: the corners are profiled on a BENT_STEP grid between wl and i0
    (b and c solved exactly at each, :func:`_bent_sse`), the least refined between its neighbours on finer
    grids (BENT_REFINE_LEVELS of BENT_REFINE_POINTS corners, to 2.5e-6 samples). The bend is taken wherever it
    lowers the least residual sum of squares (BEND_CHI2 = 0); else the straight corner stands. A price for the
    bend (AIC's 2 noise variances, until issue 9's twenty-fourth round) keeps the straight corner exactly where the
    noise hides the bend, and that corner is late: at noise of 0.2-0.3 % of the peak the end was then +0.11 to
    +0.23 samples late on average on a nearly straight fall, its z (error over uncertainty) of mean +0.5 to +0.8
    and RMS up to 1.5; taken always, +0.04 to +0.10 samples, z of mean +0.14 to +0.35 and RMS 1.02-1.13
    (tests/test_contact.py, ``test_end_unbiased_with_an_honest_uncertainty_at_moderate_noise``). The
    uncertainty is :func:`_hinge_se`'s rule on this profile: half the width of the corners within CURVE_CHI2 noise
    variances of the least over its root (inf when that reaches wl), or a uniform's over those within one.
    """
    wl, wr, i0 = (int(v) for v in window[:3])
    if not (noise > 0) or wr - i0 < 3:  # a bend is read from 4 rising samples at least
        return ts_line, math.nan
    u = np.arange(wl, wr + 1, dtype=float)
    yw = np.asarray(y[wl:wr + 1], dtype=float)
    grid = np.arange(float(wl), float(min(i0, wr - 3)) + 0.5 * BENT_STEP, BENT_STEP)
    if grid.size < 3:
        return ts_line, math.nan
    sse, straight = _bent_sse(u, yw, grid)
    k = int(np.argmin(sse))
    # the bend must lower the least residual (a few noisy samples bend a parabola as they like, but a price for
    # the bend biases the end late; the uncertainty below, never less than the straight hinge's, judges the bend)
    if not float(sse[k]) < float(np.min(straight)) - BEND_CHI2 * noise * noise:
        return ts_line, math.nan
    # refined between its neighbours: BENT_REFINE_LEVELS finer grids of BENT_REFINE_POINTS, each between the
    # neighbours of the last one's least (to BENT_STEP * (2 / (BENT_REFINE_POINTS - 1))**BENT_REFINE_LEVELS)
    lo, hi = float(grid[max(k - 1, 0)]), float(grid[min(k + 1, grid.size - 1)])
    ts, least = float(grid[k]), float(sse[k])
    for _ in range(BENT_REFINE_LEVELS):
        fine = np.linspace(lo, hi, BENT_REFINE_POINTS)
        fine_sse = _bent_sse(u, yw, fine)[0]
        j = int(np.argmin(fine_sse))
        if fine_sse[j] <= least:
            ts, least = float(fine[j]), float(fine_sse[j])
        lo, hi = float(fine[max(j - 1, 0)]), float(fine[min(j + 1, fine.size - 1)])
    level = float(sse[k]) + CURVE_CHI2 * noise * noise
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0:
        return ts, math.inf
    half = 0.5 * float(grid[inside[-1]] - grid[inside[0]]) / math.sqrt(CURVE_CHI2)
    flat = grid[sse <= float(sse[k]) + noise * noise]
    return ts, max(half, float(flat[-1] - flat[0]) / math.sqrt(12.0))


def _bent_sse(u: np.ndarray, yw: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual sums of squares of the bent hinge (:func:`_bent_corner`) at each corner, b and c solved exactly,
    c <= 0 (else the straight hinge's), and of the straight hinge; inf where b <= 0 or fewer than 3 samples are
    right of the corner."""
    g = np.maximum(u[None, :] - corners[:, None], 0.0)
    g2 = g * g
    s2, s3, s4 = np.sum(g2, axis=1), np.sum(g2 * g, axis=1), np.sum(g2 * g2, axis=1)
    y1, y2 = g @ yw, g2 @ yw
    det = s2 * s4 - s3 * s3
    ok = (np.count_nonzero(g, axis=1) >= 3) & (det > 1e-12 * np.maximum(s2 * s4, 1e-300))
    safe = np.where(ok, det, 1.0)
    b = np.where(ok, (s4 * y1 - s3 * y2) / safe, 0.0)
    c = np.where(ok, (s2 * y2 - s3 * y1) / safe, 0.0)
    yy = float(yw @ yw)
    sse = np.where(ok & (b > 0), yy - b * y1 - c * y2, np.inf)
    # a slope that eases only (c <= 0): a bend the other way is a fade into the end, the straight hinge's (the
    # curve's end and the spread judge it), and with it a tangent corner anywhere left of the rise would fit
    line = np.where(ok & (y1 > 0), yy - np.maximum(y1, 0.0) ** 2 / np.where(s2 > 0, s2, 1.0), np.inf)
    return np.where(c > 0, line, sse), line


def _hinge_se(y, ts: float, window, jump: bool) -> float:
    """Standard uncertainty [samples] of the corner ts of the hinge ``b * max(u - ts, 0)`` fitted to y[wl:wr + 1]
    (``window`` = (wl, wr, i0, noise), y read from the end concerned): the half-width of the corners between wl and
    i0 (the first sample above FOOT_SIGMA noise deviations holds force: no corner after it, as in the fit) whose
    residual sum of squares, b fitted again (b >= 0), is within CURVE_CHI2 noise variances of the least, over its
    root, or a uniform's over those within one noise variance where larger (a residual flat across them); inf when
    that reaches wl (the quiet samples do not bound it), half a sample at a jump, NaN without a
    window."""
    if jump:
        return 0.5
    if window is None:
        return math.nan
    wl, wr, i0, noise = window
    if wr - wl < 2 or i0 - wl < 1 or not noise > 0:
        return math.nan
    u = np.arange(wl, wr + 1, dtype=float)
    yw = np.asarray(y[wl:wr + 1], dtype=float)
    grid = np.arange(float(wl), float(min(i0, wr)) + 0.5 * HINGE_SE_STEP, HINGE_SE_STEP)
    g = np.maximum(u[None, :] - grid[:, None], 0.0)
    gy, gg = np.maximum(g @ yw, 0.0), np.sum(g * g, axis=1)
    sse = float(yw @ yw) - np.where(gg > 0, gy * gy / np.where(gg > 0, gg, 1.0), 0.0)
    level = float(np.min(sse)) + CURVE_CHI2 * noise * noise
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0:
        return math.inf
    i, j = int(inside[0]), int(inside[-1])
    lo = grid[i] - HINGE_SE_STEP * float(level - sse[i]) / float(sse[i - 1] - sse[i])
    hi = grid[j] if j == grid.size - 1 else grid[j] + HINGE_SE_STEP * float(level - sse[j]) / float(
        sse[j + 1] - sse[j])
    # at least a uniform's over the corners within one noise variance: a residual flat across them (a corner
    # anywhere between two samples)
    flat = grid[sse <= float(np.min(sse)) + noise * noise]
    return max(0.5 * float(hi - lo) / math.sqrt(CURVE_CHI2), float(flat[-1] - flat[0]) / math.sqrt(12.0))


def _lone_samples(xs, sigma: float, threshold: float | None = None) -> np.ndarray:
    """Samples above the contact threshold (default THRESHOLD_SIGMA noise) whose two neighbours are quiet (FOOT_SIGMA).

    A force on the ball cannot rise from zero and fall back to it within two
    sample intervals at any sample rate of raw-format v1.1: such a sample is a
    spike, not a foot or a tail.
    """
    xs = np.asarray(xs, dtype=float)
    loud = THRESHOLD_SIGMA * sigma if threshold is None else threshold
    out = np.zeros(xs.size, dtype=bool)
    if xs.size >= 3:
        quiet = xs <= FOOT_SIGMA * sigma
        out[1:-1] = (xs[1:-1] > loud) & quiet[:-2] & quiet[2:]
    return out


def _unbroken_run(xs, peak_index: int, sigma: float, thr: float, run_a: int, run_b: int) -> tuple[int, int]:
    """The run [run_a, run_b] above thr (merged across short gaps) without the lone samples at its ends (spikes)."""
    lone = _lone_samples(xs, sigma, thr)
    above = xs > thr
    while run_a < peak_index and lone[run_a]:
        run_a += int(np.flatnonzero(above[run_a + 1:peak_index + 1])[0]) + 1  # the peak is above: found
    while run_b > peak_index and lone[run_b]:
        run_b = peak_index + int(np.flatnonzero(above[peak_index:run_b])[-1])
    return run_a, run_b


def _checked_arguments(voltage_V, sample_rate_hz, t0_s):
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


def _noise_level(xs, peak, peak_index, fs, merge_gap, noise_rms_V, scale, flags) -> float:
    """Noise standard deviation in units of the largest magnitude: given, or from the quiet pre-trigger [-]."""
    if noise_rms_V is not None and math.isfinite(noise_rms_V) and noise_rms_V >= 0:
        sigma = float(noise_rms_V) / scale
    else:
        sigma0 = robust_noise(xs)
        thr0 = contact_threshold(sigma0, peak)
        starts0, _, _ = _main_run(xs > thr0, peak_index, merge_gap)
        first_crossing = int(starts0[0]) if starts0.size else peak_index
        stop = first_crossing - max(int(round(PRETRIGGER_GUARD_S * fs)), 1)
        if stop >= MIN_NOISE_SAMPLES:
            sigma = robust_noise(xs[:stop])
        else:
            flags.append("short_pretrigger")
            sigma = sigma0
    return max(sigma, _quantum(xs) / math.sqrt(12.0), NOISE_FLOOR_FRACTION * peak, 1e-300)


def _other_impacts(xs, starts, ends, k, peak, fs) -> list[tuple[int, float]]:
    """Runs above the threshold besides the main one (k) that count as impacts: (first sample, peak fraction)."""
    if starts.size <= 1:
        return []
    n = xs.size
    others = np.arange(starts.size) != k
    # a run cut off by either end of the trace may be longer than it shows: its length does not count
    long_enough = ((ends - starts + 1) / fs > SECOND_IMPACT_MIN_S) | (starts == 0) | (ends == n - 1)
    bounds = np.empty(2 * starts.size, dtype=int)
    bounds[0::2], bounds[1::2] = starts, ends + 1
    run_max = np.maximum.reduceat(np.concatenate([xs, [-np.inf]]), bounds)[0::2]
    high_enough = run_max > SECOND_IMPACT_FRACTION * peak
    counted = others & long_enough & high_enough
    out = []
    for j in np.flatnonzero(counted):
        height = _pulse_height(xs, int(starts[j]), int(ends[j]), max(int(round(SECOND_IMPACT_LOCAL_S * fs)), 2))
        if height > SECOND_IMPACT_FRACTION * peak:
            out.append((int(starts[j]), float(run_max[j] / peak)))
    return out


def _pulse_height(xs, a: int, b: int, w: int) -> float:
    """How far the run [a, b] stands above a local baseline [units of xs]: the largest of its samples less the
    baseline under it, the baseline (never below zero) interpolated between the lower quartiles of blocks of
    ``w`` samples over the run and ``w`` samples either side. An impact is a pulse of a few ms: it holds less than
    three quarters of a block, and the quartile is the record's level around it. A run that a slow wander of the
    corrected record lifted above the threshold is not: over seconds the undone decay integrates the baseline's
    small errors (bench/long_record_map.py), and the quartiles follow the wander."""
    lo, hi = max(a - w, 0), min(b + w + 1, xs.size)
    edges = list(range(lo, hi, w)) + [hi]
    if len(edges) > 2 and edges[-1] - edges[-2] < w // 2:  # a short last block joins the one before it
        del edges[-2]
    centres = np.array([0.5 * (edges[i] + edges[i + 1] - 1) for i in range(len(edges) - 1)])
    levels = np.array([np.percentile(xs[edges[i]:edges[i + 1]], 25.0) for i in range(len(edges) - 1)])
    u = np.arange(a, b + 1, dtype=float)
    return float(np.max(xs[a:b + 1] - np.maximum(np.interp(u, centres, levels), 0.0)))


@dataclass(frozen=True)
class _Hinges:
    """What :func:`_contact_ends` finds that no option changes: the edges, the start's hinge before the step is
    judged, and the end's hinge (see there)."""

    start_hinge: tuple | None  # :func:`_foot_hinge` of the start
    u_edge_start: float
    u_edge_end: float
    edge_fallback: bool
    u_end: float | None  # on the reversed trace [samples]; None when the force never returns to zero
    jump_end: bool
    w_end: list
    sigma_end: float
    ringing: bool
    end_se: float
    u_line: float | None  # the straight hinge's end, on the reversed trace [samples]


def _hinges(xs, peak_index, peak, sigma, fs) -> _Hinges:
    """The steep edges' zero crossings, the start's hinge and the end's (straight, then bent) of
    :func:`_contact_ends`."""
    n = xs.size
    lo = max(EDGE_BAND[0] * peak, min(FOOT_SIGMA * sigma, 0.5 * EDGE_BAND[1] * peak))
    hi = EDGE_BAND[1] * peak
    rev = xs[::-1]
    # steep edges: line through the lowest part of each edge, extrapolated to zero
    u_edge_start, fallback_start = _edge_zero(xs, peak_index, lo, hi)
    u_edge_end, fallback_end = _edge_zero(rev, n - 1 - peak_index, lo, hi)
    u_edge_end = n - 1 - u_edge_end
    # foot: the hinge fit where the force returns to zero
    w_end: list = []
    u_end, jump_end = _foot_start(rev, n - 1 - peak_index, sigma, fs, window=w_end)
    sigma_end = sigma
    ringing = False
    if u_end is not None:
        # Plate ringing that outlasts the contact would pass for force: measure
        # the disturbance just after the end and, when it is well above the
        # noise, find the end again with it as the noise level.
        a = int(math.ceil(n - 1 - u_end + RING_GAP_S * fs))
        b = min(a + int(round(RING_WINDOW_S * fs)), n)
        if b - a >= MIN_NOISE_SAMPLES:
            ring = float(np.sqrt(np.mean(xs[a:b] ** 2)))
            if ring > RING_SIGMA * sigma:
                ringing = True
                w_ring: list = []
                u_ring, jump_ring = _foot_start(rev, n - 1 - peak_index, ring, fs, window=w_ring)
                if u_ring is not None:
                    u_end, jump_end, w_end, sigma_end = u_ring, jump_ring, w_ring, ring
    end_se, u_line = math.nan, u_end
    if u_end is not None and not jump_end and len(w_end) == 3:
        u_end, end_se = _bent_corner(rev, w_end, sigma_end, u_end)
    return _Hinges(_foot_hinge(xs, peak_index, sigma, fs), u_edge_start, u_edge_end, fallback_start or fallback_end,
                   u_end, jump_end, w_end, sigma_end, ringing, end_se, u_line)


def _contact_ends(xs, peak_index, sigma, fs, hinges: _Hinges, flags, windows, step=False):
    """Start and end of the contact and of its steep edges [samples] from the trace's :func:`_hinges` (the same
    trace, peak and noise), adding the flags of what was seen; the dict ``windows`` receives, for "start" and "end",
    the first and last sample of each hinge's fit (on the trace read from that end), the first sample above
    FOOT_SIGMA noise deviations and the noise it was fitted with."""
    n = xs.size
    if hinges.edge_fallback:
        flags.append("edge_fallback")
    if hinges.ringing:
        flags.append("ringing_after_contact")
    # foot: the hinge fit where the force leaves zero
    w_start, step_start = [], []
    u_start, jump_start = _foot_from_hinge(xs, peak_index, sigma, hinges.start_hinge, window=w_start,
                                           step=step_start if step else None)
    u_end, jump_end, u_line = hinges.u_end, hinges.jump_end, hinges.u_line
    windows.update(start=(*w_start, sigma) if len(w_start) == 3 else None,
                   end=(*hinges.w_end, hinges.sigma_end) if len(hinges.w_end) == 3 else None,
                   start_step=step_start[0] if step_start and u_start is not None else 0.0, end_se=hinges.end_se,
                   line_end=n - 1 - u_line if u_line is not None else math.nan)
    if step_start and u_start is not None:
        flags.append("start_step")
    if jump_start and u_start is not None:
        flags.append("start_jump")
    if jump_end and u_end is not None:
        flags.append("end_jump")
    if u_start is None:
        flags.append("contact_at_trace_start")
        u_start = 0.0
    elif u_start < hinges.u_edge_start - 1.0:
        flags.append("cloth_foot")
    if u_end is None:
        flags.append("contact_at_trace_end")
        u_end = float(n - 1)
    else:
        u_end = n - 1 - u_end
        if u_end > hinges.u_edge_end + 1.0:
            flags.append("end_tail")
    return u_start, u_end, hinges.u_edge_start, hinges.u_edge_end


def _spreads(xs, peak_index, sigma, fs, u_start, u_end, step=False) -> tuple[float, float]:
    """How far each end moves when fitted from the samples above SPREAD_FACTOR times the thresholds [s]."""
    n = xs.size
    spreads = [math.nan, math.nan]
    # one line through each foot, never split where it bends: the spread then also measures how far the end
    # depends on the model of the foot (a bent tail may be the plate's lag, not the ball's force)
    u2, _ = _foot_start(xs, peak_index, SPREAD_FACTOR * sigma, fs, split=False, step=[] if step else None)
    e2, _ = _foot_start(xs[::-1], n - 1 - peak_index, SPREAD_FACTOR * sigma, fs, split=False)
    if u2 is not None:
        spreads[0] = (u2 - u_start) / fs
    if e2 is not None:
        spreads[1] = (n - 1 - e2 - u_end) / fs
    return spreads[0], spreads[1]


def end_from_curve(force, sample_rate_hz: float, start_s: float, end_s: float, noise_rms: float, *,
                   t0_s: float = 0.0) -> tuple[float, float]:
    """The contact end from the force's curve before it, with its standard uncertainty.

    In restitution the model's force ``F = kB x + cB x'`` (Eq. (14) in
    Goodwill & Haake 2004, no momentum flux after the peak) reaches zero
    smoothly, with a finite slope and a curvature of either sign: the last
    samples of a punctured ball fall steeper and steeper (concave), others
    flatten into the end (convex). A straight line through them (the hinge
    of :func:`detect_contact`) then meets zero late or early, by an amount that
    depends on how many samples stand out of the noise. Here the force is
    fitted, by least squares, with ``a s + b s^2`` (s = end - t, zero after
    the end, a >= 0) over the last ``CURVE_FITS[0][1]`` of TC and the quiet
    samples after it, the end profiled on a grid of CURVE_STEP samples within
    CURVE_SEARCH samples of ``end_s`` (above CURVE_RATE_HZ, within the time of
    CURVE_SEARCH samples at CURVE_RATE_HZ: a faster rig's end is not known to
    fewer of its samples); its standard uncertainty is the
    half-width of the ends whose residual sum of squares is within CURVE_CHI2
    (9) noise variances of the least (chi-square with one degree of freedom),
    over 3: the three-sigma interval over three. Where the residual is not a
    parabola in the end (a steep fall with a few samples on it, one of them
    low in the noise, decides between two ends) the one-sigma interval is
    narrow while the end is not known; the wider interval sees the other end
    (zoo trace 1:707 at 50 kHz, 20 noise draws: one end 0.92 % of TC early
    passed with a one-sigma uncertainty of 0.19 %). The same
    fit with a cubic over ``CURVE_FITS[1][1]`` of TC tells how much the end
    depends on the curve's model; that difference is added in quadrature.

    Parameters
    ----------
    force : array_like
        Force (or a conditioned voltage proportional to it), zero baseline,
        one sample per 1/sample_rate_hz [N] (or [V]).
    sample_rate_hz : float
        Sample rate [Hz].
    start_s, end_s : float
        Contact start and end from another estimate (e.g. the hinge's) [s].
    noise_rms : float
        Noise standard deviation of the force, same unit as ``force``.
    t0_s : float
        Time of the first sample [s].

    Returns
    -------
    end_s : float
        End of the contact from the curve [s] (NaN when the samples do not
        allow the fit).
    se_s : float
        Its standard uncertainty [s]; inf when the end is not bounded within
        the search, or when the force's slope at the end is below
        CURVE_MIN_SLOPE noise deviations per sample (above CURVE_RATE_HZ: its
        rise over a sample at CURVE_RATE_HZ, against the noise averaged over
        that time) and the force may flatten into its end; NaN with a NaN end.

    Raises
    ------
    ValueError
        For non-finite samples, a non-positive sample rate, a contact not
        inside the trace or a noise that is not positive and finite.
    """
    fs, x = _checked_arguments(force, sample_rate_hz, t0_s)
    if not (math.isfinite(start_s) and math.isfinite(end_s) and end_s > start_s):
        raise ValueError(f"need finite start_s < end_s, got start_s={start_s!r}, end_s={end_s!r}")
    u_start, u_end = (start_s - t0_s) * fs, (end_s - t0_s) * fs
    if u_start < 0 or u_end > x.size - 1:
        raise ValueError(f"contact [{start_s:.6g}, {end_s:.6g}] s lies outside the trace of {x.size} samples")
    if not (math.isfinite(noise_rms) and noise_rms > 0):
        raise ValueError(f"noise_rms must be positive and finite, got {noise_rms!r}")
    inside = x[int(math.ceil(u_start)):int(math.floor(u_end)) + 1]
    if inside.size < CURVE_MIN_SAMPLES:
        return math.nan, math.nan
    k = int(math.ceil(u_start)) + int(np.argmax(inside))
    u, se = _curve_end(x, float(noise_rms), u_start, u_end, k, k, fs)
    return t0_s + u / fs, se / fs


def _curve_end(xs, sigma: float, u_start: float, u_end: float, peak_index: int, floor_u: int,
               fs: float) -> tuple[float, float]:
    """The end from the force's curve and its standard uncertainty [samples] (see :func:`end_from_curve`); the
    fits start after the peak, and the end is not before floor_u (the last sample above the contact threshold)."""
    n_pre = max(FOOT_PRE_SAMPLES, int(math.ceil(FOOT_PRE_S * fs)))
    tc = u_end - u_start
    # above CURVE_RATE_HZ, in the time of one sample at it: the search's reach, and the slope over that time
    # against the noise averaged over it (faster sampling pins the same curve no worse)
    rate = max(fs / CURVE_RATE_HZ, 1.0)
    ends = []
    for degree, fraction in CURVE_FITS:
        lo = max(int(math.floor(u_end - max(fraction * tc, CURVE_MIN_SAMPLES))), peak_index, 0)
        hi = min(int(math.ceil(u_end)) + n_pre, xs.size - 1)
        ends.append(_profile_end(xs[lo:hi + 1], np.arange(lo, hi + 1, dtype=float), sigma, u_end, floor_u,
                                 degree, xs.size - 1, CURVE_SEARCH * rate))
    (u2, se2, slope), (u3, _, _) = ends
    if not (math.isfinite(u2) and math.isfinite(u3)):
        return u2, math.inf if math.isfinite(u2) else math.nan
    if not slope * rate ** 1.5 >= CURVE_MIN_SLOPE * sigma:
        return u2, math.inf  # a force that flattens into its end: where it meets zero is not in the samples
    return u2, math.hypot(se2, u2 - u3)


def _profile_end(y, u, sigma: float, u_end: float, floor_u: float, degree: int, last: float,
                 search: float = CURVE_SEARCH):
    """Least-squares end of ``sum_k c_k s^k`` (k = 1..degree, s = max(end - u, 0), c_1 >= 0) on a grid near
    u_end [samples], its standard uncertainty (half the width of the ends within CURVE_CHI2 noise variances of
    the least residual, over its square root; inf when that reaches the grid's edge) [samples] and the slope
    c_1 there [force per sample]; NaNs when the samples cannot tell."""
    grid = u_end + np.arange(-search, search + 0.5 * CURVE_STEP, CURVE_STEP)
    grid = grid[(grid >= floor_u) & (grid <= last)]
    if grid.size < 3 or y.size < degree + 2:
        return math.nan, math.nan, math.nan
    s = np.maximum(grid[:, None] - u[None, :], 0.0)

    def fit(s, powers):  # the residual sums of squares and the coefficients at each of the ends of s's rows
        a = np.stack([s ** p for p in powers], axis=-1)
        ata = np.einsum("gnk,gnl->gkl", a, a)
        aty = np.einsum("gnk,n->gk", a, y)
        ridge = 1e-12 * (1.0 + np.trace(ata, axis1=1, axis2=2))[:, None, None] * np.eye(len(powers))
        coef = np.linalg.solve(ata + ridge, aty[..., None])[..., 0]
        return np.sum((y[None, :] - np.einsum("gnk,gk->gn", a, coef)) ** 2, axis=1), coef

    sse, coef = fit(s, range(1, degree + 1))
    slope = np.maximum(coef[:, 0], 0.0)
    bent = np.flatnonzero(coef[:, 0] < 0)  # without the linear term where its slope is < 0 (only those ends)
    if bent.size:
        sse[bent] = fit(s[bent], range(2, degree + 1))[0]
    k = int(np.argmin(sse))
    level = sse[k] + CURVE_CHI2 * sigma * sigma
    inside = np.flatnonzero(sse <= level)
    if inside[0] == 0 or inside[-1] == grid.size - 1:
        return float(grid[k]), math.inf, float(slope[k])
    best = float(grid[k])
    curvature = sse[k - 1] - 2.0 * sse[k] + sse[k + 1]
    if 0 < k < grid.size - 1 and curvature > 0:  # the least between the grid's points, from a parabola
        best += 0.5 * CURVE_STEP * float(sse[k - 1] - sse[k + 1]) / float(curvature)
    i, j = int(inside[0]), int(inside[-1])  # the interval's edges between the grid's points, linearly
    lo = grid[i] - CURVE_STEP * float(level - sse[i]) / float(sse[i - 1] - sse[i])
    hi = grid[j] + CURVE_STEP * float(level - sse[j]) / float(sse[j + 1] - sse[j])
    return best, 0.5 * float(hi - lo) / math.sqrt(CURVE_CHI2), float(slope[k])
