"""Plate-voltage conditioning: polarity, offset, mains hum and charge-amplifier decay, without biasing the impulse.

The charge amplifier acts as a first-order high-pass with time constant tau:
``dV_meas/dt = dV_true/dt - V_meas / tau``. Integrating from the contact start
(where both are zero) gives the exact inverse used here::

    V_true(t) = V_meas(t) + (1 / tau) * integral_{start}^{t} V_meas dt'

After the contact V_true = 0, so the measured signal sits at the undershoot
``-U = -(1 / tau) * integral over the contact of V_meas``, which gives
``tau = integral / U``. U is measured as the step of the post-contact baseline
relative to the pre-contact baseline at the contact end.

The baseline model, fitted by linear least squares to the quiet samples only
(up to 100 ms of pre-trigger, and up to 50 ms of the post-contact stretch
after a guard for plate ringing):
offset + sin/cos at the mains frequency and its harmonics (one phase-continuous
model for the whole trace) + on the post-contact stretch a step and a slope
(the undershoot and its slow recovery). Offset and hum are subtracted
everywhere; the step is not subtracted but removed by the decay correction.
Contact detection (:func:`ballimpact.contact.detect_contact`) and this fit are
iterated: a rough window from the offset-removed raw trace first, then the
window found on the corrected signal until it no longer moves.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .contact import ContactResult, detect_contact, robust_noise

__all__ = ["ConditionedSignal", "ConditioningWarning", "condition_voltage"]

PRE_GUARD_S = 0.5e-3  # quiet pre-trigger ends this long before the contact start [s]
POST_GUARD_S = 2.0e-3  # quiet post stretch begins this long after the contact end (plate ringing) [s]
PRE_WINDOW_S = 0.1  # longest pre-contact stretch used for the baseline fit [s]
POST_WINDOW_S = 0.05  # longest post-contact stretch: the decay is close to a straight line over it [s]
MIN_QUIET_SAMPLES = 20  # fewest samples for a pre or post baseline [samples]
MIN_POST_S = 2.0e-3  # shortest post-contact stretch for the undershoot step [s]
UNDERSHOOT_SIGNIFICANCE = 5.0  # undershoot must exceed this many standard errors [-]
TAU_BOUNDS_S = (0.01, 1.0e4)  # plausible charge-amplifier time constants [s]
BIAS_WARN_FRACTION = 1.0e-3  # warn when an uncorrected decay could bias the impulse by more [-]
MAX_ITERATIONS = 6  # contact window / baseline iterations [-]
CONVERGED_SAMPLES = 0.01  # window change that ends the iteration [samples]
NYQUIST_MARGIN = 0.45  # harmonics above this fraction of the sample rate are skipped [-]


class ConditioningWarning(UserWarning):
    """Usable but suspect conditioning (e.g. the decay could not be estimated)."""


@dataclass(frozen=True)
class ConditionedSignal:
    """A plate voltage with baseline, hum and decay removed.

    Attributes
    ----------
    voltage_V : numpy.ndarray
        Corrected voltage, polarity applied: proportional to the force, zero
        baseline [V].
    noise_rms_V : float
        Noise standard deviation of the quiet baseline (robust) [V].
    hum_amplitude_V : float
        Peak amplitude of the mains hum fundamental [V] (0 when not fitted).
    hum_harmonic_amplitudes_V : tuple of float
        Peak amplitude of the fundamental and each harmonic fitted [V].
    tau_s : float
        Charge-amplifier time constant used for the decay correction [s]; inf
        when no correction was applied, NaN when no contact was found.
    tau_source : str
        ``"estimated"``, ``"given"`` or ``"none"``.
    undershoot_V : float
        Step of the baseline at the contact end, positive downwards [V].
    undershoot_se_V : float
        Standard error of undershoot_V [V].
    offset_V : float
        DC offset of the pre-contact baseline (polarity applied) [V].
    baseline_V : numpy.ndarray
        Offset + hum model subtracted from every sample (polarity applied) [V].
    baseline_coefficients : dict
        The fitted model: ``offset_V``, ``hum_cos_V`` and ``hum_sin_V`` (one per
        harmonic), ``hum_frequencies_hz``, ``post_step_V``, ``post_slope_V_per_s``,
        ``post_anchor_s`` (time of the step, on the trace's time axis).
    contact : ContactResult
        Contact found on the corrected voltage.
    n_iterations : int
        Window/baseline iterations done [-].
    warnings : tuple of str
        Messages of the ConditioningWarnings issued.
    """

    voltage_V: np.ndarray
    noise_rms_V: float
    hum_amplitude_V: float
    hum_harmonic_amplitudes_V: tuple[float, ...]
    tau_s: float
    tau_source: str
    undershoot_V: float
    undershoot_se_V: float
    offset_V: float
    baseline_V: np.ndarray
    baseline_coefficients: dict = field(repr=False)
    contact: ContactResult = field(repr=False)
    n_iterations: int = 0
    warnings: tuple[str, ...] = ()


@dataclass
class _BaselineFit:
    baseline: np.ndarray  # offset + hum at every sample [V]
    coef: dict
    step: float  # post step at the anchor [V]
    step_se: float  # its standard error [V]
    has_step: bool
    noise: float  # robust noise of the quiet residuals [V]
    hum_amplitudes: tuple[float, ...]


def _fit_baseline(v, fs, frequencies, start_u, end_u, pre_guard, post_guard) -> _BaselineFit:
    """Least-squares offset + hum (+ post step and slope) on the quiet samples."""
    n = v.size
    idx = np.arange(n)
    pre = (idx < start_u - pre_guard) & (idx >= start_u - pre_guard - PRE_WINDOW_S * fs)
    post = (idx > end_u + post_guard) & (idx <= end_u + post_guard + POST_WINDOW_S * fs)
    min_post = max(MIN_QUIET_SAMPLES, int(round(MIN_POST_S * fs)))
    has_pre = np.count_nonzero(pre) >= MIN_QUIET_SAMPLES
    has_step = has_pre and np.count_nonzero(post) >= min_post
    quiet = pre | post
    if np.count_nonzero(quiet) < MIN_QUIET_SAMPLES:
        # no quiet stretch at all: a median offset is the best there is
        quiet = np.ones(n, dtype=bool)
        has_step = False
    t = idx / fs
    tq = t[quiet]
    span = tq[-1] - tq[0] if tq.size else 0.0
    freqs = [f for f in frequencies if span * f >= 1.0]  # need a full period of each hum component
    cols = [np.ones(n)]
    for f in freqs:
        cols.append(np.cos(2 * np.pi * f * t))
        cols.append(np.sin(2 * np.pi * f * t))
    n_base = len(cols)
    anchor_s = end_u / fs
    if has_step:
        cols.append(post.astype(float))
        cols.append(np.where(post, t - anchor_s, 0.0))
    a_full = np.column_stack(cols)
    a = a_full[quiet]
    y = v[quiet]
    norms = np.sqrt(np.sum(a * a, axis=0))
    norms[norms == 0] = 1.0
    an = a / norms
    # normal equations of the column-normalised design: a few columns, many rows
    ata_inv = np.linalg.pinv(an.T @ an, rcond=1e-12, hermitian=True)
    coef = (ata_inv @ (an.T @ y)) / norms
    resid = y - a @ coef
    dof = max(y.size - a.shape[1], 1)
    s2 = float(resid @ resid) / dof
    baseline = a_full[:, :n_base] @ coef[:n_base]
    step = step_se = 0.0
    if has_step:
        cov_n = ata_inv * s2
        step = float(coef[n_base])
        step_se = float(math.sqrt(max(cov_n[n_base, n_base], 0.0)) / norms[n_base])
    resid_all = v - a_full @ coef
    noise_region = pre if has_pre else quiet
    noise = robust_noise(resid_all[noise_region])
    amps = tuple(float(math.hypot(coef[1 + 2 * i], coef[2 + 2 * i])) for i in range(len(freqs)))
    coef_dict = {
        "offset_V": float(coef[0]),
        "hum_frequencies_hz": tuple(float(f) for f in freqs),
        "hum_cos_V": tuple(float(coef[1 + 2 * i]) for i in range(len(freqs))),
        "hum_sin_V": tuple(float(coef[2 + 2 * i]) for i in range(len(freqs))),
        "post_step_V": step if has_step else math.nan,
        "post_slope_V_per_s": float(coef[n_base + 1]) if has_step else math.nan,
    }
    return _BaselineFit(baseline, coef_dict, step, step_se, has_step, noise, amps)


def _decay_correct(y, fs, start_u, tau):
    """Inverse first-order high-pass from the contact start: y + cumulative integral / tau."""
    i0 = max(int(math.floor(start_u)) - 1, 0)
    x = y.copy()
    if math.isfinite(tau) and i0 < y.size - 1:
        c = cumulative_trapezoid(y[i0:], dx=1.0 / fs, initial=0.0)
        x[i0:] += c / tau
    return x


def _integral_to(y, fs, start_u, end_u) -> float:
    """Trapezium integral of y from the sample before start to the sub-sample end [V s]."""
    i0 = max(int(math.floor(start_u)) - 1, 0)
    c = cumulative_trapezoid(y[i0:], dx=1.0 / fs, initial=0.0)
    return float(np.interp(end_u - i0, np.arange(c.size), c))


def condition_voltage(voltage_V, sample_rate_hz: float, *, polarity: int = 1, mains_hz: float | None = 50.0,
                      n_harmonics: int = 3, t0_s: float = 0.0, tau_s: float | None = None,
                      pre_guard_s: float = PRE_GUARD_S, post_guard_s: float = POST_GUARD_S) -> ConditionedSignal:
    """Remove polarity, offset, mains hum and charge-amplifier decay from a plate voltage.

    The force-plate voltage must be proportional to the force for kCAL to be
    found from the impulse (section 2 in Goodwill & Haake 2004); this removes
    what the sensor chain adds. See the module docstring for the method. The
    impulse is not biased by the amplifier's undershoot: the decay is undone
    with the time constant that returns the post-contact baseline to zero.

    Parameters
    ----------
    voltage_V : array_like
        Voltage as recorded, one sample per 1/sample_rate_hz [V].
    sample_rate_hz : float
        Sample rate [Hz].
    polarity : int
        +1 when compressive force gives positive voltage, -1 otherwise [-].
    mains_hz : float or None
        Mains frequency [Hz]; None or 0 fits no hum.
    n_harmonics : int
        Hum components fitted: the fundamental and its harmonics up to
        ``n_harmonics * mains_hz`` [-].
    t0_s : float
        Time of the first sample [s] (only for the times reported).
    tau_s : float, optional
        Known amplifier time constant [s]; ``math.inf`` for a DC-coupled
        amplifier. Estimated from the undershoot when omitted.
    pre_guard_s, post_guard_s : float
        Samples closer than this to the contact are left out of the baseline
        fit [s].

    Returns
    -------
    ConditionedSignal
        Corrected voltage [V] with the noise [V], hum [V], tau [s], baseline
        model and the contact found on it. When no contact is found, only
        offset and hum are removed and ``contact.found`` is False.

    Raises
    ------
    ValueError
        For non-finite samples, fewer than 3 samples, a non-positive sample rate,
        a polarity other than +1/-1 or a non-positive tau_s.

    Warns
    -----
    ConditioningWarning
        When the decay cannot be estimated (no measurable undershoot, baseline
        after the contact above the one before it, post-contact stretch too
        short, implausible tau) and could bias the impulse by more than 0.1 %.
    """
    fs = float(sample_rate_hz)
    if not math.isfinite(fs) or fs <= 0:
        raise ValueError(f"sample_rate_hz must be positive and finite, got {sample_rate_hz!r}")
    if polarity not in (1, -1):
        raise ValueError(f"polarity must be 1 or -1, got {polarity!r}")
    if mains_hz is not None and (not math.isfinite(mains_hz) or mains_hz < 0):
        raise ValueError(f"mains_hz must be non-negative and finite, got {mains_hz!r}")
    if n_harmonics < 0:
        raise ValueError(f"n_harmonics must be non-negative, got {n_harmonics}")
    if tau_s is not None and not (tau_s > 0):
        raise ValueError(f"tau_s must be positive (math.inf for no decay), got {tau_s!r}")
    if pre_guard_s < 0 or post_guard_s < 0:
        raise ValueError(f"guards must be non-negative, got pre_guard_s={pre_guard_s}, post_guard_s={post_guard_s}")
    raw = np.asarray(voltage_V, dtype=float).ravel()
    if raw.size < 3:
        raise ValueError(f"voltage_V needs at least 3 samples, got {raw.size}")
    if not np.all(np.isfinite(raw)):
        bad = np.flatnonzero(~np.isfinite(raw))
        raise ValueError(f"voltage_V holds {bad.size} non-finite samples (first at index {bad[0]})")

    # work in units of the largest magnitude: no overflow for any finite input
    scale = float(np.max(np.abs(raw)))
    if not (scale > 0 and math.isfinite(scale)):
        scale = 1.0
    v = polarity * (raw / scale)
    frequencies = []
    if mains_hz:
        frequencies = [k * mains_hz for k in range(1, n_harmonics + 1) if k * mains_hz < NYQUIST_MARGIN * fs]
    pre_guard = pre_guard_s * fs
    post_guard = post_guard_s * fs
    messages: list[str] = []

    rough = detect_contact(v - np.median(v), fs)
    if not rough.found:
        fit = _fit_baseline(v, fs, frequencies, -math.inf, -math.inf, 0.0, 0.0)
        y = v - fit.baseline
        contact = detect_contact(y, fs, t0_s=t0_s, noise_rms_V=fit.noise)
        return _result(y, fit, math.nan, "none", math.nan, contact, 0, messages, t0_s, math.nan, scale)

    start_u, end_u = rough.start_s * fs, rough.end_s * fs
    tau = math.nan
    source = "none"
    n_iter = 0
    pending: list[str] = []
    for n_iter in range(1, MAX_ITERATIONS + 1):
        fit = _fit_baseline(v, fs, frequencies, start_u, end_u, pre_guard, post_guard)
        y = v - fit.baseline
        integral = _integral_to(y, fs, start_u, end_u)
        tau, source, pending = _choose_tau(tau_s, fit, integral, (end_u - start_u) / fs, scale)
        x = _decay_correct(y, fs, start_u, tau)
        c = detect_contact(x, fs, noise_rms_V=fit.noise)
        if not c.found:
            break
        new_start, new_end = c.start_s * fs, c.end_s * fs
        moved = max(abs(new_start - start_u), abs(new_end - end_u))
        start_u, end_u = new_start, new_end
        if moved < CONVERGED_SAMPLES:
            break
    for msg in pending:
        warnings.warn(msg, ConditioningWarning, stacklevel=2)
        messages.append(msg)
    contact = detect_contact(x, fs, t0_s=t0_s, noise_rms_V=fit.noise)
    undershoot = -fit.step if fit.has_step else math.nan
    return _result(x, fit, tau, source, undershoot, contact, n_iter, messages, t0_s, end_u / fs, scale)


def _choose_tau(tau_s, fit: _BaselineFit, integral: float, duration_s: float, scale: float):
    """Time constant for the decay correction, its source and the warnings to give.

    A positive undershoot always gives tau = integral / undershoot (applying a
    noisy tau is unbiased; skipping it is not). A warning is given when the
    undershoot is not measurable (below UNDERSHOOT_SIGNIFICANCE standard
    errors) and the impulse could then be off by more than BIAS_WARN_FRACTION.
    """
    if tau_s is not None:
        return float(tau_s), "given", []
    if not fit.has_step:
        return math.inf, "none", [
            "charge-amplifier decay not corrected: no quiet baseline both before and at least "
            f"{MIN_POST_S * 1e3:g} ms after the contact to measure the undershoot"
        ]
    undershoot = -fit.step
    se = fit.step_se
    messages = []
    if integral > 0 and UNDERSHOOT_SIGNIFICANCE * se > abs(undershoot):
        # how much could an undershoot hidden in the noise change the impulse?
        bias = duration_s * UNDERSHOOT_SIGNIFICANCE * se / (2.0 * integral)
        if bias > BIAS_WARN_FRACTION:
            messages.append(
                f"charge-amplifier undershoot not measurable ({undershoot * scale * 1e3:.3g} "
                f"+/- {se * scale * 1e3:.2g} mV): "
                f"the impulse may be off by up to {bias * 100:.2g} %"
            )
    if not integral > 0:
        return math.inf, "none", messages
    if undershoot < -UNDERSHOOT_SIGNIFICANCE * se:
        return math.inf, "none", [
            f"charge-amplifier decay not corrected: the baseline after the contact is "
            f"{-undershoot * scale * 1e3:.3g} mV above the one before it (expected an undershoot)"
        ]
    if undershoot <= 0:
        return math.inf, "none", messages
    tau = integral / undershoot
    if tau > TAU_BOUNDS_S[1]:
        return math.inf, "none", messages  # DC-coupled in effect: the correction is negligible
    if tau < TAU_BOUNDS_S[0]:
        return math.inf, "none", messages + [
            f"charge-amplifier decay not corrected: estimated time constant {tau:.3g} s is below "
            f"the plausible {TAU_BOUNDS_S[0]:g} s (a baseline shift that is not the amplifier's decay?)"
        ]
    return tau, "estimated", messages


def _result(x, fit: _BaselineFit, tau, source, undershoot, contact, n_iter, messages, t0_s, anchor_s, scale):
    """Assemble the ConditionedSignal, back in volts."""
    coef = dict(fit.coef)
    for key in ("offset_V", "post_step_V", "post_slope_V_per_s"):
        coef[key] = coef[key] * scale
    for key in ("hum_cos_V", "hum_sin_V"):
        coef[key] = tuple(c * scale for c in coef[key])
    coef["post_anchor_s"] = t0_s + anchor_s if math.isfinite(anchor_s) else math.nan
    contact = replace(contact, peak_V=contact.peak_V * scale, noise_rms_V=contact.noise_rms_V * scale,
                      threshold_V=contact.threshold_V * scale)
    with np.errstate(over="ignore"):
        return ConditionedSignal(
            voltage_V=x * scale,
            noise_rms_V=float(fit.noise * scale),
            hum_amplitude_V=float(fit.hum_amplitudes[0] * scale) if fit.hum_amplitudes else 0.0,
            hum_harmonic_amplitudes_V=tuple(a * scale for a in fit.hum_amplitudes),
            tau_s=float(tau),
            tau_source=source,
            undershoot_V=float(undershoot * scale),
            undershoot_se_V=float(fit.step_se * scale) if fit.has_step else math.nan,
            offset_V=float(coef["offset_V"]),
            baseline_V=fit.baseline * scale,
            baseline_coefficients=coef,
            contact=contact,
            n_iterations=int(n_iter),
            warnings=tuple(messages),
        )
