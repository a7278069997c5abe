"""The CSV tables of a session, read from its archive: impacts.csv (per impact) and parameters.csv (per ball type)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

__all__ = ["IMPACT_COLUMNS", "PARAMETER_COLUMNS", "WITHHELD_CELLS", "CSV_FORMATS", "CSV_DEFAULT_FORMAT",
           "impacts_table", "parameters_table", "write_csv"]

#: Columns of results/<session>/impacts.csv, in order (docs/outputs.md).
IMPACT_COLUMNS = [
    "impact_id",
    "ball",
    "status",
    "reason",
    "vin_m_s",
    "vout_m_s",
    "cor",
    "contact_time_ms",
    "kcal_N_per_V",
    "impulse_N_s",
    "peak_force_N",
    "time_to_peak_ms",
    "max_displacement_mm",
    "kv_stiffness_kN_m",
    "kv_damping_N_s_m",
    "used_in_fit",
    "fit_note",
    "vin_gate_m_s",
    "vout_gate_m_s",
    "peak_note",
    # v1.2: per-quantity verdicts
    "contact_time_u_ms",
    "kcal_u_N_per_V",
    "peak_force_u_N",
    "cor_u",
    "contact_time_status",
    "kcal_status",
    "peak_status",
    "cor_status",
    "reason_code",
    "withheld_note",
]

#: The cells each quantity's status empties when it is withheld (the archive keeps the estimates).
WITHHELD_CELLS = {
    "contact_time_status": ("contact_time_ms", "kv_stiffness_kN_m", "kv_damping_N_s_m"),
    "kcal_status": ("kcal_N_per_V", "max_displacement_mm"),
    "peak_status": ("peak_force_N", "time_to_peak_ms"),
    "cor_status": ("cor", "kv_damping_N_s_m"),
}
_TEXT_COLUMNS = ("fit_note", "peak_note", "reason_code", "withheld_note")

#: Columns of results/<session>/parameters.csv, in order: identification (ball,
#: n_impacts, mass_kg), the parameters in Table 2 units (kb0_kN_m, kb0_source,
#: ak_kN_m, a, ac_kN_s_m3), the 95 % intervals of the fitted ones (ak, a, ac, then
#: kb0, NaN when kB(0) came from the config), then the relative fit residuals.
PARAMETER_COLUMNS = [
    "ball",
    "n_impacts",
    "mass_kg",
    "kb0_kN_m",
    "kb0_source",
    "ak_kN_m",
    "a",
    "ac_kN_s_m3",
    "ak_lo",
    "ak_hi",
    "a_lo",
    "a_hi",
    "ac_lo",
    "ac_hi",
    "kb0_lo",
    "kb0_hi",
    "contact_time_rmse_pct",
    "cor_rmse_pct",
    "kb_10mm_kN_m",
    "kb_10mm_lo",
    "kb_10mm_hi",
    "kb_20mm_kN_m",
    "kb_20mm_lo",
    "kb_20mm_hi",
    "itf_rebound_pred_cm",  # v1.1: the ITF 254 cm drop test predicted by the fitted model (ballimpact.itf)
    "itf_rebound_pred_cm_lo",
    "itf_rebound_pred_cm_hi",
    "itf_rebound_cm",  # v1.1: the measured rebound from session.yaml, when given
    "fit_warnings",  # issue 14: empty when all is well (ballimpact.summary.parameter_fit_warnings)
]

def _column(ds: xr.Dataset, name: str, n: int, *, text: bool = False):
    if name in ds.variables:
        values = ds[name].values
        return [("" if v is None else str(v)) for v in values] if text else values
    return [""] * n if text else np.full(n, np.nan)


def impacts_table(ds: xr.Dataset) -> pd.DataFrame:
    """The impacts.csv table: one row per impact in raw order, columns :data:`IMPACT_COLUMNS`.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive (or its per-impact part).

    Returns
    -------
    pandas.DataFrame
        SI columns as named in docs/outputs.md; ``reason`` is empty for ok impacts.
    """
    n = ds.sizes.get("impact", 0)
    data = {}
    for col in IMPACT_COLUMNS:
        if col == "impact_id":
            data[col] = _column(ds, "impact_id", n, text=True)
        elif col == "ball":
            data[col] = _column(ds, "ball_type", n, text=True)
        elif col in ("status", "reason"):
            data[col] = _column(ds, col, n, text=True)
        elif col == "used_in_fit":
            # v1.1: set by the fit-outlier search; without it every ok impact is used
            ok = np.array(_column(ds, "status", n, text=True)) == "ok"
            if "used_in_fit" in ds.variables:
                ok &= np.asarray(ds["used_in_fit"].values).astype(float) > 0
            data[col] = np.where(ok, "true", "false")
        elif col in _TEXT_COLUMNS:
            data[col] = _column(ds, col, n, text=True)
        elif col.endswith("_status"):
            data[col] = [v or "ok" for v in _column(ds, col, n, text=True)] if col in ds.variables else ["ok"] * n
        else:
            data[col] = np.asarray(_column(ds, col, n), dtype=float)
    table = pd.DataFrame(data, columns=IMPACT_COLUMNS)
    table.loc[table["status"] == "ok", "reason"] = ""
    for status, cells in WITHHELD_CELLS.items():
        table.loc[table[status] == "withheld", list(cells)] = np.nan
    return table


def parameters_table(ds: xr.Dataset) -> pd.DataFrame:
    """The parameters.csv table: one row per ball type, columns :data:`PARAMETER_COLUMNS`.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive with the per-ball variables (missing ones give NaN / empty cells).

    Returns
    -------
    pandas.DataFrame
        Parameters in the paper's Table 2 units: kB(0) [kN/m], AK [kN/m^(1+a)],
        a [-], AC [kN s/m^3]; mass [kg]; residuals [%].
    """
    from .model_data import force_agreement
    from .summary import parameter_fit_warnings

    n = ds.sizes.get("ball", 0)
    data = {}
    for col in PARAMETER_COLUMNS:
        if col == "fit_warnings":
            data["fit_message"] = _column(ds, "fit_message", n, text=True)
        elif col in ("ball", "kb0_source"):
            data[col] = _column(ds, col, n, text=True)
        elif col == "n_impacts":
            values = np.asarray(_column(ds, col, n), dtype=float)
            data[col] = pd.array(
                [int(v) if np.isfinite(v) else pd.NA for v in values], dtype="Int64"
            )
        else:
            data[col] = np.asarray(_column(ds, col, n), dtype=float)
    agreement = force_agreement(ds)
    data["force_agreement"] = [agreement.get(str(b), np.nan) for b in data["ball"]]
    columns = [c if c != "fit_warnings" else "fit_message" for c in PARAMETER_COLUMNS] + ["force_agreement"]
    table = pd.DataFrame(data, columns=columns)
    return parameter_fit_warnings(table)[PARAMETER_COLUMNS]




#: How each number of the CSV tables is written: to what its measurement supports (docs/outputs.md, "Numbers").
#: Speeds [m/s] to 1 mm/s (a 1 us timer over 4 ms of flight: 0.03 %); COR to 1e-4; times [ms] to 1 us (TC is
#: found to a fraction of a 15 us sample); kCAL [N/V] to 0.01 (the calibration holds to about 0.03 N/V); forces [N]
#: to 0.1 N; displacements [mm] to 10 um; the fitted parameters to 4-5 significant digits (their 95 % intervals are
#: several % wide).
CSV_FORMATS = {
    **dict.fromkeys(("vin_m_s", "vout_m_s", "vin_gate_m_s", "vout_gate_m_s"), "%.3f"),
    "cor": "%.4f",
    **dict.fromkeys(("contact_time_ms", "time_to_peak_ms"), "%.3f"),
    **dict.fromkeys(("kcal_N_per_V", "kv_stiffness_kN_m", "kv_damping_N_s_m", "max_displacement_mm"), "%.2f"),
    "impulse_N_s": "%.4f",
    "peak_force_N": "%.1f",
    "mass_kg": "%.5f",
    **dict.fromkeys(("kb0_kN_m", "kb0_lo", "kb0_hi", "kb_10mm_kN_m", "kb_10mm_lo", "kb_10mm_hi", "kb_20mm_kN_m",
                     "kb_20mm_lo", "kb_20mm_hi"), "%.2f"),
    **dict.fromkeys(("ak_kN_m", "ak_lo", "ak_hi"), "%.5g"),
    **dict.fromkeys(("a", "a_lo", "a_hi", "ac_kN_s_m3", "ac_lo", "ac_hi"), "%.4f"),
    **dict.fromkeys(("contact_time_rmse_pct", "cor_rmse_pct"), "%.3f"),
    **dict.fromkeys(("itf_rebound_pred_cm", "itf_rebound_pred_cm_lo", "itf_rebound_pred_cm_hi", "itf_rebound_cm"),
                    "%.1f"),
    # v1.2 standard uncertainties: to the last digit their quantity is written to, and one more
    "contact_time_u_ms": "%.4f",
    "kcal_u_N_per_V": "%.3f",
    "peak_force_u_N": "%.2f",
    "cor_u": "%.5f",
}
#: Any other number column: 6 significant digits.
CSV_DEFAULT_FORMAT = "%.6g"


def _formatted(values, fmt: str) -> list[str]:
    """Numbers as text in ``fmt``; an empty cell for NaN (and "-0" written as "0")."""
    out = []
    for value in values:
        if value is None or value is pd.NA or (isinstance(value, float) and not np.isfinite(value)):
            out.append("")
            continue
        text = fmt % value
        out.append(text[1:] if text.startswith("-") and float(text) == 0 else text)
    return out


def write_csv(table: pd.DataFrame, path) -> None:
    """
    Write a results table as CSV, each float column in its :data:`CSV_FORMATS` format.

    Parameters
    ----------
    table : pandas.DataFrame
        impacts.csv, parameters.csv or catalogue.csv rows; text and integer columns are written as they are.
    path : str or Path
        The file (written directly: the caller makes it atomic).
    """
    out = table.copy()
    for column in out.columns:
        if pd.api.types.is_float_dtype(out[column].dtype):
            out[column] = _formatted(out[column].to_numpy(), CSV_FORMATS.get(column, CSV_DEFAULT_FORMAT))
    out.to_csv(path, index=False)
