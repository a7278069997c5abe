"""The fitting rules' functions: the fit outliers named, a ball type's fit arrays, one or every ball type fitted."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

from .pipeline_base import _check_int, logger

__all__ = ["fit_arrays", "fit_ball", "fit_balls"]


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
