"""The force plate's own resonance: identified from its ringing in a trace.

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
2. **Undoing** (:func:`ballimpact.signal.undo.undo_plate_resonance`): ``A(z)`` applied to the trace
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

import itertools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._checks import finite_samples, positive_scalar
from .undo import undo_plate_resonance

__all__ = [
    "PlateResonance",
    "stated_resonance",
    "identify_plate_resonance",
    "identify_free_ringing",
    "FreeRinging",
    "fit_trace_ringing",
    "refine_plate_resonance",
]

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
FIT_RING_BAND = (1.1, 2.0)  # a known plate refined on its free ringing stays within these factors of its fn, zeta [-]


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
    plate's ringing, drowns the recursion, for a plate of a few kHz sampled
    fast), the ringing after the
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
    f_lo, f_hi = MIN_FREQUENCY_FRACTION * fs, MAX_FREQUENCY_FRACTION * fs
    residual = _ringing_residual(np.arange(n) / fs, y, noise)  # amplitudes and constant solved at each (fn, zeta)

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


class FreeRinging(NamedTuple):
    """A plate's resonance fitted to one stretch of its free ringing by :func:`fit_trace_ringing`."""

    frequency_hz: float  #: undamped natural frequency fn [Hz]
    damping_ratio: float  #: damping ratio zeta [-]
    frequency_se_hz: float  #: standard uncertainty of fn from the noise (or the residual, the larger) [Hz]
    damping_se: float  #: standard uncertainty of zeta, likewise [-]
    residual_rms: float  #: rms residual of the fit [unit of the stretch]
    result: object  #: the optimiser's result (scipy.optimize.OptimizeResult)


def fit_trace_ringing(force, sample_rate_hz: float, noise_rms: float, frequency_hz: float,
                     damping_ratio: float) -> FreeRinging:
    """A known plate's resonance refined on a stretch of its free ringing, with standard uncertainties.

    The stretch (no force acts) is ``exp(-zeta wn t) (A cos wd t + B sin wd t) + c`` plus white noise, wd = wn
    sqrt(1 - zeta^2): the amplitudes and the constant are solved for linearly at each (fn, zeta), which a
    bounded least-squares fit moves from the plate given (``frequency_hz``, ``damping_ratio``: a stated or a
    session's plate) within the factors FIT_RING_BAND of its fn and zeta. The uncertainties come from the fit's
    Jacobian, with the variance of the larger of the noise and the residual. Unlike
    :func:`identify_free_ringing` it does not search for a resonance: it measures, in one trace, the one the
    session already knows. Not in the paper; see docs/signal-processing.md, "Plate resonance".

    Parameters
    ----------
    force : array_like
        The baseline-corrected trace after a contact's end, where no force acts [V].
    sample_rate_hz : float
        Sample rate [Hz].
    noise_rms : float
        Standard deviation of the trace's white noise [V], > 0.
    frequency_hz, damping_ratio : float
        The plate the fit starts from: resonance [Hz] and damping ratio [-].

    Returns
    -------
    FreeRinging

    Raises
    ------
    ValueError
        For a non-positive sample rate, noise or resonance, a damping ratio outside (0, 1), non-finite samples,
        a stretch shorter than MIN_RING_SAMPLES, or a fit that failed or ended on a bound.
    """
    from scipy.optimize import least_squares

    fs = positive_scalar("sample_rate_hz", sample_rate_hz)
    noise = positive_scalar("noise_rms", noise_rms)
    f0 = positive_scalar("frequency_hz", frequency_hz)
    if not 0.0 < damping_ratio < 1.0:
        raise ValueError(f"damping_ratio must be in (0, 1), got {damping_ratio!r}")
    y = finite_samples("force", force)
    if y.size < MIN_RING_SAMPLES:
        raise ValueError(f"a free ringing of {y.size} samples is too short to fit (need {MIN_RING_SAMPLES})")
    residual = _ringing_residual(np.arange(y.size) / fs, y, noise)
    lo = [f0 / FIT_RING_BAND[0], damping_ratio / FIT_RING_BAND[1]]
    hi = [f0 * FIT_RING_BAND[0], min(damping_ratio * FIT_RING_BAND[1], 0.99)]  # above fs / 2: its alias's samples
    best = least_squares(residual, [f0, damping_ratio], bounds=(lo, hi), x_scale=[f0 * 0.01, damping_ratio * 0.1])
    f, zeta = (float(v) for v in best.x)
    inside = all(a * (1 + 1e-6) < v < b * (1 - 1e-6) for a, v, b in zip(lo, (f, zeta), hi))
    if not (best.success and inside):
        raise ValueError(f"the free ringing's fit from {f0:.4g} Hz, zeta {damping_ratio:.3g} failed or ended on a "
                         f"bound ({f:.4g} Hz, zeta {zeta:.3g})")
    variance = max(2.0 * float(best.cost) / max(y.size - 5, 1), 1.0)  # in noise variances (five parameters)
    jac = np.asarray(best.jac, dtype=float)
    try:
        cov = np.linalg.inv(jac.T @ jac) * variance
    except np.linalg.LinAlgError as exc:
        raise ValueError("the free ringing does not determine the resonance (singular fit)") from exc
    return FreeRinging(f, zeta, math.sqrt(max(cov[0, 0], 0.0)), math.sqrt(max(cov[1, 1], 0.0)),
                       math.sqrt(variance) * noise, best)


def _ringing_residual(t: np.ndarray, y: np.ndarray, noise: float):
    """The residual [noise deviations] of a damped sinusoid and a constant at (fn [Hz], zeta [-]), its amplitudes
    solved for linearly."""
    def residual(p):
        wn = 2.0 * math.pi * p[0]
        wd = wn * math.sqrt(max(1.0 - p[1] * p[1], 0.0))
        decay = np.exp(-p[1] * wn * t)
        b = np.column_stack([decay * np.cos(wd * t), decay * np.sin(wd * t), np.ones(t.size)])
        return (b @ np.linalg.lstsq(b, y, rcond=None)[0] - y) / noise
    return residual


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
