"""Thin functions called by the Snakemake rules: one per rule, explicit paths, atomic writes."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from . import tables
from .atomic import atomic_path
# FIGURE_STEMS: the PNG file stems make_figures writes into the figures folder; QC_DIR_NAME: its
# sub-folder of QC pages (both from the figure registry, where the workflow reads them too)
from .figure_registry import FIGURE_STEMS, QC_DIR_NAME
from .pipeline_base import _check_int, _staging, log_to_file, logger
from .pipeline_fit import fit_arrays, fit_ball, fit_balls, mark_fit_outliers  # noqa: F401
from .pipeline_impacts import (  # noqa: F401
    SNAPSHOT_FORMAT_VERSION,
    chunk_impact_ids,
    collect_impacts,
    process_chunk,
    session_impacts,
    snapshot_session,
)

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
