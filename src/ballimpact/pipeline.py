"""Thin functions called by the Snakemake rules: one per rule, explicit paths, atomic writes."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import math
import os
import shutil
import warnings
from collections import Counter
from pathlib import Path

from . import __version__
from .atomic import atomic_path
# FIGURE_STEMS: the PNG file stems make_figures writes into the figures folder; QC_DIR_NAME: its
# sub-folder of QC pages (both from the figure registry, where the workflow reads them too)
from .figure_registry import FIGURE_STEMS, QC_DIR_NAME
from .problems import TRACE_FILE_KINDS, has_kind
from . import tables

__all__ = [
    "FIGURE_STEMS",
    "log_to_file",
    "snapshot_session",
    "chunk_impact_ids",
    "process_chunk",
    "collect_impacts",
    "session_impacts",
    "fit_arrays",
    "fit_ball",
    "fit_balls",
    "write_archive",
    "make_figures",
    "make_report",
    "session_outputs",
]

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
    from .summary import clear_stale
    from .validation import validate_session

    # issue 14: the checks of `ballimpact validate` (trace headers only), so that its
    # warnings reach the run's output and summary; every session-level problem at once
    quick = validate_session(session_dir, read_traces=False)
    found = list(quick.causes) + list(quick.warnings)  # a cause behind many exclusions first
    for message in found:
        logger.warning("validate: %s", message)
    session = read_session(session_dir)
    root = session.path.resolve()
    files = {SESSION_FILE: session.path / SESSION_FILE, IMPACTS_FILE: session.path / IMPACTS_FILE}
    for row in session.impacts:
        if has_kind(row.problems, TRACE_FILE_KINDS):
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
        "impact_problems": {r.impact_id: [p.message for p in r.problems] for r in session.impacts if r.problems},
        "raw_sha256": raw_sha256,
        "warnings": found,
    }
    if Path(out_json).parent.name == "work":
        clear_stale(Path(out_json).parent.parent)  # results/<session>/ is processed again
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


def _trace_info(session, row) -> tuple[str, str]:
    """(trace path relative to the session folder, sha256) of a row; sha256 empty when unreadable."""
    if has_kind(row.problems, TRACE_FILE_KINDS):
        return row.trace, ""
    from .session import file_sha256

    path = session.trace_path(row)
    try:
        return path.resolve().relative_to(session.path.resolve()).as_posix(), file_sha256(path)
    except (OSError, ValueError):
        return row.trace, ""


def process_chunk(session_dir, chunk: int, n_chunks: int, out_nc, *, mains_hz: float | None = None) -> None:
    """
    Process impacts ``chunk, chunk + n_chunks, ...`` of a session into ``work/chunk_{chunk}.nc``.

    Rule ``process_chunk``. Impact-level faults exclude the impact only (it stays in
    the file with status ``excluded`` and the reason); one trace is in memory at a time.

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
    if mains_hz is not None and (isinstance(mains_hz, bool) or not (math.isfinite(mains_hz) and mains_hz > 0)):
        raise ValueError(f"mains_hz must be a positive number of Hz or None, got {mains_hz!r}")
    _check_int("n_chunks", n_chunks, 1)
    _check_int("chunk", chunk, 0)
    from . import archive, processing
    from .session import read_session

    session = read_session(session_dir)
    if mains_hz is not None:
        session.meta = dataclasses.replace(session.meta, mains_hz=float(mains_hz))
    ids = chunk_impact_ids([row.impact_id for row in session.impacts], chunk, n_chunks)
    rows = {row.impact_id: row for row in session.impacts}
    trace_info = {impact_id: _trace_info(session, rows[impact_id]) for impact_id in ids}

    def logged(results):
        for result in results:
            if result.status == "ok":
                logger.info("%s (%s): ok", result.impact_id, result.ball)
            else:
                logger.info("%s (%s): excluded: %s", result.impact_id, result.ball, result.reason)
            yield result

    ds = archive.impacts_dataset(logged(processing.iter_process(session, impact_ids=ids)), trace_info=trace_info)
    got = [str(i) for i in ds["impact_id"].values]
    if sorted(got) != sorted(ids):
        missing, extra = sorted(set(ids) - set(got)), sorted(set(got) - set(ids))
        raise RuntimeError(
            f"processing of chunk {chunk} of {n_chunks} returned the wrong impacts: "
            f"missing {missing[:10]}, unexpected {extra[:10]}"
        )
    Path(out_nc).parent.mkdir(parents=True, exist_ok=True)
    archive.write_dataset(ds, out_nc)
    logger.info("chunk %d of %d: %d impacts written to %s", chunk, n_chunks, len(ids), out_nc)


def _log_exclusions(order, before, status, reason, check: str) -> None:
    """Log each impact a session check excluded (its status went from ok to excluded), with the reason."""
    for impact_id, old, new, why in zip(order, before, status, reason):
        if old != new:
            logger.info("%s: excluded by the session %s check: %s", impact_id, check, why)


def collect_impacts(session_dir, chunk_ncs, out_csv, out_nc) -> None:
    """
    Join the chunk files into all impacts in raw order: ``impacts.csv`` and ``work/impacts.nc``.

    Rule ``collect_impacts``. Every impact of the raw impacts.csv must be in exactly
    one chunk (none dropped, none twice). The session kCAL check
    (:func:`ballimpact.processing.flag_calibration_outliers`) excludes impacts whose
    calibration factor is far from the session's typical value; the session median
    and robust standard deviation of kCAL [N/V] go into the file's attributes. Before
    it, the session time-constant check
    (:func:`ballimpact.processing.flag_time_constant_outliers`) excludes impacts whose
    amplifier time constant, estimated from the trace, is not the session's; the
    session's typical one [s] goes into ``time_constant_median_s``. Then
    the fit outliers of every ball type are named (:func:`mark_fit_outliers`:
    ``used_in_fit``, ``fit_note``), so that impacts.csv carries them.

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

    Raises
    ------
    ValueError
        An impact missing from the chunks, given twice, or not in the raw impacts.csv.
    """
    import numpy as np
    import xarray as xr

    from . import archive, processing
    from .session import read_session

    chunk_ncs = [Path(p) for p in chunk_ncs]
    if not chunk_ncs:
        raise ValueError("chunk_ncs must name at least one chunk file, got none")
    order = [row.impact_id for row in read_session(session_dir).impacts]
    parts = [archive.open_dataset(p) for p in chunk_ncs]
    sizes = {dim: max(part.sizes.get(dim, 1) for part in parts) for dim in ("sample", "raw_sample")}
    padded = []
    for part in parts:
        widths = {dim: (0, n - part.sizes[dim]) for dim, n in sizes.items() if dim in part.dims and part.sizes[dim] < n}
        padded.append(part.pad(widths) if widths else part)  # NaN padding of the series
    ds = xr.concat(padded, dim="impact", data_vars="all", coords="minimal", join="exact", combine_attrs="drop_conflicts")
    found = [str(i) for i in ds["impact_id"].values]
    position = {}
    for k, impact_id in enumerate(found):
        if impact_id in position:
            raise ValueError(f"impact {impact_id!r} is in more than one chunk file ({', '.join(map(str, chunk_ncs))})")
        position[impact_id] = k
    missing = [i for i in order if i not in position]
    extra = [i for i in found if i not in set(order)]
    if missing or extra:
        raise ValueError(
            f"chunk files do not match {Path(session_dir) / 'impacts.csv'}: "
            f"missing impacts {missing[:10]}, unknown impacts {extra[:10]} (re-run the chunks)"
        )
    ds = ds.isel(impact=[position[i] for i in order])
    # the session's checks (ballimpact.session_checks): one amplifier and one plate serve the session; an impact
    # unlike the others withholds what the finding can bias (its kCAL, or with the time constant its TC too)
    columns = {c: [str(v) for v in ds[c].values] if c in ds else None for c in processing.VERDICT_COLUMNS}
    columns = {c: v for c, v in columns.items() if v is not None}
    before = list(columns["status"])
    tau_names = ["amplifier_time_constant_s", "amplifier_time_constant_se_s", "amplifier_time_constant_source"]
    if all(name in ds for name in tau_names):
        columns, tau_median = processing.time_constant_outlier_columns(
            columns, *(ds[name].values for name in tau_names), ds["contact_time_ms"].values)
    else:  # chunk files written before the time constant was archived: re-run the chunks for the check
        logger.warning("chunk files without %s: the session time-constant check is skipped", ", ".join(tau_names))
        tau_median = float("nan")
    _log_exclusions(order, before, columns["status"], columns["reason"], "time-constant")
    before = list(columns["status"])
    columns, median, spread = processing.calibration_outlier_columns(columns, ds["kcal_N_per_V"].values)
    _log_exclusions(order, before, columns["status"], columns["reason"], "kCAL")
    for c, values in columns.items():
        ds[c] = ("impact", np.array(values, dtype=object), ds[c].attrs if c in ds else {})
    ds.attrs["kcal_median_N_per_V"] = median
    ds.attrs["kcal_robust_sd_N_per_V"] = spread
    ds.attrs["time_constant_median_s"] = tau_median
    meta = read_session(session_dir).meta
    ds = mark_fit_outliers(ds, meta.balls)
    ds = ds.merge(_session_rig_variables(ds, meta))
    ds = archive.set_variable_attrs(ds)
    archive.write_dataset(ds, out_nc)
    table = archive.impacts_table(ds)
    with atomic_path(out_csv) as tmp:
        tables.write_csv(table, tmp)
    n_excluded = int((table["status"] == "excluded").sum())
    logger.info("collected %d impacts from %d chunks: %d ok, %d excluded",
                len(table), len(chunk_ncs), len(table) - n_excluded, n_excluded)


def _session_rig_variables(ds, meta):
    """The session's rig identified from all its impacts (:func:`ballimpact.rig_archive.session_rig`), as archive
    variables; each warning (a stated key the traces disagree with) logged."""
    import warnings

    from .rig_archive import rig_variables, session_rig

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rig = session_rig(ds, meta)
    for w in caught:
        logger.warning("%s", w.message)
    for name, est in rig.estimates.items():
        if est.source == "identified" or est.note:
            logger.info("rig %s: %.6g [%.6g, %.6g] %s %s", name, est.value, est.low, est.high, est.source, est.note)
    return rig_variables(rig)


@contextlib.contextmanager
def _staging(folder: Path):
    """A job's hidden staging folder, removed when the job starts and when it ends.

    One fixed name per job: a run killed inside it leaves the folder behind, and
    the next run of the same job removes it first.
    """
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def session_impacts(session_dir, out_json, out_csv, out_nc, *, mains_hz: float | None = None) -> None:
    """
    Validate, process and collect a small session in one process.

    Rule ``session_impacts`` (a session of at most config ``fit_batch_impacts`` impacts
    processed as one chunk): :func:`snapshot_session`, :func:`process_chunk` (chunk 0 of
    1, into a temporary file) and :func:`collect_impacts` one after the other, the same
    calls as rules ``validate_session``, ``process_chunk`` and ``collect_impacts``, so
    the same files; it saves the start-up (Python and its imports) of two processes.

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder.
    out_json : str or Path
        The snapshot ``work/session.json`` to write.
    out_csv : str or Path
        ``impacts.csv`` to write.
    out_nc : str or Path
        ``work/impacts.nc`` to write.
    mains_hz : float or None, optional
        Mains frequency [Hz] to remove; None keeps session.yaml ``daq.mains_hz``.

    Raises
    ------
    ballimpact.session.SessionError
        A session-level fault, with a one-line message naming the file.
    """
    if mains_hz is not None and (isinstance(mains_hz, bool) or not (math.isfinite(mains_hz) and mains_hz > 0)):
        raise ValueError(f"mains_hz must be a positive number of Hz or None, got {mains_hz!r}")
    snapshot_session(session_dir, out_json)
    out_nc = Path(out_nc)
    out_nc.parent.mkdir(parents=True, exist_ok=True)
    with _staging(out_nc.parent / f".{out_nc.name}.chunk.tmp") as staging:
        chunk_nc = staging / "chunk_0.nc"
        process_chunk(session_dir, 0, 1, chunk_nc, mains_hz=mains_hz)
        collect_impacts(session_dir, [chunk_nc], out_csv, out_nc)


def _fit_mask(ds, ball: str):
    """Impacts of one ball type with status ok and positive vin, TC and COR (bool array)."""
    import numpy as np

    vin = np.asarray(ds["vin_m_s"].values, dtype=float)
    tc_s = np.asarray(ds["contact_time_ms"].values, dtype=float)
    cor = np.asarray(ds["cor"].values, dtype=float)
    with np.errstate(invalid="ignore"):
        return (
            (np.array([str(b) for b in ds["ball_type"].values]) == ball)
            & (np.array([str(v) for v in ds["status"].values]) == "ok")
            & (vin > 0) & (tc_s > 0) & (cor > 0)
        )


def mark_fit_outliers(ds, balls):
    """Name the fit outliers of every ball type: ``used_in_fit`` and ``fit_note`` per impact.

    :func:`ballimpact.fitting.detect_fit_outliers` on the ok impacts of each ball type
    (kB(0) from session.yaml when given). An impact it names keeps status ok, gets
    ``used_in_fit`` 0 and its residuals in ``fit_note``, and is left out of the fit by
    :func:`fit_arrays`. A ball type whose search fails keeps all its impacts (logged).

    Parameters
    ----------
    ds : xarray.Dataset
        Per-impact dataset (raw order).
    balls : mapping
        session.yaml ball types (``kb0_N_m`` [N/m] or None, ``mass_kg`` [kg]).

    Returns
    -------
    xarray.Dataset
        A copy with ``used_in_fit`` (int8: 1 used, 0 not) and ``fit_note`` (text).
    """
    import numpy as np

    from . import fitting

    ds = ds.copy()
    status = np.array([str(v) for v in ds["status"].values])
    used = (status == "ok").astype(np.int8)
    notes = np.array([""] * status.size, dtype=object)
    ids = [str(i) for i in ds["impact_id"].values]
    for ball, ball_type in balls.items():
        use = _fit_mask(ds, ball)
        if use.sum() < 1:
            continue
        arrays = _arrays_of(ds, use, ball_type.mass_kg)
        try:
            found = fitting.detect_fit_outliers(**arrays, kb0_N_m=ball_type.kb0_N_m)
        except (fitting.FitError, ValueError) as exc:
            logger.warning("ball %s: no search for fit outliers (%s); all ok impacts used", ball, exc)
            continue
        for k, i in enumerate(np.flatnonzero(use)):
            if not found.used[k]:
                used[i] = 0
                notes[i] = found.notes[k]
                logger.info("%s: left out of the %s fit: %s", ids[i], ball, found.notes[k])
        for msg in found.messages:
            logger.info("ball %s: %s", ball, msg)
    ds["used_in_fit"] = ("impact", used)
    ds["fit_note"] = ("impact", notes)
    return ds


def _arrays_of(ds, use, default_mass_kg: float) -> dict:
    import numpy as np

    mass = np.asarray(ds["impact_mass_kg"].values, dtype=float)
    mass = np.where(np.isfinite(mass) & (mass > 0), mass, default_mass_kg)
    vin = np.asarray(ds["vin_m_s"].values, dtype=float)
    tc_s = np.asarray(ds["contact_time_ms"].values, dtype=float) * 1e-3
    cor = np.asarray(ds["cor"].values, dtype=float)
    return {"vin_m_s": vin[use], "contact_time_s": tc_s[use], "cor": cor[use], "mass_kg": mass[use]}


def fit_arrays(ds, ball: str, default_mass_kg: float) -> dict:
    """The good impacts of one ball type, as the keyword arguments of ``fit_ball_model``.

    Parameters
    ----------
    ds : xarray.Dataset
        Per-impact dataset (``work/impacts.nc`` or the archive).
    ball : str
        Ball type key.
    default_mass_kg : float
        The ball type's mass [kg], used where an impact has none.

    Returns
    -------
    dict
        ``vin_m_s`` [m/s], ``contact_time_s`` [s], ``cor`` [-], ``mass_kg`` [kg] of the
        impacts with status ok and positive values, fit outliers (``used_in_fit`` 0,
        :func:`mark_fit_outliers`) left out.
    """
    import numpy as np

    use = _fit_mask(ds, ball)
    if "used_in_fit" in ds.variables:
        use &= np.asarray(ds["used_in_fit"].values).astype(float) > 0
    return _arrays_of(ds, use, default_mass_kg)


def fit_ball(impacts_nc, ball: str, session_dir, out_nc, *, n_bootstrap: int, seed: int) -> None:
    """
    Fit the ball model (kB(0), AK, a, AC) to the ok impacts of one ball type.

    Rule ``fit_ball``: :func:`ballimpact.fitting.fit_ball_model` on the impacts with
    status ok that are not fit outliers (named by :func:`mark_fit_outliers` in rule
    ``collect_impacts``; their ids go into ``fit_message``, their count into
    ``n_fit_outliers``), kB(0) fixed when session.yaml gives ``kb0_kN_m``, else
    extrapolated (or fitted, when impacts reach below 10 m/s).
    A ball whose fit fails (e.g. fewer than 3 ok impacts) still gets a file, with NaN
    parameters and the reason in ``fit_message``, so the rest of the session goes on.

    Parameters
    ----------
    impacts_nc : str or Path
        ``work/impacts.nc`` of the session.
    ball : str
        Ball type key (session.yaml ``balls``).
    session_dir : str or Path
        The raw session folder (label, mass and an optional fixed kB(0) of the ball type).
    out_nc : str or Path
        ``work/fit_{ball}.nc`` to write (atomically).
    n_bootstrap : int
        Bootstrap resamples for the 95 % intervals, >= 0 (0: no intervals).
    seed : int
        Seed of the bootstrap random number generator, >= 0.
    """
    _check_int("n_bootstrap", n_bootstrap, 0)
    _check_int("seed", seed, 0)
    from . import archive
    from .session import read_session

    fit_ds = _fit_ball_dataset(archive.open_dataset(impacts_nc), ball, read_session(session_dir),
                               n_bootstrap=n_bootstrap, seed=seed)
    Path(out_nc).parent.mkdir(parents=True, exist_ok=True)
    archive.write_dataset(fit_ds, out_nc)


def _fit_ball_dataset(impacts, ball: str, session, *, n_bootstrap: int, seed: int):
    """The dataset :func:`fit_ball` writes (one ball type on dim ``ball``), from the
    impacts already read (``work/impacts.nc``) and the session (:func:`ballimpact.session.read_session`)."""
    from . import archive, fitting

    if ball not in session.meta.balls:
        raise ValueError(
            f"ball {ball!r} is not defined in {session.path / 'session.yaml'} balls "
            f"(defined: {', '.join(session.meta.balls)})"
        )
    ball_type = session.meta.balls[ball]
    arrays = fit_arrays(impacts, ball, ball_type.mass_kg)
    n_used = arrays["vin_m_s"].size
    kb0_source = "config" if ball_type.kb0_N_m is not None else "extrapolated"
    vin_used = arrays["vin_m_s"]
    itf_kw = {  # v1.1: the fitted speed range (curves beyond it are extrapolated) and the ITF drop test
        "fit_vin_range_m_s": (float(vin_used.min()), float(vin_used.max())) if vin_used.size else (math.nan, math.nan),
        "itf_rebound_cm": ball_type.itf_rebound_cm, "diameter_m": ball_type.diameter_m,
        "air_density_kg_m3": session.meta.air_density_kg_m3,
    }
    outliers = []
    if "used_in_fit" in impacts.variables:
        left_out = _fit_mask(impacts, ball) & ~(impacts["used_in_fit"].values.astype(float) > 0)
        outliers = [str(i) for i in impacts["impact_id"].values[left_out]]
    try:
        # the fit outliers were named (and left out) when the impacts were collected
        fit = fitting.fit_ball_model(
            **arrays, kb0_N_m=ball_type.kb0_N_m, n_bootstrap=n_bootstrap, seed=seed, detect_outliers=False,
        )
    except fitting.FitError as exc:
        logger.warning("ball %s: fit failed with %d ok impacts: %s", ball, n_used, exc)
        fit_ds = archive.fit_dataset(
            ball, None, label=ball_type.label, mass_kg=ball_type.mass_kg, n_impacts=n_used,
            kb0_source=kb0_source, message=f"fit failed: {exc}", **itf_kw,
        )
    else:
        logger.info(
            "ball %s: %d impacts, kB(0) %.4g kN/m (%s), AK %.4g, a %.4g, AC %.4g kN s/m3; %s",
            ball, fit.n_impacts, fit.kb0_N_m / 1e3, fit.kb0_source, fit.ak / 1e3, fit.a, fit.ac / 1e3,
            "; ".join(fit.messages) or "no warnings",
        )
        fit_ds = archive.fit_dataset(
            ball, fit, label=ball_type.label,
            message=f"fit outliers left out: {', '.join(outliers)}" if outliers else "",
            **itf_kw,
        )
    fit_ds["n_fit_outliers"] = ("ball", [len(outliers)])
    return archive.set_variable_attrs(fit_ds)


def fit_balls(impacts_nc, balls, session_dir, out_nc, *, n_bootstrap: int, seed: int) -> None:
    """
    Fit every ball type of a small session in one process: :func:`fit_ball` for each, one file.

    Rule ``fit_session`` (sessions of at most config ``fit_batch_impacts`` impacts):
    the same fits as one ``fit_ball`` job per ball type, with the same seed, so the
    same numbers; it saves the start-up of a process per ball type. The per-ball
    datasets (what ``fit_ball`` writes) are joined in memory on the ``ball``
    dimension, in the order given, into one file that rule ``archive`` takes in
    place of the per-ball files; the impacts are read once.

    Parameters
    ----------
    impacts_nc : str or Path
        ``work/impacts.nc`` of the session.
    balls : sequence of str
        Ball type keys with impacts in the session, in session.yaml order.
    session_dir : str or Path
        The raw session folder.
    out_nc : str or Path
        ``work/fits.nc`` to write (atomically).
    n_bootstrap : int
        Bootstrap resamples for the 95 % intervals, >= 0.
    seed : int
        Seed of the bootstrap random number generator, >= 0.
    """
    import xarray as xr

    from . import archive
    from .session import read_session

    _check_int("n_bootstrap", n_bootstrap, 0)
    _check_int("seed", seed, 0)
    balls = [str(b) for b in balls]
    if not balls:
        raise ValueError("balls must name at least one ball type, got none")
    out_nc = Path(out_nc)
    out_nc.parent.mkdir(parents=True, exist_ok=True)
    # the staging folder of earlier versions (one file per ball type), left by a killed run
    shutil.rmtree(out_nc.parent / f".{out_nc.name}.fits.tmp", ignore_errors=True)
    # the impacts and session.yaml are read once, and each ball type's dataset (the one
    # fit_ball writes) is joined in memory: no file per ball type
    impacts = archive.open_dataset(impacts_nc)
    session = read_session(session_dir)
    parts = [_fit_ball_dataset(impacts, ball, session, n_bootstrap=n_bootstrap, seed=seed) for ball in balls]
    joined = xr.concat(parts, dim="ball", data_vars="minimal", coords="minimal", compat="override",
                       join="exact", combine_attrs="drop_conflicts")
    archive.write_dataset(joined, out_nc)
    logger.info("fits of %d ball types (%s) written to %s", len(balls), ", ".join(balls), out_nc)


def write_archive(session_dir, impacts_nc, fit_ncs, out_nc, out_parameters_csv, snapshot_json=None) -> None:
    """
    Write the session archive ``<session_id>.nc`` and ``parameters.csv``.

    Rule ``archive``: impacts + every fit + the model forces + global attributes
    (session.yaml text, sha256 of every raw file).

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
    snapshot_json : str or Path, optional
        ``work/session.json`` (:func:`snapshot_session`): its warnings (those of ``ballimpact
        validate``) go into the archive's ``validate_warnings`` attribute, and so into the report.
        None: no warnings are stored.
    """
    from . import archive
    from .session import IMPACTS_FILE, SESSION_FILE, file_sha256, read_session

    session = read_session(session_dir)
    impacts = archive.open_dataset(impacts_nc)
    fits = [archive.open_dataset(p) for p in fit_ncs]
    ds = archive.assemble_archive(impacts, fits)
    raw_sha256 = {name: file_sha256(session.path / name) for name in (SESSION_FILE, IMPACTS_FILE)}
    # trace hashes were taken when the traces were read (rule process_chunk)
    for trace_file, sha in zip(ds["trace_file"].values, ds["trace_sha256"].values):
        if trace_file and sha:
            raw_sha256[str(trace_file)] = str(sha)
    ds = archive.add_metadata(
        ds,
        session_id=session.meta.session_id,
        session_yaml_text=(session.path / SESSION_FILE).read_text(encoding="utf-8-sig"),
        raw_sha256=raw_sha256,
        synthetic=session.meta.synthetic,
        history=f"ballimpact workflow, rule archive (ballimpact.pipeline.write_archive) from {session.path}",
        validate_warnings=(json.loads(Path(snapshot_json).read_text(encoding="utf-8")).get("warnings", [])
                           if snapshot_json is not None else ()),
    )
    Path(out_nc).parent.mkdir(parents=True, exist_ok=True)
    archive.write_dataset(ds, out_nc)
    with atomic_path(out_parameters_csv) as tmp:
        tables.write_csv(archive.parameters_table(ds), tmp)
    logger.info("archive %s: %d impacts, %d ball types", out_nc, ds.sizes.get("impact", 0), ds.sizes.get("ball", 0))


def make_figures(archive_nc, out_dir, *, ds=None, images: dict | None = None) -> None:
    """
    Draw every report figure from the archive as PNG into ``out_dir``.

    Rule ``figures``: writes ``<stem>.png`` for each of :data:`FIGURE_STEMS` and the
    folder ``qc/`` with one QC page per excluded impact. Everything is drawn into a
    temporary folder inside ``out_dir`` first and then moved into place, so an
    interrupted run leaves no half-written figure or QC folder.

    Parameters
    ----------
    archive_nc : str or Path
        The session archive.
    out_dir : str or Path
        The figures folder ``results/<session_id>/figures``.
    ds : xarray.Dataset, optional
        The archive as read from ``archive_nc`` already (not read again).
    images : dict, optional
        Filled with the pixels of every PNG written, by path relative to ``out_dir``
        (:func:`ballimpact.figures.save_all`), for :func:`make_report`.
    """
    from . import archive, figures

    if ds is None:
        ds = archive.open_dataset(archive_nc)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with _staging(out_dir / ".figures.tmp") as staging:
        figures.save_all(ds, staging, images=images)
        for stem in FIGURE_STEMS:
            os.replace(staging / f"{stem}.png", out_dir / f"{stem}.png")
        qc = out_dir / QC_DIR_NAME
        if qc.exists():
            shutil.rmtree(qc)
        os.replace(staging / QC_DIR_NAME, qc)
    logger.info("figures: %d PNG files and %d QC pages in %s", len(FIGURE_STEMS),
                len(list((out_dir / QC_DIR_NAME).glob("*.png"))), out_dir)


def make_report(archive_nc, figures_dir, out_pdf, *, ds=None, images: dict | None = None) -> None:
    """
    Write the session report (PDF) from the archive and the figures.

    Rule ``report``.

    Parameters
    ----------
    archive_nc : str or Path
        The session archive.
    figures_dir : str or Path
        The figures folder written by :func:`make_figures` (its PNG files are placed
        on the pages).
    out_pdf : str or Path
        ``report.pdf`` to write (atomically).
    ds : xarray.Dataset, optional
        The archive as read from ``archive_nc`` already (not read again).
    images : dict, optional
        The pixels of the PNG files as :func:`make_figures` kept them: placed on the
        pages instead of decoding the files again.
    """
    from . import archive, report

    if ds is None:
        ds = archive.open_dataset(archive_nc)
    Path(out_pdf).parent.mkdir(parents=True, exist_ok=True)
    report.write_report(ds, out_pdf, figures_dir=figures_dir, images=images)
    logger.info("report %s: %d pages", out_pdf, report.report_page_count(ds))


def session_outputs(session_dir, impacts_nc, balls, out_fits_nc, out_nc, out_parameters_csv, figures_dir, out_pdf,
                    *, n_bootstrap: int, seed: int, snapshot_json=None) -> None:
    """
    Fits, archive, figures and report of a small session in one process.

    Rule ``session_outputs`` (sessions of at most config ``fit_batch_impacts`` impacts):
    :func:`fit_balls`, :func:`write_archive`, :func:`make_figures` and
    :func:`make_report` one after the other, the same calls as rules ``fit_session``,
    ``archive``, ``figures`` and ``report``, so the same files and numbers; it saves
    the start-up (Python and its imports) of three processes per session, a reading of
    the archive and the decoding of the PNG files for the report.

    Parameters
    ----------
    session_dir : str or Path
        The raw session folder.
    impacts_nc : str or Path
        ``work/impacts.nc`` of the session.
    balls : sequence of str
        Ball type keys with impacts in the session, in session.yaml order.
    out_fits_nc : str or Path
        ``work/fits.nc`` to write (the file of rule ``fit_session``).
    out_nc : str or Path
        The archive ``<session_id>.nc`` to write.
    out_parameters_csv : str or Path
        ``parameters.csv`` to write.
    figures_dir : str or Path
        The figures folder (``<stem>.png`` and ``qc/``).
    out_pdf : str or Path
        ``report.pdf`` to write.
    n_bootstrap : int
        Bootstrap resamples for the 95 % intervals, >= 0.
    seed : int
        Seed of the bootstrap random number generator, >= 0.
    snapshot_json : str or Path, optional
        ``work/session.json``, whose warnings the archive keeps (:func:`write_archive`).
    """
    _check_int("n_bootstrap", n_bootstrap, 0)
    _check_int("seed", seed, 0)
    fit_balls(impacts_nc, balls, session_dir, out_fits_nc, n_bootstrap=n_bootstrap, seed=seed)
    write_archive(session_dir, impacts_nc, [out_fits_nc], out_nc, out_parameters_csv, snapshot_json=snapshot_json)
    # the archive is read once for the figures and the report, and the figures' pixels go
    # to the report in memory: the same pages as rule report, which reads the PNG files
    from . import archive

    ds = archive.open_dataset(out_nc)
    images: dict = {}
    make_figures(out_nc, figures_dir, ds=ds, images=images)
    make_report(out_nc, figures_dir, out_pdf, ds=ds, images=images)
