"""Test helper: a session archive whose plate rings after every contact with a known resonance, and rig variables
set from known values (no identification runs)."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ballimpact.rig import RIG_QUANTITIES, PlateFit, Rig, RigEstimate
from ballimpact.rig_archive import rig_variables

FS_HZ = 100_000.0  # [Hz]
FN_HZ = 3000.0  # [Hz] the plate's true resonance
ZETA = 0.05  # its true damping ratio
TC_MS = 1.0  # [ms] every contact's length
NOISE_V = 1.0e-3  # [V] white noise
RING_V = 0.05  # [V] the ringing's amplitude at the contact's end
PEAK_V = 2.0  # [V] the contact's peak
TAU_S = 0.8  # [s] the amplifier time constant stated per impact
KCAL = 180.0  # [N/V]


def ringing_traces(n: int, seed: int = 0):
    """Raw traces of ``n`` contacts: a half-sine of TC_MS, then the plate's free ringing
    ``RING_V e^(-zeta wn t) cos(wd t - phi_i)`` (a random phase each) on a slow quadratic baseline, with white noise.

    Returns (time [s] from contact start, voltage [V]) arrays, shape (n, samples).
    """
    rng = np.random.default_rng(seed)
    t = np.arange(-0.5e-3, 5.0e-3, 1.0 / FS_HZ)
    tc = TC_MS * 1e-3
    wn = 2 * math.pi * FN_HZ
    wd = wn * math.sqrt(1 - ZETA**2)
    volts = []
    for _ in range(n):
        phi = rng.uniform(-math.pi, math.pi)
        after = np.clip(t - tc, 0.0, None)
        v = np.where((t >= 0) & (t <= tc), PEAK_V * np.sin(math.pi * np.clip(t, 0, tc) / tc), 0.0)
        ring = RING_V * np.exp(-ZETA * wn * after) * np.cos(wd * after - phi)
        baseline = -0.02 + 0.004 * (t / 5e-3) - 0.003 * (t / 5e-3) ** 2
        v = v + np.where(t > tc, ring, 0.0) + baseline + rng.normal(0.0, NOISE_V, t.size)
        volts.append(v)
    return np.tile(t, (n, 1)), np.array(volts)


def estimates(*, plate: str = "identified", fn_hz: float = FN_HZ, zeta: float = ZETA, n: int = 8) -> dict:
    """RigEstimate of every quantity; the plate ``identified`` (at fn_hz, zeta), ``stated`` or ``none``."""
    if plate == "identified":
        fn = RigEstimate(fn_hz, fn_hz * 0.999, fn_hz * 1.001, "identified", n)
        z = RigEstimate(zeta, zeta * 0.98, zeta * 1.02, "identified", n)
    elif plate == "stated":
        fn = RigEstimate(fn_hz, fn_hz, fn_hz, "stated", n, "the session's traces give 3.1 kHz (95 % interval 3.09-3.11)")
        z = RigEstimate(zeta, zeta, zeta, "stated", n, "the session's traces give 0.05 (95 % interval 0.049-0.051)")
    else:
        note = f"no free ringing above the noise after {n} contacts (z = 1.2, 8 needed): an ideal plate"
        fn = z = RigEstimate(math.nan, n_impacts=n, note=note)
    out = {
        "plate_resonance_hz": fn, "plate_damping_ratio": z,
        "time_constant_s": RigEstimate(TAU_S, TAU_S * 0.99, TAU_S * 1.01, "identified", n),
        "mains_hz": RigEstimate(50.0, 50.0, 50.0, "stated"),
        "hum_amplitude_V": RigEstimate(0.0, 0.0, 0.0, "identified", n),
        "noise_rms_V": RigEstimate(NOISE_V, NOISE_V * 0.95, NOISE_V * 1.05, "identified", n),
        "kcal_N_per_V": RigEstimate(KCAL, KCAL - 1.0, KCAL + 1.0, "identified", n),
        "kcal_spread": RigEstimate(0.01, source="identified", n_impacts=n),
    }
    assert list(out) == list(RIG_QUANTITIES)
    return out


def rig_dataset(ids, rig_estimates: dict, *, fitted_ids=None, warnings=()) -> xr.Dataset:
    """The rig variables of :func:`ballimpact.rig_archive.rig_variables` for these estimates; the plate fit lists
    ``fitted_ids`` (default: every id) as the impacts whose ringing it pooled."""
    fitted = tuple(ids if fitted_ids is None else fitted_ids)
    fit = PlateFit(FN_HZ, ZETA, 1.0, 1e-3, 50.0, len(fitted), RING_V / PEAK_V, np.zeros((len(fitted), 2)), fitted,
                   None)
    return rig_variables(Rig(rig_estimates, fit, tuple(warnings)))


def ringing_archive(n: int = 8, *, plate: str = "identified", fn_hz: float = FN_HZ, seed: int = 0,
                    excluded=(), warnings=()) -> xr.Dataset:
    """An archive of ``n`` impacts whose plate rings at FN_HZ, ZETA, with the per-impact variables the rig's figures
    read and the rig variables (:func:`estimates`: the plate ``plate``, at ``fn_hz``)."""
    t, v = ringing_traces(n, seed)
    ids = [f"imp-{k:03d}" for k in range(n)]
    rng = np.random.default_rng(seed + 1)
    status = np.array(["excluded" if k in excluded else "ok" for k in range(n)], dtype=object)
    ds = xr.Dataset(
        {
            "raw_time_s": (("impact", "raw_sample"), t),
            "raw_voltage_V": (("impact", "raw_sample"), v),
            "contact_time_ms": ("impact", np.full(n, TC_MS)),
            "noise_rms_V": ("impact", np.full(n, NOISE_V)),
            "sample_rate_hz": ("impact", np.full(n, FS_HZ)),
            "status": ("impact", status),
            "kcal_N_per_V": ("impact", KCAL * (1 + 0.01 * rng.standard_normal(n))),
            "kcal_u_N_per_V": ("impact", np.full(n, 0.5)),
            "kcal_status": ("impact", np.array(["ok"] * n, dtype=object)),
            "amplifier_time_constant_s": ("impact", TAU_S * (1 + 0.01 * rng.standard_normal(n))),
            "amplifier_time_constant_se_s": ("impact", np.full(n, 0.004)),
            "amplifier_time_constant_source": ("impact", np.array(["estimated"] * n, dtype=object)),
        },
        coords={"impact_id": ("impact", np.array(ids, dtype=object))},
    )
    return ds.merge(rig_dataset(ids, estimates(plate=plate, fn_hz=fn_hz, n=n), warnings=warnings))
