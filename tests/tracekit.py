"""Synthetic plate-voltage traces with known truth, for the signal-processing tests.

A known force (half-sine of duration T, optionally after a linear cloth ramp)
goes through an independent model of the sensor chain: plate ringing, the
charge amplifier's first-order high-pass (scipy.signal.lfilter, bilinear),
polarity, DC offset, mains hum with harmonics, white noise and a 16-bit ADC
(quantisation and clipping).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

HUM_HARMONICS = ((1, 1.0), (2, 0.3), (3, 0.5))  # (harmonic number, relative amplitude)


@dataclass(frozen=True)
class TraceTruth:
    """What went into a synthetic trace.

    Attributes
    ----------
    start_s, end_s : float
        First and last moment the force is non-zero [s].
    contact_time_s : float
        end_s - start_s [s].
    impulse_V_s : float
        Integral of the clean voltage (force / kCAL) over the contact [V s].
    kcal_N_per_V : float
        True calibration factor, m (vin + vout) / impulse_V_s [N/V].
    peak_V : float
        Peak of the clean voltage [V].
    mass_kg, vin_m_s, vout_m_s : float
        Ball mass [kg] and speeds [m/s] consistent with the impulse.
    time_s : numpy.ndarray
        Sample times [s].
    clean_V : numpy.ndarray
        Clean voltage at the samples (force / kCAL, no ringing) [V].
    """

    start_s: float
    end_s: float
    contact_time_s: float
    impulse_V_s: float
    kcal_N_per_V: float
    peak_V: float
    mass_kg: float
    vin_m_s: float
    vout_m_s: float
    time_s: np.ndarray
    clean_V: np.ndarray


def force_shape(u, half_sine_s, cloth_s=0.0, cloth_fraction=0.0):
    """Force shape (peak 1) at time u after first contact [-].

    Linear cloth ramp to ``cloth_fraction`` over ``cloth_s``, then
    max(cloth level, half-sine) until the half-sine's peak, then the half-sine
    down to zero at ``cloth_s + half_sine_s``.
    """
    u = np.asarray(u, dtype=float)
    s = np.zeros_like(u)
    w = u - cloth_s
    sine = np.sin(np.pi * np.clip(w, 0.0, half_sine_s) / half_sine_s)
    if cloth_s > 0 and cloth_fraction > 0:
        ramp = cloth_fraction * np.clip(u / cloth_s, 0.0, 1.0)
        rising = (u >= 0) & (w <= 0.5 * half_sine_s)
        s = np.where(rising, np.maximum(ramp, sine), s)
        s = np.where((w > 0.5 * half_sine_s) & (w <= half_sine_s), sine, s)
    else:
        s = np.where((w >= 0) & (w <= half_sine_s), sine, s)
    return s


def shape_integral(half_sine_s, cloth_s=0.0, cloth_fraction=0.0) -> float:
    """Analytic integral of :func:`force_shape` [s]."""
    total = 2.0 * half_sine_s / math.pi
    if cloth_s > 0 and cloth_fraction > 0:
        c = cloth_fraction
        total += 0.5 * c * cloth_s  # the ramp
        u_star = half_sine_s * math.asin(c) / math.pi  # where the sine overtakes the cloth level
        total += c * u_star - half_sine_s / math.pi * (1.0 - math.cos(math.pi * u_star / half_sine_s))
    return total


def make_trace(*, sample_rate_hz=66964.3, half_sine_s=4.0e-3, cloth_s=0.0, cloth_fraction=0.015, peak_V=5.0,
               pre_s=0.030, post_s=0.030, start_phase=None, tau_s=None, offset_V=0.0, hum_V=0.0, mains_hz=50.0,
               noise_V=0.0, ringing_fraction=0.0, ringing_hz=3000.0, ringing_decay_s=0.5e-3, polarity=1,
               quantise=True, adc_range_V=(-10.0, 10.0), adc_bits=16, mass_kg=0.0577, vin_m_s=20.0, cor=0.6,
               second_impact=None, seed=0):
    """Build a synthetic recorded voltage and its truth.

    Parameters
    ----------
    sample_rate_hz : float
        DAQ sample rate [Hz].
    half_sine_s : float
        Duration of the half-sine [s].
    cloth_s, cloth_fraction : float
        Duration [s] and final level (fraction of the peak) of the cloth ramp in
        front of the half-sine; cloth_s = 0 for none.
    peak_V : float
        Peak of the clean voltage [V].
    pre_s, post_s : float
        Quiet stretch before the contact and after it [s].
    start_phase : float, optional
        Position of the contact start between two samples [samples, 0-1];
        random when omitted.
    tau_s : float, optional
        Charge-amplifier time constant [s]; None for a DC-coupled chain.
    offset_V, hum_V, mains_hz, noise_V : float
        DC offset [V], hum fundamental amplitude [V] (harmonics 2 and 3 at 0.3
        and 0.5 of it, random phases), mains frequency [Hz], white noise rms [V].
    ringing_fraction, ringing_hz, ringing_decay_s : float
        Plate ringing: amplitude (fraction of peak), frequency [Hz] and decay
        time [s], starting at the steep rise.
    polarity : int
        +1 or -1.
    quantise : bool
        Apply the ADC (quantisation and clipping at the rails).
    adc_range_V, adc_bits : tuple, int
        ADC range [V] and resolution [bit].
    mass_kg, vin_m_s, cor : float
        Ball mass [kg], inbound speed [m/s] and COR [-]; kCAL follows.
    second_impact : dict, optional
        ``{"delay_s": gap after the first contact [s], "fraction": its peak
        relative to the first [-], "duration_s": [s]}``.
    seed : int
        Random seed.

    Returns
    -------
    voltage_V : numpy.ndarray
        Recorded voltage [V].
    sample_rate_hz : float
        Sample rate [Hz].
    truth : TraceTruth
        The truth.
    """
    rng = np.random.default_rng(seed)
    fs = float(sample_rate_hz)
    if not (cloth_s > 0 and cloth_fraction > 0):
        cloth_s, cloth_fraction = 0.0, 0.0
    tc = cloth_s + half_sine_s
    n = int(round((pre_s + tc + post_s) * fs))
    t = np.arange(n) / fs
    phase = rng.uniform(0.0, 1.0) if start_phase is None else float(start_phase)
    t_start = (math.floor(pre_s * fs) + phase) / fs
    u = t - t_start
    clean = peak_V * force_shape(u, half_sine_s, cloth_s, cloth_fraction)
    plate = clean.copy()
    if second_impact is not None:
        u2 = u - tc - second_impact["delay_s"]
        plate += second_impact["fraction"] * peak_V * force_shape(u2, second_impact["duration_s"])
    if ringing_fraction:
        w = u - cloth_s
        plate += np.where(
            w >= 0,
            ringing_fraction * peak_V * np.exp(-np.maximum(w, 0) / ringing_decay_s)
            * np.sin(2 * np.pi * ringing_hz * w),
            0.0,
        )
    if tau_s is not None:
        b, a = signal.bilinear([tau_s, 0.0], [tau_s, 1.0], fs)
        plate = signal.lfilter(b, a, plate)
    v = polarity * plate + offset_V
    if hum_V:
        phases = rng.uniform(0, 2 * np.pi, size=len(HUM_HARMONICS))
        for (k, rel), ph in zip(HUM_HARMONICS, phases):
            v += rel * hum_V * np.sin(2 * np.pi * k * mains_hz * t + ph)
    if noise_V:
        v += rng.normal(0.0, noise_V, size=n)
    if quantise:
        lo, hi = adc_range_V
        lsb = (hi - lo) / 2**adc_bits
        v = lo + np.clip(np.round((v - lo) / lsb), 0, 2**adc_bits - 1) * lsb
    impulse = peak_V * shape_integral(half_sine_s, cloth_s, cloth_fraction)
    kcal = mass_kg * vin_m_s * (1.0 + cor) / impulse
    truth = TraceTruth(
        start_s=t_start, end_s=t_start + tc, contact_time_s=tc, impulse_V_s=impulse, kcal_N_per_V=kcal,
        peak_V=peak_V, mass_kg=mass_kg, vin_m_s=vin_m_s, vout_m_s=cor * vin_m_s, time_s=t, clean_V=clean,
    )
    return v, fs, truth


#: A dirty but realistic chain: the settings the accuracy tests sweep around.
DIRTY = dict(
    cloth_s=0.1e-3, cloth_fraction=0.015, tau_s=0.5, offset_V=0.08, hum_V=0.02, noise_V=0.002,
    ringing_fraction=0.03, ringing_hz=3500.0, ringing_decay_s=0.6e-3,
)
