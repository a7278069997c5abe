"""Raw session reader: session.yaml and impacts.csv of one test session folder."""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass
from pathlib import Path

from .problems import Problem
from .session_csv import _check_trace, _read_impacts
from .session_files import _one_line, near_miss_name
from .session_records import (  # noqa: F401
    DEFAULT_AIR_DENSITY_KG_M3,
    GATE_COLUMNS,
    IMPACT_ID_PATTERN,
    IMPACTS_FILE,
    MASS_MAX_G,
    MASS_MIN_G,
    MASS_TYPICAL_MAX_G,
    MASS_TYPICAL_MIN_G,
    MAX_REPORTED_PROBLEMS,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    SESSION_FILE,
    BallType,
    ImpactRow,
    Session,
    SessionError,
    SessionMeta,
    SessionWarning,
    _Collector,
    _raise_collected,
)
from .session_yaml import (  # noqa: F401
    AIR_DENSITY_RANGE_KG_M3,
    DEFAULT_BALL_DIAMETER_M,
    DEFAULT_MAINS_HZ,
    FAST_BALL_SPEED_M_S,
    ISO_DATE_PATTERN,
    ITF_REBOUND_MAX_CM,
    MAX_GATE_SPACING_M,
    PLATE_RESONANCE_MAX_HZ,
    RIG_ORIENTATIONS,
    _load_yaml,
    _parse_meta,
    alias_risk,
)

__all__ = [
    "SessionError",
    "SessionWarning",
    "BallType",
    "SessionMeta",
    "ImpactRow",
    "Session",
    "read_session",
    "SessionPlan",
    "plan_session",
    "file_sha256",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "GATE_COLUMNS",
    "near_miss_name",
    "alias_risk",
]


# ---------------------------------------------------------------------- public


def read_session(path) -> Session:
    """
    Read a raw session folder (session.yaml and impacts.csv), without writing anything.

    Parameters
    ----------
    path : str or Path
        The session folder ``raw/<session_id>``; its name must equal ``session_id``.

    Returns
    -------
    Session
        Metadata (rates in [Hz], ADC range in [V], gate spacing [m], resolution [s],
        ball masses [kg]) and one :class:`ImpactRow` per impact, gate times in [s].
        Impact-level faults (missing/bad gate times, bad mass override, missing or
        escaping trace path, trace file not found) are listed in ``ImpactRow.problems``,
        as :class:`ballimpact.problems.Problem` (a kind and a message).

    Raises
    ------
    SessionError
        Session-level faults: every one found (session.yaml and impacts.csv are both
        checked), one line each naming the file, the key or line, and what is wrong;
        the lines are also in ``SessionError.problems``.

    Warns
    -----
    SessionWarning
        Usable but suspect metadata (mass outside 40-70 g, unknown keys or columns).
    """
    session_dir = Path(path)
    if not session_dir.is_dir():
        raise SessionError(f"{session_dir}: session folder not found")
    yaml_path = session_dir / SESSION_FILE
    collect = _Collector()
    data = collect(_load_yaml, yaml_path, str(yaml_path))
    meta = None
    if data is not None:
        meta = _parse_meta(data, session_dir.resolve().name, str(yaml_path), collect)
    # impacts.csv is checked too when session.yaml has problems (its ball keys only
    # when the balls section could be read), so that every problem is reported at once
    if meta is None and collect.balls is not None:
        meta_for_rows = _BallsOnly(collect.balls)
    else:
        meta_for_rows = meta
    impacts = None
    if yaml_path.is_file():  # without any session.yaml the folder is hardly a session
        impacts = collect(_read_impacts, session_dir, meta_for_rows)
    _raise_collected(collect.problems)
    return Session(path=session_dir, meta=meta, impacts=impacts)


@dataclass(frozen=True)
class _BallsOnly:
    """Stand-in for SessionMeta while session.yaml has problems: its ball types only."""

    balls: dict


def file_sha256(path) -> str:
    """
    SHA-256 digest of a file's bytes, for provenance in the archive.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    str
        Hex digest (64 characters).
    """
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


@dataclass(frozen=True)
class SessionPlan:
    """What a workflow needs to plan one session's jobs, read without ever raising.

    Attributes
    ----------
    path : Path
        The session folder.
    fault : str or None
        The session-level fault (one line naming file, key or line), None when
        the session can be processed.
    metadata : dict
        session.yaml as parsed ({} when it could not be read).
    balls : tuple of str
        Ball types that have impacts, in session.yaml order.
    n_impacts : int
        Rows of impacts.csv [-].
    trace_files : tuple of (Path or None)
        Per row, the existing trace file inside the session folder, None when
        the row's trace is missing, unreadable or escapes the folder (an
        impact-level fault that processing reports).
    present_files : tuple of Path
        session.yaml and impacts.csv where they exist (what a faulty session's
        validation depends on).
    warnings : tuple of str
        Messages of the SessionWarnings the reader gave.
    """

    path: Path
    fault: str | None
    metadata: dict
    balls: tuple[str, ...]
    n_impacts: int
    trace_files: tuple[Path | None, ...]
    present_files: tuple[Path, ...]
    warnings: tuple[str, ...] = ()


def plan_session(path) -> SessionPlan:
    """
    Read a session folder for planning: the reader's own checks, never an exception.

    A workflow calls this once per session when it builds its job graph, so
    one bad session (or one bad cell of it) can never stop another: a
    session-level fault comes back as ``fault``, an impact-level one as a
    ``None`` trace file.

    Parameters
    ----------
    path : str or Path
        The session folder ``raw/<session_id>``.

    Returns
    -------
    SessionPlan
        Ball types, impact count and trace files, or the fault.
    """
    session_dir = Path(path)
    present = tuple(p for p in (session_dir / SESSION_FILE, session_dir / IMPACTS_FILE) if _is_file(p))
    metadata: dict = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SessionWarning)
        try:
            metadata = _load_yaml(session_dir / SESSION_FILE, str(session_dir / SESSION_FILE))
            session = read_session(session_dir)
        except SessionError as exc:
            return SessionPlan(session_dir, _one_line(exc), metadata, (), 0, (), present,
                               tuple(_one_line(w.message) for w in caught))
    messages = tuple(_one_line(w.message) for w in caught if issubclass(w.category, SessionWarning))
    used = {row.ball for row in session.impacts}
    balls = tuple(key for key in session.meta.balls if key in used)
    traces = tuple(_existing_trace(session, row) for row in session.impacts)
    return SessionPlan(session_dir, None, metadata, balls, len(session.impacts), traces, present, messages)


def _existing_trace(session: Session, row: ImpactRow) -> Path | None:
    """The row's trace file when it exists inside the session folder, else None."""
    problems: list[Problem] = []
    _check_trace(row.trace, session.path, problems)
    return None if problems else session.trace_path(row)


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False
