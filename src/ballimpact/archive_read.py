"""Reading a session archive: ball types, per-ball values, parameters with intervals, impacts by ball and status."""

from __future__ import annotations

import json

import numpy as np

__all__ = [
    "PARAMETER_INTERVALS",
    "text_values",
    "balls",
    "ball_value",
    "ball_array",
    "ball_label",
    "parameter",
    "fitted_parameters",
    "impacts",
    "impact_value",
    "impact_position",
    "contact_series",
    "excluded_impacts",
    "validate_warnings",
]

#: Archive variable of each parameter with an interval -> stem of its ``<stem>_lo`` and
#: ``<stem>_hi`` variables (the 95 % interval, same units as the parameter).
PARAMETER_INTERVALS = {
    "kb0_kN_m": "kb0",
    "ak_kN_m": "ak",
    "a": "a",
    "ac_kN_s_m3": "ac",
    "kb_10mm_kN_m": "kb_10mm",
    "kb_20mm_kN_m": "kb_20mm",
    "itf_rebound_pred_cm": "itf_rebound_pred_cm",
}


def text_values(values) -> np.ndarray:
    """Text of an archive variable as a flat object array of str (None becomes "").

    Parameters
    ----------
    values : array-like
        Values of a text variable (or anything printable).

    Returns
    -------
    numpy.ndarray
        One-dimensional object array of str.
    """
    return np.array(["" if v is None else str(v) for v in np.asarray(values).ravel()], dtype=object)


def _ball_type_name(ds) -> str:
    """The variable of each impact's ball type: ``ball_type``, ``impact_ball`` in archives before version 1.2."""
    return "impact_ball" if "impact_ball" in ds.variables and "ball_type" not in ds.variables else "ball_type"


def balls(ds) -> list[str]:
    """Ball type keys of an archive: the ``ball`` coordinate, then any ball seen only in the impacts.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive (or its per-impact part).

    Returns
    -------
    list of str
        Keys in archive order.
    """
    keys = list(text_values(ds["ball"].values)) if "ball" in ds.coords else []
    if _ball_type_name(ds) in ds:
        for b in text_values(ds[_ball_type_name(ds)].values):
            if b not in keys:
                keys.append(b)
    return keys


def _ball_index(ds, ball) -> int | None:
    if "ball" not in ds.coords:
        return None
    idx = np.flatnonzero(text_values(ds["ball"].values) == ball)
    return int(idx[0]) if idx.size else None


def ball_value(ds, name: str, ball: str, default=np.nan):
    """One per-ball value of the archive, in the variable's own units (see its ``units`` attribute).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    name : str
        Per-ball variable, e.g. ``n_impacts`` or ``kb0_kN_m`` [kN/m].
    ball : str
        Ball type key.
    default : object
        Returned when the ball or the variable is not in the archive.

    Returns
    -------
    object
        The stored value (number or str).
    """
    i = _ball_index(ds, ball)
    if i is None or name not in ds:
        return default
    return ds[name].values[i]


def ball_array(ds, name: str, ball: str) -> np.ndarray | None:
    """A per-ball curve of the archive (e.g. ``model_cor`` over ``speed``) as floats, None when absent.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    name : str
        Variable on (ball, speed), (ball, model_time) or (ball, stiffness_x), in its own units.
    ball : str
        Ball type key.

    Returns
    -------
    numpy.ndarray or None
    """
    i = _ball_index(ds, ball)
    if i is None or name not in ds:
        return None
    return np.asarray(ds[name].values[i], dtype=float)


def ball_label(ds, ball: str) -> str:
    """The ball type's label for figures (``ball_label``), or its key when it has none."""
    label = ball_value(ds, "ball_label", ball, default="")
    label = "" if label is None else str(label)
    return label if label and label != "nan" else str(ball)


def parameter(ds, name: str, ball: str) -> tuple[float, float, float]:
    """A fitted parameter of one ball type with its 95 % interval, in the archive's units.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    name : str
        A key of :data:`PARAMETER_INTERVALS`, e.g. ``ak_kN_m`` (AK of Eq. (4) in
        Goodwill & Haake 2004 [kN m^-(1+a)]), ``a`` [-], ``ac_kN_s_m3`` (AC of
        Eq. (7) [kN s/m^3]) or ``kb0_kN_m`` [kN/m].
    ball : str
        Ball type key.

    Returns
    -------
    tuple of float
        (value, lower end, upper end); NaN where the archive has no value.
    """
    if name not in PARAMETER_INTERVALS:
        raise ValueError(f"parameter must be one of {sorted(PARAMETER_INTERVALS)}, got {name!r}")
    stem = PARAMETER_INTERVALS[name]
    return tuple(float(ball_value(ds, n, ball)) for n in (name, f"{stem}_lo", f"{stem}_hi"))


def fitted_parameters(ds, ball: str) -> tuple[float, float, float, float, float] | None:
    """The fitted model parameters of one ball type in SI units, None when missing or failed.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive with the per-ball variables.
    ball : str
        Ball type key.

    Returns
    -------
    tuple of float or None
        (mass [kg], kB(0) [N/m], AK [N m^-(1+a)], a [-], AC [N s/m^3]) of Eqs. (4)
        and (7) in Goodwill & Haake 2004; None when any is missing, NaN or negative,
        or the mass or a is not positive.
    """
    names = ("mass_kg", "kb0_kN_m", "ak_kN_m", "a", "ac_kN_s_m3")
    if "ball" not in ds.coords or any(n not in ds for n in names):
        return None
    idx = np.flatnonzero(ds["ball"].values.astype(str) == ball)
    if idx.size == 0:
        return None
    m, kb0, ak, a, ac = (float(ds[n].values[idx[0]]) for n in names)
    values = (m, kb0 * 1e3, ak * 1e3, a, ac * 1e3)
    if not all(np.isfinite(values)) or m <= 0 or a <= 0 or min(values) < 0:
        return None
    return values


def impacts(ds, ball: str | None = None, status: str | None = None, *, quantity_ok: str | None = None) -> np.ndarray:
    """Positions (raw order) of the impacts of a ball type and/or status.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    ball : str, optional
        Ball type key; None for every ball.
    status : str, optional
        ``ok`` or ``excluded``; None for both.
    quantity_ok : str, optional
        Only the impacts whose ``<quantity_ok>_status`` is ``ok`` (v1.2: ``contact_time``, ``kcal``, ``peak``,
        ``cor``); an archive without that variable keeps every impact.

    Returns
    -------
    numpy.ndarray
        Integer positions on the ``impact`` dimension.
    """
    n = ds.sizes.get("impact", 0)
    keep = np.ones(n, dtype=bool)
    if ball is not None:
        keep &= text_values(ds[_ball_type_name(ds)].values) == ball
    if status is not None:
        keep &= text_values(ds["status"].values) == status
    if quantity_ok is not None and f"{quantity_ok}_status" in ds:
        keep &= text_values(ds[f"{quantity_ok}_status"].values) == "ok"
    return np.flatnonzero(keep)


def impact_value(ds, name: str, i: int, default=np.nan) -> float:
    """A per-impact number of impact position ``i``, in the variable's units (e.g. ``vin_m_s`` [m/s])."""
    return float(ds[name].values[i]) if name in ds else default


def impact_position(ds, impact_id: str) -> int:
    """Position of an impact on the ``impact`` dimension; KeyError when it is not in the archive."""
    ids = text_values(ds["impact_id"].values) if ds.sizes.get("impact", 0) else np.array([], dtype=object)
    idx = np.flatnonzero(ids == str(impact_id))
    if not idx.size:
        raise KeyError(f"impact_id {impact_id!r} is not in the archive")
    return int(idx[0])


def contact_series(ds, i: int, *names: str) -> list[np.ndarray]:
    """Finite part of the contact series of impact position ``i`` (rows where ``time_s`` is finite).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    i : int
        Impact position.
    *names : str
        Series on (impact, sample), e.g. ``force_N`` [N] or ``displacement_m`` [m].

    Returns
    -------
    list of numpy.ndarray
        Time since contact start [s], then each named series (NaN when the archive lacks it).
    """
    t = np.asarray(ds["time_s"].values[i], dtype=float) if "time_s" in ds else np.empty(0)
    keep = np.isfinite(t)
    out = [t[keep]]
    for name in names:
        out.append(np.asarray(ds[name].values[i], dtype=float)[keep] if name in ds else np.full(keep.sum(), np.nan))
    return out


def excluded_impacts(ds) -> list[tuple[str, str, str]]:
    """(impact_id, ball, reason) of every excluded impact, in raw order."""
    if ds.sizes.get("impact", 0) == 0:
        return []
    ids, keys, reasons = (text_values(ds[n].values) for n in ("impact_id", _ball_type_name(ds), "reason"))
    return [(ids[i], keys[i], reasons[i]) for i in impacts(ds, status="excluded")]


def validate_warnings(ds) -> list[str]:
    """The warnings of reading and validating the session (attribute ``validate_warnings``, JSON text); [] for an
    archive written without them (before the attribute existed) or whose attribute does not parse."""
    text = ds.attrs.get("validate_warnings")
    if not isinstance(text, str):
        return []
    try:
        values = json.loads(text)
    except ValueError:
        return []
    return [str(w) for w in values] if isinstance(values, list) else []
