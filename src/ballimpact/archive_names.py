"""Names in the session archive: short long_names, variables renamed between versions, the impact index."""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__ = ["LONG_NAME_MAX", "SHORT_NAMES", "short_long_name", "RENAMED_VARIABLES", "current_names",
           "with_impact_index"]


#: Longest ``long_name`` [characters]: a plot's axis label (long_name [units]) must fit beside its axis.
LONG_NAME_MAX = 40
#: Short names of the variables whose VARIABLE_ATTRS text does not shorten well at its first clause.
SHORT_NAMES = {
    "model_agreement_fraction": "model force agreement",
    "peak_note": "why the peak is withheld",
    "amplifier_time_constant_se_s": "time constant standard error",
    "fit_vin_min_m_s": "slowest inbound speed fitted",
    "fit_vin_max_m_s": "fastest inbound speed fitted",
    "raw_time_s": "time of the raw sample",
    "model_rms_N": "RMS model - measured force",
    "fit_note": "why left out of the fit",
    "used_in_fit": "used in the fit",
    "contact_time_rmse_pct": "relative RMS TC residual",
    "cor_rmse_pct": "relative RMS COR residual",
    "contact_time_scatter_pct": "relative TC scatter about the fit",
    "cor_scatter_pct": "relative COR scatter about the fit",
    "itf_rebound_pred_cm": "predicted ITF drop-test rebound",
    "itf_rebound_pred_cm_lo": "predicted ITF rebound, 95 % lower end",
    "itf_rebound_pred_cm_hi": "predicted ITF rebound, 95 % upper end",
    "itf_rebound_cm": "measured ITF drop-test rebound",
    "itf_impact_speed_m_s": "ITF drop-test impact speed",
    "itf_drop_test_cor": "ITF drop-test COR",
    "impact_id": "impact id",
    "model_time_s": "time since first contact (model)",
    "stiffness_x_m": "displacement of the stiffness curve",
    "trace_file": "trace file",
    "kcal_N_per_V": "calibration factor kCAL",
    "max_displacement_mm": "largest displacement",
    "noise_rms_V": "baseline noise",
    "hum_amplitude_V": "mains hum amplitude removed",
    "mains_frequency_hz": "mains frequency removed",
    "amplifier_time_constant_s": "amplifier time constant undone",
    "plate_resonance_hz": "plate resonance undone",
    "plate_damping_ratio": "plate damping ratio",
    "rig_value": "session rig value",
    "rig_low": "session rig value, 95 % lower end",
    "rig_high": "session rig value, 95 % upper end",
    "rig_source": "session rig value's source",
    "rig_n_impacts": "impacts the rig value rests on",
    "rig_note": "session rig note",
    "voltage_V": "force-plate voltage",
    "velocity_m_s": "ball velocity",
    "displacement_m": "ball displacement",
    "model_force_N": "model force (Eq. 14)",
    "kv_force_N": "Kelvin-Voigt force",
    "ak_a_correlation": "AK-a correlation",
    "kb_10mm_kN_m": "stiffness kB(10 mm)",
    "kb_10mm_lo": "kB(10 mm), 95 % lower end",
    "kb_10mm_hi": "kB(10 mm), 95 % upper end",
    "kb_20mm_kN_m": "stiffness kB(20 mm)",
    "kb_20mm_lo": "kB(20 mm), 95 % lower end",
    "kb_20mm_hi": "kB(20 mm), 95 % upper end",
    "n_fit_outliers": "fit outliers",
    "paper_kb0_kN_m": "kB(0), paper Table 2",
    "itf_model_cor": "model COR at the ITF drop test",
    "model_contact_time_ms_lo": "model TC, 95 % lower end",
    "model_contact_time_ms_hi": "model TC, 95 % upper end",
    "model_cor_lo": "model COR, 95 % lower end",
    "model_cor_hi": "model COR, 95 % upper end",
    "model_contact_time_ms_pred_lo": "TC prediction, 95 % lower end",
    "model_contact_time_ms_pred_hi": "TC prediction, 95 % upper end",
    "model_cor_pred_lo": "COR prediction, 95 % lower end",
    "model_cor_pred_hi": "COR prediction, 95 % upper end",
    "comp_stiffness_force_N": "stiffness force kB x",
    "comp_displacement_m": "model displacement",
    "model_stiffness_kN_m": "model stiffness kB(x)",
    "vin_gate_m_s": "inbound speed at the gates",
    "vout_gate_m_s": "rebound speed at the gates",
}


def short_long_name(name: str, text: str) -> tuple[str, str]:
    """
    A variable's ``long_name`` (at most :data:`LONG_NAME_MAX` characters) and ``comment`` from its description.

    Parameters
    ----------
    name : str
        The variable's name.
    text : str
        Its description (:data:`VARIABLE_ATTRS`).

    Returns
    -------
    tuple of str
        (long_name, comment): the description itself and "" when it is short; else a short name (from
        :data:`SHORT_NAMES`, or the description's first clause, or its first words) and the whole description.
    """
    if len(text) <= LONG_NAME_MAX and name not in SHORT_NAMES:
        return text, ""
    short = SHORT_NAMES.get(name)
    if short is None:
        cuts = [text.index(sep) for sep in (" (", ", ", ": ", "; ", " = ") if sep in text]
        cuts = [c for c in cuts if 6 <= c <= LONG_NAME_MAX]
        short = text[:min(cuts)] if cuts else text[:text.rindex(" ", 0, LONG_NAME_MAX + 1)]
    return short, text


#: Archive variables renamed since an earlier version: old name -> name now.
RENAMED_VARIABLES = {"impact_ball": "ball_type"}


def current_names(ds: xr.Dataset) -> xr.Dataset:
    """An archive with the variables of an earlier version under their names now (:data:`RENAMED_VARIABLES`).

    Parameters
    ----------
    ds : xarray.Dataset
        A session archive of any version.

    Returns
    -------
    xarray.Dataset
        The same data; unchanged when there is nothing to rename.
    """
    old = {k: v for k, v in RENAMED_VARIABLES.items() if k in ds.variables and v not in ds.variables}
    return ds.rename(old) if old else ds


def with_impact_index(ds: xr.Dataset) -> xr.Dataset:
    """The archive with the impact ids as the index of the ``impact`` dimension (coordinate ``impact``).

    So ``xarray.open_dataset(archive).sel(impact="b1-03")`` finds an impact by its id; ``impact_id`` stays, as
    in archives of version 1.1.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive or part of one.

    Returns
    -------
    xarray.Dataset
        With the coordinate ``impact`` (text), when ``impact_id`` is there and ``impact`` is not.
    """
    if "impact_id" not in ds.variables or "impact" not in ds.dims or "impact" in ds.variables:
        return ds
    ids = np.array(["" if v is None else str(v) for v in ds["impact_id"].values], dtype=object)
    return ds.assign_coords(impact=("impact", ids, {"long_name": "impact id", "units": "1",
                                                    "comment": "impact_id of the raw impacts.csv"}))

