"""Reading impacts.csv: its header, and each row's gate times, mass and trace path checked into an ImpactRow."""

from __future__ import annotations

import csv
import io
import math
import re
import warnings
from pathlib import Path, PurePosixPath, PureWindowsPath

from .problems import Problem, ProblemKind
from .session_files import _decode_utf8, _one_line, _read_bytes
from .session_records import (
    GATE_COLUMNS,
    IMPACT_ID_PATTERN,
    IMPACTS_FILE,
    MASS_MAX_G,
    MASS_MIN_G,
    MASS_TYPICAL_MAX_G,
    MASS_TYPICAL_MIN_G,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    SESSION_FILE,
    BallType,
    ImpactRow,
    SessionError,
    SessionWarning,
    _normalise_trace,
    _raise_collected,
)



def _parse_gate(cell: str, column: str, problems: list[Problem]) -> float:
    text = cell.strip()
    if not text:
        problems.append(Problem(ProblemKind.GATE_TIME_MISSING, f"missing gate time {column}"))
        return math.nan
    try:
        value = float(text)
    except ValueError:
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"non-numeric gate time {column}: {text!r}"))
        return math.nan
    if not math.isfinite(value):
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"non-finite gate time {column}: {text!r}"))
        return math.nan
    if value < 0:
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"negative gate time {column}: {text}"))
    return value


def _check_gate_order(gates: dict[str, float], cells: dict[str, str], problems: list[Problem]) -> None:
    pairs = (
        ("gate_in_1_s", "gate_in_2_s", True),
        ("gate_in_2_s", "gate_out_2_s", False),
        ("gate_out_2_s", "gate_out_1_s", True),
    )
    for first, second, strict in pairs:
        a, b = gates[first], gates[second]
        if math.isnan(a) or math.isnan(b):
            continue
        if (a >= b) if strict else (a > b):
            relation = "earlier than" if strict else "no later than"
            problems.append(Problem(
                ProblemKind.GATE_ORDER,
                f"gate times out of order: {first} ({cells[first].strip()}) must be {relation} "
                f"{second} ({cells[second].strip()})",
            ))


def _parse_mass(cell: str, ball: BallType, problems: list[Problem], where: str) -> float:
    text = cell.strip()
    if not text:
        return ball.mass_kg
    try:
        mass_g = float(text)
    except ValueError:
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-numeric mass_g: {text!r}"))
        return math.nan
    if not math.isfinite(mass_g):
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-finite mass_g: {text!r}"))
        return math.nan
    if mass_g <= 0:
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-positive mass_g: {text}"))
        return math.nan
    if not MASS_MIN_G < mass_g < MASS_MAX_G:
        problems.append(Problem(ProblemKind.MASS_INVALID,
                                f"implausible mass_g: {text} (must be in ({MASS_MIN_G:g}, {MASS_MAX_G:g}) g)"))
        return math.nan
    if not MASS_TYPICAL_MIN_G <= mass_g <= MASS_TYPICAL_MAX_G:
        warnings.warn(
            f"{where}: mass_g {text} g is outside the usual {MASS_TYPICAL_MIN_G:g}-{MASS_TYPICAL_MAX_G:g} g "
            "of a tennis ball",
            SessionWarning,
            stacklevel=5,
        )
    return mass_g / 1000.0


def _check_trace(cell: str, session_dir: Path, problems: list[Problem]) -> None:
    trace = cell.strip()
    if not trace:
        problems.append(Problem(ProblemKind.TRACE_PATH_MISSING, "missing trace path"))
        return
    normalised = _normalise_trace(trace)
    if PurePosixPath(normalised).is_absolute() or PureWindowsPath(trace).drive:
        problems.append(Problem(ProblemKind.TRACE_PATH_ESCAPES,
                                f"trace path escapes the session folder (absolute path): {trace}"))
        return
    root = session_dir.resolve()
    # ValueError: a NUL byte in the cell; OSError also covers a file name too long
    # for the OS (ENAMETOOLONG), which Path.exists() re-raises. Both are faults of
    # this one row, not of the session (bad-input suite: tests/test_bad_input.py).
    try:
        full = (root / normalised).resolve()
    except (OSError, RuntimeError, ValueError) as exc:  # symlink loops, NUL bytes
        problems.append(Problem(ProblemKind.TRACE_PATH_UNRESOLVABLE,
                                f"trace path cannot be resolved: {trace!r} ({exc})"))
        return
    if full == root or not full.is_relative_to(root):
        problems.append(Problem(ProblemKind.TRACE_PATH_ESCAPES, f"trace path escapes the session folder: {trace}"))
        return
    try:
        exists, is_file = full.exists(), full.is_file()
    except (OSError, ValueError) as exc:  # e.g. [Errno 36] File name too long
        problems.append(Problem(ProblemKind.TRACE_PATH_UNRESOLVABLE,
                                f"trace path cannot be resolved: {trace!r} ({exc.strerror or exc})"))
        return
    if not exists:
        problems.append(Problem(ProblemKind.TRACE_NOT_FOUND, f"trace file not found: {trace}"))
    elif not is_file:
        problems.append(Problem(ProblemKind.TRACE_NOT_A_FILE, f"trace path is not a file: {trace}"))


def _separator_hint(header: list[str]) -> str:
    """Why a header lacks the required columns, when the cause is the separator."""
    joined = ",".join(header)
    for sep, name in ((";", "semicolons"), ("\t", "tabs"), ("|", "'|'")):
        if sep in joined and sum(c in joined for c in REQUIRED_COLUMNS) >= 3:
            return (
                f"; the columns are separated by {name}: save {IMPACTS_FILE} comma-separated "
                "(in a spreadsheet: CSV, comma as separator, point as decimal mark)"
            )
    return ""


def _read_impacts(session_dir: Path, meta) -> list[ImpactRow]:
    """Impact rows; ``meta`` is a SessionMeta or None (session.yaml unusable: the rows'
    structure is still checked, every session-level problem collected)."""
    balls = meta.balls if meta is not None else None
    session_problems: list[str] = []
    path = session_dir / IMPACTS_FILE
    file = str(path)
    data = _read_bytes(path, file, "every session folder needs an impacts.csv")
    if not data.strip():
        raise SessionError(
            f"{file}: file is empty (expected a header row with columns {', '.join(REQUIRED_COLUMNS)})"
        )
    text = _decode_utf8(data, file)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    rows: list[ImpactRow] = []
    first_line: dict[str, int] = {}
    header: list[str] | None = None
    index: dict[str, int] = {}
    previous_line_num = 0
    while True:
        line = previous_line_num + 1
        try:
            record = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise SessionError(f"{file}: line {reader.line_num}: malformed CSV: {exc}") from None
        previous_line_num = reader.line_num
        if not record or all(not cell.strip() for cell in record) and len(record) <= 1:
            continue  # blank line
        if header is None:
            header = _impacts_header(record, file, line)
            index = {name: i for i, name in enumerate(header)}
            continue
        if len(record) != len(header):
            hint = ""
            if len(record) > len(header) and re.search(r"\d,\d", ",".join(record)):
                hint = " (decimal commas? write gate times with a decimal point, e.g. 4.219063 not 4,219063)"
            session_problems.append(f"{file}: line {line}: expected {len(header)} fields, got {len(record)}{hint}")
            continue
        cells = {name: record[i] for name, i in index.items()}
        row = _impact_row(cells, line, file, balls, first_line, session_problems, session_dir)
        if row is not None:
            rows.append(row)
    if header is None:
        raise SessionError(
            f"{file}: file is empty (expected a header row with columns {', '.join(REQUIRED_COLUMNS)})"
        )
    _raise_collected(session_problems)
    if not rows and balls is not None:
        raise SessionError(f"{file}: no impact rows (only the header)")
    return rows


def _impacts_header(record: list[str], file: str, line: int) -> list[str]:
    """The header row of impacts.csv: no duplicate, every required column; warns of unknown ones."""
    header = [cell.strip() for cell in record]
    duplicated = sorted({c for c in header if header.count(c) > 1})
    if duplicated:
        raise SessionError(f"{file}: line {line}: duplicate column(s) in header: {', '.join(duplicated)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise SessionError(
            f"{file}: line {line}: missing required column(s): {', '.join(missing)} "
            f"(header has: {_one_line(', '.join(header))})" + _separator_hint(header)
        )
    unknown = [c for c in header if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:
        warnings.warn(
            f"{file}: line {line}: unknown column(s) ignored: {', '.join(unknown)}",
            SessionWarning,
            stacklevel=4,
        )
    return header


def _impact_row(cells: dict[str, str], line: int, file: str, balls, first_line: dict[str, int],
                session_problems: list[str], session_dir: Path) -> ImpactRow | None:
    """One data row of impacts.csv as an ImpactRow with its impact-level problems, or None:
    a session-level fault (bad or duplicate impact_id, undefined ball) is appended to
    ``session_problems``; ``balls`` None (session.yaml unusable) checks only the structure."""
    impact_id = cells["impact_id"].strip()
    if not IMPACT_ID_PATTERN.fullmatch(impact_id):
        session_problems.append(
            f"{file}: line {line}: impact_id {impact_id!r} is not valid "
            "(allowed: letters, digits, '_' and '-', at least one)"
        )
        return None
    if impact_id in first_line:
        session_problems.append(
            f"{file}: line {line}: impact_id {impact_id!r} duplicates line {first_line[impact_id]}"
        )
        return None
    first_line[impact_id] = line
    ball_key = cells["ball"].strip()
    if balls is None:
        return None  # session.yaml balls unusable: only the structure of the rows is checked
    if ball_key in balls and balls[ball_key] is None:
        return None  # a ball type with problems of its own in session.yaml
    if ball_key not in balls:
        session_problems.append(
            f"{file}: line {line}: ball {ball_key!r} is not defined in {SESSION_FILE} balls "
            f"(valid: {', '.join(balls)})"
        )
        return None
    problems: list[Problem] = []
    gates = {column: _parse_gate(cells[column], column, problems) for column in GATE_COLUMNS}
    _check_gate_order(gates, cells, problems)
    mass_kg = _parse_mass(cells.get("mass_g", ""), balls[ball_key], problems, f"{file}: line {line}")
    trace = cells["trace"].strip()
    _check_trace(trace, session_dir, problems)
    return ImpactRow(
        impact_id=impact_id,
        ball=ball_key,
        trace=trace,
        gate_in_1_s=gates["gate_in_1_s"],
        gate_in_2_s=gates["gate_in_2_s"],
        gate_out_2_s=gates["gate_out_2_s"],
        gate_out_1_s=gates["gate_out_1_s"],
        mass_kg=mass_kg,
        note=cells.get("note", "").strip(),
        line=line,
        problems=problems,
    )
