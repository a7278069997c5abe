"""The session's checks: each impact's kCAL, amplifier time constant and peak against the session's rig."""

from __future__ import annotations

import math

import numpy as np

from .checks import QUANTITIES
from .problems import Problem, ProblemKind
from .signal.noise import robust_noise
from .verdicts import judge_quantities

__all__ = [
    "KCAL_MAX_ROBUST_Z", "KCAL_MAX_RELATIVE", "TAU_MAX_Z", "TAU_MAX_IMPULSE", "VERDICT_COLUMNS",
    "flag_calibration_outliers", "flag_time_constant_outliers", "apply_session_flags",
    "calibration_outlier_columns", "time_constant_outlier_columns", "apply_calibration_check",
    "apply_time_constant_check", "PLATE_PEAK_NOISE_SIGMA", "plate_overshoot", "flag_plate_overshoots",
    "plate_overshoot_columns",
]

#: Session-level kCAL check: a finding when both the robust z-score and the relative
#: deviation from the session median exceed these.
KCAL_MAX_ROBUST_Z = 5.0
KCAL_MAX_RELATIVE = 0.10
#: Session time-constant check: an impact whose amplifier time constant was estimated from its trace is a finding
#: when its kappa = 1 / tau differs from the session's median kappa by more than this many joint standard
#: errors ... [-]
TAU_MAX_Z = 5.0
#: ... and by enough to move its impulse, and kCAL, by more than this fraction (kappa TC / 2) [-]
TAU_MAX_IMPULSE = 0.003
#: Session plate check of the peak: the bound of the plate's overshoot at the largest sample is raised by this many
#: standard deviations of its estimate from the noise [-]
PLATE_PEAK_NOISE_SIGMA = 2.0


def flag_calibration_outliers(kcal_N_per_V, ok, *, max_robust_z=KCAL_MAX_ROBUST_Z, max_relative=KCAL_MAX_RELATIVE):
    """Impacts whose kCAL is far from the session's typical value for the plate.

    kCAL varies a little between impacts (section 2 of Goodwill & Haake 2004),
    so a value far from the rest points at a bad gate time or trace. Typical =
    median over the ``ok`` impacts; spread = 1.4826 x median absolute deviation.
    An impact is flagged when its robust z-score exceeds ``max_robust_z`` AND it
    lies more than ``max_relative`` from the median.

    Parameters
    ----------
    kcal_N_per_V : array_like
        kCAL of every impact [N/V] (NaN where none).
    ok : array_like of bool
        Impacts to take the typical value from.
    max_robust_z : float
        Largest robust z-score accepted [-].
    max_relative : float
        Largest relative deviation accepted [-].

    Returns
    -------
    reasons : list of str
        Per impact, "" or the exclusion reason.
    median : float
        Session median kCAL [N/V] (NaN with fewer than 3 ok impacts).
    spread : float
        Robust standard deviation [N/V].
    """
    k = np.asarray(kcal_N_per_V, dtype=float)
    ok = np.asarray(ok, dtype=bool) & np.isfinite(k)
    reasons = [""] * k.size
    if ok.sum() < 3:
        return reasons, math.nan, math.nan
    med = float(np.median(k[ok]))
    spread = robust_noise(k[ok])
    for i in np.flatnonzero(ok):
        rel = abs(k[i] - med) / med
        z = abs(k[i] - med) / spread if spread > 0 else math.inf
        if z > max_robust_z and rel > max_relative:
            reasons[i] = (
                f"calibration factor {k[i]:.1f} N/V is {100 * rel:.0f} % from the session median "
                f"{med:.1f} N/V (robust z = {z:.1f})"
            )
    return reasons, med, spread


#: The per-impact columns a session check's finding updates (:func:`apply_session_flags`).
VERDICT_COLUMNS = ("status", "reason", "reason_code", "withheld_note", "peak_note", "contact_time_status",
                   "kcal_status", "peak_status", "cor_status")


def apply_session_flags(columns: dict, flags: list[str], kind: ProblemKind) -> dict:
    """Per-impact verdict columns with a session check's findings applied, as :meth:`ImpactResult.find` would.

    Each flagged impact withholds what the finding withholds (:func:`ballimpact.verdicts.judge_quantities`: the
    quantities the check of ``kind`` can bias); it is excluded, its flag appended to ``reason``, when that
    withholds TC or COR, and otherwise keeps ``ok`` with the flag in ``withheld_note`` (and ``peak_note`` for the
    peak).

    Parameters
    ----------
    columns : dict
        :data:`VERDICT_COLUMNS` -> one value per impact (a missing column is taken as empty or ``ok``).
    flags : list of str
        Per impact, "" or the finding's message.
    kind : ProblemKind
        The session check's kind.

    Returns
    -------
    dict
        New lists, one per column of :data:`VERDICT_COLUMNS`.
    """
    n = len(flags)
    out = {c: [str(v) for v in columns.get(c, [""] * n)] for c in VERDICT_COLUMNS}
    for c in VERDICT_COLUMNS:
        if c.endswith("_status"):
            out[c] = [v or "ok" for v in out[c]]
    code = kind.value
    for k, flag in enumerate(flags):
        if not flag:
            continue
        v = judge_quantities([Problem(kind, flag)], dict.fromkeys(QUANTITIES, 0.0))  # what the finding withholds
        withheld = [q for q in QUANTITIES if v.status[q] != "ok"]
        for q in withheld:
            out[f"{q}_status"][k] = "withheld"
        out["reason_code"][k] = ";".join(dict.fromkeys([c for c in out["reason_code"][k].split(";") if c] + [code]))
        if v.excluded or out["contact_time_status"][k] != "ok" or out["cor_status"][k] != "ok":
            out["status"][k] = "excluded"
            out["reason"][k] = f"{out['reason'][k]}; {flag}" if out["reason"][k] else flag
            out["withheld_note"][k] = out["peak_note"][k] = ""
        else:
            note = "; ".join(f"{q}: {v.why[q]}" for q in withheld)
            out["withheld_note"][k] = f"{out['withheld_note'][k]}; {note}" if out["withheld_note"][k] else note
            out["peak_note"][k] = v.why["peak"] if "peak" in withheld else out["peak_note"][k]
    return out


def _find_flagged_results(results: list, flags: list[str], kind: ProblemKind) -> None:
    """Record, in place, a finding of ``kind`` with the flag's message on every result whose flag is not empty."""
    for r, flag in zip(results, flags):
        if flag:
            r.find(Problem(kind, flag))


def calibration_outlier_columns(columns: dict, kcal_N_per_V):
    """The session kCAL check on table columns (:func:`apply_session_flags` with KCAL_OUTLIER).

    Parameters
    ----------
    columns : dict
        :data:`VERDICT_COLUMNS` -> one value per impact.
    kcal_N_per_V : array_like
        Per impact kCAL [N/V].

    Returns
    -------
    columns : dict
        With the outliers of :func:`flag_calibration_outliers` applied.
    median, spread : float
        Session median and robust standard deviation of kCAL [N/V].
    """
    ok = [s == "ok" and k == "ok" for s, k in zip(columns["status"], columns.get("kcal_status", columns["status"]))]
    flags, median, spread = flag_calibration_outliers(kcal_N_per_V, ok)
    return apply_session_flags(columns, flags, ProblemKind.KCAL_OUTLIER), median, spread


def flag_time_constant_outliers(tau_s, tau_se_s, contact_time_ms, ok, *, max_z=TAU_MAX_Z,
                                 max_impulse=TAU_MAX_IMPULSE):
    """Impacts whose charge-amplifier time constant, estimated from the trace, is not the session's.

    One charge amplifier serves a session, so every trace decays with the same time
    constant. Where it is estimated (no ``plate.time_constant_s``), something else in
    the baseline can take its place: a step of the level within the contact is, to
    the fit, what the amplifier's undershoot looks like (``bench/step_map.py`` 2:249: a
    step of -2.7 % of the peak took 5.7 s for 0.082 s and kCAL came out 2.8 % low), and
    nothing in the one trace tells them apart. The session's other impacts do. In
    kappa = 1 / tau [1/s]: typical = median over the ``ok`` impacts with an estimate
    (at least 3), its standard error 1.2533 x robust spread / sqrt(n). An ok impact is
    flagged when its kappa is more than ``max_z`` joint standard errors from the
    median AND the difference moves its impulse by more than ``max_impulse``: undoing
    the decay adds kappa times the running integral of the signal, which over a pulse
    symmetric in time adds kappa TC / 2 of the impulse (and of 1 / kCAL).

    Parameters
    ----------
    tau_s : array_like
        Time constant of every impact [s]; NaN where none was estimated (given, not
        corrected, or the impact excluded before).
    tau_se_s : array_like
        Its standard error [s] (NaN where none).
    contact_time_ms : array_like
        Contact time TC [ms].
    ok : array_like of bool
        Impacts to take the typical value from and to judge.
    max_z : float
        Largest accepted difference in joint standard errors [-].
    max_impulse : float
        Largest accepted effect on the impulse [-].

    Returns
    -------
    reasons : list of str
        Per impact, "" or the exclusion reason.
    median_s : float
        Session's typical time constant, 1 / median kappa [s] (NaN with fewer than
        3 estimates).
    """
    if not (max_z > 0 and max_impulse > 0):
        raise ValueError(f"max_z and max_impulse must be positive, got {max_z!r} and {max_impulse!r}")
    tau = np.asarray(tau_s, dtype=float).ravel()
    se = np.asarray(tau_se_s, dtype=float).ravel()
    tc = np.asarray(contact_time_ms, dtype=float).ravel() * 1e-3
    ok = np.asarray(ok, dtype=bool).ravel()
    if not (se.size == tc.size == ok.size == tau.size):
        raise ValueError(f"tau_s, tau_se_s, contact_time_ms and ok must have one value per impact, got "
                         f"{tau.size}, {se.size}, {tc.size} and {ok.size}")
    use = ok & np.isfinite(tau) & (tau > 0) & np.isfinite(se) & (se > 0)
    reasons = [""] * tau.size
    if use.sum() < 3:
        return reasons, math.nan
    kappa = np.where(use, 1.0 / np.where(use, tau, 1.0), np.nan)
    kappa_se = np.where(use, se / np.where(use, tau, 1.0) ** 2, np.nan)  # d(1/tau) = dtau / tau^2
    med = float(np.median(kappa[use]))
    med_se = 1.2533 * robust_noise(kappa[use]) / math.sqrt(use.sum())
    for i in np.flatnonzero(use):
        diff = abs(kappa[i] - med)
        z = diff / math.hypot(kappa_se[i], med_se)
        impulse = diff * tc[i] / 2.0 if np.isfinite(tc[i]) else math.inf
        if z > max_z and impulse > max_impulse:
            typical = 1.0 / med if med > 0 else math.inf
            reasons[i] = (
                f"charge-amplifier time constant {tau[i]:.3g} s estimated, unlike the session's {typical:.3g} s "
                f"({int(use.sum())} impacts; {z:.0f} standard errors): the impulse and kCAL may be off by "
                f"{100 * impulse:.2g} %; a step in the baseline within the contact taken for the decay? (give "
                "plate.time_constant_s)"
            )
    return reasons, (1.0 / med if med > 0 else math.inf)


def time_constant_outlier_columns(columns: dict, tau_s, tau_se_s, tau_source, contact_time_ms):
    """The session time-constant check on table columns (:func:`apply_session_flags` with TIME_CONSTANT_OUTLIER).

    Parameters
    ----------
    columns : dict
        :data:`VERDICT_COLUMNS` -> one value per impact.
    tau_s, tau_se_s : array_like
        Per impact, the amplifier time constant and its standard error [s].
    tau_source : sequence of str
        Per impact, ``estimated``, ``given``, ``none`` or empty: only estimates are judged.
    contact_time_ms : array_like
        Per impact TC [ms].

    Returns
    -------
    columns : dict
        With the outliers of :func:`flag_time_constant_outliers` applied.
    median_s : float
        Session's typical time constant [s] (NaN with fewer than 3 estimates).
    """
    estimated = [str(s) == "estimated" for s in tau_source]
    tau = np.where(estimated, np.asarray(tau_s, dtype=float), np.nan)
    flags, median = flag_time_constant_outliers(tau, tau_se_s, contact_time_ms,
                                                [s == "ok" for s in columns["status"]])
    return apply_session_flags(columns, flags, ProblemKind.TIME_CONSTANT_OUTLIER), median


def apply_time_constant_check(results: list) -> float:
    """Judge, in place, ok impacts whose estimated time constant is not the session's (TIME_CONSTANT_OUTLIER);
    returns it [s]."""
    tau = [r.tau_s if r.tau_source == "estimated" else math.nan for r in results]
    flags, median = flag_time_constant_outliers(tau, [r.tau_se_s for r in results],
                                                [r.contact_time_ms for r in results],
                                                [r.status == "ok" for r in results])
    _find_flagged_results(results, flags, ProblemKind.TIME_CONSTANT_OUTLIER)
    return median


def apply_calibration_check(results: list) -> tuple[float, float]:
    """Withhold, in place, the kCAL (and peak) of impacts whose kCAL is an outlier of the session; returns (median,
    spread) [N/V]."""
    flags, median, spread = flag_calibration_outliers([r.kcal_N_per_V for r in results],
                                                      [r.status == "ok" and r.kcal_status == "ok" for r in results])
    _find_flagged_results(results, flags, ProblemKind.KCAL_OUTLIER)
    return median, spread


def plate_overshoot(voltage_V, fs: float, fn_hz: float, zeta: float, noise_V: float) -> float:
    """How far a plate moves the largest sample of a contact from the force's peak [-, relative to the peak].

    The plate senses the force F through its second-order response, x''/wn^2 + (2 zeta/wn) x' + x = F, so that
    F = x + (2 zeta/wn) x' + x''/wn^2 (wn = 2 pi fn). A damped plate of 8-16 kHz answers the force's jump at first
    contact (section 3.2.4 in Goodwill & Haake 2004) with a lobe that no ringing check sees, up to 25 % above the
    force's peak. The force is undone so at every sample, x' and x'' from parabolas fitted over an eighth of the
    plate's period either side (Savitzky-Golay; at least one sample), and the effect is the largest sample's
    distance from that force's peak, plus PLATE_PEAK_NOISE_SIGMA standard deviations of the undone samples from the
    noise. The fits flatten the undone force's sharp features a little, so that the distance errs high where
    the plate lifted the peak.

    Parameters
    ----------
    voltage_V : array_like
        The contact's conditioned voltage, proportional to the sensed force, at the sample rate [V] (NaN padding
        allowed).
    fs : float
        Sample rate [Hz].
    fn_hz, zeta : float
        The plate's resonance [Hz] and damping ratio [-].
    noise_V : float
        The noise's standard deviation [V].

    Returns
    -------
    float
        The effect [-], at least 0; NaN where the contact has too few samples or an input is not finite.
    """
    from scipy.signal import savgol_coeffs, savgol_filter

    x = np.asarray(voltage_V, dtype=float)
    x = x[np.isfinite(x)]
    h = max(int(round(fs / (8.0 * fn_hz))), 1) if fs > 0 and fn_hz > 0 else 0
    if not (h > 0 and x.size >= 2 * h + 3 and zeta >= 0 and math.isfinite(noise_V)):
        return math.nan
    wn = 2.0 * math.pi * fn_hz
    w = 2 * h + 1
    slope = savgol_filter(x, w, 2, deriv=1, delta=1.0 / fs, mode="interp")
    curvature = savgol_filter(x, w, 2, deriv=2, delta=1.0 / fs, mode="interp")
    force = x + (2.0 * zeta / wn) * slope + curvature / wn ** 2
    top = float(np.max(force))
    if not (top > 0 and np.max(x) > 0):
        return math.nan
    # the undone sample's deviation from the noise: the inverse's weights over the fit's window
    weights = ((2.0 * zeta / wn) * savgol_coeffs(w, 2, deriv=1, delta=1.0 / fs, use="dot")
               + savgol_coeffs(w, 2, deriv=2, delta=1.0 / fs, use="dot") / wn ** 2)
    weights[h] += 1.0
    spread = abs(noise_V) * float(np.sqrt(np.sum(weights ** 2)))
    return (abs(float(np.max(x)) - top) + PLATE_PEAK_NOISE_SIGMA * spread) / top


def flag_plate_overshoots(voltage_V, fs, noise_V, peak_u, peak_is_spike, check, fn_hz: float, zeta: float):
    """Impacts whose peak the session's plate may lift beyond its tolerance (:func:`plate_overshoot`).

    The bound enters the peak's budget as a uniform distribution (as a finding's estimated effect,
    :func:`ballimpact.verdicts.judge_quantities`): an impact is flagged when twice the root sum of squares of its
    peak's standard uncertainty and the bound over sqrt 3 exceeds the peak's tolerance.

    Parameters
    ----------
    voltage_V : sequence of array_like
        Per impact, the contact's conditioned voltage [V].
    fs, noise_V : array_like
        Per impact, the sample rate [Hz] and the noise's standard deviation [V].
    peak_u : array_like
        Per impact, the peak's relative standard uncertainty [-].
    peak_is_spike : array_like of bool
        Per impact, the peak is the pre-buckling spike (its tolerance is the spike's).
    check : array_like of bool
        Per impact, whether to judge it (an ok peak sensed through the plate, not undone).
    fn_hz, zeta : float
        The session's plate: resonance [Hz] (the low end of its interval, the larger bound) and damping ratio [-].

    Returns
    -------
    list of str
        Per impact, "" or the finding's message.
    """
    from .checks import TOLERANCES
    from .verdicts import COVERAGE

    flags = []
    for v, f, n, u, spike, judge in zip(voltage_V, fs, noise_V, peak_u, peak_is_spike, check):
        bound = plate_overshoot(v, float(f), fn_hz, zeta, float(n)) if judge else math.nan
        tol = TOLERANCES["peak_spike" if spike else "peak"]
        u = float(u) if math.isfinite(float(u)) else 0.0
        if not (math.isfinite(bound) and COVERAGE * math.hypot(u, bound / math.sqrt(3.0)) > tol):
            flags.append("")
            continue
        flags.append(f"peak force on plate ringing: the session's plate ({fn_hz / 1e3:.3g} kHz, damping ratio "
                     f"{zeta:.2g}) may lift the largest sample up to {100 * bound:.2g} % above the force's peak "
                     "(its inverse at the sample)")
    return flags


def plate_overshoot_columns(columns: dict, voltage_V, fs, noise_V, peak_u, time_to_peak_ms, plate_undone,
                            fn_hz: float, zeta: float) -> dict:
    """The session plate check of the peak on table columns (:func:`apply_session_flags` with PEAK_ON_RINGING).

    Parameters
    ----------
    columns : dict
        :data:`VERDICT_COLUMNS` -> one value per impact.
    voltage_V : sequence of array_like
        Per impact, the contact's conditioned voltage [V].
    fs, noise_V, peak_u : array_like
        Per impact, the sample rate [Hz], the noise [V] and the peak's relative standard uncertainty [-].
    time_to_peak_ms : array_like
        Per impact, the time from the contact's start to the peak [ms] (before the model's buckling: the spike).
    plate_undone : array_like of bool
        Per impact, whether its own processing undid a plate (its peak then judged there).
    fn_hz, zeta : float
        The session's plate (NaN: none, nothing judged).

    Returns
    -------
    dict
        With the flagged peaks withheld.
    """
    from .model import BUCKLING_TIME_S

    if not (math.isfinite(fn_hz) and math.isfinite(zeta)):
        return columns
    check = [str(p) == "ok" and not undone for p, undone in zip(columns["peak_status"], plate_undone)]
    spike = np.asarray(time_to_peak_ms, dtype=float) < 1e3 * BUCKLING_TIME_S
    flags = flag_plate_overshoots(voltage_V, fs, noise_V, peak_u, spike, check, fn_hz, zeta)
    return apply_session_flags(columns, flags, ProblemKind.PEAK_ON_RINGING)
