"""The rule functions from a raw session to its impacts: the snapshot, chunks processed, the impacts collected."""

from __future__ import annotations

import dataclasses
import json
import math
from collections import Counter
from pathlib import Path

from . import __version__
from . import tables
from .atomic import atomic_path
from .pipeline_base import _check_int, _staging, _write_text_atomic, logger
from .pipeline_fit import mark_fit_outliers
from .problems import TRACE_FILE_KINDS, has_kind

__all__ = ["snapshot_session", "chunk_impact_ids", "process_chunk", "collect_impacts", "session_impacts"]

SNAPSHOT_FORMAT_VERSION = 1  # version of the work/session.json layout


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


def _joined(parts):
    """The per-impact datasets ``parts`` concatenated along ``impact``, their series NaN-padded to one length."""
    import xarray as xr

    sizes = {dim: max(part.sizes.get(dim, 1) for part in parts) for dim in ("sample", "raw_sample")}
    padded = []
    for part in parts:
        widths = {dim: (0, n - part.sizes[dim]) for dim, n in sizes.items() if dim in part.dims and part.sizes[dim] < n}
        padded.append(part.pad(widths) if widths else part)  # NaN padding of the series
    return xr.concat(padded, dim="impact", data_vars="all", coords="minimal", join="exact",
                     combine_attrs="drop_conflicts")


def _verdict_columns(ds) -> dict:
    """The verdict columns of ``ds`` (:data:`ballimpact.session_checks.VERDICT_COLUMNS` it holds) as lists of str."""
    from .session_checks import VERDICT_COLUMNS

    return {c: [str(v) for v in ds[c].values] for c in VERDICT_COLUMNS if c in ds}


def _with_columns(ds, columns: dict):
    """``ds`` with its per-impact text columns replaced by ``columns`` (name -> one value per impact)."""
    import numpy as np

    for c, values in columns.items():
        ds[c] = ("impact", np.array(values, dtype=object), ds[c].attrs if c in ds else {})
    return ds


def _with_session_plate(ds, session, order, mains_hz=None):
    """``ds`` with the impacts whose TC a plate's ringing, or a hum their own record could not resolve, withheld
    processed again with the plate and the mains frequency the session identified from all its impacts, as if
    stated, where that keeps their TC and COR (:mod:`ballimpact.session_plate`); the others as they were.
    ``session`` (:class:`ballimpact.session.Session`) is left as it is; ``mains_hz`` is config's (None: none)."""
    from . import archive, processing, session_plate

    columns = (ds["impact_id"].values, ds["contact_time_status"].values, ds["reason_code"].values)
    if not session_plate.retry_candidates(*columns, mains=True):
        return ds
    rig = _session_rig(ds, session.meta)
    plate = session_plate.session_plate(rig)
    mains = session_plate.session_mains(rig) if mains_hz is None and session.meta.mains_hz is None else None
    ids = session_plate.retry_candidates(*columns, plate=plate is not None, mains=mains is not None)
    if not ids:
        return ds
    given = mains_hz if mains_hz is not None else mains
    session = dataclasses.replace(session, meta=dataclasses.replace(
        session.meta, **({} if plate is None else {"plate_resonance": plate,
                                                   "plate_uncertainty": session_plate.session_plate_uncertainty(rig)}),
        **({} if given is None else {"mains_hz": float(given)})))
    kept = [r for r in processing.iter_process(session, impact_ids=ids)
            if r.contact_time_status == "ok" and r.cor_status == "ok"]
    if not kept:
        return ds
    rows = {row.impact_id: row for row in session.impacts}
    used = ", ".join(([f"plate ({plate[0]:.6g} Hz, damping ratio {plate[1]:.3g})"] if plate else [])
                     + ([f"mains ({mains:g} Hz)"] if mains else []))
    for r in kept:
        logger.info("%s (%s): TC kept with the session's %s", r.impact_id, r.ball, used)
    new = archive.impacts_dataset(kept, trace_info={r.impact_id: _trace_info(session, rows[r.impact_id])
                                                    for r in kept})
    replaced = {r.impact_id for r in kept}
    joined = _joined([ds.isel(impact=[k for k, i in enumerate(order) if i not in replaced]), new])
    position = {str(i): k for k, i in enumerate(joined["impact_id"].values)}
    return joined.isel(impact=[position[i] for i in order])


def collect_impacts(session_dir, chunk_ncs, out_csv, out_nc, *, mains_hz: float | None = None) -> None:
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
    ``used_in_fit``, ``fit_note``), so that impacts.csv carries them. First, the impacts whose TC
    a plate's ringing withheld are processed again with the plate the session identified from all
    its impacts (:mod:`ballimpact.session_plate`), where that keeps their TC.

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
    mains_hz : float or None, optional
        Mains frequency [Hz] the chunks were processed with (config ``mains_hz``); None keeps session.yaml's.

    Raises
    ------
    ValueError
        An impact missing from the chunks, given twice, or not in the raw impacts.csv.
    """
    from . import archive, processing, rig_archive
    from .session import read_session

    chunk_ncs = [Path(p) for p in chunk_ncs]
    if not chunk_ncs:
        raise ValueError("chunk_ncs must name at least one chunk file, got none")
    session = read_session(session_dir)
    order = [row.impact_id for row in session.impacts]
    ds = _joined([archive.open_dataset(p) for p in chunk_ncs])
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
    ds = _with_session_plate(ds.isel(impact=[position[i] for i in order]), session, order, mains_hz)
    # the session's checks (ballimpact.session_checks): one amplifier and one plate serve the session; an impact
    # unlike the others withholds what the finding can bias (its kCAL, or with the time constant its TC too)
    columns = _verdict_columns(ds)
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
    ds = _with_columns(ds, columns)
    ds.attrs["kcal_median_N_per_V"] = median
    ds.attrs["kcal_robust_sd_N_per_V"] = spread
    ds.attrs["time_constant_median_s"] = tau_median
    meta = session.meta
    rig = _session_rig(ds, meta)
    ds = _plate_overshoot_check(ds, rig)
    ds = mark_fit_outliers(ds, meta.balls)
    ds = ds.merge(rig_archive.rig_variables(rig))
    ds = archive.set_variable_attrs(ds)
    archive.write_dataset(ds, out_nc)
    table = archive.impacts_table(ds)
    with atomic_path(out_csv) as tmp:
        tables.write_csv(table, tmp)
    n_excluded = int((table["status"] == "excluded").sum())
    logger.info("collected %d impacts from %d chunks: %d ok, %d excluded",
                len(table), len(chunk_ncs), len(table) - n_excluded, n_excluded)


def _plate_overshoot_check(ds, rig):
    """``ds`` with the session plate check of the peak applied to its verdict columns
    (:func:`ballimpact.session_checks.plate_overshoot_columns`): the plate stated, or identified (its interval's low
    resonance, the larger bound)."""
    import numpy as np

    from . import session_checks
    from .rig_archive import floats_of

    fn, zeta = rig["plate_resonance_hz"], rig["plate_damping_ratio"]
    if fn.source == "none" or zeta.source == "none":
        return ds
    low = fn.low if fn.source == "identified" and np.isfinite(fn.low) else fn.value
    with np.errstate(invalid="ignore", divide="ignore"):
        peak_u = floats_of(ds, "peak_force_u_N") / floats_of(ds, "peak_force_N")
    columns = session_checks.plate_overshoot_columns(
        _verdict_columns(ds), ds["voltage_V"].values, floats_of(ds, "sample_rate_hz"), floats_of(ds, "noise_rms_V"), peak_u,
        floats_of(ds, "time_to_peak_ms"), np.isfinite(floats_of(ds, "plate_resonance_hz")), float(low),
        float(zeta.value))
    return _with_columns(ds, columns)


def _session_rig(ds, meta):
    """The session's rig identified from all its impacts (:func:`ballimpact.rig_archive.session_rig`); each warning
    (a stated key the traces disagree with) logged."""
    import warnings

    from .rig_archive import session_rig

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rig = session_rig(ds, meta)
    for w in caught:
        logger.warning("%s", w.message)
    for name, est in rig.estimates.items():
        if est.source == "identified" or est.note:
            logger.info("rig %s: %.6g [%.6g, %.6g] %s %s", name, est.value, est.low, est.high, est.source, est.note)
    return rig


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
        collect_impacts(session_dir, [chunk_nc], out_csv, out_nc, mains_hz=mains_hz)
