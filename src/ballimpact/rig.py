"""The session's rig, identified once from all its impacts: plate resonance, amplifier, mains, noise and kCAL."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .model import CLOTH_DISPLACEMENT_M
from .signal.noise import robust_noise

__all__ = [
    "RING_GAP_S", "RING_GAP_FRACTION", "RING_WINDOW_S", "RING_MIN_SAMPLES", "RING_POLY_DEGREE", "RING_MIN_HZ",
    "RING_MAX_FRACTION", "DAMPING_BOUNDS", "UNDAMPED_FACTOR", "DETECT_Z", "MIN_IMPACTS", "COVERAGE",
    "STATED_DISAGREE_Z",
    "RIG_QUANTITIES", "RigWarning", "RingingSegment", "PlateFit", "RigEstimate", "Rig",
    "ringing_segments", "fit_free_ringing", "pooled_ringing", "ringing_response", "pooled_time_constant",
    "pooled_median", "identify_rig",
]

RING_GAP_S = 0.1e-3  # the free ringing is read from this long after the contact's end ... [s]
RING_GAP_FRACTION = 0.03  # ... or this fraction of TC, the longer (an end found early leaves force in it) [-]
RING_WINDOW_S = 3.0e-3  # ... over this long, or to the record's end [s]
RING_MIN_SAMPLES = 24  # fewest samples of a segment [samples]
RING_POLY_DEGREE = 3  # the baseline under the ringing (undershoot, drift, slow hum): a polynomial of this degree [-]
RING_MIN_HZ = 500.0  # resonances looked for from this frequency ... [Hz]
RING_MAX_FRACTION = 0.45  # ... to this fraction of the sample rate (or the stated bandwidth, the lower) [-]
DAMPING_BOUNDS = (1.0e-3, 0.7)  # damping ratios fitted within these [-]
UNDAMPED_FACTOR = 2.0  # a damping ratio within this factor of its lower bound: a line that does not decay [-]
DETECT_Z = 8.0  # the pooled ringing's chi-square gain stands this many of its deviations above chance: a plate [-]
MIN_IMPACTS = 5  # fewer impacts with a free ringing: the session is too small to identify its plate [-]
COVERAGE = 2.0  # intervals are the estimate +- this many standard uncertainties (about 95 %) [-]
STATED_DISAGREE_Z = 3.0  # a stated value this many standard uncertainties off the session's own: a warning [-]

#: The rig's quantities, in the archive's order: name -> (unit, meaning).
RIG_QUANTITIES = {
    "plate_resonance_hz": ("Hz", "the plate's first resonance"),
    "plate_damping_ratio": ("1", "its damping ratio"),
    "time_constant_s": ("s", "the charge amplifier's time constant"),
    "mains_hz": ("Hz", "the mains frequency whose hum was removed"),
    "hum_amplitude_V": ("V", "the hum's amplitude, median over the impacts"),
    "noise_rms_V": ("V", "the trace's white noise, median over the impacts"),
    "kcal_N_per_V": ("N/V", "the typical calibration factor (median over the ok impacts)"),
    "kcal_spread": ("1", "kCAL's robust relative spread between impacts"),
}


class RigWarning(UserWarning):
    """A session's traces disagree with what its session.yaml states about the rig."""


@dataclass(frozen=True)
class RingingSegment:
    """The sensed signal after one contact's end: where the plate rings freely."""

    impact_id: str
    time_s: np.ndarray  #: from the segment's first sample [s]
    voltage_V: np.ndarray  #: the raw trace there, polarity applied [V]
    noise_rms_V: float  #: the trace's white noise [V]
    peak_V: float  #: the contact's largest sample [V]


class PlateFit(NamedTuple):
    """A plate resonance fitted to the pooled free ringing (:func:`fit_free_ringing`)."""

    frequency_hz: float  #: undamped natural frequency fn [Hz]
    damping_ratio: float  #: zeta [-]
    frequency_u_hz: float  #: standard uncertainty of fn [Hz]
    damping_u: float  #: standard uncertainty of zeta [-]
    detection_z: float  #: the ringing's chi-square gain over chance, in its standard deviations [-]
    n_impacts: int  #: segments fitted [-]
    amplitude_fraction: float  #: the ringing at each segment's start over its contact's peak, median [-]
    amplitudes: np.ndarray  #: (cos, sin) amplitude of each segment [V], shape (n, 2)
    impact_ids: tuple  #: the impact of each segment
    result: object  #: scipy.optimize.OptimizeResult of the pooled fit

    @property
    def detected(self) -> bool:
        """Whether the ringing stands DETECT_Z deviations above chance and decays: a damping ratio off the fit's
        lower bound, its interval clear of zero (a line that may not decay after the contact is interference, or
        the force's own tail, not the plate's free ringing)."""
        return bool(self.detection_z > DETECT_Z and self.damping_ratio > UNDAMPED_FACTOR * DAMPING_BOUNDS[0]
                    and self.damping_ratio - COVERAGE * self.damping_u > 0)


@dataclass(frozen=True)
class RigEstimate:
    """One quantity of the rig: value, 95 % interval, and where it came from."""

    value: float
    low: float = math.nan
    high: float = math.nan
    source: str = "none"  #: "stated" (session.yaml), "identified" (the session's traces) or "none"
    n_impacts: int = 0  #: impacts it rests on [-]
    note: str = ""


@dataclass(frozen=True)
class Rig:
    """What one session's impacts say of the rig that recorded them (:func:`identify_rig`)."""

    estimates: dict  #: name of RIG_QUANTITIES -> RigEstimate
    plate_fit: PlateFit | None = None
    warnings: tuple = field(default=())

    def __getitem__(self, name: str) -> RigEstimate:
        if name not in self.estimates:
            raise KeyError(f"unknown rig quantity {name!r}; valid names: {', '.join(RIG_QUANTITIES)}")
        return self.estimates[name]


def ringing_segments(impact_ids, raw_time_s, raw_voltage_V, contact_time_ms, noise_rms_V, use, *,
                     vout_m_s=None) -> list:
    """The free ringing after each contact: the raw trace from a gap after the end, RING_WINDOW_S long.

    The gap is RING_GAP_S, or RING_GAP_FRACTION of TC, or with the rebound speed the time the ball takes to leave
    the cloth's 2 mm (:data:`ballimpact.model.CLOTH_DISPLACEMENT_M`), whose light load an end read in the noise
    may have left out: the longest.

    Parameters
    ----------
    impact_ids : sequence of str
        Impact ids.
    raw_time_s, raw_voltage_V : sequence of array_like
        Each impact's whole trace: time from its contact's start [s] and voltage, polarity applied [V] (NaN padded).
    contact_time_ms : array_like
        Each contact's TC [ms].
    noise_rms_V : array_like
        Each trace's white noise [V].
    use : array_like of bool
        Impacts to read (one contact, found, not a fault).
    vout_m_s : array_like, optional
        Each rebound speed [m/s].

    Returns
    -------
    list of RingingSegment
        One per impact used whose record holds RING_MIN_SAMPLES samples after the gap.
    """
    out = []
    for i, impact_id in enumerate(impact_ids):
        tc, sigma = float(contact_time_ms[i]) * 1e-3, float(noise_rms_V[i])
        if not (use[i] and math.isfinite(tc) and tc > 0 and math.isfinite(sigma) and sigma > 0):
            continue
        t, v = np.asarray(raw_time_s[i], dtype=float), np.asarray(raw_voltage_V[i], dtype=float)
        good = np.isfinite(t) & np.isfinite(v)
        t, v = t[good], v[good]
        vout = float(vout_m_s[i]) if vout_m_s is not None else math.nan
        cloth = CLOTH_DISPLACEMENT_M / vout if math.isfinite(vout) and vout > 0 else 0.0
        start = tc + max(RING_GAP_S, RING_GAP_FRACTION * tc, cloth)
        inside = (t >= start) & (t < start + RING_WINDOW_S)
        contact = (t >= 0.0) & (t <= tc)
        if inside.sum() < RING_MIN_SAMPLES or not contact.any():
            continue
        ts = t[inside]
        out.append(RingingSegment(str(impact_id), ts - ts[0], v[inside], sigma, float(np.max(v[contact]))))
    return out


class _Pooled:
    """The segments stacked, each less its baseline's columns (variable projection of the linear parameters)."""

    def __init__(self, segments, mains_hz):
        n = max(s.time_s.size for s in segments)
        self.t = np.zeros((len(segments), n))
        self.mask = np.zeros((len(segments), n), dtype=bool)
        y = np.zeros((len(segments), n))
        q = []
        for i, s in enumerate(segments):
            k = s.time_s.size
            self.t[i, :k], self.mask[i, :k], y[i, :k] = s.time_s, True, s.voltage_V / s.noise_rms_V
            q.append(_baseline_basis(s.time_s, mains_hz, n))
        m = max(b.shape[1] for b in q)
        self.q = np.stack([np.pad(b, ((0, 0), (0, m - b.shape[1]))) for b in q])  # (segments, n, m), orthonormal
        self.y = self._project(y)
        self.weight = np.array([1.0 / s.noise_rms_V for s in segments])

    def _project(self, a):
        """``a`` (segments, n[, k]) less its projection on each segment's baseline columns."""
        if a.ndim == 2:
            return (a - np.einsum("snm,sm->sn", self.q, np.einsum("snm,sn->sm", self.q, a))) * self.mask
        return (a - np.einsum("snm,smk->snk", self.q, np.einsum("snm,snk->smk", self.q, a))) * self.mask[..., None]

    def columns(self, fn: float, zeta: float):
        """The ringing's two columns (decaying cosine and sine) per segment, scaled and projected."""
        wn = 2.0 * math.pi * fn
        wd = wn * math.sqrt(max(1.0 - zeta * zeta, 1e-12))
        envelope = np.exp(-zeta * wn * self.t)
        r = np.stack([envelope * np.cos(wd * self.t), envelope * np.sin(wd * self.t)], axis=-1)
        return self._project(r * self.weight[:, None, None])

    def solve(self, fn: float, zeta: float):
        """(residuals (segments, n), amplitudes (segments, 2) [V]) of the ringing fitted at (fn, zeta)."""
        r = self.columns(fn, zeta)
        a = np.einsum("snk,snl->skl", r, r) + 1e-12 * np.eye(2)
        b = np.einsum("snk,sn->sk", r, self.y)
        c = np.linalg.solve(a, b[..., None])[..., 0]
        return self.y - np.einsum("snk,sk->sn", r, c), c


def _baseline_basis(t: np.ndarray, mains_hz: float | None, n: int) -> np.ndarray:
    """Orthonormal columns of a segment's baseline: a polynomial, and the mains harmonics it cannot follow."""
    span = max(float(t[-1]), 1e-9)
    cols = [(t / span) ** k for k in range(RING_POLY_DEGREE + 1)]
    if mains_hz and mains_hz > 0:
        for h in range(1, 6):  # a harmonic of a quarter of a cycle or more over the segment bends beyond the cubic
            if h * mains_hz * span >= 0.25:
                cols += [np.cos(2 * math.pi * h * mains_hz * t), np.sin(2 * math.pi * h * mains_hz * t)]
    q, _ = np.linalg.qr(np.column_stack(cols))
    return np.pad(q, ((0, n - t.size), (0, 0)))


def _spectral_start(pooled: _Pooled, fs: float, f_lo: float, f_hi: float) -> float:
    """The frequency of the largest line of the segments' summed periodograms, within [f_lo, f_hi] [Hz]."""
    n_fft = int(2 ** math.ceil(math.log2(max(8 * pooled.t.shape[1], 256))))
    power = np.sum(np.abs(np.fft.rfft(pooled.y, n=n_fft, axis=1)) ** 2, axis=0)
    freqs = np.fft.rfftfreq(n_fft, 1.0 / fs)
    band = (freqs >= f_lo) & (freqs <= f_hi)
    return float(freqs[band][np.argmax(power[band])]) if band.any() else math.sqrt(f_lo * f_hi)


def fit_free_ringing(segments, sample_rate_hz: float, *, mains_hz: float | None = None,
                     max_frequency_hz: float | None = None) -> PlateFit:
    """Fit one damped resonance to the free ringing after every contact of a session.

    After the ball leaves, the force is zero and a second-order plate (raw-format v1.2: resonance fn, damping
    ratio zeta) rings freely: ``e^(-zeta wn t) (a cos(wd t) + b sin(wd t))``, ``wn = 2 pi fn``,
    ``wd = wn sqrt(1 - zeta^2)``, on a slow baseline (the amplifier's undershoot, drift, hum: a cubic and the mains
    harmonics a cubic cannot follow). One (fn, zeta) serves every segment; each has its own (a, b) and baseline,
    projected out (variable projection), so the fit has two nonlinear parameters whatever the number of impacts.
    Residuals are weighted by each trace's noise. The start is the largest line of the summed periodograms.

    The standard uncertainties are the larger of the fit's (its Jacobian, scaled by the reduced chi-square) and
    the jackknife's over the impacts, which also holds what differs between impacts beyond the noise.

    Parameters
    ----------
    segments : sequence of RingingSegment
        The free ringing of each impact (:func:`ringing_segments`), at least 2.
    sample_rate_hz : float
        Sample rate [Hz].
    mains_hz : float, optional
        Mains frequency [Hz] whose harmonics join the baseline.
    max_frequency_hz : float, optional
        Highest resonance looked for [Hz] (default and at most RING_MAX_FRACTION of the sample rate).

    Returns
    -------
    PlateFit
        The resonance, its uncertainties and detection statistic; ``detected`` says whether there is one.

    Raises
    ------
    ValueError
        Fewer than 2 segments, or a sample rate that is not positive.
    RuntimeError
        The optimiser failed.
    """
    from scipy.optimize import least_squares

    fs = float(sample_rate_hz)
    if not (math.isfinite(fs) and fs > 0):
        raise ValueError(f"sample_rate_hz must be positive, got {sample_rate_hz!r}")
    if len(segments) < 2:
        raise ValueError(f"fit_free_ringing needs at least 2 segments, got {len(segments)}")
    f_hi = RING_MAX_FRACTION * fs if max_frequency_hz is None else min(RING_MAX_FRACTION * fs, max_frequency_hz)
    f_lo = min(RING_MIN_HZ, 0.5 * f_hi)
    pooled = _Pooled(list(segments), mains_hz)
    bounds = ([math.log(f_lo), math.log(DAMPING_BOUNDS[0])], [math.log(f_hi), math.log(DAMPING_BOUNDS[1])])

    def residuals(p, rows=slice(None)):
        r, _ = pooled.solve(math.exp(p[0]), math.exp(p[1]))
        return r[rows][pooled.mask[rows]]

    f0 = _spectral_start(pooled, fs, f_lo, f_hi)
    starts = [np.array([math.log(f0), math.log(z)]) for z in (0.01, 0.03, 0.1, 0.3)]
    p0 = min(starts, key=lambda p: float(np.sum(residuals(p) ** 2)))
    res = least_squares(residuals, p0, bounds=bounds, x_scale=[0.05, 0.5], method="trf")
    if not res.success and res.status <= 0:
        raise RuntimeError(f"plate resonance fit to the free ringing failed: {res.message}")
    chi0, chi1 = float(np.sum(pooled.y ** 2)), float(np.sum(res.fun ** 2))
    k = 2 * len(segments) + 2
    z = (chi0 - chi1 - k) / math.sqrt(2 * k)
    u_log = _jacobian_uncertainties(res, pooled.mask.sum())
    if z > DETECT_Z:  # the jackknife's refits only where there is a resonance to report
        u_log = np.maximum(u_log, _jackknife_uncertainties(residuals, res.x, bounds, len(segments)))
    fn, zeta = math.exp(res.x[0]), math.exp(res.x[1])
    _, amps = pooled.solve(fn, zeta)  # [V]: the columns carry the weight the scaled samples do
    fraction = float(np.median([math.hypot(*a) / s.peak_V for a, s in zip(amps, segments)]))
    return PlateFit(fn, zeta, fn * float(u_log[0]), zeta * float(u_log[1]), z,
                    len(segments), fraction, amps, tuple(s.impact_id for s in segments), res)


def _jacobian_uncertainties(res, n_samples: int) -> np.ndarray:
    """Standard uncertainties of the fitted log-parameters from the Jacobian and the reduced chi-square."""
    j = res.jac
    dof = max(n_samples - j.shape[1], 1)
    s2 = max(float(np.sum(res.fun ** 2)) / dof, 1.0)
    try:
        cov = np.linalg.inv(j.T @ j) * s2
    except np.linalg.LinAlgError:
        return np.full(2, np.inf)
    return np.sqrt(np.clip(np.diag(cov), 0.0, None))


def _jackknife_uncertainties(residuals, x, bounds, n: int) -> np.ndarray:
    """Jackknife standard uncertainties of the fitted log-parameters over the segments (each left out once)."""
    from scipy.optimize import least_squares

    keep = np.ones(n, dtype=bool)
    xs = []
    for i in range(n):
        keep[i] = False
        r = least_squares(lambda p: residuals(p, keep), x, bounds=bounds, x_scale=[0.05, 0.5], max_nfev=30)
        xs.append(r.x)
        keep[i] = True
    xs = np.asarray(xs)
    return np.sqrt((n - 1) / n * np.sum((xs - xs.mean(axis=0)) ** 2, axis=0))


def pooled_ringing(segments, fit: PlateFit, *, mains_hz: float | None = None) -> list:
    """Each segment's free ringing with its baseline removed, beside the fitted ringing, for a figure.

    Parameters
    ----------
    segments : sequence of RingingSegment
        The segments :func:`fit_free_ringing` was given.
    fit : PlateFit
        Its result.
    mains_hz : float, optional
        As given to the fit [Hz].

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        Per segment: time from its start [s], the observed ringing and the fitted one [V].
    """
    out = []
    for s, amps in zip(segments, fit.amplitudes):
        q = _baseline_basis(s.time_s, mains_hz, s.time_s.size)
        observed = s.voltage_V - q @ (q.T @ s.voltage_V)
        model = ringing_response(s.time_s, fit.frequency_hz, fit.damping_ratio, amps)
        out.append((s.time_s, observed, model - q @ (q.T @ model)))
    return out


def ringing_response(time_s, frequency_hz: float, damping_ratio: float, amplitudes) -> np.ndarray:
    """The free ringing ``e^(-zeta wn t) (a cos(wd t) + b sin(wd t))`` of :func:`fit_free_ringing` [V].

    Parameters
    ----------
    time_s : array_like
        Time from the segment's start [s].
    frequency_hz, damping_ratio : float
        fn [Hz] and zeta [-].
    amplitudes : tuple of float
        (a, b) [V].
    """
    t = np.asarray(time_s, dtype=float)
    wn = 2.0 * math.pi * frequency_hz
    wd = wn * math.sqrt(max(1.0 - damping_ratio ** 2, 1e-12))
    a, b = amplitudes
    return np.exp(-damping_ratio * wn * t) * (a * np.cos(wd * t) + b * np.sin(wd * t))


def pooled_time_constant(tau_s, tau_u_s) -> RigEstimate:
    """The session's amplifier time constant from each impact's estimate: an inverse-variance mean of 1/tau.

    The decay rate kappa = 1/tau enters the undershoot linearly, so its estimates are averaged; the interval is
    widened by the Birge ratio (the scatter beyond the standard errors) when that exceeds 1.

    Parameters
    ----------
    tau_s, tau_u_s : array_like
        Each impact's estimated time constant and its standard error [s] (NaN: none).

    Returns
    -------
    RigEstimate
        source "identified", or "none" with fewer than MIN_IMPACTS estimates.
    """
    tau, u = np.asarray(tau_s, dtype=float), np.asarray(tau_u_s, dtype=float)
    good = np.isfinite(tau) & (tau > 0) & np.isfinite(u) & (u > 0)
    if good.sum() < MIN_IMPACTS:
        return RigEstimate(math.nan, note=f"{int(good.sum())} impacts with an estimated time constant: too few")
    kappa, ku = 1.0 / tau[good], u[good] / tau[good] ** 2
    w = 1.0 / ku ** 2
    mean = float(np.sum(w * kappa) / np.sum(w))
    se = math.sqrt(1.0 / float(np.sum(w)))
    birge = math.sqrt(float(np.sum(w * (kappa - mean) ** 2)) / max(int(good.sum()) - 1, 1))
    se *= max(birge, 1.0)
    lo_k, hi_k = mean - COVERAGE * se, mean + COVERAGE * se
    return RigEstimate(1.0 / mean, 1.0 / hi_k, 1.0 / lo_k if lo_k > 0 else math.inf, "identified", int(good.sum()))


def pooled_median(values, *, relative_spread: bool = False) -> RigEstimate:
    """The median of per-impact values with the interval of a median (1.2533 sigma / sqrt(n), sigma from the MAD).

    With ``relative_spread`` the estimate is the robust relative spread (1.4826 MAD / median) instead.
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < MIN_IMPACTS:
        return RigEstimate(math.nan, note=f"{x.size} impacts: too few")
    med = float(np.median(x))
    sigma = robust_noise(x)
    if relative_spread:
        return RigEstimate(sigma / med if med else math.nan, source="identified", n_impacts=int(x.size))
    half = COVERAGE * 1.2533 * sigma / math.sqrt(x.size)
    return RigEstimate(med, med - half, med + half, "identified", int(x.size))


def _stated_check(name: str, stated: float, estimate: RigEstimate, unit: str, scale: float = 1.0) -> str:
    """A warning when the session's own estimate puts a stated value more than STATED_DISAGREE_Z of its standard
    uncertainties away (its interval holds COVERAGE of them), else ""."""
    if estimate.source != "identified" or not all(map(math.isfinite, (estimate.low, estimate.high))):
        return ""
    u = (estimate.high - estimate.low) / (2.0 * COVERAGE)
    if not u > 0 or abs(stated - estimate.value) <= STATED_DISAGREE_Z * u:
        return ""
    return (f"session.yaml states {name} = {stated * scale:.4g} {unit}, but the session's {estimate.n_impacts} "
            f"impacts give {estimate.value * scale:.4g} {unit} (95 % interval {estimate.low * scale:.4g}-"
            f"{estimate.high * scale:.4g}): the stated value is used; check the tap test or the amplifier's setting")


def _plate_estimates(segments, fs, stated, mains_hz, bandwidth_hz, warn):
    """(resonance, damping ratio, fit) of the plate: stated, identified from the pooled free ringing, or none."""
    fit = None
    if len(segments) >= MIN_IMPACTS:
        try:
            fit = fit_free_ringing(segments, fs, mains_hz=mains_hz, max_frequency_hz=bandwidth_hz)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            warn(f"plate resonance not identified: {exc}")
    if fit is not None and fit.detected:
        fn = RigEstimate(fit.frequency_hz, fit.frequency_hz - COVERAGE * fit.frequency_u_hz,
                         fit.frequency_hz + COVERAGE * fit.frequency_u_hz, "identified", fit.n_impacts)
        zeta = RigEstimate(fit.damping_ratio, max(fit.damping_ratio - COVERAGE * fit.damping_u, 0.0),
                           fit.damping_ratio + COVERAGE * fit.damping_u, "identified", fit.n_impacts)
    elif fit is not None and fit.detection_z > DETECT_Z:
        note = (f"a line at {fit.frequency_hz / 1e3:.3g} kHz after {fit.n_impacts} contacts that may not decay "
                f"(damping ratio {fit.damping_ratio:.2g} +- {COVERAGE * fit.damping_u:.2g}): interference or the "
                "force's own tail, not a plate's free ringing")
        fn = zeta = RigEstimate(math.nan, n_impacts=fit.n_impacts, note=note)
    elif fit is not None:
        note = (f"no free ringing above the noise after {fit.n_impacts} contacts (z = {fit.detection_z:.1f}, "
                f"{DETECT_Z:g} needed): an ideal plate, or one resonating above the band")
        fn = zeta = RigEstimate(math.nan, n_impacts=fit.n_impacts, note=note)
    else:
        note = (f"{len(segments)} impacts with a free ringing after the contact: too few to identify the plate "
                f"(at least {MIN_IMPACTS}); each trace is judged alone")
        fn = zeta = RigEstimate(math.nan, n_impacts=len(segments), note=note)
    if stated is None:
        return fn, zeta, fit
    for name, value, est, unit, scale in (("plate.resonance_hz", stated[0], fn, "kHz", 1e-3),
                                          ("plate.damping_ratio", stated[1], zeta, "", 1.0)):
        msg = _stated_check(name, value, est, unit, scale)
        if msg:
            warn(msg)
    return (RigEstimate(stated[0], stated[0], stated[0], "stated", fn.n_impacts, _identified_note(fn, 1e-3, "kHz")),
            RigEstimate(stated[1], stated[1], stated[1], "stated", zeta.n_impacts, _identified_note(zeta, 1.0, "")),
            fit)


def _identified_note(est: RigEstimate, scale: float, unit: str) -> str:
    """Beside a stated value: what the session's own traces gave."""
    if est.source != "identified":
        return ""
    return (f"the session's traces give {est.value * scale:.4g} {unit} (95 % interval {est.low * scale:.4g}-"
            f"{est.high * scale:.4g})").replace("  ", " ")


def _mains_estimate(stated, mains_hz, sources) -> RigEstimate:
    """The mains frequency: stated, or the one most impacts' hum was found at (the interval: the lowest and highest
    found)."""
    if stated:
        return RigEstimate(float(stated), float(stated), float(stated), "stated")
    f = np.asarray(mains_hz, dtype=float)
    found = np.array([s == "detected" for s in sources]) & np.isfinite(f) & (f > 0)
    if not found.any():
        return RigEstimate(0.0, source="none", note="no hum found in any trace")
    values, counts = np.unique(f[found], return_counts=True)
    best = float(values[np.argmax(counts)])
    note = ", ".join(f"{v:g} Hz in {c}" for v, c in zip(values, counts))
    return RigEstimate(best, float(values[0]), float(values[-1]), "identified", int(found.sum()),
                       f"hum found at {note} of the impacts")


def identify_rig(impacts: dict, sample_rate_hz: float, *, stated_plate=None, stated_time_constant_s=None,
                 stated_mains_hz=None, bandwidth_hz=None) -> Rig:
    """Identify the session's rig once, from all its impacts.

    One plate, one amplifier and one mains supply serve every impact of a session; the evidence of each is
    pooled over the impacts: the plate's free ringing after every contact (:func:`fit_free_ringing`), the time
    constant each trace's undershoot gave (:func:`pooled_time_constant`), the hum and noise of every trace and the
    kCAL of every ok impact (:func:`pooled_median`). A value the session.yaml states is used as stated; where the
    traces disagree with it a :class:`RigWarning` says so.

    Parameters
    ----------
    impacts : dict
        Per impact, sequences of equal length: ``impact_id``, ``raw_time_s`` and ``raw_voltage_V`` (each a 1-D
        array [s], [V], polarity applied), ``contact_time_ms`` [ms], ``noise_rms_V`` [V], ``hum_amplitude_V``
        [V], ``mains_hz`` [Hz], ``mains_source``, ``tau_s``, ``tau_se_s`` [s], ``tau_source``, ``kcal_N_per_V``
        [N/V], ``sample_rate_hz`` [Hz], ``usable`` (bool: one contact found, no fault) and ``kcal_ok`` (bool);
        optionally ``vout_m_s`` [m/s] (:func:`ringing_segments`' gap).
    sample_rate_hz : float
        The session's sample rate [Hz].
    stated_plate : tuple of float, optional
        session.yaml ``plate.resonance_hz`` [Hz] and ``plate.damping_ratio`` [-].
    stated_time_constant_s, stated_mains_hz : float, optional
        session.yaml ``plate.time_constant_s`` [s] and ``daq.mains_hz`` [Hz].
    bandwidth_hz : float, optional
        session.yaml ``daq.bandwidth_hz`` [Hz]: no resonance is looked for above it.

    Returns
    -------
    Rig
        Each quantity of RIG_QUANTITIES with its interval and source, the plate's fit, and the warnings.
    """
    found: list[str] = []

    def warn(msg: str) -> None:
        found.append(msg)
        warnings.warn(msg, RigWarning, stacklevel=3)

    fs = float(sample_rate_hz)
    same_rate = np.isclose(np.asarray(impacts["sample_rate_hz"], dtype=float), fs, rtol=1e-6)
    use = np.asarray(impacts["usable"], dtype=bool) & same_rate
    segments = ringing_segments(impacts["impact_id"], impacts["raw_time_s"], impacts["raw_voltage_V"],
                                impacts["contact_time_ms"], impacts["noise_rms_V"], use,
                                vout_m_s=impacts.get("vout_m_s"))
    mains = _mains_estimate(stated_mains_hz, impacts["mains_hz"], impacts["mains_source"])
    fn, zeta, fit = _plate_estimates(segments, fs, stated_plate, mains.value or None, bandwidth_hz, warn)
    estimated = np.array([s == "estimated" for s in impacts["tau_source"]]) & use
    tau = pooled_time_constant(np.where(estimated, impacts["tau_s"], np.nan), impacts["tau_se_s"])
    if stated_time_constant_s is not None:
        msg = _stated_check("plate.time_constant_s", float(stated_time_constant_s), tau, "s")
        if msg:
            warn(msg)
        tau = RigEstimate(float(stated_time_constant_s), float(stated_time_constant_s),
                          float(stated_time_constant_s), "stated", tau.n_impacts, _identified_note(tau, 1.0, "s"))
    kcal_ok = np.asarray(impacts["kcal_ok"], dtype=bool) & use
    kcal = np.where(kcal_ok, np.asarray(impacts["kcal_N_per_V"], dtype=float), np.nan)
    estimates = {
        "plate_resonance_hz": fn, "plate_damping_ratio": zeta, "time_constant_s": tau, "mains_hz": mains,
        "hum_amplitude_V": pooled_median(np.where(use, impacts["hum_amplitude_V"], np.nan)),
        "noise_rms_V": pooled_median(np.where(use, impacts["noise_rms_V"], np.nan)),
        "kcal_N_per_V": pooled_median(kcal),
        "kcal_spread": pooled_median(kcal, relative_spread=True),
    }
    return Rig(estimates, fit, tuple(found))
