"""The force plate's own resonance: identified from its ringing in a trace, and undone.

Goodwill & Haake (2004, section 4) see oscillations in their measured force
that the one-degree-of-freedom ball model does not have. Part of such an
oscillation can be the plate's: a piezoelectric platform is a mass on stiff
sensors, so the force it reports is the applied force passed through a
second-order mechanical response,

    F_sensed'' + 2 zeta wn F_sensed' + wn^2 F_sensed = wn^2 F     (unit static gain),

with its resonance fn = wn / 2 pi from below 1 kHz to 30 kHz and damping ratio
zeta of a few per cent (raw-format v1.1). The paper does not treat it; this
module is our addition (see docs/signal-processing.md, "Plate resonance").

Sampled at fs, the plate's free response obeys exactly a two-term recursion
(its poles z = exp(s / fs)), and its response to a force that is linear between
samples is exactly the first-order-hold discretisation B(z) / A(z) of the
continuous plate. So:

1. **Identification** (:func:`identify_plate_resonance`): the ball's force is
   smooth, the ringing is not. The second difference of the trace removes most
   of the force and keeps the ringing, which then follows the recursion
   ``d[n] = a1 d[n-1] + a2 d[n-2]``. The noise of a second difference is
   correlated over two samples, so a plain least-squares fit is biased; the
   coefficients are estimated with instrumental variables (the second
   difference ``lag`` samples earlier, uncorrelated with that noise). The poles
   give fn and zeta.
2. **Undoing** (:func:`undo_plate_resonance`): ``A(z)`` applied to the trace
   leaves ``B(z) F``; B has one zero inside and one outside the unit circle
   (about -0.27 and -3.7 for a resonance well below fs), so it is inverted by a
   causal pass for the inner zero and a backward pass for the outer one: a
   stable two-sided filter with unit static gain. The impulse (so kCAL) is
   unchanged; noise above the resonance is amplified, as it must be.

A resonance above fs / 2 (no anti-aliasing filter) folds onto its alias: its
poles are still those of the samples, but its continuous fn is not known from
them. Nothing here can tell; the caller must check the undone force (see
``conditioning``).
"""
from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ._checks import finite_samples, positive_scalar

__all__ = [
    "stated_resonance","PlateResonance", "identify_plate_resonance", "identify_free_ringing", "undo_plate_resonance",
           "lowpass_zero_phase", "undone_noise_gain", "lowpass_kernel",
           "lowpass_spread_samples", "refine_plate_resonance", "undone_end", "FrontFit", "front_responses", "fit_front",
           "undone_impulse_response"]

IV_LAG = 5  # samples between a second difference and its instrument (its noise is correlated over 2) [samples]
MIN_RING_SAMPLES = 16  # fewest samples to identify the resonance from [samples]
MAX_FREQUENCY_FRACTION = 0.45  # a resonance identified above this fraction of fs is not trusted [-]
MIN_FREQUENCY_FRACTION = 0.005  # ... nor one below this fraction of fs [-]
MAX_DAMPING_RATIO = 0.5  # a "resonance" more damped than this is no ringing [-]
MIN_DAMPING_RATIO = 0.005  # ... and one damped less (rings for > 30 periods per e-fold) is no plate on its mounts [-]
RING_NOISE_FACTOR = 3.0  # the ringing's second difference stands out of the noise's by this in rms [-]
REFINEMENTS = 2  # fits repeated with the smoothing chosen from the last estimate [-]
START_SMOOTHING = (1, 2, 4, 8, 16)  # moving averages tried in turn for a first estimate [samples]
FREE_RING_MIN_CHI2 = 100.0  # a free ringing's fit lowers the stretch's sum of squares by this many residual
#                             variances (each at least the noise's) [-]
FREE_RING_START_DAMPING = tuple(np.geomspace(0.01, 0.4, 9))  # its fit starts from the best of these damping
FREE_RING_START_FACTORS = tuple(np.geomspace(0.7, 1.4, 11))  # ratios and factors of the stretch's spectral peak [-]
REFINE_BAND = 1.5  # the refinement minimises the undone force's ringing within this factor of the first fn [-]
REFINE_STEP = (0.05, 0.5)  # its first steps in log(fn) and log(zeta) [-]
REFINE_TOLERANCE = 2.0e-3  # ... and the step in log(fn) at which it stops [-]
REFINE_MAX_EVALUATIONS = 80  # ... or after this many undone forces [-]
END_TERMS = 3  # an end fitted as a jump, a line and (3) a parabola from it [-]
END_GRID_SAMPLES = 0.05  # an end fitted through the plate's undoing and the low-pass is found on this grid [samples]
NOISE_RESPONSE_HALF = 64  # the inverse's impulse response kept this far each side for the noise's covariance: its zeros
#                           (about -0.27 and -1.3 to -3.7) leave less than 1e-7 of it there [samples]


@dataclass(frozen=True)
class PlateResonance:
    """A plate's second-order resonance as identified from a trace.

    Attributes
    ----------
    frequency_hz : float
        Undamped natural frequency fn = wn / 2 pi [Hz].
    damping_ratio : float
        Damping ratio zeta [-].
    a1, a2 : float
        The recursion of the sampled free response,
        ``x[n] = a1 x[n-1] + a2 x[n-2]`` [-].
    """

    frequency_hz: float
    damping_ratio: float
    a1: float
    a2: float


def stated_resonance(frequency_hz: float, damping_ratio: float, sample_rate_hz: float) -> PlateResonance:
    """The resonance a session states (``plate.resonance_hz``, ``plate.damping_ratio``) as sampled at a rate.

    The poles s = -zeta wn +- i wn sqrt(1 - zeta^2) map to z = exp(s / fs), whose recursion
    ``x[n] = a1 x[n-1] + a2 x[n-2]`` has a1 = 2 r cos(theta), a2 = -r^2.

    Parameters
    ----------
    frequency_hz : float
        Undamped natural frequency fn [Hz].
    damping_ratio : float
        Damping ratio zeta, 0 < zeta < 1 [-].
    sample_rate_hz : float
        Sample rate [Hz].

    Returns
    -------
    PlateResonance
    """
    if not (frequency_hz > 0 and 0 < damping_ratio < 1 and sample_rate_hz > 0):
        raise ValueError(f"need fn > 0 Hz, 0 < zeta < 1 and fs > 0 Hz, got {frequency_hz!r}, {damping_ratio!r}, "
                         f"{sample_rate_hz!r}")
    wn = 2.0 * math.pi * frequency_hz
    s = complex(-damping_ratio * wn, wn * math.sqrt(1.0 - damping_ratio**2)) / sample_rate_hz
    z = complex(math.exp(s.real) * math.cos(s.imag), math.exp(s.real) * math.sin(s.imag))
    return PlateResonance(float(frequency_hz), float(damping_ratio), float(2.0 * z.real), float(-abs(z) ** 2))


def _resonance_from_recursion(a1: float, a2: float, fs: float) -> PlateResonance | None:
    """The continuous resonance of the poles of ``z^2 - a1 z - a2`` (None when they are not a decaying pair)."""
    if not (math.isfinite(a1) and math.isfinite(a2)) or a1 * a1 + 4.0 * a2 >= 0.0 or not -1.0 < a2 < 0.0:
        return None
    r = math.sqrt(-a2)
    theta = math.acos(max(-1.0, min(1.0, a1 / (2.0 * r))))
    s = complex(math.log(r), theta) * fs  # the pole in the s plane [1/s]
    wn = abs(s)
    return PlateResonance(wn / (2.0 * math.pi), -s.real / wn, float(a1), float(a2))


def _iv_recursion(d: np.ndarray, lag: int):
    """(a1, a2) of ``d[n] = a1 d[n-1] + a2 d[n-2]`` by instrumental variables ``lag`` samples back; None if singular."""
    if d.size < MIN_RING_SAMPLES + lag + 1:
        return None
    y = d[lag + 1:]
    regressors = np.column_stack([d[lag:-1], d[lag - 1:-2]])
    instruments = np.column_stack([d[1:-lag], d[:-lag - 1]])
    zx = instruments.T @ regressors
    if not np.all(np.isfinite(zx)) or abs(np.linalg.det(zx)) <= 1e-300 * max(float(np.max(np.abs(zx))), 1e-300) ** 2:
        return None
    a1, a2 = np.linalg.solve(zx, instruments.T @ y)
    return float(a1), float(a2)


def _noise_only(d: np.ndarray, k: int, noise_rms: float) -> bool:
    """The smoothed second difference d within RING_NOISE_FACTOR of what white noise alone gives, in rms."""
    taps = np.diff(np.ones(k) / k, 2, prepend=[0.0, 0.0], append=[0.0, 0.0])  # the filter x -> d
    expected = noise_rms * math.sqrt(float(np.sum(taps ** 2)))
    return float(np.sqrt(np.mean(d ** 2))) <= RING_NOISE_FACTOR * expected


def identify_plate_resonance(force, sample_rate_hz: float, *, lag: int = IV_LAG,
                             noise_rms: float | None = None) -> PlateResonance | None:
    """The plate resonance that rings in a stretch of a trace, or None when none can be identified.

    The recursion of the free response holds for any linear filtering of the
    trace, so it is fitted to the second difference of the trace smoothed by a
    moving average of k samples: k = 1 first (then 2, 4, ... of
    START_SMOOTHING while nothing stands out of the noise or no decaying
    oscillation is found: a resonance far below fs bends the raw second
    difference little), then k chosen from that
    estimate (a quarter of the resonance's period: the ringing passes at 90 %,
    the noise above it is cut) and the fit repeated, REFINEMENTS times. The
    smoothed noise is correlated over k + 1 samples, so the instruments go
    ``lag + k - 1`` samples back.

    Parameters
    ----------
    force : array_like
        A stretch of the baseline-corrected trace that holds the ringing: from
        just after the force's jump at the contact start to a little after the
        contact (proportional to force; any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    lag : int
        Delay of the instrumental variables for k = 1 [samples], at least 3.
    noise_rms : float, optional
        Standard deviation of the trace's white noise, in the unit of
        ``force``. When given, the smoothed second difference must stand out of
        what that noise alone gives by RING_NOISE_FACTOR in rms, or nothing
        is identified (noise has a "recursion" too).

    Returns
    -------
    PlateResonance or None
        None when the stretch is too short, the recursion has no decaying
        oscillation, or its frequency is outside MIN_FREQUENCY_FRACTION-
        MAX_FREQUENCY_FRACTION of fs or its damping ratio outside
        MIN_DAMPING_RATIO-MAX_DAMPING_RATIO. An oscillation damped less than
        MIN_DAMPING_RATIO outlasts the contact many times over: a ball's force
        cannot have set it ringing that way (it would take an impulse), so it
        is not taken for the plate's.

    Raises
    ------
    ValueError
        For a non-positive sample rate, lag below 3, a negative noise_rms or
        non-finite samples.
    """
    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if noise_rms is not None and not (noise_rms >= 0):
        raise ValueError(f"noise_rms must be non-negative, got {noise_rms!r}")
    if int(lag) < 3:
        raise ValueError(f"lag must be at least 3 samples (the second difference's noise spans 2), got {lag!r}")
    x = finite_samples("force", force)
    lag = int(lag)

    def fit(k):
        """(resonance or None, the smoothed second difference is noise only) for a moving average of k samples."""
        smooth = np.convolve(x, np.ones(k) / k, mode="valid") if k > 1 else x
        d = np.diff(smooth, 2)
        if noise_rms is not None and _noise_only(d, k, noise_rms):
            return None, True
        coef = _iv_recursion(d, lag + k - 1)
        return (None if coef is None else _resonance_from_recursion(*coef, fs)), False

    res = None
    # a resonance far below fs bends the raw second difference little (by (2 pi fn / fs)^2) and its
    # noise may hide it: when k = 1 finds nothing, the trace is smoothed more, as long as the
    # resonance found is slow enough for that smoothing (at least 2 k samples per period)
    for k in START_SMOOTHING:
        found, _ = fit(k)
        if found is not None and (k == 1 or fs / found.frequency_hz >= 2.0 * k):
            res = found
            break
    if res is None:
        return None
    for _ in range(REFINEMENTS):
        k_next = max(int(fs / (4.0 * res.frequency_hz)), 1)
        if k_next == k:
            break
        k = k_next
        found, noise_only = fit(k)
        if noise_only:
            return None
        if found is None:
            break
        res = found
    if res is None or not (MIN_FREQUENCY_FRACTION * fs <= res.frequency_hz <= MAX_FREQUENCY_FRACTION * fs) \
            or not MIN_DAMPING_RATIO <= res.damping_ratio <= MAX_DAMPING_RATIO:
        return None
    return res


def identify_free_ringing(force, sample_rate_hz: float, noise_rms: float) -> PlateResonance | None:
    """The plate resonance of a stretch of free ringing (no force acts), by a fit of a damped sinusoid; or None.

    After the contact no force acts on the plate, so the trace there is the
    plate's free response, ``exp(-zeta wn t) (A cos wd t + B sin wd t)``
    with wd = wn sqrt(1 - zeta^2), plus a constant (what the baseline left)
    and noise (the amplitudes and the constant solved for linearly at each fn
    and zeta: a fit in two parameters). Where
    :func:`identify_plate_resonance` finds nothing in the contact and after
    it (the force's own second difference, many times longer than a damped
    plate's ringing, drowns the recursion: zoo trace
    2:600, a 3.5 kHz plate damped 0.22 at 196 kHz), the ringing after the
    contact alone can still show it. The fit (least squares, bounded) starts
    from the best of a grid: FREE_RING_START_FACTORS of the peak of the
    stretch's spectrum (no taper: the ringing decays from the stretch's start)
    by FREE_RING_START_DAMPING. Not in the paper; see docs/signal-processing.md, "Plate
    resonance".

    Parameters
    ----------
    force : array_like
        A stretch of the baseline-corrected trace after the contact, where no
        force acts (proportional to force; any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    noise_rms : float
        Standard deviation of the trace's white noise, in the unit of
        ``force`` (> 0).

    Returns
    -------
    PlateResonance or None
        None when the stretch is shorter than MIN_RING_SAMPLES, the fit lowers
        the stretch's sum of squares about its mean by less than
        FREE_RING_MIN_CHI2 variances of the fit's residual (each at least the
        noise's: a residual the ringing does not explain, e.g. force left in
        the stretch, asks more of it; the noise estimate itself may be off by
        tens of per cent), or the resonance is outside
        MIN_FREQUENCY_FRACTION-MAX_FREQUENCY_FRACTION of fs or
        MIN_DAMPING_RATIO-MAX_DAMPING_RATIO.

    Raises
    ------
    ValueError
        For a non-positive sample rate or noise_rms, or non-finite samples.
    """
    from scipy.optimize import least_squares

    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    noise = positive_scalar("noise_rms", noise_rms)
    y = finite_samples("force", force)
    n = y.size
    if n < MIN_RING_SAMPLES:
        return None
    t = np.arange(n) / fs
    f_lo, f_hi = MIN_FREQUENCY_FRACTION * fs, MAX_FREQUENCY_FRACTION * fs

    def basis(f, zeta):
        wn = 2.0 * math.pi * f
        wd = wn * math.sqrt(max(1.0 - zeta * zeta, 0.0))
        decay = np.exp(-zeta * wn * t)
        return np.column_stack([decay * np.cos(wd * t), decay * np.sin(wd * t), np.ones(n)])

    def residual(p):  # the amplitudes and the constant are linear: solved for at each (fn, zeta)
        b = basis(*p)
        return (b @ np.linalg.lstsq(b, y, rcond=None)[0] - y) / noise

    spectrum = np.abs(np.fft.rfft(y - y.mean(), 8 * n))  # no taper: a decaying ringing is in the first samples
    freq = np.fft.rfftfreq(8 * n, 1.0 / fs)
    inside = (freq >= f_lo) & (freq <= f_hi)
    if not np.any(inside):
        return None
    f0 = float(freq[inside][np.argmax(spectrum[inside])])
    grid = [(min(max(factor * f0, f_lo), f_hi), zeta0)
            for factor, zeta0 in itertools.product(FREE_RING_START_FACTORS, FREE_RING_START_DAMPING)]
    start = min(grid, key=lambda p: float(np.sum(residual(p) ** 2)))
    best = least_squares(residual, start, bounds=([f_lo, MIN_DAMPING_RATIO], [f_hi, MAX_DAMPING_RATIO]),
                         x_scale=[f0, 0.1])
    chi2 = 2.0 * float(best.cost)
    chi2_flat = float(np.sum(((y - y.mean()) / noise) ** 2))
    variance = max(chi2 / max(n - 5, 1), 1.0)  # the residual's, in noise variances (five parameters)
    f, zeta = float(best.x[0]), float(best.x[1])
    if chi2_flat - chi2 < FREE_RING_MIN_CHI2 * variance:
        return None
    if not (f_lo < f < f_hi and MIN_DAMPING_RATIO < zeta < MAX_DAMPING_RATIO):
        return None  # on a bound: no resonance the fit could place
    return _poles_resonance(f, zeta, fs)


def _poles_resonance(frequency_hz: float, damping_ratio: float, fs: float) -> PlateResonance:
    """The PlateResonance of a continuous fn [Hz] and zeta [-], with the recursion of its sampled poles."""
    wn = 2.0 * math.pi * frequency_hz
    r = math.exp(-damping_ratio * wn / fs)
    theta = wn * math.sqrt(max(1.0 - damping_ratio * damping_ratio, 0.0)) / fs
    return PlateResonance(float(frequency_hz), float(damping_ratio), 2.0 * r * math.cos(theta), -r * r)


def _ringing_in_band(undone: np.ndarray, fs: float, f_lo: float, f_hi: float) -> float:
    """Rms spectral amplitude of a stretch of force, less a quartic, within f_lo-f_hi [unit of the force].

    The stretch is detrended by a least-squares quartic (the force's smooth
    shape), Hann-windowed and zero-padded 4x (as ``conditioning`` looks for a
    ringing line); the amplitude is the rms of the bins in the band.
    """
    n = undone.size
    u = np.linspace(-1.0, 1.0, n)
    r = undone - np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyfit(u, undone, 4))
    w = np.hanning(n)
    amp = 2.0 * np.abs(np.fft.rfft(r * w, 4 * n)) / w.sum()
    f = np.fft.rfftfreq(4 * n, 1.0 / fs)
    sel = (f > f_lo) & (f < f_hi)
    return float(np.sqrt(np.mean(amp[sel] ** 2))) if np.any(sel) else math.inf


def refine_plate_resonance(force, sample_rate_hz: float, plate: PlateResonance, *,
                           band: float = REFINE_BAND) -> PlateResonance:
    """The resonance near ``plate`` that leaves the least ringing in the undone force.

    The instrumental-variable fit of :func:`identify_plate_resonance` is
    disturbed by the smooth force's own second difference and by the noise:
    its fn can be off by a few per cent and zeta by a factor of 2-3 (zoo
    traces at 20-200 kHz). Undone with such a resonance, the force still rings
    near fn (the true plate's response over the assumed one has a resonance
    and an anti-resonance there, excited by every sharp feature of the force,
    its jump from zero first); undone with the true one, it does not ring.
    So fn and zeta are refined (Nelder-Mead in log fn and log zeta, from
    ``plate``) to minimise the rms spectral amplitude of the undone stretch,
    less a quartic, between fn / band and fn * band (fn of ``plate``). The
    force's own spectrum in that band is seen too: a damped plate, whose
    ringing is small against it, gets its zeta only roughly (and fn to about
    a per cent at 10 samples per period; tests/test_plate.py). Not in the
    paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        A stretch of the baseline-corrected trace around the contact, with a
        little quiet trace before it and the ringing after it (proportional
        to force; any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    plate : PlateResonance
        The first estimate (e.g. from :func:`identify_plate_resonance`).
    band : float
        Half-width of the band as a factor of the first fn [-], above 1.

    Returns
    -------
    PlateResonance
        The refined resonance (the first estimate when the refinement leaves
        more ringing, or leaves MIN_DAMPING_RATIO-MAX_DAMPING_RATIO or
        MIN_FREQUENCY_FRACTION-MAX_FREQUENCY_FRACTION of fs).

    Raises
    ------
    ValueError
        For a non-positive sample rate, a band not above 1 or non-finite samples.
    """
    from scipy.optimize import minimize

    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not band > 1.0:
        raise ValueError(f"band must be above 1, got {band!r}")
    x = finite_samples("force", force)
    f0, z0 = float(plate.frequency_hz), float(plate.damping_ratio)
    f_lo, f_hi = f0 / band, min(f0 * band, 0.5 * fs)
    if x.size < MIN_RING_SAMPLES or not f_hi > f_lo:
        return plate

    def valid(fn, zeta):
        return (MIN_FREQUENCY_FRACTION * fs <= fn <= MAX_FREQUENCY_FRACTION * fs
                and MIN_DAMPING_RATIO <= zeta <= MAX_DAMPING_RATIO)

    def cost(v):
        fn, zeta = f0 * math.exp(v[0]), z0 * math.exp(v[1])
        if not valid(fn, zeta):
            return math.inf
        try:
            value = _ringing_in_band(undo_plate_resonance(x, fs, fn, zeta), fs, f_lo, f_hi)
        except ValueError:  # complex zeros: not a plate this sampling can undo
            return math.inf
        return value if math.isfinite(value) else math.inf

    first = cost([0.0, 0.0])
    res = minimize(cost, [0.0, 0.0], method="Nelder-Mead",
                   options={"xatol": REFINE_TOLERANCE, "fatol": 0.0, "maxfev": REFINE_MAX_EVALUATIONS,
                            "initial_simplex": [[0.0, 0.0], [REFINE_STEP[0], 0.0], [0.0, REFINE_STEP[1]]]})
    fn, zeta = f0 * math.exp(float(res.x[0])), z0 * math.exp(float(res.x[1]))
    if not (float(res.fun) < first and valid(fn, zeta)):
        return plate
    return _poles_resonance(fn, zeta, fs)


def plate_discretisation(frequency_hz: float, damping_ratio: float, sample_rate_hz: float):
    """First-order-hold discretisation of the plate: numerator b (3 taps) and denominator a [-].

    Exact for a force linear between samples: ``A(z) F_sensed = B(z) F`` with
    unit static gain, B(1) = A(1).
    """
    from scipy import signal

    if not (frequency_hz > 0 and damping_ratio >= 0 and sample_rate_hz > 0):
        raise ValueError(f"need frequency_hz > 0, damping_ratio >= 0 and sample_rate_hz > 0, got "
                         f"{frequency_hz!r}, {damping_ratio!r}, {sample_rate_hz!r}")
    wn = 2.0 * math.pi * float(frequency_hz)
    if damping_ratio < 1.0:
        return _foh_underdamped(wn, float(damping_ratio), 1.0 / float(sample_rate_hz))
    b, a, _ = signal.cont2discrete(([wn * wn], [1.0, 2.0 * damping_ratio * wn, wn * wn]), 1.0 / sample_rate_hz,
                                   method="foh")
    b = np.ravel(b)[-3:]
    return b, np.ravel(a)


def _foh_underdamped(wn: float, zeta: float, h: float):
    """:func:`plate_discretisation` in closed form for zeta < 1 (b, a) [-]: no matrix exponential.

    The first-order hold of H(s) is ``(z - 1)^2 / (h z)`` times the z-transform
    of the sampled ramp response ``r(t) = t - c + exp(-zeta wn t) (c cos wd t
    + d sin wd t)``, c = 2 zeta / wn, d = (2 zeta^2 - 1) / wd. With the poles
    p exp(+-i theta) (p = exp(-zeta wn h), theta = wd h) and
    ``A(z) = z^2 - 2 p cos(theta) z + p^2`` this is B(z) / A(z) with
    ``B = A - (c / h) (z - 1) A + (z - 1)^2 (c z - c p cos theta + d p sin theta) / h``
    (its z^3 terms cancel).
    """
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    c, d = 2.0 * zeta / wn, (2.0 * zeta * zeta - 1.0) / wd
    p, theta = math.exp(-zeta * wn * h), wd * h
    a = np.array([1.0, -2.0 * p * math.cos(theta), p * p])
    num = (np.concatenate([[0.0], a]) - (c / h) * np.convolve([1.0, -1.0], a)
           + np.convolve([1.0, -2.0, 1.0], [c, -c * p * math.cos(theta) + d * p * math.sin(theta)]) / h)
    return num[-3:], a


def undo_plate_resonance(sensed, sample_rate_hz: float, frequency_hz: float, damping_ratio: float) -> np.ndarray:
    """The applied force from the plate's sensed force, its second-order resonance undone.

    Parameters
    ----------
    sensed : array_like
        Baseline-corrected trace, proportional to the sensed force [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The plate's resonance [Hz] and damping ratio [-] (e.g. from
        :func:`identify_plate_resonance`).

    Returns
    -------
    numpy.ndarray
        The applied force in the unit of ``sensed`` [V], same length; unit
        static gain, so its integral (the impulse) is that of ``sensed`` up to
        the ends of the record.
    """
    x = finite_samples("sensed", sensed)
    return _undo_rows(x, sample_rate_hz, frequency_hz, damping_ratio)


def _undo_rows(x: np.ndarray, fs: float, frequency_hz: float, damping_ratio: float) -> np.ndarray:
    """:func:`undo_plate_resonance` along the last axis of x (one trace or many at once) [unit of x]."""
    from scipy import signal

    b, a = plate_discretisation(frequency_hz, damping_ratio, fs)
    w = signal.lfilter(a, [1.0], x, axis=-1) / b[0]
    zeros = np.roots(b)
    if np.any(np.abs(np.imag(zeros)) > 1e-9 * np.abs(zeros)):
        raise ValueError(f"the plate's sampled response has complex zeros {zeros}: not a second-order plate "
                         "sampled below its resonance's decay")
    for zero in zeros:
        z = float(np.real(zero))
        if abs(z) < 1.0:  # causal pass: u[n] = w[n] + z u[n-1]
            w = signal.lfilter([1.0], [1.0, -z], w, axis=-1)
        else:  # backward pass: F[n-1] = (F[n] - u[n]) / z, stable since |1 / z| < 1
            w = signal.lfilter([0.0, -1.0 / z], [1.0, -1.0 / z], w[..., ::-1], axis=-1)[..., ::-1]
    return w


def lowpass_kernel(sample_rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """The taps of the :func:`lowpass_zero_phase` kernel with half amplitude at ``cutoff_hz`` [-].

    A Hann (raised-cosine) window ``0.5 (1 + cos(pi n / W))`` over
    ``|n| <= W`` samples, ``W = fs / (2 cutoff_hz)``, normalised to unit sum;
    ``2 floor(W) + 1`` taps, centred. A continuous Hann window of full width
    T has half amplitude at f = 1 / T and its first zero at 2 / T.
    """
    w_half = 0.5 * float(sample_rate_hz) / float(cutoff_hz)  # [samples]
    n = np.arange(-math.floor(w_half), math.floor(w_half) + 1)
    taps = 0.5 * (1.0 + np.cos(np.pi * n / w_half)) if w_half > 0 else np.ones(1)
    return taps / np.sum(taps)


def lowpass_spread_samples(sample_rate_hz: float, cutoff_hz: float) -> tuple[float, float]:
    """Half-width (its support) and standard deviation of the :func:`lowpass_zero_phase` kernel [samples]."""
    taps = lowpass_kernel(sample_rate_hz, cutoff_hz)
    n = np.arange(taps.size) - taps.size // 2
    return float(taps.size // 2), float(math.sqrt(np.sum(taps * n * n)))


class UndoneEnd(NamedTuple):
    """An end of a contact fitted by :func:`undone_end`."""

    index: float  #: the end [samples, fractional index]
    slope: float  #: the force's slope b there [unit of the force per sample], positive into the contact
    jump: float  #: its jump a there [unit of the force] (0 at an end)
    residual: float  #: rms residual of the fit [unit of the force]
    uncertainty: float  #: standard uncertainty of the end from the fit's profile [samples]
    first: int  #: first sample of the fit's window [-]
    correction: np.ndarray  #: the fitted force less what the chain made of it, over the window [unit of the force]
    noise_se: float = math.nan  #: its standard uncertainty from the chain's coloured noise [samples] (NaN: not asked)


def _end_columns(frequency_hz: float, damping_ratio: float, fs: float, taps: np.ndarray, step: float, span: int):
    """The low-passed undone plate responses to a unit step, ramp and parabola starting at ``frac`` samples.

    For each fraction ``frac`` of a sample on a grid of ``step``: the arrays
    ``K * undo(P f(n - frac))`` for f = H(t), t H(t), t^2 H(t) and, last, the
    parabola t^2 for all t (P the plate's continuous response, analytic: :func:`front_responses`;
    undo :func:`undo_plate_resonance`; K the low-pass taps) over
    ``n = -span .. span``; an array of shape (fractions, 4, 2 span + 1) [-].
    """
    pad = 40 + taps.size  # the undo's backward pass starts from rest this far beyond the window: 0.27^40
    n = np.arange(-span - pad, span + pad + 1, dtype=float)
    wn = 2.0 * math.pi * frequency_hz / fs  # [rad / sample]
    zeta = damping_ratio
    p0, p1 = 2.0 * (4.0 * zeta * zeta - 1.0) / (wn * wn), -4.0 * zeta / wn  # the parabola's steady response
    t = n[None, :] - np.arange(0.0, 1.0 - 1e-9, step)[:, None]  # [frac, n]
    steady_q = t * t + p1 * t + p0
    responses = np.concatenate([np.moveaxis(front_responses(t, wn, zeta, 0.0), -1, 1), steady_q[:, None, :]],
                               axis=1)  # [frac, response, n]: step, ramp, parabola (analytic), the steady parabola
    u = _undo_rows(responses, fs, frequency_hz, damping_ratio)
    if taps.size > 1:
        from scipy.ndimage import convolve1d

        u = convolve1d(u, taps, axis=-1, mode="constant")
    return u[..., pad:-pad]


def undone_end(force, sample_rate_hz: float, frequency_hz: float, damping_ratio: float, cutoff_hz: float,
               index: float, side: str, *, inside_samples: int = 4, reach_samples: int = 2,
               noise_rms: float | None = None):
    """Where a force that starts (or ends) as a line, seen through the plate, its undoing and a low-pass, starts (ends).

    Near a contact's start the force is zero before ts and about
    ``a + b (t - ts) + q (t - ts)^2`` after it (a > 0: a jump from zero, as
    the model's force at its start); near its end it falls to zero at ts
    as ``b (ts - t) + q (ts - t)^2``, with no jump (a ball leaves the plate
    when its force has fallen to zero). Undone (:func:`undo_plate_resonance`), the force
    is returned exactly where it is linear between samples, and the interval
    that holds the end leaves a transient (the undo assumes a line between
    samples); :func:`lowpass_zero_phase` then spreads it by up to the
    kernel's half-width W. So the end is fitted through that chain: for ts on
    a grid of END_GRID_SAMPLES, the plate's continuous step and ramp
    responses from ts, undone and low-passed, are fitted (a and b) to the
    force by least squares over a window from W + 3 samples outside the
    earliest candidate to W + ``inside_samples`` inside the latest; the ts
    of the least residual wins. An end is a start of the force ``L - a H(t -
    ts) + b (t - ts)+`` with L the line ``a + b (ts - t)``, so both sides use the
    same responses. Not in the paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        The undone (and low-passed) force (any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    frequency_hz, damping_ratio : float
        The resonance undone [Hz] and its damping ratio [-].
    cutoff_hz : float
        The low-pass's half-amplitude frequency [Hz]; ``inf`` for none.
    index : float
        The end found on the force (e.g. by ``detect_contact``) [samples]:
        candidates from W + ``reach_samples`` samples before it (start) to
        2 W + ``reach_samples`` after it (mirrored at an end).
    side : str
        ``"start"`` or ``"end"``.
    inside_samples : int
        Samples of the line fitted beyond the kernel's reach [samples], at least 2.
    reach_samples : int
        Candidates reach this many samples (and the kernel's W, 2 W inside)
        beyond ``index`` on each side [samples], at least 1: more where the
        end found on the force may be several samples off (a foot in the
        amplified noise of an exact undone force).
    noise_rms : float, optional
        Standard deviation of the sensed trace's white noise, in the unit of
        ``force`` [V]. When given, the end's standard uncertainty from that
        noise as the chain colours it is returned too (``noise_se``; see
        :func:`_end_noise_se`).

    Returns
    -------
    UndoneEnd or None
        The end [samples, fractional index], the line's slope b at it, its
        jump a at it, the rms residual of the fit [unit of the force per
        sample, unit of the force, unit of the force], the end's standard
        uncertainty [samples] (the farthest end whose fit leaves at most one
        residual variance more per independent sample of the low-passed
        noise, correlated over about ``1 / sum(K^2)`` samples) and, from the
        window's first sample on, the fitted force less what the undoing and
        the kernel made of it (added to the force, it restores the end's
        jump and the impulse the kernel spread outside it); None
        when the window leaves the record or the best end is at the edge of
        the candidates (no end inside them).

    Raises
    ------
    ValueError
        For a non-positive sample rate or cutoff, a side other than "start"
        or "end", inside_samples below 2, reach_samples below 1 or non-finite samples.
    """
    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not cutoff_hz > 0:
        raise ValueError(f"cutoff_hz must be positive, got {cutoff_hz!r}")
    if not (frequency_hz > 0 and 0 <= damping_ratio < 1):
        raise ValueError(f"need frequency_hz > 0 and 0 <= damping_ratio < 1, got {frequency_hz!r}, {damping_ratio!r}")
    if side not in ("start", "end"):
        raise ValueError(f"side must be 'start' or 'end', got {side!r}")
    if int(inside_samples) < 2:
        raise ValueError(f"inside_samples must be at least 2, got {inside_samples!r}")
    if int(reach_samples) < 1:
        raise ValueError(f"reach_samples must be at least 1, got {reach_samples!r}")
    y = finite_samples("force", force)
    if not math.isfinite(index):
        return None
    taps = np.ones(1) if math.isinf(cutoff_hz) else lowpass_kernel(fs, cutoff_hz)
    w = taps.size // 2
    sign = 1 if side == "start" else -1
    # candidates ts from k_lo to k_hi (the start's side), the window from lo to hi
    r = int(reach_samples)
    if side == "start":
        k_lo, k_hi = int(math.floor(index)) - w - r, int(math.ceil(index)) + 2 * w + r
        lo, hi = k_lo - w - 3, k_hi + w + int(inside_samples)
    else:
        k_lo, k_hi = int(math.floor(index)) - 2 * w - r, int(math.ceil(index)) + w + r
        lo, hi = k_lo - w - int(inside_samples), k_hi + w + 3
    if lo < 0 or hi >= y.size:
        return None
    span = 32 * ((hi - lo + 2) // 32 + 1)  # the columns' half-length, shared by windows of similar length
    cols = _end_columns_cached(float(frequency_hz), float(damping_ratio), fs, float(cutoff_hz), END_GRID_SAMPLES, span)
    data = y[lo:hi + 1]
    n = np.arange(lo, hi + 1, dtype=float)
    fracs = np.arange(0.0, 1.0 - 1e-9, END_GRID_SAMPLES)
    # every candidate ts = k + frac at once: its design (jump, line, parabola through the chain) [ts, n, term]
    ks = np.arange(k_lo, k_hi + 1)
    idx = (lo - ks + span)[:, None] + np.arange(data.size)[None, :]  # column index of sample n for each k
    design = np.stack([cols[:, i, :][:, idx] for i in range(3)], axis=-1)  # [frac, k, n, term]
    design = np.swapaxes(design, 0, 1).reshape(-1, data.size, 3)  # ts = k + frac, k-major
    ts_all = (ks[:, None] + fracs[None, :]).ravel()
    if sign < 0:  # an end: Q(t) (1 - H(t - ts)), Q = a - b (t - ts) + q (t - ts)^2 for all t
        parabola = np.swapaxes(cols[:, 3, :][:, idx], 0, 1).reshape(-1, data.size)
        design = np.stack([1.0 - design[..., 0], (ts_all[:, None] - n[None, :]) + design[..., 1],
                           parabola - design[..., 2]], axis=-1)
        design = design[..., 1:END_TERMS]  # a ball's force falls to zero continuously as it leaves: no jump
    else:
        design = design[..., :END_TERMS]
    gram = np.swapaxes(design, 1, 2) @ design
    rhs = np.swapaxes(design, 1, 2) @ data
    ridge = 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(gram.shape[-1])  # never singular
    coef = np.linalg.solve(gram + ridge + 1e-300, rhs[..., None])[..., 0]
    sse_all = np.sum((data[None, :] - (design @ coef[..., None])[..., 0]) ** 2, axis=1)
    i_best = int(np.argmin(sse_all))
    best = np.concatenate([[0.0], coef[i_best]]) if sign < 0 else coef[i_best]
    sse, end, a, b = float(sse_all[i_best]), float(ts_all[i_best]), float(best[0]), float(best[1])
    if not (k_lo < end < k_hi):  # at the edge of the candidates: no end inside them
        return None
    resid2 = sse / max(data.size - design.shape[-1] - 1, 1)
    # the ends whose fit is worse by less than one residual variance per independent sample of the
    # low-passed noise (correlated over about 1 / sum(taps^2) samples): a standard uncertainty
    rise = resid2 / float(np.sum(taps ** 2))
    spread = float(np.max(np.abs(ts_all[sse_all <= sse + rise] - end)))
    # the force the fit says is there, less what the chain made of it: the kernel's spread and the undoing's
    # transient at the end, to be added back to the low-passed force over the window
    q = float(best[2]) if best.size > 2 else 0.0
    u = (n - end) * sign
    model = np.where(u >= 0, a + b * u + q * u * u, 0.0)
    correction = model - design[i_best] @ coef[i_best]
    noise_se = math.nan
    if noise_rms is not None:
        # the model's change with the end, its linear terms held: central differences on the grid (the best end is
        # inside the candidates, so both neighbours are on it)
        d_end = (design[i_best + 1] - design[i_best - 1]) @ coef[i_best] / (2.0 * END_GRID_SAMPLES)
        noise_se = _end_noise_se(np.column_stack([d_end, design[i_best]]), sse,
                                 _undone_noise_autocorrelation(float(frequency_hz), float(damping_ratio), fs,
                                                               float(cutoff_hz)), float(noise_rms))
    return UndoneEnd(float(end), float(b), float(a), math.sqrt(resid2), float(spread), int(lo), correction,
                     float(noise_se))


def _end_noise_se(jac: np.ndarray, sse: float, autocorrelation: np.ndarray, noise_rms: float) -> float:
    """Standard uncertainty of an end fitted by least squares in noise the plate's undoing has coloured [samples].

    ``jac`` [n, 1 + terms] holds the fitted force's derivative with respect
    to the end [unit of the force per sample] and the fit's linear columns
    [-, samples, samples^2] over the window's n samples. The undone (and
    low-passed) force's noise is the sensed white noise ``noise_rms`` passed
    through the chain, so its covariance is ``noise_rms^2 R`` with R the
    Toeplitz matrix of the chain's impulse response's ``autocorrelation``
    (lag 0 first): strongly correlated (the inverse amplifies the noise near
    and above the resonance by up to ``(fs / 2 fn)^2``, the low-pass keeps
    what lies below its cutoff), which no residual over the window shows
    (a whole stretch of samples moves together). The ordinary least squares'
    covariance is then the sandwich ``A^-1 J^T C J A^-1`` (A = J^T J,
    linearised at the fit: ordinary least squares in correlated noise), and its
    first diagonal element the end's variance. The noise variance is raised by
    the residual sum of squares ``sse`` over what that noise alone leaves
    (``noise_rms^2 tr((I - P) R)``, P the fit's hat matrix) where larger: a
    force the model does not fit. Zoo-like rigs: ``python
    bench/overshoot_map.py --n 400 --seed 5`` trace 5:350, whose end the fit
    put 2.0 samples early while its residual allowed half a sample.
    """
    n = jac.shape[0]
    if autocorrelation.size < n:
        autocorrelation = np.concatenate([autocorrelation, np.zeros(n - autocorrelation.size)])
    lag = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    cov = autocorrelation[lag]  # [n, n], in units of the sensed noise's variance
    gram = jac.T @ jac
    scale = np.sqrt(np.diag(gram))
    if not np.all(scale > 0) or not np.all(np.isfinite(scale)):
        return math.inf
    jn = jac / scale  # columns of unit norm: the solve is well conditioned whatever the terms' units
    try:
        inv = np.linalg.inv(jn.T @ jn)
    except np.linalg.LinAlgError:
        return math.inf
    meat = jn.T @ cov @ jn
    sandwich = inv @ meat @ inv
    expected = float(np.trace(cov) - np.trace(inv @ meat))  # tr((I - P) R): the residual noise alone leaves
    variance = noise_rms * noise_rms * max(1.0, sse / (noise_rms * noise_rms * expected)) \
        if noise_rms > 0 and expected > 0 else sse / max(expected, 1e-300)
    se2 = variance * float(sandwich[0, 0]) / float(scale[0] ** 2)
    return math.sqrt(se2) if se2 >= 0 and math.isfinite(se2) else math.inf


@functools.lru_cache(maxsize=16)
def _undone_noise_autocorrelation(frequency_hz: float, damping_ratio: float, fs: float, cutoff_hz: float) -> np.ndarray:
    """Autocorrelation of the impulse response of the plate's inverse and the low-pass, lag 0 first [-]: the
    undone force's noise covariance over the sensed white noise's variance, at each lag [samples]."""
    half = NOISE_RESPONSE_HALF + (0 if math.isinf(cutoff_hz) else int(math.ceil(0.5 * fs / cutoff_hz)))
    h = undone_impulse_response(fs, frequency_hz, damping_ratio, half, cutoff_hz)
    full = np.correlate(h, h, mode="full")
    return full[h.size - 1:].copy()


@functools.lru_cache(maxsize=16)
def _end_columns_cached(frequency_hz: float, damping_ratio: float, fs: float, cutoff_hz: float, step: float,
                        span: int):
    """:func:`_end_columns` for one plate [Hz, -], sample rate and cutoff [Hz], grid and span, kept for reuse."""
    taps = np.ones(1) if math.isinf(cutoff_hz) else lowpass_kernel(fs, cutoff_hz)
    return _end_columns(frequency_hz, damping_ratio, fs, taps, step, span)


def lowpass_zero_phase(force, sample_rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """A zero-phase low-pass of a trace on a compact kernel: half amplitude near ``cutoff_hz``, unit static gain.

    The kernel (:func:`lowpass_kernel`) is a Hann window of half-width
    ``W = fs / (2 cutoff_hz)`` samples, normalised to unit sum: symmetric
    (no delay, so a contact's ends do not move as a whole), non-negative (no
    overshoot, so a force that starts from zero does not dip below it), of
    unit static gain (the impulse, so kCAL, is kept) and compact: a force
    that is zero before t0 stays exactly zero before t0 - W / fs, so a
    contact can grow by at most W samples at each end (no tail to find in
    the noise, as a Gaussian's is). Its response falls to half at about
    ``cutoff_hz`` and to zero at twice it: it cuts the noise that undoing a
    plate resonance amplifies by ``(f / fn)^2`` above the resonance. Not in
    the paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        Trace, proportional to force (any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    cutoff_hz : float
        Frequency of half amplitude [Hz]; ``inf`` returns the trace unchanged.

    Returns
    -------
    numpy.ndarray
        The smoothed trace, same unit and length [V]; the record's ends are
        reflected.

    Raises
    ------
    ValueError
        For a non-positive sample rate or cutoff, or non-finite samples.
    """
    from scipy.ndimage import convolve1d

    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not cutoff_hz > 0:
        raise ValueError(f"cutoff_hz must be positive, got {cutoff_hz!r}")
    x = finite_samples("force", force)
    if math.isinf(cutoff_hz):
        return x.copy()
    return convolve1d(x, lowpass_kernel(fs, cutoff_hz), mode="reflect")


def undone_noise_gain(sample_rate_hz: float, frequency_hz: float, damping_ratio: float,
                      cutoff_hz: float = math.inf) -> float:
    """Rms gain of white noise through the plate's inverse and a :func:`lowpass_zero_phase` at ``cutoff_hz`` [-].

    The square root of the sum of squares of the chain's impulse response:
    the undone force's noise is this times the sensed trace's white noise.

    Parameters
    ----------
    sample_rate_hz, frequency_hz : float
        Sample rate and the plate's resonance [Hz].
    damping_ratio : float
        The plate's damping ratio [-].
    cutoff_hz : float
        Half-amplitude frequency of the low-pass [Hz]; ``inf`` for none.

    Returns
    -------
    float
        Rms gain [-]: ``(fs / 2 fn)^2``-ish near the Nyquist frequency for the
        bare inverse, about 1 for a cutoff at the resonance.
    """
    fs = float(sample_rate_hz)
    half = 64 + (0 if math.isinf(cutoff_hz) else int(math.ceil(0.5 * fs / cutoff_hz)))
    h = undone_impulse_response(fs, frequency_hz, damping_ratio, half, cutoff_hz)
    return float(np.sqrt(np.sum(h * h)))


def undone_impulse_response(sample_rate_hz: float, frequency_hz: float, damping_ratio: float, half_samples: int,
                            cutoff_hz: float = math.inf) -> np.ndarray:
    """Impulse response of the plate's inverse (:func:`undo_plate_resonance`), then a :func:`lowpass_zero_phase`
    at ``cutoff_hz``: what the undone force's sample takes from a sensed sample at each lag [-].

    Parameters
    ----------
    sample_rate_hz, frequency_hz : float
        Sample rate and the plate's resonance [Hz].
    damping_ratio : float
        The plate's damping ratio [-].
    half_samples : int
        Lags kept each side of zero [samples] (the inverse is two-sided).
    cutoff_hz : float
        Half-amplitude frequency of the low-pass [Hz]; ``inf`` for none.

    Returns
    -------
    numpy.ndarray
        ``2 half_samples + 1`` values [-], lag ``d`` at index ``half_samples + d``.
    """
    impulse = np.zeros(2 * int(half_samples) + 1)
    impulse[int(half_samples)] = 1.0
    h = undo_plate_resonance(impulse, sample_rate_hz, frequency_hz, damping_ratio)
    return h if math.isinf(cutoff_hz) else lowpass_zero_phase(h, sample_rate_hz, cutoff_hz)


FRONT_RISE_MAX = 4.0  # the force's jump rises over at most this many samples (the model's 10 us step) [samples]
FRONT_START_SPAN = 3.0  # the force's start is looked for up to this many samples before the contact's first [samples]
FRONT_MAX_FREQUENCY = 0.45  # resonances fitted up to this fraction of the sample rate [-]
FRONT_GRID_FREQUENCIES = 16  # the starting grid: this many resonances, log-spaced ... [-]
FRONT_GRID_DAMPING = (0.03, 0.1, 0.2, 0.35)  # ... each with these damping ratios [-]
FRONT_MAX_EVALUATIONS = 60  # least-squares evaluations from the grid's best at most [-]
FRONT_DROP_MAX_DAMPING = 0.4  # with the drop at buckling, damping ratios fitted up to this [-]


class FrontFit(NamedTuple):
    """A contact's front fitted by :func:`fit_front`: a jump, a ramp and a parabola, through a plate or an ideal one."""

    frequency_hz: float  #: the plate's resonance [Hz] (inf: an ideal plate)
    damping_ratio: float  #: its damping ratio [-]
    start: float  #: where the force starts [samples, fractional index]
    rise: float  #: the samples over which its jump rises [samples]
    jump: float  #: the jump [unit of the force]
    slope: float  #: the ramp's slope after the start [unit of the force per sample]
    curvature: float  #: the parabola's coefficient [unit of the force per sample^2]
    rss: float  #: residual sum of squares over the window [unit of the force^2]
    n_samples: int  #: samples in the window [-]
    drop_start: float = math.inf  #: where a second jump (the drop at buckling) starts [samples] (inf: none fitted)
    drop: float = 0.0  #: that jump, rising over ``rise`` too (negative: a drop) [unit of the force]
    drop_slope: float = 0.0  #: the change of the ramp's slope from it [unit of the force per sample]
    drop_curvature: float = 0.0  #: ... and of the parabola's coefficient [unit of the force per sample^2]
    spike_index: int = -1  #: the sample a single-sample electrical spike was fitted on (-1: none) [-]
    spike: float = 0.0  #: that spike, added to the sensed force (not through the plate) [unit of the force]
    cubic: float = 0.0  #: a cubic's coefficient from the start (0 with a drop) [unit of the force per sample^3]
    drop_cubic: float = 0.0  #: ... and its change at the drop [unit of the force per sample^3]

    def force(self, index) -> np.ndarray:
        """The fitted applied force (not the sensed one) at fractional sample indices [unit of the force]."""
        def jump(u):
            ramp = np.clip(u / self.rise, 0.0, 1.0) if self.rise > 0 else (u >= 0).astype(float)
            return np.where(u >= 0, ramp, 0.0)

        u = np.asarray(index, dtype=float) - self.start
        out = np.where(u >= 0, self.jump * jump(u) + u * (self.slope + u * (self.curvature + u * self.cubic)), 0.0)
        if math.isfinite(self.drop_start):
            v = np.asarray(index, dtype=float) - self.drop_start
            out = out + self.drop * jump(v) + np.where(
                v >= 0, v * (self.drop_slope + v * (self.drop_curvature + v * self.drop_cubic)), 0.0)
        return out


def front_responses(u, wn, zeta, rise, *, cubic: bool = False):
    """The plate's response to a jump rising linearly over ``rise`` samples, a ramp and a parabola from u = 0.

    Analytic (the continuous second-order plate of unit static gain sampled
    at u): the step response ``1 - exp(-zeta wn u) (cos wd u + zeta wn / wd
    sin wd u)``, the ramp response ``u - c + exp(-zeta wn u) (c cos wd u + d
    sin wd u)`` (c = 2 zeta / wn, d = (2 zeta^2 - 1) / wd) and the
    parabola's; the jump rising over ``rise`` samples is the difference of
    two ramp responses over ``rise``. ``wn = inf`` is an ideal plate (the
    force itself). With ``cubic``, also the response to u^3: ``u^3 + A u^2 +
    B u + C - exp(-zeta wn u) (C cos wd u + (zeta wn C + B) / wd sin wd u)``
    with A = -6 zeta / wn, B = (24 zeta^2 - 6) / wn^2 and C = 24 zeta (1 -
    2 zeta^2) / wn^3 (the polynomial solves the plate's equation, the
    oscillation starts it at rest).

    Parameters
    ----------
    u : array_like
        Time since the force's start [samples], any shape (broadcast with the others).
    wn : array_like
        The resonance's angular frequency [rad per sample] (inf: no resonance).
    zeta : array_like
        Its damping ratio, 0 to 1 [-].
    rise : array_like
        The samples over which the jump rises [samples], >= 0 (0: a step).
    cubic : bool
        Also return the response to the cubic u^3.

    Returns
    -------
    numpy.ndarray
        Shape ``broadcast(...) + (3,)`` (``(4,)`` with ``cubic``): the
        responses to the unit jump, the unit ramp u, the parabola u^2 [-,
        samples, samples^2] (and the cubic u^3 [samples^3]), zero before u = 0.
    """
    u, wn, zeta, rise = (np.asarray(v, dtype=float) for v in (u, wn, zeta, rise))
    shape = np.broadcast_shapes(u.shape, wn.shape, zeta.shape, rise.shape)
    ideal = ~np.isfinite(wn)
    all_ideal, any_ideal = bool(np.all(ideal)), bool(np.any(ideal))
    if not all_ideal:  # the plate's constants, once per resonance (not per sample)
        w = np.where(ideal, 1.0, wn)
        z = np.where(ideal, 0.5, zeta)
        sigma, wd = z * w, w * np.sqrt(np.maximum(1.0 - z * z, 1e-12))
        c, d = 2.0 * z / w, (2.0 * z * z - 1.0) / wd
        p0, p1 = 2.0 * (4.0 * z * z - 1.0) / (w * w), -4.0 * z / w
        qb = (-sigma * p0 - p1) / wd
        c2, c1, c0 = -6.0 * z / w, (24.0 * z * z - 6.0) / (w * w), 24.0 * z * (1.0 - 2.0 * z * z) / w ** 3
        cb = (sigma * c0 + c1) / wd

    def responses(v, all_three=True):  # (step, ramp, parabola) responses at v, or the ramp's alone
        v = np.broadcast_to(v, shape)
        on = v >= 0
        t = np.where(on, v, 0.0)
        if all_ideal:
            ramp = t
        else:
            decay = np.exp(-sigma * t)
            cos, sin = np.cos(wd * t), np.sin(wd * t)
            ramp = np.where(ideal, t, t - c + decay * (c * cos + d * sin)) if any_ideal else \
                t - c + decay * (c * cos + d * sin)
        ramp = np.where(on, ramp, 0.0)
        if not all_three:
            return ramp
        if all_ideal:
            step, par = np.ones(shape), t * t
        else:
            step = 1.0 - decay * (cos + sigma / wd * sin)
            par = t * t + p1 * t + p0 + decay * (-p0 * cos + qb * sin)
            if any_ideal:
                step, par = np.where(ideal, 1.0, step), np.where(ideal, t * t, par)
        if not cubic:
            return np.where(on, step, 0.0), ramp, np.where(on, par, 0.0)
        if all_ideal:
            cub = t ** 3
        else:
            cub = t * (t * (t + c2) + c1) + c0 - decay * (c0 * cos + cb * sin)
            if any_ideal:
                cub = np.where(ideal, t ** 3, cub)
        return np.where(on, step, 0.0), ramp, np.where(on, par, 0.0), np.where(on, cub, 0.0)

    step, ramp, *higher = responses(u)
    spread = np.broadcast_to(rise > 1e-9, shape)
    jump = np.where(spread, (ramp - responses(u - rise, all_three=False)) / np.where(spread, rise, 1.0), step)
    return np.stack([jump, ramp, *higher], axis=-1)


def fit_front(force, sample_rate_hz: float, first: int, last: int, start: float, *, resonance: bool = True,
              drop: bool = False, rise_max: float = FRONT_RISE_MAX, refine: bool = True, spike=None,
              damping=None, drop_within=None, cubic: bool = False):
    """The front of a contact (a jump from zero, a ramp, a parabola) through a plate fitted to its samples.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake
    2004: the cloth carries no load below 2 mm of compression, kB = kCONST
    for the first 0.2 ms, Eq. (14) F = kB x + (cB + cM) x') the force jumps
    from zero and then rises smoothly to the spike: ``J r(t - ts) + b (t -
    ts) + q (t - ts)^2`` with r a rise from 0 to 1 over a few microseconds.
    A plate of resonance fn and damping zeta answers the jump with a rise
    over part of its period, an overshoot and a damped oscillation. The
    samples ``first .. last`` are fitted with that force through the plate
    (:func:`front_responses`; J, b, q linear, fn, zeta, ts and the rise by
    nonlinear least squares from a grid) or, with ``resonance=False``,
    through an ideal plate. Comparing the two says whether the samples need
    the plate's ringing, and the fit says how far the ringing lifts a sample
    above the force. Not in the paper; see docs/signal-processing.md, "Plate resonance", and
    docs/robustness-history.md.

    Parameters
    ----------
    force : array_like
        The sensed force (any unit) [V].
    sample_rate_hz : float
        Sample rate [Hz].
    first, last : int
        The window's first and last sample [-] (a few before the start, up to the peak).
    start : float
        The contact start found [samples, fractional index]: the force's start
        is looked for from FRONT_START_SPAN samples before its first sample
        to that sample.
    resonance : bool
        Fit through a plate (fn up to FRONT_MAX_FREQUENCY of the sample
        rate, and down to one period over the window) or an ideal one.
    drop : bool
        Also fit a second jump (rising over the same samples) and a change
        of the ramp's slope and of the parabola from anywhere in the window
        after the force's first sample: the model's drop at buckling
        (section 3.2.4: kB falls from kCONST to Eq. (4) 0.2 ms after first
        contact), for a window that runs on past the pre-buckling spike;
        the jump and the ramp before it then rise (>= 0) and the drop
        falls (<= 0), as the model's force does.
    rise_max : float
        The most samples the jumps may rise over [samples] (FRONT_RISE_MAX:
        the model's 10 us step at up to 400 kHz).
    refine : bool
        Refine the starting grid's best fit by least squares; False returns
        the grid's best (a residual no smaller than the refined one's; fast).
    spike : sequence of int, optional
        Samples (inside the window) where a single-sample electrical spike
        may be: the fit also takes a free value added to one of them (not
        through the plate: the spike is the amplifier's, after the plate):
        each candidate is fitted from the fit without a spike and from the
        starting grid's best with it, and the least residual of all is the
        fit (``spike_index``, ``spike``; about twice as many fits as
        candidates: with a free spike, spurious fits at a bound of the grid
        beat its rows near the true plate, and the fit from them stays
        there). A spike on the plate's ringing, which
        :func:`ballimpact.conditioning.remove_spikes` cannot tell from the
        ringing's own swings, otherwise raises the residual of the fit
        through the plate as much as the ideal one's (``python
        bench/spike_ends_map.py --n 400 --seed 2`` trace 2:349).
    damping : (float, float), optional
        The damping ratios the plate's may take, (lowest, highest) within 0
        to 1 [-]; by default 0.005 to 0.9 (FRONT_DROP_MAX_DAMPING with ``drop``).
    drop_within : float, optional
        With ``drop``, the drop is looked for up to this many samples after the
        force's first sample [samples]; by default anywhere in the window.
    cubic : bool
        Also fit a cubic from the start (with ``drop``, a cubic from the drop,
        as the parabola): a force that starts smoothly (a half-sine's foot)
        curves more over a long window than a parabola can follow.

    Returns
    -------
    FrontFit or None
        The fit; None when the window holds fewer than 8 samples, leaves the
        record, or no resonance fits between one period over the window and
        FRONT_MAX_FREQUENCY of fs. With ``drop``, its ``drop_*`` fields hold
        the drop and the changes after it (``curvature`` is 0: no parabola
        before the drop).
        With ``spike``, ``spike_index`` and ``spike`` hold the spike's sample
        and value (-1 and 0 when no candidate is inside the window).

    Raises
    ------
    ValueError
        For a non-positive sample rate, a non-finite start, a negative or
        non-finite rise_max, or non-finite samples.
    """
    from scipy.optimize import least_squares

    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    if not math.isfinite(start):
        raise ValueError(f"start must be finite, got {start!r}")
    if not (rise_max >= 0 and math.isfinite(rise_max)):
        raise ValueError(f"rise_max must be finite and non-negative, got {rise_max!r}")
    if damping is None:
        zeta_grid, zeta_lo, zeta_hi = FRONT_GRID_DAMPING, 0.005, FRONT_DROP_MAX_DAMPING if drop else 0.9
    else:
        zeta_lo, zeta_hi = (float(v) for v in damping)
        if not 0.0 < zeta_lo < zeta_hi < 1.0:
            raise ValueError(f"damping must be (lowest, highest) with 0 < lowest < highest < 1, got {damping!r}")
        zeta_grid = tuple(np.geomspace(zeta_lo, zeta_hi, 4))
    if drop_within is not None and not (drop_within > 0 and math.isfinite(drop_within)):
        raise ValueError(f"drop_within must be positive and finite, got {drop_within!r}")
    x = finite_samples("force", force)
    first, last = int(first), int(last)
    if first < 0 or last >= x.size or last - first + 1 < 8:
        return None
    y = x[first:last + 1]
    n = np.arange(first, last + 1, dtype=float)
    k0 = float(math.ceil(start))
    t_lo, t_hi = k0 - FRONT_START_SPAN, k0
    drop_last = float(last) if drop_within is None else min(float(last), k0 + float(drop_within))
    w_hi = 2.0 * math.pi * FRONT_MAX_FREQUENCY
    w_lo = 2.0 * math.pi / max(last - start + 1.0, 1.0)  # at least one period over the window
    if resonance and w_lo >= w_hi:
        return None

    def unconstrained(design):  # least squares of J, b, q (and the drop's) for each design [..., n, 3 or 5]
        gram = np.swapaxes(design, -1, -2) @ design
        rhs = np.swapaxes(design, -1, -2) @ y
        ridge = 1e-12 * (np.trace(gram, axis1=-2, axis2=-1)[..., None, None] + 1e-300) * np.eye(design.shape[-1])
        coef = np.linalg.solve(gram + ridge, rhs[..., None])[..., 0]
        resid = y - (design @ coef[..., None])[..., 0]
        return np.sum(resid * resid, axis=-1), coef, resid

    def solve(design):  # (rss, coef, resid); with the drop, J >= 0, b >= 0 and the drop <= 0
        if not drop:
            return unconstrained(design)
        gram = np.swapaxes(design, -1, -2) @ design
        rhs = (np.swapaxes(design, -1, -2) @ y)[..., None]
        m = design.shape[-1]  # 5, or 6 with a spike's column
        ridge = 1e-12 * (np.trace(gram, axis1=-2, axis2=-1)[..., None, None] + 1e-300) * np.eye(m)
        best_rss, best_coef = None, None
        for off in itertools.product((False, True), repeat=3):  # each sign-constrained column free or held at 0
            keep = np.array([not off[0], not off[1], not off[2]] + [True] * (m - 3), dtype=float)
            coef = np.linalg.solve(gram * np.outer(keep, keep) + ridge, rhs * keep[:, None])[..., 0]
            rss = float(y @ y) - 2.0 * np.sum(coef * rhs[..., 0], axis=-1) \
                + np.einsum("...i,...ij,...j->...", coef, gram, coef)
            sign = coef[..., :3] * np.array([1.0, 1.0, -1.0])
            rss = np.where(np.all(sign >= -1e-12 * (1.0 + np.abs(coef[..., :3])), axis=-1), rss, np.inf)
            if best_rss is None:
                best_rss, best_coef = rss, coef
            else:
                better = rss < best_rss
                best_rss, best_coef = np.where(better, rss, best_rss), np.where(better[..., None], coef, best_coef)
        resid = y - (design @ best_coef[..., None])[..., 0]
        return np.sum(resid * resid, axis=-1), best_coef, resid

    if resonance:
        g = np.meshgrid(np.geomspace(w_lo, w_hi, FRONT_GRID_FREQUENCIES), zeta_grid,
                        (k0 - 2.0, k0 - 1.0), (0.5, 1.5), indexing="ij")
        grid = np.stack([v.ravel() for v in g], axis=1)  # wn, zeta, ts, rise
    else:
        # through an ideal plate a sample sees the jump's rise only where it falls: a fine grid, no local minimum
        g = np.meshgrid(np.arange(t_lo, t_hi + 1e-9, 0.125), np.arange(0.0, rise_max + 1e-9, 0.25),
                        indexing="ij")
        grid = np.stack([np.full(g[0].size, np.inf), np.zeros(g[0].size), g[0].ravel(), g[1].ravel()], axis=1)
    if drop:  # the drop's start on every half sample after the force's first contact sample
        tb = np.arange(k0 + 0.5, drop_last, 0.5)
        grid = np.column_stack([np.repeat(grid, tb.size, axis=0), np.tile(tb, grid.shape[0])])
        if grid.size == 0:
            return None

    spike_col = None  # the spike's column (a unit at its sample), once chosen

    def design_of(rows):  # the responses of each row of (wn, zeta, ts, rise[, tb]) [rows, n, 3 or 5, +1 w. spike]
        cols = front_responses(n[None, :] - rows[:, 2:3], rows[:, 0:1], rows[:, 1:2], rows[:, 3:4],
                               cubic=cubic and not drop)
        if drop:
            later = front_responses(n[None, :] - rows[:, 4:5], rows[:, 0:1], rows[:, 1:2], rows[:, 3:4], cubic=cubic)
            # no parabola before the drop, and the ramp up to it rises by at most the jump: J = a + b L, a, b >= 0
            span = np.maximum(rows[:, 4:5] - rows[:, 2:3], 0.0)[..., None]  # L, from the start to the drop [samples]
            cols = np.concatenate([cols[..., :1], cols[..., 1:2] + span * cols[..., :1], later], axis=-1)
        if spike_col is None:
            return cols
        return np.concatenate([cols, np.broadcast_to(spike_col, cols.shape[:-1])[..., None]], axis=-1)

    candidates = sorted({int(k) - first for k in (spike or ()) if first <= int(k) <= last})
    if spike is not None and not candidates:  # no candidate inside the window: the fit without a spike
        return fit_front(x, fs, first, last, start, resonance=resonance, drop=drop, rise_max=rise_max, refine=refine,
                         damping=damping, drop_within=drop_within, cubic=cubic)

    # the free parameters: (wn, zeta, ts, rise) through a plate, (ts, rise) through an ideal one
    if resonance:
        lo, hi = np.array([0.8 * w_lo, zeta_lo, t_lo, 0.0]), np.array([w_hi, zeta_hi, t_hi, rise_max])
        full, free = np.atleast_2d, slice(None)
    else:
        lo, hi, free = np.array([t_lo, 0.0]), np.array([t_hi, rise_max]), slice(2, None)

        def full(q):
            q = np.atleast_2d(q)
            return np.column_stack([np.full(q.shape[0], np.inf), np.zeros(q.shape[0]), q])
    if drop:
        lo, hi = np.append(lo, k0), np.append(hi, drop_last)

    def residuals(rows):  # the residuals of each row of free parameters, all at once [rows, n]
        rows = full(rows)
        return solve(design_of(rows))[2]

    def jacobian(q, *_):  # forward differences (backward at an upper bound), in one batch
        step = 1e-6 * np.maximum(np.abs(q), 1e-2) * np.where(q < hi - 1e-9, 1.0, -1.0)
        r = residuals(np.vstack([q, q + np.diag(step)]))
        return ((r[1:] - r[0]) / step[:, None]).T

    def fitted(p0):  # the parameters from p0 (refined when asked) and their linear least squares
        if refine:
            q = least_squares(lambda v: residuals(v)[0], np.clip(p0[free], lo, hi), jac=jacobian, bounds=(lo, hi),
                              x_scale="jac", max_nfev=FRONT_MAX_EVALUATIONS).x
            p0 = full(q)[0]
        return p0, solve(design_of(p0[None, :]))

    if not candidates:
        p, solved = fitted(grid[int(np.argmin(solve(design_of(grid))[0]))])
        return _front_fit(p, solved, drop, fs, y.size, cubic=cubic)
    # a free spike makes spurious fits on the grid (at a bound) beat the grid's rows near the true plate: each
    # candidate is also fitted from the fit without a spike, and the least residual of all is the fit
    plain = fit_front(x, fs, first, last, start, resonance=resonance, drop=drop, rise_max=rise_max, refine=refine,
                      damping=damping, drop_within=drop_within, cubic=cubic)
    if plain is None:
        return None
    starts = [np.array([2.0 * math.pi * plain.frequency_hz / fs, plain.damping_ratio, plain.start, plain.rise]
                       + ([plain.drop_start] if drop else []))]
    best = None
    for unit in np.eye(y.size)[candidates]:
        spike_col = unit
        for p0 in starts + [grid[int(np.argmin(solve(design_of(grid))[0]))]]:
            p, solved = fitted(p0)
            if best is None or solved[0][0] < best[0]:
                best = (float(solved[0][0]), p, solved, unit)
    spike_col = best[3]
    return _front_fit(best[1], best[2], drop, fs, y.size, first, spike_col, cubic=cubic)


def _front_fit(p, solved, drop: bool, fs: float, n: int, first: int = 0, spike_col=None, *,
               cubic: bool = False) -> FrontFit:
    """The FrontFit of parameters p (wn, zeta, ts, rise[, tb]) and their linear least squares (rss, coef, resid);
    with ``spike_col`` (the spike's unit column, the window's first sample ``first``), the spike's sample and value
    from the last coefficient; with ``cubic``, the cubic's from the one before."""
    rss, coef = float(solved[0][0]), solved[1][0]
    spiked = ()
    if spike_col is not None:
        spiked, coef = (first + int(np.argmax(spike_col)), float(coef[-1])), coef[:-1]
    cubed = {}
    if cubic:
        cubed, coef = {"drop_cubic" if drop else "cubic": float(coef[-1])}, coef[:-1]
    if drop:  # (J - b L, b, D, the slope's and the parabola's change at the drop): no parabola before it
        span = max(float(p[4] - p[2]), 0.0)
        coef, extra = (np.array([coef[0] + coef[1] * span, coef[1], 0.0]),
                       (float(p[4]), float(coef[2]), float(coef[3]), float(coef[4])))
    else:
        extra = ()
    fit = FrontFit(float(p[0] * fs / (2.0 * math.pi)), float(p[1]), float(p[2]), float(p[3]), float(coef[0]),
                   float(coef[1]), float(coef[2]), float(rss), int(n), *extra, **cubed)
    return fit._replace(spike_index=spiked[0], spike=spiked[1]) if spiked else fit
