"""Undoing the plate's resonance: its discretised inverse, the zero-phase low-pass and the noise they pass."""

from __future__ import annotations

import math

import numpy as np

from .._checks import finite_samples, positive_scalar

__all__ = [
    "plate_discretisation",
    "plate_undoable",
    "undo_plate_resonance",
    "undo_rows",
    "lowpass_kernel",
    "lowpass_spread_samples",
    "lowpass_zero_phase",
    "undone_noise_gain",
    "undone_impulse_response",
]


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
    return undo_rows(x, sample_rate_hz, frequency_hz, damping_ratio)


def plate_undoable(frequency_hz: float, damping_ratio: float, sample_rate_hz: float) -> bool:
    """Whether a plate's resonance (fn [Hz], zeta [-]) sampled at ``sample_rate_hz`` [Hz] can be undone.

    The inverse runs through the zeros of the sampled plate (:func:`plate_discretisation`), one pass each; they are
    real for a resonance the samples resolve, and complex for one too far above half the sample rate (a plate of
    26 kHz at 34 kHz, say), whose sampled response has no such inverse.
    """
    b, _ = plate_discretisation(frequency_hz, damping_ratio, sample_rate_hz)
    return _real_zeros(b) is not None


def _real_zeros(b) -> np.ndarray | None:
    """The zeros of the sampled plate's numerator ``b`` (real parts) when all are real, else None."""
    zeros = np.roots(b)
    return None if np.any(np.abs(np.imag(zeros)) > 1e-9 * np.abs(zeros)) else np.real(zeros)


def undo_rows(x: np.ndarray, fs: float, frequency_hz: float, damping_ratio: float) -> np.ndarray:
    """:func:`undo_plate_resonance` along the last axis of x (one trace or many at once) [unit of x]."""
    from scipy import signal

    b, a = plate_discretisation(frequency_hz, damping_ratio, fs)
    w = signal.lfilter(a, [1.0], x, axis=-1) / b[0]
    zeros = _real_zeros(b)
    if zeros is None:
        raise ValueError(f"the plate's sampled response has complex zeros {np.roots(b)}: not a second-order plate "
                         "sampled below its resonance's decay (plate_undoable)")
    for zero in zeros:
        z = float(zero)
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
