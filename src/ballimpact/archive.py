"""The session archive file: its variables, CF/ACDD attributes, assembly and netCDF4 read and write (xarray at the edge).

Layout (one root group, see docs/outputs.md):

* dims ``impact``, ``sample`` (contact series, NaN padded), ``raw_sample`` (whole
  trace, NaN padded), ``ball``, ``speed``, ``model_time``, ``stiffness_x``;
* per impact: ``impact`` (the index: impact ids), ``impact_id`` (the same), ``ball_type``, ``status``, ``reason``,
  ``trace_file``, ``trace_sha256`` and the scalar results of :data:`IMPACT_COLUMNS`,
  plus ``impact_mass_kg`` and ``sample_rate_hz``, ``model_agreement_fraction`` and
  ``model_rms_N``, and how the trace was conditioned: ``noise_rms_V``,
  ``hum_amplitude_V``, ``mains_frequency_hz`` / ``mains_source``,
  ``amplifier_time_constant_s`` / ``_se_s`` / ``_source``, ``plate_resonance_hz`` and
  ``plate_damping_ratio``;
* per ball: the fitted parameters of :data:`PARAMETER_COLUMNS` (``mass_kg`` is the
  ball type's mass, which is why the per-impact mass is called ``impact_mass_kg``),
  ``ball_label``, ``fit_message``, ``ak_a_correlation`` and the paper's Table 2
  values ``paper_*``;
* model curves over ``speed``, force components over ``model_time`` (20 m/s) and
  the stiffness law over ``stiffness_x`` (computed by :mod:`ballimpact.model_data`).

Every variable carries ``units`` and ``long_name`` (:data:`VARIABLE_ATTRS`); text
variables are stored as netCDF variable-length strings. The CSV tables are made by
:mod:`ballimpact.tables`, reading an archive by :mod:`ballimpact.archive_read`.
"""

from __future__ import annotations

import datetime
import json
import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from .atomic import atomic_path
# The model-derived data and the CSV tables have their own modules; their names stay
# importable from here for the callers of the archive.
from .model_data import (  # noqa: F401
    AGREEMENT_START_S,
    AGREEMENT_TOLERANCE,
    COMPONENT_SPEED_M_S,
    MODEL_TIME_STEPS,
    SPEED_GRID_M_S,
    STIFFNESS_X_M,
    add_model_forces,
    force_components,
    itf_drop_test,
    kelvin_voigt_force,
    speed_curves,
    stiffness_curve,
)
from .archive_attrs import AK_UNITS as _AK_UNITS, VARIABLE_ATTRS  # noqa: F401  (re-exported)
from .archive_names import current_names, short_long_name, with_impact_index
from .tables import IMPACT_COLUMNS, PARAMETER_COLUMNS, impacts_table, parameters_table  # noqa: F401

__all__ = [
    "IMPACT_COLUMNS",
    "PARAMETER_COLUMNS",
    "VARIABLE_ATTRS",
    "PAPER_REFERENCE",
    "AGREEMENT_START_S",
    "AGREEMENT_TOLERANCE",
    "impacts_dataset",
    "impacts_table",
    "parameters_table",
    "paper_parameters_dataset",
    "fit_dataset",
    "SPEED_GRID_M_S",
    "MODEL_TIME_STEPS",
    "COMPONENT_SPEED_M_S",
    "STIFFNESS_X_M",
    "add_model_forces",
    "assemble_archive",
    "set_variable_attrs",
    "add_metadata",
    "write_dataset",
    "open_dataset",
]

#: Citation of the paper the model comes from (ACDD ``references``).
PAPER_REFERENCE = (
    "Goodwill S R, Haake S J (2004) Modelling of tennis ball impacts on a rigid surface. "
    "Proc. IMechE Part C 218:1139-1153, doi:10.1243/0954406042369125"
)


#: ACDD-1.3 ``keywords`` of every archive.
ACDD_KEYWORDS = ("tennis ball, impact, coefficient of restitution, contact time, force platform, "
                 "viscoelastic model, Goodwill and Haake 2004, sports engineering")
_AK_COMMENT = (
    "AK in kN m-(1+a) with x in metres, where a is the stiffness exponent of the same ball "
    "(variable a): the unit differs from ball to ball, so it has no UDUNITS form and the "
    "variable carries no units attribute. kB(x) = kB(0) + AK x^a is in kN m-1."
)
#: ACDD coverage_content_type of a data variable, by name: the first matching prefix wins.
_CONTENT_TYPES = (
    (("status", "reason", "peak_note", "withheld_note", "reason_code", "finding_", "contact_time_status", "kcal_status",
      "peak_status", "cor_status", "contact_time_u", "kcal_u", "peak_force_u", "cor_u", "fit_message", "interval_method", "kb0_source", "model_agreement", "model_rms",
      "contact_time_rmse", "cor_rmse", "n_impacts", "fit_", "rig_source", "rig_n_impacts", "rig_note"),
     "qualityInformation"),
    (("paper_",), "referenceInformation"),
    (("model_", "comp_", "kv_force", "kb0", "ak", "a", "ac", "kb_", "itf_rebound_pred", "itf_model", "itf_impact_speed"),
     "modelResult"),
    (("ball_type", "trace_", "ball_label", "sample_rate", "impact_mass", "mass_kg", "used_in_fit", "mains_source",
      "amplifier_time_constant_source", "rig_unit"),
     "auxiliaryInformation"),
)
_PER_IMPACT_SCALARS = [
    # (archive name, ImpactResult attribute)
    ("vin_m_s", "vin_m_s"),
    ("vout_m_s", "vout_m_s"),
    ("cor", "cor"),
    ("contact_time_ms", "contact_time_ms"),
    ("kcal_N_per_V", "kcal_N_per_V"),
    ("impulse_N_s", "impulse_N_s"),
    ("peak_force_N", "peak_force_N"),
    ("time_to_peak_ms", "time_to_peak_ms"),
    ("max_displacement_mm", "max_displacement_mm"),
    ("kv_stiffness_kN_m", "kv_stiffness_kN_m"),
    ("kv_damping_N_s_m", "kv_damping_N_s_m"),
    ("impact_mass_kg", "mass_kg"),
    ("sample_rate_hz", "sample_rate_hz"),
    ("vin_gate_m_s", "vin_gate_m_s"),
    ("vout_gate_m_s", "vout_gate_m_s"),
    # how the trace was conditioned (ballimpact.signal.conditioning): what a lab checks an exclusion against
    ("noise_rms_V", "noise_rms_V"),
    ("hum_amplitude_V", "hum_amplitude_V"),
    ("mains_frequency_hz", "mains_hz"),
    ("amplifier_time_constant_s", "tau_s"),
    ("amplifier_time_constant_se_s", "tau_se_s"),
    ("plate_resonance_hz", "plate_resonance_hz"),
    ("plate_damping_ratio", "plate_damping_ratio"),
    # v1.2: each quantity's standard uncertainty, from its error budget (ballimpact.verdicts)
    ("contact_time_u_ms", "contact_time_u_ms"),
    ("kcal_u_N_per_V", "kcal_u_N_per_V"),
    ("peak_force_u_N", "peak_force_u_N"),
    ("cor_u", "cor_u"),
]
_SERIES = ["time_s", "voltage_V", "force_N", "velocity_m_s", "displacement_m"]

_TEXT_PER_IMPACT = ["ball_type", "status", "reason", "trace_file", "trace_sha256"]
_CONDITIONING_TEXT = [
    # (archive name, ImpactResult attribute)
    ("mains_source", "mains_source"),
    ("amplifier_time_constant_source", "tau_source"),
    ("peak_note", "peak_note"),
    # v1.2 per-quantity verdicts
    ("contact_time_status", "contact_time_status"),
    ("kcal_status", "kcal_status"),
    ("peak_status", "peak_status"),
    ("cor_status", "cor_status"),
    ("reason_code", "reason_code"),
    ("withheld_note", "withheld_note"),
]


def _text_array(values) -> np.ndarray:
    """Object array of Python str (netCDF variable-length strings)."""
    return np.array(["" if v is None else str(v) for v in values], dtype=object)


def _float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _as_1d(value) -> np.ndarray:
    if value is None:
        return np.empty(0)
    return np.asarray(value, dtype=float).ravel()


def _pad(rows: list[np.ndarray], length: int, dtype) -> np.ndarray:
    out = np.full((len(rows), length), np.nan, dtype=dtype)
    for i, row in enumerate(rows):
        out[i, : row.size] = row
    return out


def coverage_content_type(name: str) -> str:
    """ACDD-1.3 ``coverage_content_type`` of an archive data variable.

    Parameters
    ----------
    name : str
        Variable name.

    Returns
    -------
    str
        ``qualityInformation`` (status, reasons, fit diagnostics),
        ``referenceInformation`` (the paper's Table 2), ``modelResult`` (fitted
        parameters and model curves), ``auxiliaryInformation`` (labels, masses,
        file names) or ``physicalMeasurement`` (everything measured).
    """
    for prefixes, kind in _CONTENT_TYPES:
        if any(name == p or (p.endswith("_") and name.startswith(p)) or name.startswith(p + "_") for p in prefixes):
            return kind
    return "physicalMeasurement"


def set_variable_attrs(ds: xr.Dataset, *, overwrite: bool = False) -> xr.Dataset:
    """Fill ``units``, ``long_name`` (short) and ``comment`` (the rest) of every known variable from
    :data:`VARIABLE_ATTRS`.

    Parameters
    ----------
    ds : xarray.Dataset
        Archive or part of one; modified in place and returned.
    overwrite : bool, optional
        Replace attributes that are already set.

    Returns
    -------
    xarray.Dataset
        ``ds``. Variables unknown to :data:`VARIABLE_ATTRS` and lacking ``units`` or
        ``long_name`` raise a warning (the archive contract wants both everywhere).
    """
    for name in list(ds.variables):
        attrs = ds[name].attrs
        if name in VARIABLE_ATTRS:
            units, description = VARIABLE_ATTRS[name]
            long_name, comment = short_long_name(name, description)
            if units == _AK_UNITS:
                # kN m-(1+a) changes with each ball's a: no UDUNITS unit exists for it
                attrs.pop("units", None)
                attrs["units_metadata"] = f"non-UDUNITS: {_AK_UNITS}"
                comment = f"{comment} {_AK_COMMENT}".strip()
            elif overwrite or "units" not in attrs:
                attrs["units"] = units
            if overwrite or "long_name" not in attrs:
                attrs["long_name"] = long_name
                if comment:
                    attrs["comment"] = comment
        elif "units" not in attrs or "long_name" not in attrs:
            warnings.warn(
                f"archive variable {name!r} has no units/long_name and is not in VARIABLE_ATTRS",
                stacklevel=2,
            )
        if name not in ds.coords and (overwrite or "coverage_content_type" not in attrs):
            attrs["coverage_content_type"] = coverage_content_type(name)
    return ds


def impacts_dataset(
    results: Iterable,
    *,
    max_raw_samples: int | None = None,
    trace_info: Mapping[str, tuple[str, str]] | None = None,
) -> xr.Dataset:
    """Per-impact part of the archive from processed impacts.

    Parameters
    ----------
    results : iterable of ImpactResult
        Processed impacts in raw order (``ballimpact.processing.ImpactResult`` or any
        object with the same attributes). Series may be empty (impact excluded
        before the contact was found).
    max_raw_samples : int, optional
        Decimate each raw trace (every k-th sample) to at most this many samples;
        None keeps the whole trace.
    trace_info : mapping, optional
        impact_id -> (trace file relative to the session, its SHA-256). Otherwise
        taken from the results' ``trace_file`` / ``trace_sha256`` attributes (or
        ``trace``) when they have them, else empty.

    Returns
    -------
    xarray.Dataset
        Dims ``impact``, ``sample``, ``raw_sample`` (each at least 1 long, NaN
        padded). ``kv_force_N`` is the Kelvin-Voigt force of Eqs. (1)-(3) in Goodwill &
        Haake 2004 on each impact's time samples; ``model_force_N``,
        ``model_agreement_fraction`` and ``model_rms_N`` are NaN until
        :func:`add_model_forces` runs with the fitted parameters.
    """
    if max_raw_samples is not None and (int(max_raw_samples) != max_raw_samples or max_raw_samples < 2):
        raise ValueError(f"max_raw_samples must be an integer >= 2 or None, got {max_raw_samples!r}")
    trace_info = {} if trace_info is None else dict(trace_info)
    columns = _ImpactColumns()
    for r in results:
        columns.add(r, trace_info, max_raw_samples)
    return set_variable_attrs(columns.dataset())


class _ImpactColumns:
    """The per-impact variables of the archive, filled one processed impact at a time."""

    def __init__(self):
        self.ids = []
        self.findings = []  # per impact: {check code: (count, message, effects)}
        self.text = {k: [] for k in _TEXT_PER_IMPACT + [name for name, _ in _CONDITIONING_TEXT]}
        self.scalars = {name: [] for name, _ in _PER_IMPACT_SCALARS}
        self.series = {k: [] for k in _SERIES}
        self.raw_t, self.raw_v = [], []

    def add(self, r, trace_info, max_raw_samples) -> None:
        """Append one ImpactResult-like object (validated: unique id, status, series lengths)."""
        impact_id = str(r.impact_id)
        if impact_id in self.ids:
            raise ValueError(f"duplicate impact_id {impact_id!r} in the results")
        self.ids.append(impact_id)
        status = str(r.status)
        if status not in ("ok", "excluded"):
            raise ValueError(f"impact {impact_id}: status must be 'ok' or 'excluded', got {status!r}")
        trace_file, trace_sha = trace_info.get(
            impact_id,
            (getattr(r, "trace_file", None) or getattr(r, "trace", None) or "", getattr(r, "trace_sha256", "") or ""),
        )
        self.text["ball_type"].append(r.ball)
        self.text["status"].append(status)
        self.text["reason"].append("" if status == "ok" else (r.reason or ""))
        self.text["trace_file"].append(trace_file)
        self.text["trace_sha256"].append(trace_sha)
        for name, attr in _CONDITIONING_TEXT:
            self.text[name].append(getattr(r, attr, "") or "")
        for name, attr in _PER_IMPACT_SCALARS:
            value = _float(getattr(r, attr, math.nan))
            if name == "amplifier_time_constant_s" and math.isinf(value):
                value = math.nan  # no decay corrected (inf in processing): NaN, with its source "none"
            self.scalars[name].append(value)
        self._add_series(r, impact_id)
        self._add_raw(r, impact_id, max_raw_samples)
        found = {}
        for p in getattr(r, "problems", []) or []:
            count, message, effects = found.get(p.kind.value, (0, p.message, {}))
            merged = {q: max(effects.get(q, -math.inf), float(v)) for q, v in p.effects.items()}
            found[p.kind.value] = (count + 1, message, {**effects, **merged})
        self.findings.append(found)

    def _add_series(self, r, impact_id) -> None:
        n = _as_1d(getattr(r, "time_s", None)).size
        for k in _SERIES:
            arr = _as_1d(getattr(r, k, None))
            if arr.size != n:
                raise ValueError(
                    f"impact {impact_id}: series {k} has {arr.size} samples but time_s has {n}"
                )
            self.series[k].append(arr)

    def _add_raw(self, r, impact_id, max_raw_samples) -> None:
        rt, rv = _as_1d(getattr(r, "raw_time_s", None)), _as_1d(getattr(r, "raw_voltage_V", None))
        if rt.size != rv.size:
            raise ValueError(
                f"impact {impact_id}: raw_time_s has {rt.size} samples but raw_voltage_V has {rv.size}"
            )
        if max_raw_samples is not None and rv.size > max_raw_samples:
            step = math.ceil(rv.size / max_raw_samples)
            rt, rv = rt[::step], rv[::step]
        self.raw_t.append(rt)
        self.raw_v.append(rv)

    def dataset(self) -> xr.Dataset:
        """The per-impact dataset (series NaN padded, model forces NaN until fitted)."""
        scalars, n_impact = self.scalars, len(self.ids)
        n_sample = max([s.size for s in self.series["time_s"]] + [1])
        n_raw = max([s.size for s in self.raw_v] + [1])
        dims, raw_dims = ("impact", "sample"), ("impact", "raw_sample")
        data_vars = {k: ("impact", _text_array(v)) for k, v in self.text.items()}
        data_vars.update({k: ("impact", np.asarray(v, dtype=float)) for k, v in scalars.items()})
        for k in _SERIES:
            data_vars[k] = (dims, _pad(self.series[k], n_sample, np.float64))
        kv = [
            kelvin_voigt_force(
                t, scalars["vin_m_s"][i], scalars["impact_mass_kg"][i],
                scalars["kv_stiffness_kN_m"][i], scalars["kv_damping_N_s_m"][i],
            )
            for i, t in enumerate(self.series["time_s"])
        ]
        data_vars["kv_force_N"] = (dims, _pad(kv, n_sample, np.float64))
        data_vars["model_force_N"] = (dims, np.full((n_impact, n_sample), np.nan))
        data_vars["model_agreement_fraction"] = ("impact", np.full(n_impact, np.nan))
        data_vars["model_rms_N"] = ("impact", np.full(n_impact, np.nan))
        data_vars.update(_findings_variables(self.findings))
        data_vars["raw_time_s"] = (raw_dims, _pad(self.raw_t, n_raw, np.float32))
        data_vars["raw_voltage_V"] = (raw_dims, _pad(self.raw_v, n_raw, np.float32))
        return xr.Dataset(data_vars, coords={"impact_id": ("impact", _text_array(self.ids))})


def _findings_variables(findings: list) -> dict:
    """The (impact, check) variables of every finding: how many, the first message, and each estimated effect."""
    from .checks import CHECKS

    codes = list(CHECKS)
    n = len(findings)
    count = np.zeros((n, len(codes)), dtype=np.int16)
    message = np.full((n, len(codes)), "", dtype=object)
    effects = {q: np.full((n, len(codes)), np.nan) for q in ("contact_time", "kcal", "peak")}
    for i, found in enumerate(findings):
        for code, (k, text, eff) in found.items():
            j = codes.index(code)
            count[i, j], message[i, j] = k, text
            for q, v in eff.items():
                if q in effects and math.isfinite(v):
                    effects[q][i, j] = v
    dims = ("impact", "check")
    out = {"finding_count": (dims, count), "finding_message": (dims, _text_array(message.ravel()).reshape(n, -1)
                                                                if n else np.empty((0, len(codes)), dtype=object))}
    out.update({f"finding_effect_{q}": (dims, v) for q, v in effects.items()})
    out["check"] = ("check", _text_array(codes))
    return out


def paper_parameters_dataset(balls: Iterable[str]) -> xr.Dataset:
    """Table 2 of Goodwill & Haake 2004 on the ``ball`` dimension (NaN for other ball keys).

    Parameters
    ----------
    balls : iterable of str
        Ball type keys of the session.

    Returns
    -------
    xarray.Dataset
        ``paper_kb0_kN_m`` [kN/m], ``paper_ak_kN_m`` [kN/m^(1+a)], ``paper_a`` [-],
        ``paper_ac_kN_s_m3`` [kN s/m^3].
    """
    from .balls import BALLS

    keys = [str(b) for b in balls]
    cols = {"paper_kb0_kN_m": "kb0_kN_m", "paper_ak_kN_m": "ak_kN_m", "paper_a": "a", "paper_ac_kN_s_m3": "ac_kN_s_m3"}
    data = {name: np.full(len(keys), np.nan) for name in cols}
    for i, key in enumerate(keys):
        if key in BALLS:
            table = BALLS[key].params.table_units()
            for name, col in cols.items():
                data[name][i] = table[col]
    ds = xr.Dataset({k: ("ball", v) for k, v in data.items()}, coords={"ball": _text_array(keys)})
    return set_variable_attrs(ds)


def fit_dataset(
    ball: str,
    fit=None,
    *,
    label: str | None = None,
    mass_kg: float = math.nan,
    n_impacts: int = 0,
    kb0_source: str = "",
    message: str = "",
    fit_vin_range_m_s: tuple[float, float] = (math.nan, math.nan),
    itf_rebound_cm: float | None = None,
    diameter_m: float | None = None,
    air_density_kg_m3: float | None = None,
) -> xr.Dataset:
    """Per-ball part of the archive (``ball`` dimension of length 1) from a fit.

    Parameters in the units of Table 2 of Goodwill & Haake 2004 with their 95 %
    intervals, the model curves TC [ms], COR [-] and peak force [N] on
    :data:`SPEED_GRID_M_S` with 95 % confidence and prediction bands
    (:func:`ballimpact.fitting.model_curves`), kB(10 mm) and kB(20 mm) with intervals,
    the force components of Eq. (14) at :data:`COMPONENT_SPEED_M_S` on 0.01 ms
    steps, the stiffness law kB(x) of Eq. (4) on :data:`STIFFNESS_X_M`, and the
    paper's Table 2 values.

    Parameters
    ----------
    ball : str
        Ball type key.
    fit : ballimpact.fitting.BallFit, optional
        The fit (SI units); None when it failed or there were too few impacts: the
        parameters and curves are NaN and ``message`` says why.
    label : str, optional
        Ball label for figures (default: the key).
    mass_kg : float
        Ball type mass [kg], used when ``fit`` is None (otherwise ``fit.mass_kg``).
    n_impacts : int
        Good impacts of the ball, used when ``fit`` is None.
    kb0_source : str
        "config" or "extrapolated", used when ``fit`` is None.
    message : str
        Why there is no fit (``fit`` None), or extra text for ``fit_message``.
    fit_vin_range_m_s : tuple of float
        Slowest and fastest inbound speed of the impacts fitted [m/s]; the model
        curves outside are extrapolations.
    itf_rebound_cm : float, optional
        Measured ITF drop-test rebound [cm] (session.yaml ``itf_rebound_cm``).
    diameter_m, air_density_kg_m3 : float, optional
        Ball diameter [m] and air density [kg/m^3] of the drop-test prediction
        (:mod:`ballimpact.itf`); defaults 65.4 mm and 1.2 kg/m^3.

    Returns
    -------
    xarray.Dataset
    """
    from .model import TIME_STEP_S

    if not isinstance(ball, str) or not ball:
        raise ValueError(f"ball must be a non-empty ball type key, got {ball!r}")
    if fit is None:
        params = dict.fromkeys(_FIT_PARAMETERS, math.nan)
        text = {"kb0_source": kb0_source, "fit_message": message or "no fit", "interval_method": "none"}
        mass, n_used = float(mass_kg), int(n_impacts)
    else:
        params, text = _fit_parameters(fit), _fit_text(fit, message)
        mass, n_used = float(fit.mass_kg), int(fit.n_impacts)
    data = {k: ("ball", np.array([v], dtype=float)) for k, v in params.items()}
    data.update({k: ("ball", _text_array([v])) for k, v in text.items()})
    data["ball_label"] = ("ball", _text_array([label or ball]))
    data["mass_kg"] = ("ball", np.array([mass], dtype=float))
    data["n_impacts"] = ("ball", np.array([n_used], dtype=np.int64))
    data.update({k: ("ball", np.array([v], dtype=float)) for k, v in itf_drop_test(
        fit, mass, fit_vin_range_m_s, itf_rebound_cm, diameter_m, air_density_kg_m3).items()})
    data.update({k: (("ball", "speed"), v[None, :]) for k, v in speed_curves(fit).items()})
    data.update({k: (("ball", "model_time"), v[None, :]) for k, v in force_components(fit).items()})
    data["model_stiffness_kN_m"] = (("ball", "stiffness_x"), stiffness_curve(fit)[None, :])
    ds = xr.Dataset(
        data,
        coords={
            "ball": _text_array([ball]),
            "speed_m_s": ("speed", SPEED_GRID_M_S.copy()),
            "model_time_s": ("model_time", np.arange(MODEL_TIME_STEPS) * TIME_STEP_S),
            "stiffness_x_m": ("stiffness_x", STIFFNESS_X_M.copy()),
        },
    )
    ds = ds.merge(paper_parameters_dataset([ball]))
    return set_variable_attrs(ds)


#: Per-ball numbers of :func:`fit_dataset`, in archive order (NaN without a fit).
_FIT_PARAMETERS = (
    "kb0_kN_m", "kb0_lo", "kb0_hi", "ak_kN_m", "ak_lo", "ak_hi", "a", "a_lo", "a_hi",
    "ac_kN_s_m3", "ac_lo", "ac_hi", "ak_a_correlation", "contact_time_rmse_pct", "cor_rmse_pct",
    "kb_10mm_kN_m", "kb_10mm_lo", "kb_10mm_hi", "kb_20mm_kN_m", "kb_20mm_lo", "kb_20mm_hi",
    "contact_time_scatter_pct", "cor_scatter_pct", "bootstrap_dropped")


def _fit_parameters(fit) -> dict[str, float]:
    """The numbers of :data:`_FIT_PARAMETERS` from a fit, in Table 2 units (kN, %)."""
    nan, kn = math.nan, 1e3
    params = dict(
        kb0_kN_m=fit.kb0_N_m / kn, kb0_lo=fit.kb0_lo / kn, kb0_hi=fit.kb0_hi / kn,
        ak_kN_m=fit.ak / kn, ak_lo=fit.ak_lo / kn, ak_hi=fit.ak_hi / kn,
        a=fit.a, a_lo=fit.a_lo, a_hi=fit.a_hi,
        ac_kN_s_m3=fit.ac / kn, ac_lo=fit.ac_lo / kn, ac_hi=fit.ac_hi / kn,
        ak_a_correlation=fit.ak_a_correlation,
        contact_time_rmse_pct=fit.contact_time_rmse_pct, cor_rmse_pct=fit.cor_rmse_pct,
    )
    # v1.1: the well-determined stiffness at 10 and 20 mm, scatter and bootstrap drops
    # (getattr: a fit object without them leaves NaN)
    for mm in (10, 20):
        for name, attr in ((f"kb_{mm}mm_kN_m", f"kb_{mm}mm_N_m"), (f"kb_{mm}mm_lo", f"kb_{mm}mm_lo"),
                           (f"kb_{mm}mm_hi", f"kb_{mm}mm_hi")):
            params[name] = float(getattr(fit, attr, nan)) / kn
    params["contact_time_scatter_pct"] = 100.0 * float(getattr(fit, "contact_time_scatter", nan))
    params["cor_scatter_pct"] = 100.0 * float(getattr(fit, "cor_scatter", nan))
    params["bootstrap_dropped"] = float(getattr(fit, "bootstrap_dropped", nan))
    return {k: params[k] for k in _FIT_PARAMETERS}


def _fit_text(fit, message: str) -> dict[str, str]:
    """kb0_source, fit_message and interval_method of a fit."""
    notes = list(getattr(fit, "messages", None) or [])
    if message:
        notes.append(message)
    return {
        "kb0_source": fit.kb0_source,
        "fit_message": "; ".join(["ok"] + notes),
        "interval_method": str(getattr(fit, "interval_method", "") or "none"),
    }


def assemble_archive(impacts: xr.Dataset, fits: Iterable[xr.Dataset]) -> xr.Dataset:
    """Merge the per-impact dataset and the per-ball fit datasets into one archive.

    Adds the paper's Table 2 values (``paper_*``) when the fits do not carry them,
    fills the model forces (:func:`add_model_forces`) and the variable attributes.

    Parameters
    ----------
    impacts : xarray.Dataset
        From :func:`impacts_dataset` (possibly concatenated chunks, raw order).
    fits : iterable of xarray.Dataset
        One dataset per ball type on the ``ball`` dimension (length 1 each).

    Returns
    -------
    xarray.Dataset
        The archive without the global attributes (see :func:`add_metadata`).
    """
    fits = list(fits)
    ds = impacts
    if fits:
        try:
            per_ball = xr.concat(
                fits, dim="ball", data_vars="minimal", coords="minimal", compat="override",
                join="exact", combine_attrs="drop_conflicts",
            )
        except ValueError as err:
            raise ValueError(
                f"the fit datasets do not share their speed / model_time / stiffness_x grids: {err}"
            ) from err
        balls = [str(b) for b in per_ball["ball"].values]
        dupes = sorted({b for b in balls if balls.count(b) > 1})
        if dupes:
            raise ValueError(f"more than one fit dataset for ball type(s) {dupes}")
        ds = xr.merge([impacts, per_ball], combine_attrs="drop_conflicts", join="exact", compat="no_conflicts")
    if "ball" in ds.coords and "paper_a" not in ds:
        ds = ds.merge(paper_parameters_dataset(ds["ball"].values))
    if "ball" in ds.coords:
        ds = ds.assign_coords(ball=_text_array(ds["ball"].values))
    ds = add_model_forces(ds) if "ball" in ds.coords else ds
    return set_variable_attrs(ds)


def _utc_now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def add_metadata(
    ds: xr.Dataset,
    *,
    session_id: str,
    session_yaml_text: str,
    raw_sha256: Mapping[str, str],
    synthetic: bool,
    history: str,
    validate_warnings: Sequence[str] = (),
) -> xr.Dataset:
    """Set the CF-1.10 / ACDD-1.3 global attributes of the archive.

    Parameters
    ----------
    ds : xarray.Dataset
        The archive; a shallow copy with new attributes is returned.
    session_id : str
        Session identifier (folder name).
    session_yaml_text : str
        The raw session.yaml text, stored verbatim in ``session_yaml``.
    raw_sha256 : mapping of str to str
        Relative path of every raw file -> SHA-256 hex digest; stored as JSON text.
    synthetic : bool
        True when the session came from the synthetic generator; stored as 1/0
        (netCDF has no boolean attributes).
    history : str
        What made the file (e.g. the command); prefixed with the UTC time.
    validate_warnings : sequence of str, optional
        The warnings of reading and validating the session (usable but suspect input:
        ``ballimpact.validation.validate_session``); stored as JSON text, so that the
        report and later readers carry them.

    Returns
    -------
    xarray.Dataset
        Copy of ``ds`` with title, summary, history, source, date_created,
        references, Conventions, software_version, session_id, synthetic,
        session_yaml, raw_sha256, validate_warnings and the session's date, operator
        and description.
    """
    from . import __version__

    if not isinstance(session_id, str) or not session_id:
        raise ValueError(f"session_id must be a non-empty string, got {session_id!r}")
    if not isinstance(session_yaml_text, str):
        raise ValueError(f"session_yaml_text must be str, got {type(session_yaml_text).__name__}")
    bad = [k for k, v in dict(raw_sha256).items() if not isinstance(k, str) or not isinstance(v, str)]
    if bad:
        raise ValueError(f"raw_sha256 must map str paths to str digests; bad key(s): {bad[:3]}")
    if isinstance(validate_warnings, str) or not all(isinstance(w, str) for w in validate_warnings):
        raise ValueError(f"validate_warnings must be a sequence of str, got {validate_warnings!r}")
    meta = _session_meta(session_yaml_text)
    created = _utc_now()
    description = str(meta.get("description", "") or "")
    summary = _acdd_summary(session_id, synthetic, description)
    out = ds.copy()
    out.attrs = dict(ds.attrs)
    out.attrs.update(
        {
            "title": f"Tennis ball impacts on a rigid surface, session {session_id}",
            "keywords": ACDD_KEYWORDS,
            "keywords_vocabulary": "free text",
            "summary": summary,
            "history": f"{created} {history} (ballimpact {__version__})",
            "source": (
                "synthetic force-platform traces and light-gate times (ballimpact.synth)"
                if synthetic
                else "piezoelectric force platform with charge amplifier and light gates"
            ),
            "date_created": created,
            "references": PAPER_REFERENCE,
            "Conventions": "CF-1.10, ACDD-1.3",
            "software_version": __version__,
            "session_id": session_id,
            "session_date": str(meta.get("date", "") or ""),
            "operator": str(meta.get("operator", "") or ""),
            "session_description": description,
            "synthetic": np.int8(1 if synthetic else 0),
            "session_yaml": session_yaml_text,
            "raw_sha256": json.dumps(dict(sorted(dict(raw_sha256).items())), indent=None),
            "validate_warnings": json.dumps(list(validate_warnings), indent=None),
        }
    )
    return out


def _session_meta(session_yaml_text: str) -> dict:
    """The session.yaml mapping, or {} when the text does not parse (it is archived as is)."""
    try:
        import yaml

        parsed = yaml.safe_load(session_yaml_text) or {}
        return parsed if isinstance(parsed, dict) else {}
    except Exception:  # the text is archived as is; a parse failure only loses the summary fields
        return {}


def _acdd_summary(session_id: str, synthetic: bool, description: str) -> str:
    """The ACDD ``summary`` attribute: what the archive holds, and the session's description."""
    kind = "synthetic session from the ballimpact generator" if synthetic else "laboratory session"
    summary = (
        f"Normal impacts of tennis balls on a rigid force platform ({kind} {session_id}): "
        "per-impact light-gate speeds, COR, contact time, calibrated force, centre-of-mass "
        "velocity and displacement, and the Goodwill & Haake (2004) viscoelastic ball model "
        "fitted per ball type."
    )
    if description:
        summary += f" Session description: {description}"
    return summary


def _encoding(ds: xr.Dataset) -> dict:
    enc = {}
    for name, var in ds.variables.items():
        if var.dtype.kind in "fiub":
            if var.ndim == 0 or var.size == 0:
                continue
            enc[name] = {"zlib": True, "complevel": 4}
            if var.dtype.kind == "f":
                enc[name]["_FillValue"] = np.nan
        elif var.dtype.kind in "OUS":
            enc[name] = {"dtype": str}
    return enc


def _text_to_object(ds: xr.Dataset) -> xr.Dataset:
    """Make every text variable an object array of str (variable-length strings in netCDF)."""
    ds = ds.copy()
    for name in list(ds.variables):
        var = ds[name]
        if var.dtype.kind in "OUS":
            values = np.asarray(var.values)
            fixed = np.array(
                ["" if (v is None or (isinstance(v, float) and math.isnan(v))) else str(v) for v in values.ravel()],
                dtype=object,
            ).reshape(values.shape)
            if fixed.size == 0:  # xarray infers float for empty object arrays; keep them text
                fixed = fixed.astype("U1")
            if name in ds.coords:
                ds = ds.assign_coords({name: (var.dims, fixed, var.attrs)})
            else:
                ds[name] = (var.dims, fixed, var.attrs)
    return ds


def write_dataset(ds: xr.Dataset, path) -> Path:
    """Write the archive to netCDF4, atomically.

    Every numeric variable is compressed (zlib, level 4), text is stored as
    variable-length strings. The file is written beside ``path`` under a temporary
    name and moved into place with :func:`os.replace`, so an interrupted run never
    leaves a half-written file under the final name.

    Parameters
    ----------
    ds : xarray.Dataset
        Dataset to write.
    path : str or Path
        Destination; its folder must exist.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise FileNotFoundError(f"cannot write {path}: folder {path.parent} does not exist")
    ds = _text_to_object(with_impact_index(ds))
    for var in ds.variables.values():
        var.encoding = {}
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, mode="w", engine="netcdf4", format="NETCDF4", encoding=_encoding(ds))
    return path


def open_dataset(path) -> xr.Dataset:
    """Read an archive (or intermediate file) fully into memory and close the file.

    Parameters
    ----------
    path : str or Path
        netCDF4 file written by :func:`write_dataset`.

    Returns
    -------
    xarray.Dataset
        Text variables as object arrays of str.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"archive not found: {path}")
    with xr.open_dataset(path, engine="netcdf4", decode_times=False, decode_timedelta=False) as f:
        ds = f.load()
    return _text_to_object(current_names(ds).drop_vars("impact", errors="ignore"))
