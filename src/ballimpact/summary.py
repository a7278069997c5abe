"""Run summary: what a user must see at the end of a run (exclusions, fit warnings, session errors, stale results)."""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from pathlib import Path

from .problems import ProblemKind, kind_of_message

__all__ = [
    "NOT_DETERMINED",
    "OPEN_INTERVAL",
    "WIDE_INTERVAL_FACTOR",
    "FORCE_AGREEMENT_WARNING",
    "STALE_FILE",
    "undetermined_parameters",
    "fit_warnings",
    "parameter_fit_warnings",
    "mark_stale",
    "clear_stale",
    "session_summary",
    "rig_summary",
    "run_summary",
]

#: How a parameter that sits on its search bound is shown instead of an interval.
NOT_DETERMINED = "not determined (at bound)"
#: How a parameter whose value is inside its search range but whose 95 % interval reaches a bound is described.
OPEN_INTERVAL = "95 % interval reaches the search bound: the data bound it on one side only"
#: A 95 % interval of AK or AC whose ends differ by more than this factor [-] is a fit warning (the demo's, 10
#: impacts per ball: 2.6-3.7 for AK, 1.04-1.07 for AC; a synth session of 3 impacts per ball: 38-1900 for AK;
#: hand-made half-sine sessions: about 1e4). AK and a are correlated: a factor of a few is normal.
WIDE_INTERVAL_FACTOR = 100.0
#: A ball type whose impacts' median model_agreement_fraction is below this [-] gets a fit warning: the model's
#: force does not follow the measured one (measured by bench/force_shape_map.py; see docs/outputs.md).
FORCE_AGREEMENT_WARNING = 0.8
#: File written into results/<session_id>/ when a session-level error left an earlier run's results there.
STALE_FILE = "STALE"
#: Results an earlier run leaves in results/<session_id>/ (outputs.md).
RESULT_FILES = ("impacts.csv", "parameters.csv", "report.pdf", "figures")

_PARAM_NAMES = {"ak": "AK", "a": "a", "ac": "AC"}
#: Relative RMS residual of TC or COR above which the fit is suspect [%] (the paper's model
#: agrees with its measurements within about 5 %).
RESIDUAL_WARNING_PCT = 5.0
_BOUND_TOL = 1e-3  # fraction of the (log) search range within which a value counts as on the bound


def _search_bounds_table_units() -> dict[str, tuple[float, float, bool]]:
    """Search bounds of the fit in the units of parameters.csv, and whether to compare in log.

    AK [kN/m^(1+a)] is searched as kR = AK xR^a (fitting.py), so its bounds follow from
    those of kR [N/m] and a [-]; AC [kN s/m^3]; a [-].
    """
    from .fitting import PARAMETER_BOUNDS, REFERENCE_DISPLACEMENT_M

    kr_lo, kr_hi = PARAMETER_BOUNDS["kr_N_m"]
    a_lo, a_hi = PARAMETER_BOUNDS["a"]
    ac_lo, ac_hi = PARAMETER_BOUNDS["ac"]
    xr = REFERENCE_DISPLACEMENT_M
    return {
        "ak": (kr_lo / xr**a_lo / 1e3, kr_hi / xr**a_hi / 1e3, True),
        "a": (a_lo, a_hi, False),
        "ac": (ac_lo / 1e3, ac_hi / 1e3, True),
    }


def _on_bound(value: float, lo: float, hi: float, log: bool) -> bool:
    if not math.isfinite(value) or (log and value <= 0):
        return False
    f = math.log if log else (lambda x: x)
    span = f(hi) - f(lo)
    return min(abs(f(value) - f(lo)), abs(f(value) - f(hi))) < _BOUND_TOL * span


def _numbers(values, key: str, value_name: str) -> list[float]:
    """[value, lo, hi] of one parameter from a parameters.csv row (NaN where missing)."""
    numbers = []
    for name in (value_name, f"{key}_lo", f"{key}_hi"):
        try:
            numbers.append(float(values.get(name, math.nan)))
        except (TypeError, ValueError):
            numbers.append(math.nan)
    return numbers


_VALUE_NAMES = {"ak": "ak_kN_m", "a": "a", "ac": "ac_kN_s_m3"}


def undetermined_parameters(values, fit_message: str = "") -> dict[str, str]:
    """
    The fitted parameters whose value, or an end of whose 95 % interval, sits on the fit's search bound.

    A value on its bound (or one the fit says "sits on its search bound", or whose interval
    spans the whole search range) is not determined by the data: :data:`NOT_DETERMINED`,
    and no interval. A value inside its
    range whose interval reaches a bound is determined on one side only: :data:`OPEN_INTERVAL`.

    Parameters
    ----------
    values : mapping
        ``ak_kN_m``, ``ak_lo``, ``ak_hi`` [kN/m^(1+a)], ``a``, ``a_lo``, ``a_hi`` [-],
        ``ac_kN_s_m3``, ``ac_lo``, ``ac_hi`` [kN s/m^3] (a parameters.csv row; missing = NaN).
    fit_message : str
        The fit's message (archive ``fit_message``); "<name> sits on its search bound"
        there also counts.

    Returns
    -------
    dict
        ``{"ak" | "a" | "ac": NOT_DETERMINED or OPEN_INTERVAL}`` for each such parameter.
    """
    bounds = _search_bounds_table_units()
    found = {}
    for key, value_name in _VALUE_NAMES.items():
        lo, hi, log = bounds[key]
        value, v_lo, v_hi = _numbers(values, key, value_name)
        said = re.search(rf"(^|[;:] ?){re.escape(_PARAM_NAMES[key])}( \(via kR\))? sits on its search bound",
                         fit_message or "")
        if said or _on_bound(value, lo, hi, log) or (_on_bound(v_lo, lo, hi, log) and _on_bound(v_hi, lo, hi, log)):
            found[key] = NOT_DETERMINED  # the value, or the whole "interval", is the search range's
        elif _on_bound(v_lo, lo, hi, log) or _on_bound(v_hi, lo, hi, log):
            found[key] = OPEN_INTERVAL
    return found


def _interval_notes(values, undetermined: dict) -> list[str]:
    """Fit warnings of the AK and AC intervals wider than WIDE_INTERVAL_FACTOR (a parameters.csv row)."""
    notes = []
    for key in ("ak", "ac"):
        if key in undetermined:
            continue
        _, lo, hi = _numbers(values, key, _VALUE_NAMES[key])
        if math.isfinite(lo) and math.isfinite(hi) and lo > 0 and hi / lo > WIDE_INTERVAL_FACTOR:
            notes.append(f"{_PARAM_NAMES[key]} barely determined: its 95 % interval [{lo:,.4g}, {hi:,.4g}] spans a "
                         f"factor {hi / lo:,.0f} (more than {WIDE_INTERVAL_FACTOR:g})")
    return notes


def _force_note(force_agreement: float) -> list[str]:
    """The fit warning of a ball whose model force does not follow the measured one (agreement [-])."""
    try:
        share = float(force_agreement)
    except (TypeError, ValueError):
        return []
    if not math.isfinite(share) or share >= FORCE_AGREEMENT_WARNING:
        return []
    return [f"model force unlike the measured force: within 10 % of the peak on {100 * share:.0f} % of the contact "
            f"(median impact; tennis balls: {100 * FORCE_AGREEMENT_WARNING:.0f} % or more): not the kind of ball the "
            "model describes, or the plate distorts the force; do not use these parameters"]


def fit_warnings(fit_message: str, undetermined: dict[str, str] | None = None, *,
                 contact_time_rmse_pct: float = math.nan, cor_rmse_pct: float = math.nan,
                 values=None, force_agreement: float = math.nan) -> str:
    """
    One-line warnings of a ball's fit: empty when all is well.

    Parameters
    ----------
    fit_message : str
        The archive's ``fit_message``: "ok" followed by "; " and the fit's notes, or
        "fit failed: ..." / "no fit".
    undetermined : dict, optional
        :func:`undetermined_parameters` of the ball.
    contact_time_rmse_pct, cor_rmse_pct : float, optional
        Relative RMS residuals of TC and COR [%]; above :data:`RESIDUAL_WARNING_PCT`
        the model does not describe the impacts (e.g. a mistyped ball mass).
    values : mapping, optional
        The ball's parameters.csv row: AK and AC intervals wider than
        :data:`WIDE_INTERVAL_FACTOR` are warned about.
    force_agreement : float, optional
        Median over the ball's ok impacts of ``model_agreement_fraction`` [-]
        (:func:`ballimpact.model_data.force_agreement`); below
        :data:`FORCE_AGREEMENT_WARNING` the model's force shape is not the measured one.

    Returns
    -------
    str
        "AC not determined (at bound); ..." then the fit's own notes, "; "-separated.
    """
    text = "" if fit_message is None else str(fit_message).strip()
    if text in ("nan", "None"):
        text = ""
    if text == "ok":
        text = ""
    elif text.startswith("ok; "):
        text = text[4:]
    notes = _force_note(force_agreement)
    for key, verdict in (undetermined or {}).items():
        if verdict == NOT_DETERMINED:
            notes.append(f"{_PARAM_NAMES[key]} {verdict}")
        elif f"the {_PARAM_NAMES[key]} interval reaches" not in text:  # the fit may have said it already
            notes.append(f"{_PARAM_NAMES[key]}: {verdict}")
    notes += _interval_notes({} if values is None else values, undetermined or {})
    for what, value in (("TC", contact_time_rmse_pct), ("COR", cor_rmse_pct)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            continue
        if math.isfinite(value) and value > RESIDUAL_WARNING_PCT:
            notes.append(f"{what} residual {value:.1f} % RMS (> {RESIDUAL_WARNING_PCT:g} %): the model does not "
                         "describe these impacts; check the ball mass and the gate times")
    return "; ".join(notes + ([text] if text else []))


def parameter_fit_warnings(table):
    """
    parameters.csv with a ``fit_warnings`` column, and no interval for an undetermined parameter.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`ballimpact.archive.parameters_table` rows; a ``fit_message`` column (the
        archive's) and a ``force_agreement`` column [-] (median model_agreement_fraction),
        when present, are read and dropped.

    Returns
    -------
    pandas.DataFrame
        The same rows: ``<param>_lo`` / ``_hi`` emptied (NaN) for each parameter on its
        search bound, the end on the bound alone for an interval that reaches it,
        ``fit_warnings`` (text, empty when all is well) appended.
    """
    table = table.copy()
    messages = table.pop("fit_message") if "fit_message" in table else [""] * len(table)
    agreement = table.pop("force_agreement") if "force_agreement" in table else [math.nan] * len(table)
    bounds = _search_bounds_table_units()
    column = []
    for i, message, share in zip(table.index, messages, agreement):
        row = table.loc[i]
        undetermined = undetermined_parameters(row, "" if message is None else str(message))
        for key, verdict in undetermined.items():
            ends = [f"{key}_lo", f"{key}_hi"]
            if verdict == OPEN_INTERVAL:  # only the end the search bound set
                lo, hi, log = bounds[key]
                ends = [e for e in ends if _on_bound(float(row.get(e, math.nan)), lo, hi, log)]
            table.loc[i, ends] = math.nan
        column.append(fit_warnings(message, undetermined, contact_time_rmse_pct=row.get("contact_time_rmse_pct"),
                                   cor_rmse_pct=row.get("cor_rmse_pct"), values=row, force_agreement=share))
    table["fit_warnings"] = column
    return table


# ---------------------------------------------------------------------- stale results


def mark_stale(results_session_dir, reason: str) -> Path | None:
    """
    Mark an earlier run's results of a session as stale after a session-level error.

    Parameters
    ----------
    results_session_dir : str or Path
        ``results/<session_id>``.
    reason : str
        The session-level error (one line per problem).

    Returns
    -------
    Path or None
        The ``STALE`` file written, None when there were no earlier results.
    """
    folder = Path(results_session_dir)
    present = [name for name in RESULT_FILES if (folder / name).exists()]
    present += [p.name for p in sorted(folder.glob("*.nc"))]
    if not present:
        return None
    path = folder / STALE_FILE
    path.write_text(
        "STALE: these results come from an earlier run. The raw session now has a session-level error,\n"
        "so it was not processed again and these files do not reflect the current raw data:\n  "
        + "\n  ".join(present)
        + "\n\nThe error:\n  " + "\n  ".join(str(reason).splitlines())
        + "\n\nFix the raw session and run again; this file is removed when the session is processed.\n",
        encoding="utf-8",
    )
    return path


def clear_stale(results_session_dir) -> None:
    """Remove the ``STALE`` mark of a session (it is being processed again)."""
    path = Path(results_session_dir) / STALE_FILE
    if path.is_file():
        path.unlink()


# ---------------------------------------------------------------------- the summary


#: Summary labels of the exclusion kinds whose message reads badly with its numbers left out.
_SUMMARY_LABELS = {ProblemKind.KCAL_OUTLIER: "calibration factor far from the session median",
                   ProblemKind.TOO_FEW_SAMPLES: "too few samples in the contact"}
#: A number with its unit (the value of one impact: left out of a label) [m/s, ms, s, N/V, N, %, Hz, kHz, V, mm, m].
_VALUE = re.compile(r"(?<![\w.])[-+]?\d[\d.]*(e[-+]?\d+)?(\s*(m/s|ms|s|N/V|N|%|Hz|kHz|V|mm|m)(?![\w/]))?")
_LOCATION = re.compile(r"^(line \d+|channel .* sample \d+|LVM segment \d+)$")


def _trace_fault_label(first: str) -> str:
    """"unreadable trace: <file>: line 7: <what>" -> "unreadable trace: <what>" (the file and place left out)."""
    head, *parts = first.split(": ")
    parts = [p for p in parts if not ("/" in p or "\\" in p or _LOCATION.match(p.strip()))]
    return f"{head}: {parts[0]}" if parts else head


def _reason_kind(reason: str) -> str:
    """The summary label of an exclusion reason: its first reason, file names and values left out."""
    first = str(reason).split("; ")[0].strip()
    kind = kind_of_message(first)
    if kind is ProblemKind.POLARITY:
        return first  # "pulse is negative: plate.polarity is +1" says it all
    if kind in _SUMMARY_LABELS:
        return _SUMMARY_LABELS[kind]
    first = re.sub(r"\s*[(\[][^()\[\]]*\d[^()\[\]]*[)\]](\s*N/V)?", "", first)  # "(3 found: ...)", "[100, 400] N/V"
    if kind in (ProblemKind.TRACE_UNREADABLE, ProblemKind.TRACE_UNUSABLE):
        first = _trace_fault_label(first)
    else:
        first = first.split(": ")[0]
    first = _VALUE.sub("", first)  # "0.014 m/s", "1.200": one impact's values
    first = re.sub(r"\S*/\S*", "...", first)  # a path
    return " ".join(first.split())


def _verdict_counts(rows: list[dict]) -> tuple[Counter, Counter]:
    """Excluded impacts by their first fault's code (else their first code), labelled with their reason's head; and
    the quantities withheld on ok impacts, by quantity and code (impacts.csv v1.2 ``reason_code``, the statuses).
    Rows without codes (impacts.csv before v1.2) are grouped by their reason's head."""
    from .checks import CHECKS

    heads: dict[str, list[str]] = {}
    for r in rows:
        if r["status"] == "ok":
            continue
        codes = [c for c in (r.get("reason_code") or "").split(";") if c in CHECKS]
        faults = [c for c in codes if CHECKS[c].fault]
        key = (faults or codes or [_reason_kind(r["reason"])])[0]
        heads.setdefault(key, []).append(_reason_kind(r["reason"]))
    excluded: Counter = Counter()
    for key, texts in heads.items():  # one line per code: its reasons' head where they share it, else its title
        label = texts[0] if len(set(texts)) == 1 or key not in CHECKS else CHECKS[key].title
        excluded[label] += len(texts)
    withheld: Counter = Counter()
    for r in rows:
        if r["status"] != "ok":
            continue
        if "peak_status" not in r:  # impacts.csv v1.1: the peak withheld, its note
            if (r.get("peak_note") or "").strip():
                withheld["peak", _reason_kind(r["peak_note"])] += 1
            continue
        codes = [c for c in (r.get("reason_code") or "").split(";") if c in CHECKS]
        for q, column in (("kCAL", "kcal_status"), ("peak", "peak_status")):
            if r.get(column) == "withheld":
                why = [CHECKS[c].title for c in codes if q.lower() in CHECKS[c].biases] or ["its uncertainty"]
                withheld[q, why[0]] += 1
    return excluded, withheld


def _read_csv_rows(path: Path) -> list[dict]:
    import csv

    with open(path, encoding="utf-8", newline="") as fh:
        return list(csv.DictReader(fh))


def _session_fault(folder: Path) -> str:
    """The session-level error logged by the failed validate_session (or, for a small session,
    small_session) job, if any."""
    marker = "session-level fault: "
    logs = [folder / "logs" / f"{rule}.log" for rule in ("validate_session", "small_session")]
    logs = [log for log in logs if log.is_file()]
    if not logs:
        return ""
    # the job that ran last: a session once faulty (validate_session), then fixed and small
    # (small_session), keeps its old validate_session log
    text = max(logs, key=lambda log: log.stat().st_mtime_ns).read_text(encoding="utf-8", errors="replace")
    if marker not in text:
        return ""
    fault = text.rsplit(marker, 1)[1]
    lines = []
    for line in fault.splitlines():
        if re.match(r"\d{4}-\d{2}-\d{2} \d{2}:\d{2}:\d{2}", line):
            break  # the next log record
        lines.append(line.strip())
    return "\n".join(line for line in lines if line)


def rig_summary(ds) -> list[str]:
    """Lines of the session's rig (:mod:`ballimpact.rig_archive`) for the run summary: the plate and the time
    constant with their source, then each warning (a stated key the traces disagree with); none for an archive
    without the rig.

    Parameters
    ----------
    ds : xarray.Dataset
        The session archive (or ``work/impacts.nc``).

    Returns
    -------
    list of str
        Indented by 4 spaces, as :func:`session_summary`'s.
    """
    from .rig_archive import read_rig, rig_warnings

    rig = read_rig(ds)
    if not rig:
        return []
    fn, zeta, tau = rig["plate_resonance_hz"], rig["plate_damping_ratio"], rig["time_constant_s"]
    parts = [f"plate {fn.value / 1e3:.4g} kHz, zeta {zeta.value:.3g} ({fn.source})"
             if fn.source != "none" and math.isfinite(fn.value) else "plate not identified"]
    parts.append(f"time constant {tau.value:.4g} s ({tau.source})" if math.isfinite(tau.value)
                 else "time constant not identified")
    return [f"    rig: {'; '.join(parts)}"] + [f"    rig warning: {w}" for w in rig_warnings(ds)]


def _archive_rig_lines(archive: Path) -> list[str]:
    """:func:`rig_summary` of a session archive on disk; none when it is missing or cannot be read."""
    if not archive.is_file():
        return []
    import xarray as xr

    try:
        with xr.open_dataset(archive) as ds:
            return rig_summary(ds)
    except (OSError, ValueError, KeyError):  # a damaged archive: the summary goes on without the rig
        return []


def session_summary(results_session_dir, *, fault: str = "") -> list[str]:
    """
    Summary lines of one session's results: impacts ok / excluded by reason, fit
    warnings, the rig (:func:`rig_summary`), validate warnings, session-level errors and stale results.

    Parameters
    ----------
    results_session_dir : str or Path
        ``results/<session_id>``.
    fault : str, optional
        A session-level error found before the run (parse time); else the log of the
        session's validate_session job is read.

    Returns
    -------
    list of str
        The first line names the session; the others are indented by 4 spaces.
    """
    folder = Path(results_session_dir)
    name = folder.name
    fault = _session_fault(folder) or fault  # the job's log lists every problem
    snapshot_path = folder / "work" / "session.json"
    if fault or not snapshot_path.is_file():
        lines = [f"  {name}: SESSION-LEVEL ERROR, not processed:"]
        problems = fault.splitlines() or ["(no snapshot; see the logs in " + str(folder / "logs") + ")"]
        lines += [f"    error: {p}" for p in problems]
        if (folder / STALE_FILE).is_file():
            lines.append(f"    STALE: the results in {folder} are from an earlier run (see {folder / STALE_FILE})")
        return lines
    snapshot = json.loads(snapshot_path.read_text(encoding="utf-8"))
    impacts_csv = folder / "impacts.csv"
    if not impacts_csv.is_file():
        return [f"  {name}: incomplete: impacts.csv was not written (see the logs in {folder / 'logs'})"]
    rows = _read_csv_rows(impacts_csv)
    n_ok = sum(r["status"] == "ok" for r in rows)
    lines = [f"  {name}: {len(rows)} impacts, {n_ok} ok, {len(rows) - n_ok} excluded"]
    excluded, withheld = _verdict_counts(rows)
    lines += [f"    excluded {count:3d} x {label}" for label, count in excluded.most_common()]
    lines += [f"    ok, {q} withheld {count:3d} x {label}" for (q, label), count in withheld.most_common()]
    params = folder / "parameters.csv"
    if params.is_file():
        for row in _read_csv_rows(params):
            text = row.get("fit_warnings", "")
            lines.append(f"    fit {row['ball']}: " + (f"WARNING: {text}" if text else "ok"))
    else:
        lines.append(f"    fit: parameters.csv was not written (see the logs in {folder / 'logs'})")
    lines += _archive_rig_lines(folder / f"{name}.nc")
    for warning in snapshot.get("warnings", []):
        lines.append(f"    validate warning: {warning}")
    missing = [n for n in ("report.pdf", f"{name}.nc") if not (folder / n).is_file()]
    if missing:
        lines.append(f"    incomplete: {', '.join(missing)} not written (see the logs in {folder / 'logs'})")
    return lines


def run_summary(results_dir, sessions, faults: dict[str, str] | None = None) -> str:
    """
    The terminal summary of a workflow run: :func:`session_summary` of every session.

    Parameters
    ----------
    results_dir : str or Path
        The run's results folder.
    sessions : sequence of str
        Session ids of the run.
    faults : dict, optional
        Session id -> session-level error found when the workflow was parsed.

    Returns
    -------
    str
        Several lines, no trailing newline.
    """
    faults = faults or {}
    lines = ["", "=" * 78, f"ballimpact run summary ({len(sessions)} session(s), results in {results_dir})"]
    for session in sessions:
        lines += session_summary(Path(results_dir) / session, fault=faults.get(session, ""))
    lines.append("=" * 78)
    return "\n".join(lines)
