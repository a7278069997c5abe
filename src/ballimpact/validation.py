"""File-level validation of a raw session: metadata, impact rows and every trace file."""

from __future__ import annotations

import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from .session import read_session
from .traces import TraceError, read_trace

__all__ = ["ValidationReport", "validate_session", "format_validation"]

RATE_SIGNIFICANT_DIGITS = 9  # sample rates are grouped after rounding to this many digits


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

    @property
    def impacts_with_problems(self) -> list[str]:
        """Impact ids that have at least one problem, in report order, without repeats."""
        return list(dict.fromkeys(impact_id for impact_id, _ in self.problems if impact_id))

    @property
    def ok(self) -> bool:
        """True when no problem was found."""
        return not self.problems


def validate_session(path) -> ValidationReport:
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
        A session-level fault (the session cannot be processed at all).
    """
    path = Path(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        session = read_session(path)
        problems: list[tuple[str, str]] = []
        rates: Counter = Counter()
        sources: Counter = Counter()
        formats: Counter = Counter()
        trace_users: dict[Path, str] = {}
        for row in session.impacts:
            problems.extend((row.impact_id, message) for message in row.problems)
            if any(message.startswith(("missing trace path", "trace ")) for message in row.problems):
                continue  # no readable trace file to look at
            trace_path = session.trace_path(row)
            key = trace_path.resolve()
            if key in trace_users:
                warnings.warn(f"{row.impact_id}: trace {row.trace} is also the trace of impact {trace_users[key]}")
            else:
                trace_users[key] = row.impact_id
            try:
                trace = read_trace(trace_path, session.meta.sample_rate_hz)
            except TraceError as exc:
                problems.append((row.impact_id, str(exc)))
                continue
            rates[float(f"{trace.sample_rate_hz:.{RATE_SIGNIFICANT_DIGITS}g}")] += 1
            sources[trace.sample_rate_source] += 1
            formats[trace.format] += 1
            del trace  # one trace in memory at a time
    per_ball = Counter(row.ball for row in session.impacts)
    return ValidationReport(
        session_id=session.meta.session_id,
        n_impacts=len(session.impacts),
        impacts_per_ball={ball: per_ball[ball] for ball in session.meta.balls if per_ball[ball]},
        sample_rates_hz=dict(sorted(rates.items())),
        trace_formats=dict(sorted(formats.items())),
        problems=problems,
        sample_rate_sources=dict(sorted(sources.items())),
        warnings=[str(w.message) for w in caught],
    )


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
        if session_level:
            verdict += " (see the session problems above)"
    if report.warnings:
        verdict += f"; {len(report.warnings)} warning(s)"
    lines.append(verdict)
    return "\n".join(lines)
