"""Test helper: a complete, schema-conforming archive built from the forward model, without processing or fitting."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import xarray as xr

from ballimpact.archive import (
    COMPONENT_SPEED_M_S,
    MODEL_TIME_STEPS,
    SPEED_GRID_M_S,
    STIFFNESS_X_M,
    add_metadata,
    assemble_archive,
    impacts_dataset,
    set_variable_attrs,
)
from ballimpact.balls import BALLS
from ballimpact.processing import ImpactResult
from ballimpact.model import kelvin_voigt_parameters, simulate_impact, structural_stiffness

SAMPLE_RATE_HZ = 1.0e5  # [Hz] the model's own step (0.01 ms), so no resampling is needed
PRE_TRIGGER_SAMPLES = 150  # quiet samples before the contact in the raw trace
POST_SAMPLES = 250  # quiet samples after the contact
KCAL_N_PER_V = 250.0  # [N/V] nominal calibration factor
INTERVAL_FRACTION = 0.03  # half width of the made-up 95 % intervals, relative

SESSION_YAML = """\
session_id: {session_id}
date: 2026-11-21
operator: "Fixture Operator"
description: "Archive fixture built from the Goodwill & Haake (2004) model with Table 2 parameters and a little noise; {n_balls} ball types, several speeds, a few planted exclusions. This description is deliberately long so that the report has to wrap it over more than one line without running off the page."
synthetic: true
plate: {{polarity: 1}}
daq: {{sample_rate_hz: 100000.0, adc_range_v: [-10.0, 10.0]}}
gates: {{spacing_m: 0.1, resolution_s: 1.0e-6}}
balls:
{balls}
"""


def impact_result(impact_id, ball, **fields):
    """A ballimpact.processing.ImpactResult, sampled at the fixture's rate unless given."""
    fields.setdefault("sample_rate_hz", SAMPLE_RATE_HZ)
    return ImpactResult(impact_id=impact_id, ball=ball, **fields)


def _params(ball):
    return (BALLS[ball] if ball in BALLS else BALLS["pressurised"]).params


def _label(ball):
    return BALLS[ball].label if ball in BALLS else f"Custom: {ball}"


def _measured(impact_id, ball, vin, rng, *, status="ok", reason="", keep_series=True, clip_v=None):
    """A 'measured' impact: the model's force with noise, the calibration and a raw trace."""
    p = _params(ball)
    sim = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, record=True)
    good = np.isfinite(sim.force_N)
    t = sim.time_s[good]
    force = sim.force_N[good] + rng.normal(0.0, 3.0, good.sum())
    force[0] = 0.0
    kcal = KCAL_N_PER_V * (1 + rng.normal(0.0, 0.02))
    volt = force / kcal
    tc_s = float(sim.contact_time_s) * (1 + rng.normal(0.0, 0.005))
    cor = float(sim.cor) * (1 + rng.normal(0.0, 0.005))
    vout = cor * vin
    kb, cb = kelvin_voigt_parameters(p.mass_kg, tc_s, cor)
    noise = rng.normal(0.0, 0.004, PRE_TRIGGER_SAMPLES + volt.size + POST_SAMPLES)
    raw_v = noise + np.concatenate([np.zeros(PRE_TRIGGER_SAMPLES), volt, np.zeros(POST_SAMPLES)])
    if clip_v is not None:
        raw_v = np.minimum(raw_v, clip_v)
    raw_t = (np.arange(raw_v.size) - PRE_TRIGGER_SAMPLES) / SAMPLE_RATE_HZ
    r = impact_result(
        impact_id=impact_id,
        ball=ball,
        status=status,
        reason=reason,
        vin_m_s=vin,
        vout_m_s=vout,
        cor=cor,
        contact_time_ms=tc_s * 1e3,
        kcal_N_per_V=kcal,
        impulse_N_s=p.mass_kg * (vin + vout),
        peak_force_N=float(force.max()),
        time_to_peak_ms=float(t[np.argmax(force)]) * 1e3,
        max_displacement_mm=float(np.nanmax(sim.displacement_m)) * 1e3,
        kv_stiffness_kN_m=float(kb) / 1e3,
        kv_damping_N_s_m=float(cb),
        mass_kg=p.mass_kg,
        raw_time_s=raw_t,
        raw_voltage_V=raw_v,
        # the raw trace above: white noise, no hum, no amplifier decay, no plate ringing
        noise_rms_V=0.004,
        hum_amplitude_V=0.0,
        mains_hz=0.0,
        mains_source="none",
        tau_s=math.inf,
        tau_source="none",
    )
    if keep_series:
        r.time_s = t
        r.voltage_V = volt
        r.force_N = force
        r.velocity_m_s = sim.velocity_m_s[good]
        r.displacement_m = sim.displacement_m[good]
    return r


def _excluded_early(impact_id, ball, vin, rng, reason, *, with_raw=True):
    """An impact excluded before its contact was found: no series, raw time from the first sample."""
    r = impact_result(impact_id=impact_id, ball=ball, status="excluded", reason=reason, vin_m_s=vin)
    r.mass_kg = _params(ball).mass_kg
    if with_raw:
        n = 900
        r.raw_time_s = np.arange(n) / SAMPLE_RATE_HZ
        r.raw_voltage_V = rng.normal(0.0, 0.004, n) + 2.5 * np.exp(-(((np.arange(n) - 400) / 60.0) ** 2))
    return r


def _ball_fit(ball, n_impacts, *, failed=False, reason="no good impacts"):
    """Per-ball part: 'fitted' parameters = Table 2, made-up intervals, curves from the model."""
    p = _params(ball)
    table = p.table_units()
    nan = np.nan
    n_speed, n_time, n_x = SPEED_GRID_M_S.size, MODEL_TIME_STEPS, STIFFNESS_X_M.size
    values = {
        "ball_label": _label(ball),
        "mass_kg": p.mass_kg,
        "n_impacts": int(n_impacts),
        "kb0_source": "config" if ball in BALLS else "extrapolated",
        "fit_message": "converged" if not failed else f"fit failed: {reason}",
    }
    if failed:
        for name in ("kb0_kN_m", "ak_kN_m", "a", "ac_kN_s_m3", "ak_a_correlation",
                     "contact_time_rmse_pct", "cor_rmse_pct"):
            values[name] = nan
        for name in ("kb0", "ak", "a", "ac"):
            values[f"{name}_lo"] = values[f"{name}_hi"] = nan
        curves = {k: np.full(n_speed, nan) for k in (
            "model_contact_time_ms", "model_contact_time_ms_lo", "model_contact_time_ms_hi",
            "model_cor", "model_cor_lo", "model_cor_hi", "model_peak_force_N")}
        comps = {k: np.full(n_time, nan) for k in (
            "comp_total_force_N", "comp_stiffness_force_N", "comp_damping_force_N",
            "comp_momentum_flux_force_N", "comp_displacement_m")}
        stiff = np.full(n_x, nan)
    else:
        values.update(
            kb0_kN_m=table["kb0_kN_m"], ak_kN_m=table["ak_kN_m"], a=table["a"], ac_kN_s_m3=table["ac_kN_s_m3"],
            ak_a_correlation=0.9, contact_time_rmse_pct=1.2, cor_rmse_pct=0.8,
        )
        f = INTERVAL_FRACTION
        for name, col in (("ak", "ak_kN_m"), ("a", "a"), ("ac", "ac_kN_s_m3")):
            values[f"{name}_lo"], values[f"{name}_hi"] = table[col] * (1 - f), table[col] * (1 + f)
        if values["kb0_source"] == "extrapolated":
            values["kb0_lo"], values["kb0_hi"] = table["kb0_kN_m"] * (1 - f), table["kb0_kN_m"] * (1 + f)
        else:
            values["kb0_lo"] = values["kb0_hi"] = nan
        sim = simulate_impact(SPEED_GRID_M_S, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        corners = np.array([[s1, s2, s3] for s1 in (-1, 1) for s2 in (-1, 1) for s3 in (-1, 1)], float)
        scale = 1 + f * corners  # (8, 3)
        band = simulate_impact(
            SPEED_GRID_M_S[None, :], p.mass_kg, p.kb0_N_m,
            (p.ak * scale[:, 0])[:, None], (p.a * scale[:, 1])[:, None], (p.ac * scale[:, 2])[:, None],
        )
        tc_ms = band.contact_time_s * 1e3
        curves = {
            "model_contact_time_ms": sim.contact_time_s * 1e3,
            "model_contact_time_ms_lo": np.minimum(tc_ms.min(axis=0), sim.contact_time_s * 1e3),
            "model_contact_time_ms_hi": np.maximum(tc_ms.max(axis=0), sim.contact_time_s * 1e3),
            "model_cor": sim.cor,
            "model_cor_lo": np.minimum(band.cor.min(axis=0), sim.cor),
            "model_cor_hi": np.maximum(band.cor.max(axis=0), sim.cor),
            "model_peak_force_N": sim.peak_force_N,
        }
        comp = simulate_impact(COMPONENT_SPEED_M_S, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, record=True)
        m = min(comp.time_s.size, n_time)
        comps = {}
        for name, arr in (
            ("comp_total_force_N", comp.force_N), ("comp_stiffness_force_N", comp.stiffness_force_N),
            ("comp_damping_force_N", comp.damping_force_N),
            ("comp_momentum_flux_force_N", comp.momentum_flux_force_N),
            ("comp_displacement_m", comp.displacement_m),
        ):
            out = np.full(n_time, nan)
            out[:m] = arr[:m]
            comps[name] = out
        stiff = structural_stiffness(STIFFNESS_X_M, p.kb0_N_m, p.ak, p.a) / 1e3
    data = {k: ("ball", np.array([v], dtype=object if isinstance(v, str) else None)) for k, v in values.items()}
    data.update({k: (("ball", "speed"), v[None, :]) for k, v in curves.items()})
    data.update({k: (("ball", "model_time"), v[None, :]) for k, v in comps.items()})
    data["model_stiffness_kN_m"] = (("ball", "stiffness_x"), stiff[None, :])
    ds = xr.Dataset(
        data,
        coords={
            "ball": np.array([ball], dtype=object),
            "speed_m_s": ("speed", SPEED_GRID_M_S),
            "model_time_s": ("model_time", np.arange(n_time) * 1e-5),
            "stiffness_x_m": ("stiffness_x", STIFFNESS_X_M),
        },
    )
    return set_variable_attrs(ds)


def make_results(
    *,
    balls=("pressurised", "punctured"),
    speeds_m_s=(15.0, 20.0, 25.0, 30.0),
    no_good_ball=None,
    with_exclusions=True,
    seed=0,
):
    """The list of fake ImpactResults in raw order (interleaved balls, then the exclusions)."""
    rng = np.random.default_rng(seed)
    results = []
    k = 0
    for vin in speeds_m_s:
        for ball in balls:
            k += 1
            impact_id = f"i{k:03d}"
            if ball == no_good_ball:
                results.append(
                    _excluded_early(impact_id, ball, vin, rng, "more than one impact in the trace (2 found)")
                )
            else:
                results.append(_measured(impact_id, ball, float(vin) + rng.normal(0, 0.1), rng))
    if with_exclusions:
        b0, b1 = balls[0], balls[-1]
        results.insert(
            2,
            _measured(
                "clip01", b0, 27.0, rng, status="excluded",
                reason="clipping: 14 samples at the ADC rail (+10 V) during the contact",
                clip_v=2.6,
            ),
        )
        results.insert(5, _excluded_early("gate01", b1, 22.0, rng, "missing gate time gate_out_1_s"))
        results.append(
            _excluded_early("trace01", b0, np.nan, rng, "trace file not found: traces/trace01.csv", with_raw=False)
        )
    return results


def make_archive(
    *,
    balls=("pressurised", "punctured"),
    speeds_m_s=(15.0, 20.0, 25.0, 30.0),
    no_good_ball=None,
    failed_fit_ball=None,
    with_exclusions=True,
    synthetic=True,
    session_id="fixture-session-01",
    seed=0,
) -> xr.Dataset:
    """A complete archive from known inputs.

    Parameters
    ----------
    balls : sequence of str
        Ball keys; Table 2 keys use their parameters, other keys borrow ball 1's
        (and get NaN paper values).
    speeds_m_s : sequence of float
        Inbound speeds [m/s] of the good impacts of each ball.
    no_good_ball : str, optional
        A ball whose impacts are all excluded (its fit fails: NaN parameters).
    failed_fit_ball : str, optional
        A ball with good impacts whose fit failed (NaN parameters).
    with_exclusions : bool
        Plant one clipped, one missing-gate and one missing-trace impact.
    """
    results = make_results(
        balls=balls, speeds_m_s=speeds_m_s, no_good_ball=no_good_ball,
        with_exclusions=with_exclusions, seed=seed,
    )
    trace_info = {
        r.impact_id: (f"traces/{r.impact_id}.csv", hashlib.sha256(r.impact_id.encode()).hexdigest())
        for r in results
    }
    impacts = impacts_dataset(results, trace_info=trace_info)
    fits = []
    for ball in balls:
        n_ok = sum(1 for r in results if r.ball == ball and r.status == "ok")
        if ball == no_good_ball:
            fits.append(_ball_fit(ball, 0, failed=True, reason="no good impacts"))
        elif ball == failed_fit_ball:
            fits.append(_ball_fit(ball, n_ok, failed=True, reason="did not converge"))
        else:
            fits.append(_ball_fit(ball, n_ok))
    ds = assemble_archive(impacts, fits)
    ball_yaml = "\n".join(
        f"  {b}:\n    label: \"{_label(b)}\"\n    mass_g: {_params(b).mass_kg * 1e3:.1f}" for b in balls
    )
    yaml_text = SESSION_YAML.format(session_id=session_id, n_balls=len(balls), balls=ball_yaml)
    raw_sha = {"session.yaml": "0" * 64, "impacts.csv": "1" * 64}
    raw_sha.update({f"traces/{r.impact_id}.csv": "2" * 64 for r in results})
    return add_metadata(
        ds,
        session_id=session_id,
        session_yaml_text=yaml_text,
        raw_sha256=raw_sha,
        synthetic=synthetic,
        history="tests/archive_fixture.py make_archive",
    )
