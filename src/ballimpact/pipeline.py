"""Thin functions called by the Snakemake rules: one per rule, explicit paths, atomic writes."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import shutil
import tempfile
import warnings
from collections import Counter
from pathlib import Path

from . import __version__

__all__ = [
    "FIGURE_STEMS",
    "log_to_file",
    "atomic_path",
    "atomic_dir",
    "snapshot_session",
    "process_chunk",
    "collect_impacts",
    "fit_ball",
    "write_archive",
    "make_figures",
    "make_report",
]

#: PNG file stems that :func:`make_figures` writes into the figures folder (the
#: workflow's rule ``figures`` lists the same names in workflow/rules/common.smk).
FIGURE_STEMS = (
    "fig7_contact_time_cor",
    "fig8_stiffness",
    "fig9_force_curves",
    "fig10_components",
    "fig2b_kelvin_voigt",
    "kcal",
)
QC_DIR_NAME = "qc"  # sub-folder of the figures folder with one QC page per impact

SNAPSHOT_FORMAT_VERSION = 1  # version of the work/session.json layout

logger = logging.getLogger(__name__)


# ------------------------------------------------------------------ logging, atomic writes


@contextlib.contextmanager
def log_to_file(log_path):
    """
    Send logging and warnings to a rule's log file while the block runs.

    A :class:`ballimpact.session.SessionError` (a session-level fault) is logged and
    turned into ``SystemExit`` with its one-line message, so Snakemake shows that line
    instead of a traceback; any other exception is logged with its traceback and
    re-raised.

    Parameters
    ----------
    log_path : str or Path
        The log file (created or truncated).

    Yields
    ------
    logging.Logger
        The ``ballimpact`` logger.
    """
    from .session import SessionError

    log_path = Path(log_path)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    handler = logging.FileHandler(log_path, mode="w", encoding="utf-8")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    root = logging.getLogger()
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(logging.INFO)
    logging.captureWarnings(True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")  # every suspect-input warning reaches the log
            yield logging.getLogger("ballimpact")
    except SessionError as exc:
        logging.getLogger("ballimpact").error("session-level fault: %s", exc)
        raise SystemExit(f"error: {exc}") from None
    except BaseException:
        logging.getLogger("ballimpact").exception("failed")
        raise
    finally:
        logging.captureWarnings(False)
        root.removeHandler(handler)
        root.setLevel(old_level)
        handler.close()


@contextlib.contextmanager
def atomic_path(path):
    """
    Write a file atomically: yield a temporary path in the same folder, then rename it.

    The temporary file keeps the target's suffix (writers that infer the format from
    it, such as matplotlib or xarray, work unchanged). On an exception the temporary
    file is removed and the target is left untouched.

    Parameters
    ----------
    path : str or Path
        The final file.

    Yields
    ------
    Path
        The temporary file to write (it does not exist yet).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    tmp.unlink()  # writers create it themselves (some refuse to overwrite)
    try:
        yield tmp
        if not tmp.exists():
            raise RuntimeError(f"{path}: nothing was written to the temporary file {tmp}")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


@contextlib.contextmanager
def atomic_dir(path):
    """
    Fill a folder atomically: yield an empty temporary folder beside it, then rename it.

    Parameters
    ----------
    path : str or Path
        The final folder; an existing one is replaced.

    Yields
    ------
    Path
        The temporary folder to fill.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    try:
        yield tmp
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)


def _write_text_atomic(path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _check_int(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return value


# ------------------------------------------------------------------------ rule functions


def snapshot_session(session_dir, out_json) -> dict:
    """
    Read a raw session and record what was read: counts and the sha256 of every raw file.

    Rule ``validate_session``. Session-level faults stop the session here.

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder ``raw/<session_id>``.
    out_json : str or Path
        The snapshot ``work/session.json`` to write (atomically).

    Returns
    -------
    dict
        The snapshot: ``session_id``, ``n_impacts``, ``impacts_per_ball``,
        ``impact_problems`` (impact-level faults found while reading, by impact id)
        and ``raw_sha256`` (path relative to the session folder -> sha256 of the file:
        session.yaml, impacts.csv and every trace file that exists).

    Raises
    ------
    ballimpact.session.SessionError
        A session-level fault, with a one-line message naming the file.
    """
    from .session import IMPACTS_FILE, SESSION_FILE, file_sha256, read_session

    session = read_session(session_dir)
    root = session.path.resolve()
    files = {SESSION_FILE: session.path / SESSION_FILE, IMPACTS_FILE: session.path / IMPACTS_FILE}
    for row in session.impacts:
        if any(p.startswith(("missing trace path", "trace ")) for p in row.problems):
            continue  # no readable trace file inside the session folder
        trace = session.trace_path(row)
        if trace.is_file():
            files[trace.resolve().relative_to(root).as_posix()] = trace
    raw_sha256 = {name: file_sha256(path) for name, path in sorted(files.items())}
    per_ball = Counter(row.ball for row in session.impacts)
    snapshot = {
        "format_version": SNAPSHOT_FORMAT_VERSION,
        "software_version": __version__,
        "session_id": session.meta.session_id,
        "synthetic": session.meta.synthetic,
        "n_impacts": len(session.impacts),
        "impacts_per_ball": {key: per_ball[key] for key in session.meta.balls if per_ball[key]},
        "impact_problems": {r.impact_id: list(r.problems) for r in session.impacts if r.problems},
        "raw_sha256": raw_sha256,
    }
    _write_text_atomic(out_json, json.dumps(snapshot, indent=2, sort_keys=True) + "\n")
    logger.info(
        "session %s: %d impacts (%s), %d with problems found while reading, %d raw files hashed",
        snapshot["session_id"],
        snapshot["n_impacts"],
        ", ".join(f"{k}: {n}" for k, n in snapshot["impacts_per_ball"].items()),
        len(snapshot["impact_problems"]),
        len(raw_sha256),
    )
    return snapshot


def chunk_impact_ids(impact_ids, chunk: int, n_chunks: int) -> list:
    """
    Impact ids of one chunk: rows ``chunk, chunk + n_chunks, ...`` in raw order.

    Parameters
    ----------
    impact_ids : sequence of str
        All impact ids of the session, in raw order.
    chunk : int
        Chunk index, 0 <= chunk < n_chunks.
    n_chunks : int
        Number of chunks of the session, >= 1.

    Returns
    -------
    list of str
    """
    _check_int("n_chunks", n_chunks, 1)
    _check_int("chunk", chunk, 0)
    if chunk >= n_chunks:
        raise ValueError(f"chunk must be smaller than n_chunks ({n_chunks}), got {chunk}")
    return list(impact_ids)[chunk::n_chunks]


def process_chunk(session_dir, chunk: int, n_chunks: int, out_nc, *, mains_hz: float | None = None) -> None:
    """
    Process impacts ``chunk, chunk + n_chunks, ...`` of a session into ``work/chunk_{chunk}.nc``.

    Rule ``process_chunk``. Impact-level faults exclude the impact only (it stays in
    the file with status ``excluded`` and the reason).

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder.
    chunk : int
        Chunk index, 0 <= chunk < n_chunks.
    n_chunks : int
        Number of chunks of the session.
    out_nc : str or Path
        The chunk file to write (atomically).
    mains_hz : float or None, optional
        Mains frequency [Hz] to remove; None keeps session.yaml ``daq.mains_hz``.
    """
    _check_int("n_chunks", n_chunks, 1)
    _check_int("chunk", chunk, 0)
    if chunk >= n_chunks:
        raise ValueError(f"chunk must be smaller than n_chunks ({n_chunks}), got {chunk}")
    if mains_hz is not None and not (math.isfinite(mains_hz) and mains_hz > 0):
        raise ValueError(f"mains_hz must be a positive number of Hz or None, got {mains_hz!r}")
    # TODO(lead): needs ballimpact.processing (iter_process) and a per-impact results ->
    # xarray.Dataset writer (ballimpact.archive); the session's mains_hz is replaced by
    # dataclasses.replace(session.meta, mains_hz=mains_hz) when mains_hz is given.
    raise NotImplementedError("process_chunk waits for ballimpact.processing and ballimpact.archive")


def collect_impacts(session_dir, chunk_ncs, out_csv, out_nc) -> None:
    """
    Join the chunk files into all impacts in raw order: ``impacts.csv`` and ``work/impacts.nc``.

    Rule ``collect_impacts``; adds the session's kCAL QC.

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder (gives the raw order of the impacts).
    chunk_ncs : sequence of str or Path
        Every ``work/chunk_{i}.nc`` of the session.
    out_csv : str or Path
        ``impacts.csv`` to write (atomically), columns of outputs.md.
    out_nc : str or Path
        ``work/impacts.nc`` to write (atomically).
    """
    if not list(chunk_ncs):
        raise ValueError("chunk_ncs must name at least one chunk file, got none")
    # TODO(lead): needs ballimpact.processing (IMPACT_COLUMNS) and ballimpact.archive
    # (concatenate chunk datasets, reorder to raw order, kCAL QC).
    raise NotImplementedError("collect_impacts waits for ballimpact.processing and ballimpact.archive")


def fit_ball(impacts_nc, ball: str, session_dir, out_nc, *, n_bootstrap: int, seed: int) -> None:
    """
    Fit the ball model (kB(0), AK, a, AC) to the ok impacts of one ball type.

    Rule ``fit_ball``.

    Parameters
    ----------
    impacts_nc : str or Path
        ``work/impacts.nc`` of the session.
    ball : str
        Ball type key (session.yaml ``balls``).
    session_dir : str or Path
        The raw session folder (mass and an optional fixed kB(0) of the ball type).
    out_nc : str or Path
        ``work/fit_{ball}.nc`` to write (atomically).
    n_bootstrap : int
        Bootstrap resamples for the 95 % intervals, >= 0.
    seed : int
        Seed of the bootstrap random number generator, >= 0.
    """
    _check_int("n_bootstrap", n_bootstrap, 0)
    _check_int("seed", seed, 0)
    if not ball:
        raise ValueError("ball must be a ball type key, got an empty string")
    # TODO(lead): needs ballimpact.fitting (fit_ball_model) and ballimpact.archive (fit dataset).
    raise NotImplementedError("fit_ball waits for ballimpact.fitting and ballimpact.archive")


def write_archive(session_dir, impacts_nc, fit_ncs, out_nc, out_parameters_csv) -> None:
    """
    Write the session archive ``<session_id>.nc`` and ``parameters.csv``.

    Rule ``archive``: impacts + every fit + global attributes (provenance, raw sha256).

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder (session.yaml text and raw file hashes for the attributes).
    impacts_nc : str or Path
        ``work/impacts.nc``.
    fit_ncs : sequence of str or Path
        Every ``work/fit_{ball}.nc`` of the session.
    out_nc : str or Path
        The archive to write (atomically).
    out_parameters_csv : str or Path
        ``parameters.csv`` to write (atomically), one row per ball type.
    """
    # TODO(lead): needs ballimpact.archive.
    raise NotImplementedError("write_archive waits for ballimpact.archive")


def make_figures(archive_nc, out_dir) -> None:
    """
    Draw every report figure from the archive as PNG into ``out_dir``.

    Rule ``figures``: writes ``<stem>.png`` for each of :data:`FIGURE_STEMS` and the
    folder ``qc/`` with one QC page per impact.

    Parameters
    ----------
    archive_nc : str or Path
        The session archive.
    out_dir : str or Path
        The figures folder ``results/<session_id>/figures``.
    """
    # TODO(lead): needs ballimpact.figures; write each PNG through atomic_path and the
    # QC pages through atomic_dir(Path(out_dir) / QC_DIR_NAME).
    raise NotImplementedError("make_figures waits for ballimpact.figures")


def make_report(archive_nc, figures_dir, out_pdf) -> None:
    """
    Write the session report (PDF) from the archive and the figures.

    Rule ``report``.

    Parameters
    ----------
    archive_nc : str or Path
        The session archive.
    figures_dir : str or Path
        The figures folder written by :func:`make_figures`.
    out_pdf : str or Path
        ``report.pdf`` to write (atomically).
    """
    # TODO(lead): needs ballimpact.report.
    raise NotImplementedError("make_report waits for ballimpact.report")
