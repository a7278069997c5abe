"""The session's rig between the impacts dataset and the archive: gathered, identified, stored and read back."""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from typing import NamedTuple

from .rig import (RIG_QUANTITIES, PlateFit, Rig, RigEstimate, identify_rig, pooled_ringing, ringing_response,
                  ringing_segments)

__all__ = ["RIG_DIM", "floats_of", "RingingOverlay", "session_rig", "rig_variables", "read_rig", "rig_warnings", "plate_impacts",
           "ringing_overlay"]

RIG_DIM = "rig_quantity"  #: the archive's dimension of the rig's quantities (RIG_QUANTITIES, in order)


def _texts(ds: xr.Dataset, name: str) -> list[str]:
    return [str(v) for v in ds[name].values] if name in ds else [""] * ds.sizes["impact"]


def floats_of(ds: xr.Dataset, name: str) -> np.ndarray:
    """The per-impact variable ``name`` of ``ds`` as floats; NaN where ``ds`` lacks it."""
    return np.asarray(ds[name].values, dtype=float) if name in ds else np.full(ds.sizes["impact"], np.nan)


def session_rig(ds: xr.Dataset, meta) -> Rig:
    """Identify the rig of a session from its impacts dataset (``work/impacts.nc``) and its session.yaml.

    The impacts whose trace was read and whose contact was found, with no fault excluding them, lend their free
    ringing, hum, noise and time constant; those whose kCAL is ok lend their kCAL (:func:`ballimpact.rig.identify_rig`).

    Parameters
    ----------
    ds : xarray.Dataset
        The per-impact dataset (:func:`ballimpact.archive.impacts_dataset`, chunks joined).
    meta : ballimpact.session.SessionMeta
        The session's metadata (its stated keys).

    Returns
    -------
    Rig
    """
    from .checks import check_of
    from .problems import ProblemKind

    codes = _texts(ds, "reason_code")
    status = _texts(ds, "status")
    fault_codes = {k.value for k in ProblemKind if check_of(k).fault}
    usable = [s != "excluded" or not (set(c.split(";")) & fault_codes) for s, c in zip(status, codes)]
    usable = np.asarray(usable) & np.isfinite(floats_of(ds, "contact_time_ms"))
    impacts = {
        "impact_id": [str(v) for v in ds["impact_id"].values],
        "raw_time_s": ds["raw_time_s"].values, "raw_voltage_V": ds["raw_voltage_V"].values,
        "contact_time_ms": floats_of(ds, "contact_time_ms"), "noise_rms_V": floats_of(ds, "noise_rms_V"),
        "hum_amplitude_V": floats_of(ds, "hum_amplitude_V"), "mains_hz": floats_of(ds, "mains_frequency_hz"),
        # an impact whose hum was not resolved (50 and 60 Hz alike, or a hum bending under the contact) lends no
        # mains frequency
        "mains_source": [s if ProblemKind.MAINS_UNRESOLVED.value not in c.split(";") else "unresolved"
                         for s, c in zip(_texts(ds, "mains_source"), codes)],
        "tau_s": floats_of(ds, "amplifier_time_constant_s"),
        "tau_se_s": floats_of(ds, "amplifier_time_constant_se_s"),
        "tau_source": _texts(ds, "amplifier_time_constant_source"),
        "kcal_N_per_V": floats_of(ds, "kcal_N_per_V"), "sample_rate_hz": floats_of(ds, "sample_rate_hz"),
        "vout_m_s": floats_of(ds, "vout_m_s"),
        "usable": usable,
        "kcal_ok": np.array([s == "ok" for s in _texts(ds, "kcal_status")]),
    }
    return identify_rig(impacts, meta.sample_rate_hz, stated_plate=meta.plate_resonance,
                        stated_time_constant_s=meta.time_constant_s, stated_mains_hz=meta.mains_hz,
                        bandwidth_hz=meta.bandwidth_hz)


def rig_variables(rig: Rig) -> xr.Dataset:
    """The rig as archive variables on the ``rig_quantity`` dimension (value, interval, source, impacts, note).

    The plate fit's detection statistic and the warnings go into attributes of ``rig_value``.
    """
    names = list(RIG_QUANTITIES)
    est = [rig[n] for n in names]
    text = lambda values: np.array(values, dtype=object)  # noqa: E731
    ds = xr.Dataset(
        {
            "rig_value": (RIG_DIM, np.array([e.value for e in est], dtype=float)),
            "rig_low": (RIG_DIM, np.array([e.low for e in est], dtype=float)),
            "rig_high": (RIG_DIM, np.array([e.high for e in est], dtype=float)),
            "rig_source": (RIG_DIM, text([e.source for e in est])),
            "rig_n_impacts": (RIG_DIM, np.array([e.n_impacts for e in est], dtype=np.int32)),
            "rig_unit": (RIG_DIM, text([RIG_QUANTITIES[n][0] for n in names])),
            "rig_note": (RIG_DIM, text([e.note for e in est])),
        },
        coords={RIG_DIM: text(names)},
    )
    fit = rig.plate_fit
    ds["rig_value"].attrs.update({
        "plate_detection_z": float(fit.detection_z) if fit is not None else math.nan,
        "plate_ringing_fraction": float(fit.amplitude_fraction) if fit is not None else math.nan,
        "plate_impacts": ",".join(_segment_ids(fit)),
        "rig_warnings": json.dumps(list(rig.warnings)),
    })
    return ds


def _segment_ids(fit) -> list[str]:
    return [] if fit is None else list(fit.impact_ids)


def read_rig(ds: xr.Dataset) -> dict:
    """The rig stored by :func:`rig_variables`: name -> RigEstimate; empty for an archive without one."""
    if "rig_value" not in ds:
        return {}
    out = {}
    for i, name in enumerate(str(n) for n in ds[RIG_DIM].values):
        out[name] = RigEstimate(float(ds["rig_value"].values[i]), float(ds["rig_low"].values[i]),
                                float(ds["rig_high"].values[i]), str(ds["rig_source"].values[i]),
                                int(ds["rig_n_impacts"].values[i]), str(ds["rig_note"].values[i]))
    return out


def rig_warnings(ds: xr.Dataset) -> list[str]:
    """The warnings of the rig's identification stored in the archive (stated keys the traces disagree with)."""
    if "rig_value" not in ds:
        return []
    return list(json.loads(ds["rig_value"].attrs.get("rig_warnings", "[]")))


def plate_impacts(ds: xr.Dataset) -> list[str]:
    """The impacts whose free ringing the plate's fit pooled (``rig_value``'s attribute ``plate_impacts``)."""
    if "rig_value" not in ds:
        return []
    text = str(ds["rig_value"].attrs.get("plate_impacts", "") or "")
    return [i for i in text.split(",") if i]


class RingingOverlay(NamedTuple):
    """The pooled free ringing of an archive, each impact's on one curve (:func:`ringing_overlay`)."""

    frequency_hz: float  #: fn the curves are drawn for [Hz]
    damping_ratio: float  #: zeta [-]
    source: str  #: "identified" or "stated"
    impact_ids: tuple  #: the impact of each curve
    curves: list  #: per impact (time [s], ringing / its amplitude [-]); each lies on exp(-zeta wn t) cos(wd t)


def ringing_overlay(ds: xr.Dataset) -> RingingOverlay | None:
    """The free ringing after every contact the plate's fit pooled, rebuilt from the archive for a figure.

    Each impact's ringing segment is read again from its raw trace (:func:`ballimpact.rig.ringing_segments`, for
    the impacts of :func:`plate_impacts`). At the session's resonance (fn, zeta: ``rig_value``, identified or
    stated) the segment's amplitudes (a, b) and baseline (a cubic and the mains harmonics of
    :func:`ballimpact.rig.pooled_ringing`) are its least-squares fit, as in the pooled fit; the baseline is taken
    off. ``a cos(wd t) + b sin(wd t) = A cos(wd t - phi)``, ``A = hypot(a, b)``; with ``t' = t - phi / wd`` the
    ringing is ``A e^(-zeta wn phi / wd) e^(-zeta wn t') cos(wd t')``, so dividing by that amplitude puts every
    impact on one curve ``e^(-zeta wn t') cos(wd t')``, which the curves are against.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive (or ``work/impacts.nc``) with the rig variables and the raw traces.

    Returns
    -------
    RingingOverlay or None
        None when the archive has no rig, no plate resonance (source "none") or no impact whose ringing was fitted.
    """
    rig = read_rig(ds)
    fn_est, zeta_est = rig.get("plate_resonance_hz"), rig.get("plate_damping_ratio")
    if fn_est is None or zeta_est is None or fn_est.source == "none" or "raw_time_s" not in ds:
        return None
    fn, zeta = fn_est.value, zeta_est.value
    if not (math.isfinite(fn) and fn > 0 and math.isfinite(zeta) and 0 <= zeta < 1):
        return None
    wanted = set(plate_impacts(ds))
    ids = [str(v) for v in ds["impact_id"].values]
    use = np.array([i in wanted for i in ids])
    segments = ringing_segments(ids, ds["raw_time_s"].values, ds["raw_voltage_V"].values,
                                floats_of(ds, "contact_time_ms"), floats_of(ds, "noise_rms_V"), use,
                                vout_m_s=floats_of(ds, "vout_m_s"))
    if not segments:
        return None
    mains = rig["mains_hz"].value if "mains_hz" in rig else math.nan
    mains = mains if math.isfinite(mains) and mains > 0 else None
    n = len(segments)
    unit = PlateFit(fn, zeta, math.nan, math.nan, math.nan, n, math.nan, np.tile([1.0, 0.0], (n, 1)),
                    tuple(s.impact_id for s in segments), None)
    cos_cols = pooled_ringing(segments, unit, mains_hz=mains)  # each segment's cos column less its baseline part
    sin_cols = pooled_ringing(segments, unit._replace(amplitudes=np.tile([0.0, 1.0], (n, 1))), mains_hz=mains)
    wn = 2.0 * math.pi * fn
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    curves, used = [], []
    for seg, (t, observed, pc), (_, _, ps) in zip(segments, cos_cols, sin_cols):
        (a, b), *_ = np.linalg.lstsq(np.column_stack([pc, ps]), observed, rcond=None)
        amplitude = math.hypot(a, b)
        if not amplitude > 0:
            continue
        # observed - its baseline fitted jointly with the ringing = its projection + the ringing's baseline part
        ringing = observed - (a * pc + b * ps) + ringing_response(t, fn, zeta, (a, b))
        shift = math.atan2(b, a) / wd
        curves.append((t - shift, ringing / (amplitude * math.exp(-zeta * wn * shift))))
        used.append(seg.impact_id)
    if not curves:
        return None
    return RingingOverlay(fn, zeta, fn_est.source, tuple(used), curves)
