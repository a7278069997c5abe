"""File-level validation of a raw session: metadata, impact rows and every trace file."""

from __future__ import annotations

import math
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .problems import TRACE_FILE_KINDS, ProblemKind, has_kind
from .processing import PHYSICAL_BOUNDS
from .processing import _opposite_pulse_reason as opposite_pulse_problem  # the very test processing applies
from .session import PLATE_RESONANCE_MAX_HZ, alias_risk, read_session
from .traces import TraceError, read_trace, trace_header_rate

__all__ = ["ValidationReport", "validate_session", "format_validation"]

RATE_SIGNIFICANT_DIGITS = 9  # sample rates are grouped after rounding to this many digits
SPEED_RANGE_M_S = PHYSICAL_BOUNDS["vin_m_s"]  # [m/s] inbound speeds processing accepts
COR_RANGE = PHYSICAL_BOUNDS["cor"]  # [-] rebound / inbound speeds processing accepts
RATE_RTOL = 0.005  # daq.sample_rate_hz vs a trace's own rate: largest relative difference
RATE_RANGE_HZ = (1.0e3, 1.0e7)  # [Hz] plausible daq.sample_rate_hz (the rigs: 20-200 kHz)


def gate_speed_problems(spacing_m: float, gates_s) -> list[str]:
    """
    Inbound speed and COR from one impact's gate times, and what processing would refuse in them.

    Parameters
    ----------
    spacing_m : float
        Gate spacing [m] (session.yaml ``gates.spacing_m``).
    gates_s : sequence of 4 float
        gate_in_1, gate_in_2, gate_out_2, gate_out_1 [s]; NaN when missing.

    Returns
    -------
    list of str
        Empty when the inbound speed is in :data:`SPEED_RANGE_M_S` [m/s] and the COR in
        :data:`COR_RANGE` [-], the bounds of ``ballimpact.processing.PHYSICAL_BOUNDS`` (or when
        they cannot be computed: the reader reports missing or disordered gate times itself).
    """
    in_1, in_2, out_2, out_1 = (float(g) for g in gates_s)
    found = []
    dt_in, dt_out = in_2 - in_1, out_1 - out_2
    vin = spacing_m / dt_in if math.isfinite(dt_in) and dt_in > 0 else math.nan
    vout = spacing_m / dt_out if math.isfinite(dt_out) and dt_out > 0 else math.nan
    lo, hi = SPEED_RANGE_M_S
    if math.isfinite(vin) and not lo <= vin <= hi:
        found.append(f"inbound speed {vin:.4g} m/s from the gate times is outside {lo:g}-{hi:g} m/s")
    cor_lo, cor_hi = COR_RANGE
    if math.isfinite(vin) and math.isfinite(vout) and not cor_lo <= vout / vin <= cor_hi:
        found.append(f"COR {vout / vin:.3g} from the gate times (rebound {vout:.4g} m/s) is outside "
                     f"{cor_lo:g}-{cor_hi:g}")
    return found


def _units_hint(speeds: list[float]) -> str:
    """Which unit mistake a set of implausible gate speeds [m/s] points to."""
    median = float(np.median(speeds))
    if 1e-4 <= median < 0.1:
        return (f" (median {median:.3g} m/s: are the gate times in ms instead of s? "
                f"in s the speeds would be {median * 1e3:.3g} m/s)")
    if median > 1e3:
        return (f" (median {median:.3g} m/s: are the gate times in us, or gates.spacing_m in mm? "
                "gate times must be in s, the spacing in m)")
    return f" (median {median:.3g} m/s: check the gate times [s] and gates.spacing_m [m])"


def pulse_sign(voltage_V) -> int:
    """
    Sign of the largest excursion of a trace from its baseline (the impact pulse).

    Parameters
    ----------
    voltage_V : array_like
        The trace [V].

    Returns
    -------
    int
        +1 for a positive pulse, -1 for a negative one, 0 for a flat trace.
    """
    v = np.asarray(voltage_V, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return 0
    dev = v - np.median(v)
    top, bottom = float(dev.max()), float(-dev.min())
    if top == bottom:
        return 0
    return 1 if top > bottom else -1


@dataclass
class ValidationReport:
    """What a session holds and every file-level problem found, by impact id."""

    session_id: str
    n_impacts: int
    impacts_per_ball: dict[str, int]  # ball key -> number of impacts (session.yaml order)
    sample_rates_hz: dict[float, int]  # [Hz] rate (9 significant digits) -> number of traces read at it
    trace_formats: dict[str, int]  # "csv" / "tdms" -> number of traces read
    problems: list[tuple[str, str]]  # (impact_id or "", message)
    sample_rate_sources: dict[str, int] = field(default_factory=dict)  # "header", "time_s", ...
    warnings: list[str] = field(default_factory=list)  # usable but suspect input
    causes: list[str] = field(default_factory=list)  # one cause behind many problems (gate times in ms, polarity)

    @property
    def impacts_with_problems(self) -> list[str]:
        """Impact ids that have at least one problem, in report order, without repeats."""
        return list(dict.fromkeys(impact_id for impact_id, _ in self.problems if impact_id))

    @property
    def ok(self) -> bool:
        """True when no problem was found."""
        return not self.problems


def trace_own_rate(path) -> float | None:
    """
    The sample rate a trace file gives itself, read from its header only (no samples).

    Parameters
    ----------
    path : str or Path
        A ``.csv`` (``# sample_rate_hz: ...`` header line), ``.tdms`` (channel property
        ``wf_increment`` [s]) or ``.lvm`` trace (``Delta_X`` [s] of its channel header).

    Returns
    -------
    float or None
        [Hz]; None when the header gives none or cannot be read (``validate`` reads the
        whole trace and reports why).
    """
    try:
        return trace_header_rate(path)
    except Exception:  # noqa: BLE001 - a damaged file: processing reports it
        return None


def validate_session(path, *, read_traces: bool = True) -> ValidationReport:
    """
    Read a session and every one of its traces (one at a time) and collect all problems.

    Only file-level checks are made: clipping, double impacts and calibration are
    judged later by processing.

    Parameters
    ----------
    path : str or Path
        The session folder ``raw/<session_id>``.

    Returns
    -------
    ValidationReport
        Counts per ball type, sample rates [Hz] and formats of the traces, and every
        impact-level problem as ``(impact_id, message)`` (trace errors included).

    Raises
    ------
    SessionError
        A session-level fault (the session cannot be processed at all); its
        ``problems`` list every session-level problem found, one line each.

    Notes
    -----
    With ``read_traces=False`` (the workflow's quick check) only the trace headers are
    read: the sample rates are compared, the traces themselves not checked.
    """
    path = Path(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        session = read_session(path)
        meta = session.meta
        tally = _Tally()
        for row in session.impacts:
            _check_row_gates(row, meta.gate_spacing_m, tally)
            if has_kind(row.problems, TRACE_FILE_KINDS):
                continue  # no readable trace file to look at
            _check_row_trace(session, row, read_traces, tally)
        causes = []
        if len(tally.bad_speeds) >= max(2, len(session.impacts) // 2):
            causes.append(
                f"{len(tally.bad_speeds)} of {len(session.impacts)} impacts have an inbound gate speed outside "
                f"{SPEED_RANGE_M_S[0]:g}-{SPEED_RANGE_M_S[1]:g} m/s{_units_hint(tally.bad_speeds)}"
            )
        _check_sample_rate(meta.sample_rate_hz, [r for _, _, r in tally.own_rates], tally.n_default_rate)
        _check_odd_rates(meta.sample_rate_hz, tally.own_rates, tally.n_default_rate)
        _check_alias_rates(meta.sample_rate_hz, meta.bandwidth_hz, [r for _, _, r in tally.own_rates])
        causes += _polarity_cause(meta.polarity, tally.signs)
    per_ball = Counter(row.ball for row in session.impacts)
    return ValidationReport(
        session_id=session.meta.session_id,
        n_impacts=len(session.impacts),
        impacts_per_ball={ball: per_ball[ball] for ball in session.meta.balls if per_ball[ball]},
        sample_rates_hz=dict(sorted(tally.rates.items())),
        trace_formats=dict(sorted(tally.formats.items())),
        problems=tally.problems,
        sample_rate_sources=dict(sorted(tally.sources.items())),
        warnings=[str(w.message) for w in caught],
        causes=causes,
    )


@dataclass
class _Tally:
    """What :func:`validate_session` gathers over the impacts of a session."""

    problems: list = field(default_factory=list)  # (impact_id, message)
    rates: Counter = field(default_factory=Counter)  # [Hz] trace sample rates, rounded
    sources: Counter = field(default_factory=Counter)  # where each trace's rate came from
    formats: Counter = field(default_factory=Counter)  # trace formats
    trace_users: dict = field(default_factory=dict)  # resolved trace path -> first impact_id
    bad_speeds: list = field(default_factory=list)  # [m/s] implausible inbound gate speeds
    own_rates: list = field(default_factory=list)  # (impact_id, trace, rate [Hz]) of traces that give their own rate
    n_default_rate: int = 0  # traces that take daq.sample_rate_hz
    signs: Counter = field(default_factory=Counter)  # pulse sign per trace


def _check_row_gates(row, spacing_m: float, tally: _Tally) -> None:
    """The reader's problems of one row, then its implausible gate speeds (gate spacing [m])."""
    tally.problems.extend((row.impact_id, problem.message) for problem in row.problems)
    gates = (row.gate_in_1_s, row.gate_in_2_s, row.gate_out_2_s, row.gate_out_1_s)
    if has_kind(row.problems, ProblemKind.GATE_ORDER):
        return
    speed_problems = gate_speed_problems(spacing_m, gates)
    tally.problems.extend((row.impact_id, message) for message in speed_problems)
    if any(m.startswith("inbound") for m in speed_problems):
        tally.bad_speeds.append(spacing_m / (gates[1] - gates[0]))


def _check_row_trace(session, row, read_traces: bool, tally: _Tally) -> None:
    """One row's trace: shared with another impact (warning), its sample rate, format and pulse
    sign; only its header's rate when ``read_traces`` is false. One trace in memory at a time."""
    trace_path = session.trace_path(row)
    key = trace_path.resolve()
    if key in tally.trace_users:
        warnings.warn(f"{row.impact_id}: trace {row.trace} is also the trace of impact {tally.trace_users[key]}")
    else:
        tally.trace_users[key] = row.impact_id
    if not read_traces:
        rate = trace_own_rate(trace_path)
        if rate is None:
            tally.n_default_rate += 1
        else:
            tally.own_rates.append((row.impact_id, row.trace, rate))
        return
    try:
        trace = read_trace(trace_path, session.meta.sample_rate_hz)
    except TraceError as exc:
        tally.problems.append((row.impact_id, str(exc)))
        return
    tally.rates[float(f"{trace.sample_rate_hz:.{RATE_SIGNIFICANT_DIGITS}g}")] += 1
    tally.sources[trace.sample_rate_source] += 1
    tally.formats[trace.format] += 1
    if trace.sample_rate_source == "session":
        tally.n_default_rate += 1
    else:
        tally.own_rates.append((row.impact_id, row.trace, trace.sample_rate_hz))
    wrong_sign = opposite_pulse_problem(trace.voltage_V, session.meta.polarity)
    if wrong_sign is not None:  # processing excludes the impact for it: so does the verdict
        tally.problems.append((row.impact_id, wrong_sign.message))
    tally.signs[pulse_sign(trace.voltage_V)] += 1


def _check_sample_rate(rate_hz: float, own_rates: list[float], n_default: int) -> None:
    """Warn when daq.sample_rate_hz [Hz] is implausible or agrees with none of the traces' own rates."""
    lo, hi = RATE_RANGE_HZ
    if not lo <= rate_hz <= hi:
        hint = f" (in kHz? {rate_hz:g} kHz would be {rate_hz * 1e3:g} Hz)" if rate_hz < lo else ""
        warnings.warn(f"daq.sample_rate_hz = {rate_hz:g} Hz is outside the plausible {lo:g}-{hi:g} Hz{hint}")
        return
    if not own_rates:
        return
    if any(abs(r - rate_hz) <= RATE_RTOL * r for r in own_rates):
        return
    common = Counter(float(f"{r:.6g}") for r in own_rates).most_common(1)[0][0]
    use = (f"; the {n_default} trace(s) without a rate of their own are read at {rate_hz:g} Hz"
           if n_default else "; each trace's own rate is used")
    warnings.warn(
        f"daq.sample_rate_hz = {rate_hz:g} Hz disagrees with the rate every trace gives itself "
        f"(mostly {common:g} Hz, from trace headers / time_s / TDMS wf_increment){use}: correct session.yaml"
    )


def _check_alias_rates(rate_hz: float, bandwidth_hz: float | None, own_rates: list[float]) -> None:
    """Warn when traces carry their own sample rate [Hz] too slow to rule out an aliased plate resonance, and
    session.yaml states no `daq.bandwidth_hz` [Hz]. Below twice PLATE_RESONANCE_MAX_HZ at daq.sample_rate_hz,
    reading session.yaml has warned already."""
    slow = [r for r in own_rates if r < 2.0 * PLATE_RESONANCE_MAX_HZ]
    if bandwidth_hz is not None or not slow or rate_hz < 2.0 * PLATE_RESONANCE_MAX_HZ:
        return
    warnings.warn(f"{len(slow)} trace(s) sampled below {2e-3 * PLATE_RESONANCE_MAX_HZ:g} kHz by their own rate, and "
                  f"daq.bandwidth_hz not given: {alias_risk(min(slow))}")


def _check_odd_rates(rate_hz: float, own_rates: list, n_default: int) -> None:
    """Warn of each trace whose own sample rate [Hz] disagrees with daq.sample_rate_hz [Hz] while most of the
    session's other traces agree with it: a wrong header scales that impact's times (TC, kCAL) by the ratio."""
    rates = [r for _, _, r in own_rates]
    for k, (impact_id, trace, rate) in enumerate(own_rates):
        if abs(rate - rate_hz) <= RATE_RTOL * rate_hz:
            continue
        others = rates[:k] + rates[k + 1:]
        agree = n_default + sum(abs(r - rate_hz) <= RATE_RTOL * rate_hz for r in others)
        if agree <= (len(others) + n_default) / 2:
            continue  # most traces disagree with session.yaml: _check_sample_rate says so
        n_others = len(others) + n_default
        agreeing = f"the session's other {n_others}" if agree == n_others else f"{agree} of the other {n_others}"
        warnings.warn(
            f"{impact_id}: trace {trace} gives its own sample rate as {rate:g} Hz, but daq.sample_rate_hz and "
            f"{agreeing} traces say {rate_hz:g} Hz: "
            f"read at {rate:g} Hz, its contact time comes out x{rate_hz / rate:.3g} and its kCAL "
            f"x{rate / rate_hz:.3g} of what {rate_hz:g} Hz gives; correct the file's sample rate if it is wrong"
        )


def _polarity_cause(polarity: int, signs: Counter) -> list[str]:
    """The likely cause when most traces pulse the other way than plate.polarity says (empty list if not)."""
    opposite = signs.get(-polarity, 0)
    n = opposite + signs.get(polarity, 0)
    if n and opposite > n / 2:
        sign = "negative" if polarity == 1 else "positive"
        return [f"{opposite} of {n} traces show a {sign} pulse but plate.polarity is {polarity:+d}: "
                f"is plate.polarity {-polarity:+d}? (each such impact is excluded)"]
    return []


def _counts(mapping: dict, unit: str = "") -> str:
    if not mapping:
        return "none"
    return ", ".join(f"{key}{unit}: {count}" for key, count in mapping.items())


def format_validation(report: ValidationReport) -> str:
    """
    Human-readable validation text: what was found, every problem by impact, a verdict.

    Parameters
    ----------
    report : ValidationReport
        Result of :func:`validate_session`.

    Returns
    -------
    str
        Several lines, no trailing newline; the last line is the verdict.
    """
    rates = {f"{rate:.10g}": count for rate, count in report.sample_rates_hz.items()}
    lines = [
        f"Session {report.session_id}: {report.n_impacts} impacts",
        f"  impacts per ball type: {_counts(report.impacts_per_ball)}",
        f"  sample rates:          {_counts(rates, ' Hz')}"
        + (f" (from {_counts(report.sample_rate_sources)})" if report.sample_rate_sources else ""),
        f"  trace formats:         {_counts(report.trace_formats)}",
    ]
    lines.extend(f"Likely cause: {cause}" for cause in report.causes)
    if report.problems:
        lines.append(f"Problems ({len(report.problems)}):")
        lines.extend(f"  {impact_id or '(session)'}: {message}" for impact_id, message in report.problems)
    else:
        lines.append("Problems: none")
    if report.warnings:
        lines.append(f"Warnings ({len(report.warnings)}):")
        lines.extend(f"  {message}" for message in report.warnings)
    bad = report.impacts_with_problems
    session_level = any(not impact_id for impact_id, _ in report.problems)
    if not report.problems:
        verdict = f"Verdict: OK, all {report.n_impacts} impacts passed the file-level checks"
    else:
        verdict = (
            f"Verdict: PROBLEMS, {len(bad)} of {report.n_impacts} impacts will be excluded; "
            f"{report.n_impacts - len(bad)} can be processed"
        )
        if report.n_impacts and len(bad) == report.n_impacts:
            verdict = f"Verdict: NOTHING TO PROCESS, all {report.n_impacts} impacts will be excluded"
        if session_level:
            verdict += " (see the session problems above)"
    if report.warnings:
        verdict += f"; {len(report.warnings)} warning(s)"
    lines.append(verdict)
    return "\n".join(lines)
