"""Tests of ballimpact.rig: the session's plate, amplifier, mains and kCAL identified from all its impacts.

The traces here are made in this file, apart from ``ballimpact.synth`` and the benches: a half-sine force through
a second-order plate integrated by scipy.signal.lsim, or the free ringing written down analytically.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import signal

from ballimpact import rig
from ballimpact.rig import (COVERAGE, DETECT_Z, MIN_IMPACTS, RIG_QUANTITIES, RigWarning, RingingSegment,
                            fit_free_ringing, identify_rig, pooled_median, pooled_time_constant, ringing_segments)

FS = 100_000.0


def _free_segments(rng, n, fn, zeta, *, amplitude=0.02, noise=1e-3, length_s=3e-3):
    """n analytic free ringings of random phase on a random cubic baseline, with white noise [V]."""
    t = np.arange(int(length_s * FS)) / FS
    wn = 2 * math.pi * fn
    wd = wn * math.sqrt(1 - zeta ** 2)
    out = []
    for i in range(n):
        phase, amp = rng.uniform(0, 2 * math.pi), amplitude * rng.uniform(0.5, 1.5)
        ring = amp * np.exp(-zeta * wn * t) * np.cos(wd * t + phase)
        base = np.polyval(rng.normal(0, 0.01, 4), t / t[-1])
        out.append(RingingSegment(f"i{i}", t, ring + base + rng.normal(0, noise, t.size), noise, 1.0))
    return out


@pytest.mark.parametrize("fn, zeta", [(1500.0, 0.02), (4000.0, 0.08), (12000.0, 0.12)])
def test_fit_free_ringing_covers_the_truth(fn, zeta):
    hits = []
    for seed in range(12):
        fit = fit_free_ringing(_free_segments(np.random.default_rng(seed), 12, fn, zeta), FS)
        assert fit.detected
        hits.append(abs(fit.frequency_hz - fn) <= COVERAGE * fit.frequency_u_hz
                    and abs(fit.damping_ratio - zeta) <= COVERAGE * fit.damping_u)
        assert_allclose(fit.frequency_hz, fn, rtol=0.01)
        assert_allclose(fit.damping_ratio, zeta, rtol=0.15)
    assert sum(hits) >= 10, hits  # about 95 % intervals: at least 10 of 12


def test_fit_free_ringing_finds_nothing_in_noise():
    for seed in range(8):
        rng = np.random.default_rng(100 + seed)
        fit = fit_free_ringing(_free_segments(rng, 20, 3000.0, 0.05, amplitude=0.0), FS)
        assert not fit.detected, fit.detection_z
        assert fit.detection_z < DETECT_Z


def test_fit_free_ringing_pools_what_no_trace_shows_alone():
    """A ringing of 0.6 noise deviations at its start: under the detection in one trace, clear in thirty."""
    rng = np.random.default_rng(7)
    segments = _free_segments(rng, 30, 2500.0, 0.03, amplitude=0.6e-3)
    alone = [fit_free_ringing(segments[i:i + 2], FS).detection_z for i in range(0, 6, 2)]
    pooled = fit_free_ringing(segments, FS)
    assert max(alone) < pooled.detection_z
    assert pooled.detected
    assert_allclose(pooled.frequency_hz, 2500.0, rtol=0.01)


def test_fit_free_ringing_validates():
    with pytest.raises(ValueError, match="at least 2 segments"):
        fit_free_ringing([], FS)
    with pytest.raises(ValueError, match="sample_rate_hz must be positive"):
        fit_free_ringing(_free_segments(np.random.default_rng(0), 3, 2000.0, 0.05), 0.0)


def _plate_session(rng, n, fn, zeta, *, tau=2.0, noise=1e-3, kcal=500.0):
    """n impacts of half-sine forces (TC 4-5 ms, 500-2000 N) through a second-order plate (lsim) and a charge
    amplifier's high-pass (time constant tau), sampled at FS; the impacts mapping identify_rig takes."""
    wn = 2 * math.pi * fn
    plate = signal.lti([wn * wn], [1.0, 2 * zeta * wn, wn * wn])
    keys = ("impact_id", "raw_time_s", "raw_voltage_V", "contact_time_ms", "noise_rms_V", "hum_amplitude_V",
            "mains_hz", "mains_source", "tau_s", "tau_se_s", "tau_source", "kcal_N_per_V", "sample_rate_hz",
            "usable", "kcal_ok")
    impacts = {k: [] for k in keys}
    for i in range(n):
        tc, peak = rng.uniform(4e-3, 5e-3), rng.uniform(500.0, 2000.0)
        t = np.arange(-2e-3, 30e-3, 1 / FS)
        force = np.where((t >= 0) & (t <= tc), peak * np.sin(np.pi * np.clip(t, 0, tc) / tc), 0.0)
        _, sensed, _ = signal.lsim(plate, force, t - t[0])
        volts = sensed / kcal
        volts = volts - np.cumsum(volts) / FS / tau  # first order in t / tau: the amplifier's undershoot
        volts = volts + rng.normal(0, noise, t.size)
        for k, v in (("impact_id", f"i{i}"), ("raw_time_s", t), ("raw_voltage_V", volts),
                     ("contact_time_ms", 1e3 * tc), ("noise_rms_V", noise), ("hum_amplitude_V", 0.0),
                     ("mains_hz", 0.0), ("mains_source", "none"), ("tau_s", tau * rng.normal(1, 0.02)),
                     ("tau_se_s", 0.02 * tau), ("tau_source", "estimated"),
                     ("kcal_N_per_V", kcal * rng.normal(1, 0.005)), ("sample_rate_hz", FS), ("usable", True),
                     ("kcal_ok", True)):
            impacts[k].append(v)
    return impacts


def test_identify_rig_finds_a_plate_through_lsim():
    fn, zeta = 3100.0, 0.06
    r = identify_rig(_plate_session(np.random.default_rng(3), 20, fn, zeta), FS)
    f, z = r["plate_resonance_hz"], r["plate_damping_ratio"]
    assert f.source == z.source == "identified"
    assert f.low <= fn <= f.high and z.low <= zeta <= z.high
    assert f.high - f.low < 0.02 * fn
    assert r["time_constant_s"].low <= 2.0 <= r["time_constant_s"].high
    assert_allclose(r["kcal_N_per_V"].value, 500.0, rtol=0.005)
    assert set(r.estimates) == set(RIG_QUANTITIES)


def test_identify_rig_stated_plate_used_and_checked():
    impacts = _plate_session(np.random.default_rng(4), 15, 5000.0, 0.05)
    with pytest.warns(RigWarning, match=r"plate.resonance_hz = 4\.5 kHz"):
        r = identify_rig(impacts, FS, stated_plate=(4500.0, 0.05))
    assert r["plate_resonance_hz"].value == 4500.0 and r["plate_resonance_hz"].source == "stated"
    assert "the session's traces give 5" in r["plate_resonance_hz"].note
    assert any("plate.resonance_hz" in w for w in r.warnings)


def test_identify_rig_stated_plate_within_the_identified_interval_is_not_warned(recwarn):
    impacts = _plate_session(np.random.default_rng(7), 15, 5000.0, 0.05)
    identified = identify_rig(impacts, FS)
    stated = identify_rig(impacts, FS, stated_plate=(identified["plate_resonance_hz"].value,
                                                      identified["plate_damping_ratio"].value))
    assert not [w for w in recwarn if issubclass(w.category, RigWarning)]
    assert stated.warnings == ()
    assert identified["plate_resonance_hz"].low <= 5000.0 <= identified["plate_resonance_hz"].high


def test_identify_rig_ideal_plate_and_small_session():
    impacts = _plate_session(np.random.default_rng(6), 12, 3000.0, 0.05)
    ideal = {k: v for k, v in impacts.items()}
    ideal["raw_voltage_V"] = [np.where(t >= 0, 0, 0) + np.random.default_rng(i).normal(0, 1e-3, t.size)
                              for i, t in enumerate(impacts["raw_time_s"])]
    r = identify_rig(ideal, FS)
    assert r["plate_resonance_hz"].source == "none"
    assert "no free ringing above the noise" in r["plate_resonance_hz"].note
    small = {k: v[:MIN_IMPACTS - 1] for k, v in impacts.items()}
    r = identify_rig(small, FS)
    assert r["plate_resonance_hz"].source == "none"
    assert "too few to identify the plate" in r["plate_resonance_hz"].note


def test_ringing_segments_skip_what_cannot_ring():
    impacts = _plate_session(np.random.default_rng(8), 3, 3000.0, 0.05)
    use = [True, False, True]
    tc = list(impacts["contact_time_ms"])
    tc[2] = math.nan
    segs = ringing_segments(impacts["impact_id"], impacts["raw_time_s"], impacts["raw_voltage_V"], tc,
                            impacts["noise_rms_V"], use)
    assert [s.impact_id for s in segs] == ["i0"]
    assert segs[0].time_s[0] == 0.0
    assert_allclose(segs[0].time_s[-1], rig.RING_WINDOW_S, atol=1.5 / FS)


def test_pooled_time_constant_is_an_inverse_variance_mean_of_kappa():
    est = pooled_time_constant([2.0] * 6, [0.1] * 6)
    assert_allclose(est.value, 2.0, rtol=1e-12)
    # kappa = 0.5 /s, its standard error 0.1 / 4 = 0.025 per impact, 0.025 / sqrt(6) pooled
    se = 0.025 / math.sqrt(6)
    assert_allclose([est.low, est.high], [1 / (0.5 + COVERAGE * se), 1 / (0.5 - COVERAGE * se)], rtol=1e-12)
    scattered = pooled_time_constant([1.0, 4.0] * 3, [0.01] * 6)
    assert scattered.high - scattered.low > 0.5  # the Birge ratio widens it to the scatter
    assert pooled_time_constant([2.0] * 3, [0.1] * 3).source == "none"


def test_pooled_median_interval():
    x = np.random.default_rng(0).normal(10.0, 1.0, 400)
    est = pooled_median(x)
    assert est.low < 10.0 < est.high
    assert_allclose(est.high - est.low, 2 * COVERAGE * 1.2533 / 20.0, rtol=0.15)
    assert_allclose(pooled_median(x, relative_spread=True).value, 0.1, rtol=0.15)


def test_a_line_that_does_not_decay_is_not_the_plate():
    """A steady tone after every contact (interference) stands far out of the noise but does not decay: no plate."""
    segments = _free_segments(np.random.default_rng(9), 12, 6000.0, 0.0, amplitude=0.01)
    fit = fit_free_ringing(segments, FS)
    assert fit.detection_z > DETECT_Z and not fit.detected
    impacts = _plate_session(np.random.default_rng(10), 8, 3000.0, 0.05)
    ideal = dict(impacts, raw_voltage_V=[np.random.default_rng(i).normal(0, 1e-3, t.size) + 0.01 * np.cos(
        2 * math.pi * 6000.0 * t) for i, t in enumerate(impacts["raw_time_s"])])
    r = identify_rig(ideal, FS)
    assert r["plate_resonance_hz"].source == "none"
    assert "may not decay" in r["plate_resonance_hz"].note
