"""Contact detection on a plate voltage: the main contact, its ends at sub-sample precision and other impacts.

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

from .clipping import detect_clipping, true_runs
from .curve_end import curve_end
from .ends import contact_ends, end_spreads, find_hinges, hinge_se, unbroken_run
from .noise import MIN_NOISE_SAMPLES, checked_arguments, contact_threshold, robust_noise, smallest_step

__all__ = ["ContactResult", "contact_samples", "end_standard_uncertainties", "detect_contact", "ContactSearch"]

SECOND_IMPACT_FRACTION = 0.05  # another impact reaches this fraction of the main peak [-]
SECOND_IMPACT_MIN_S = 0.3e-3  # ... and lasts longer than this [s]
SECOND_IMPACT_LOCAL_S = 20e-3  # ... above the level of the record in blocks this long around it [s]
RING_GAP_MAX_S = 0.75e-3  # a run this close to the contact, the force swinging below zero between them ... [s]
RING_SWING_SIGMA = 6.0  # ... by this many noise deviations ... [-]
RING_MEAN_FRACTION = 0.1  # ... while its mean around the gap stays above this fraction of the peak, is a piece of
#                           the contact that a plate's ringing split off, not another impact [-]
RING_LOBE_SWING = 0.5  # a run shorter than RING_GAP_MAX_S with the force below minus this fraction of its height
#                        within its length after it is a lobe of the plate's free ringing, not another impact [-]
MERGE_GAP_S = 0.1e-3  # runs above threshold closer than this are one run [s]
PRETRIGGER_GUARD_S = 0.5e-3  # gap between the noise window and the first crossing [s]
MIN_CONTACT_SAMPLES = 3  # fewest samples above threshold for a contact [samples]
NOISE_FLOOR_FRACTION = 1e-6  # lower bound of the noise estimate, fraction of the peak [-]


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
        sample times the jump (a few tenths of a per cent of kCAL at 20-25 kHz).
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


def _merge_runs(starts, ends, max_gap: int):
    """Merge runs separated by fewer than max_gap samples below threshold."""
    if starts.size <= 1:
        return starts, ends
    gaps = starts[1:] - ends[:-1] - 1
    keep = np.concatenate([[True], gaps >= max_gap])
    new_starts = starts[keep]
    new_ends = ends[np.concatenate([keep[1:], [True]])]
    return new_starts, new_ends


def _not_found(noise, threshold, peak_index, peak, clipped, flags) -> ContactResult:
    return ContactResult(
        found=False, start_s=math.nan, end_s=math.nan, edge_start_s=math.nan, edge_end_s=math.nan,
        start_index=-1, end_index=-1, peak_index=int(peak_index), peak_V=float(peak),
        n_impacts=0, noise_rms_V=float(noise), threshold_V=float(threshold),
        clipped=bool(clipped), flags=tuple(flags) + ("no_contact",),
    )


def _main_run(above: np.ndarray, peak_index: int, merge_gap: int):
    starts, ends = _merge_runs(*true_runs(above), merge_gap)
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
    applied (see :func:`ballimpact.signal.conditioning.condition_voltage`): the force
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
    fs, x = checked_arguments(voltage_V, sample_rate_hz, t0_s)
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
        fs, x = checked_arguments(voltage_V, sample_rate_hz, 0.0)
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
        others_found = _other_impacts(xs, starts, ends, k, peak, fs, sigma)
        if others_found:
            flags.append("multiple_impacts")
        self._xs, self._scale, self._peak_index, self._peak = xs, scale, peak_index, peak
        # consistency: the run above threshold lies inside the contact, start < end inside the trace. A spike
        # just before (after) the contact that the merging of runs joined to it is no force on the ball.
        self._sigma, self._thr = sigma, thr
        self._run = unbroken_run(xs, peak_index, sigma, thr, int(starts[k]), int(ends[k]))
        self._others, self._flags = others_found, tuple(flags)
        self._hinges = find_hinges(xs, peak_index, peak, sigma, fs)

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
        u_start, u_end, u_edge_start, u_edge_end = contact_ends(xs, peak_index, sigma, fs, self._hinges, flags,
                                                                 windows, step)
        # the end's spread is the straight line's: how far its end depends on the samples near the noise (its
        # bend's corner moves less, and the checks on the spread were set on the line's)
        u_line = windows.get("line_end", math.nan)
        if not math.isfinite(u_line):
            u_line = u_end
        spreads = end_spreads(xs, peak_index, sigma, fs, u_start, u_line, step) if spread else (math.nan, math.nan)
        run_a, run_b = self._run
        u_start = min(max(u_start, 0.0), float(run_a))
        u_end = max(min(u_end, n - 1.0), float(run_b))
        u_line = max(min(u_line, n - 1.0), float(run_b))
        u_edge_start = min(max(u_edge_start, u_start), float(run_a))
        u_edge_end = max(min(u_edge_end, u_end), float(run_b))
        # the ends' uncertainties go with the curve's (what the conditioning's checks read)
        ses = _end_ses(xs, u_start, u_end, windows, flags) if curve else (math.nan, math.nan)
        by_curve = (math.nan, math.nan)
        # also after an end flagged as a jump: a concave fade's last step out of low noise looks like one, and the
        # curve's uncertainty tells whether its end is pinned
        if curve and not {"ringing_after_contact", "contact_at_trace_end"} & set(flags):
            by_curve = curve_end(xs, sigma, u_start, u_line, peak_index, max(run_b, peak_index), fs)

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


def _end_ses(xs, u_start, u_end, windows, flags):
    """Standard uncertainties of the start and the end from their hinges' fits [samples] (see
    :func:`ballimpact.signal.ends.hinge_se`)."""
    n = xs.size
    # a start in the middle of a step's interval: a uniform's deviation over it goes with the hinge's
    return (math.hypot(hinge_se(xs, u_start, windows.get("start"), "start_jump" in flags),
                       windows.get("start_step", 0.0) / math.sqrt(12.0)),
            # the bent hinge's (one more parameter) and never less than the straight one's: where no straight
            # line pins the end, no bend does
            np.fmax(hinge_se(xs[::-1], n - 1 - u_end, windows.get("end"), "end_jump" in flags),
                    windows.get("end_se", math.nan)))


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
    return max(sigma, smallest_step(xs) / math.sqrt(12.0), NOISE_FLOOR_FRACTION * peak, 1e-300)


def _other_impacts(xs, starts, ends, k, peak, fs, sigma=0.0) -> list[tuple[int, float]]:
    """Runs above the threshold besides the main one (k) that count as impacts: (first sample, peak fraction).

    A plate's ringing does not count: runs split off the contact (:func:`_ringing_pieces`) and lobes of its free
    ringing (:func:`_ringing_lobes`).
    """
    if starts.size <= 1:
        return []
    n = xs.size
    bounds = np.empty(2 * starts.size, dtype=int)
    bounds[0::2], bounds[1::2] = starts, ends + 1
    run_max = np.maximum.reduceat(np.concatenate([xs, [-np.inf]]), bounds)[0::2]
    others = np.arange(starts.size) != k
    others[_ringing_pieces(xs, starts, ends, k, peak, fs, sigma)] = False
    others &= ~_ringing_lobes(xs, starts, ends, run_max, fs)
    # a run cut off by either end of the trace may be longer than it shows: its length does not count
    long_enough = ((ends - starts + 1) / fs > SECOND_IMPACT_MIN_S) | (starts == 0) | (ends == n - 1)
    high_enough = run_max > SECOND_IMPACT_FRACTION * peak
    counted = others & long_enough & high_enough
    out = []
    for j in np.flatnonzero(counted):
        height = _pulse_height(xs, int(starts[j]), int(ends[j]), max(int(round(SECOND_IMPACT_LOCAL_S * fs)), 2))
        if height > SECOND_IMPACT_FRACTION * peak:
            out.append((int(starts[j]), float(run_max[j] / peak)))
    return out


def _ringing_pieces(xs, starts, ends, k, peak, fs, sigma) -> list[int]:
    """The runs above the threshold that are pieces of the main one (k), split off by a plate's ringing.

    A plate ringing at 1-3 kHz swings a contact's force below the threshold and back, splitting its run: from the
    main run outwards, a run less than RING_GAP_MAX_S [s] from the last piece, the force swinging below zero
    between them (by RING_SWING_SIGMA noise deviations ``sigma``) while its mean over the gap and the gap's length
    either side stays above RING_MEAN_FRACTION of the peak, is a piece too. A ball pulls on nothing, and its force
    is what the sensed force averages to over a period of the plate: positive inside the contact; between two
    contacts the plate rings freely about zero, and a ball that left the plate is away for longer (the zoos'
    second contacts come 1 ms or more after the first).
    """
    pieces = []
    for step in (-1, 1):
        last = k
        for j in range(k + step, -1 if step < 0 else starts.size, step):
            a, b = (ends[j] + 1, starts[last]) if step < 0 else (ends[last] + 1, starts[j])
            gap = b - a
            if not (0 < gap < RING_GAP_MAX_S * fs and float(np.min(xs[a:b])) < -RING_SWING_SIGMA * sigma
                    and float(np.mean(xs[max(a - gap, 0):b + gap])) > RING_MEAN_FRACTION * peak):
                break
            pieces.append(j)
            last = j
    return pieces


def _ringing_lobes(xs, starts, ends, run_max, fs) -> np.ndarray:
    """Which runs above the threshold (their largest samples ``run_max``) are lobes of a plate's free ringing (a
    boolean per run).

    A ringing swings both ways about zero and a ball's contact does not: a run shorter than RING_GAP_MAX_S [s]
    (half a period of a plate of 0.67 kHz or more; a ball's contact lasts milliseconds) whose force falls below
    minus RING_LOBE_SWING of its height within its own length after its end is a lobe, however high.
    """
    out = np.zeros(starts.size, dtype=bool)
    for j, (a, b) in enumerate(zip(starts, ends)):
        length = b - a + 1
        after = xs[b + 1:b + 1 + length]
        if length < RING_GAP_MAX_S * fs and after.size and a < b:
            out[j] = float(np.min(after)) < -RING_LOBE_SWING * float(run_max[j])
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
