"""Tests of conditioning's integrity checks that the sampled mutation run asked for: the 50/60 Hz hum checks
(`mains_problems`, the problem each branch exists for), the level before the contact, spikes in short records.

The rest of conditioning's tests are in tests/test_conditioning.py.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose
from tracekit import make_trace

from ballimpact.signal.integrity import MAINS_AMBIGUOUS_FRACTION, mains_problems
from ballimpact.signal.baseline import BaselineFit
from ballimpact.signal.conditioning import condition_voltage
from ballimpact.signal.spikes import remove_spikes
from ballimpact.problems import ProblemKind

FS = 10_000.0  # [Hz]
N = 200


def _fit(baseline, hum_amplitudes=(0.004, 0.001), quiet=slice(10, 150)):
    q = np.zeros(N, dtype=bool)
    q[quiet] = True
    return BaselineFit(baseline=np.asarray(baseline, dtype=float), coef={}, kappa=0.0, kappa_se=0.0, has_post=False,
                        noise=1e-4, hum_amplitudes=hum_amplitudes, bic=0.0, quiet=q, pre=q, post=np.zeros(N, bool))


def _problems(fit, peak, ambiguous, start_u=0.0, end_u=49.5, scale=2.0):
    return mains_problems(np.zeros(N), FS, fit, peak, scale, ambiguous, start_u, end_u)


# --- mains_problems on hand-built baselines (scaled units; scale = 2 V per unit) ------------


@pytest.mark.parametrize("peak", [1.0, 0.5])
@pytest.mark.parametrize(("factor", "flagged"), [(2.0, True), (0.5, False)])
def test_two_fits_alike_on_the_quiet_samples_that_differ_under_the_contact(peak, factor, flagged):
    """50 and 60 Hz baselines that differ under the contact by more than MAINS_AMBIGUOUS_FRACTION of the peak."""
    d = factor * MAINS_AMBIGUOUS_FRACTION * peak
    base = np.full(N, 0.3)  # offset and hum of the chosen fit
    other = base.copy()
    other[0] = base[0] + d  # the largest difference at the first sample of the contact (start_u = 0)
    other[20] = base[20] - 0.5 * d
    other[50] = base[50] + 0.9 * d  # the sample after the end (end_u = 49.5) is still under the contact
    other[52:] = base[52:] + 10 * d  # after the contact: not counted
    out = _problems(_fit(base), peak, (50.0, 60.0, other))
    if not flagged:
        assert out == []
        return
    assert [p.kind for p in out] == [ProblemKind.MAINS_UNRESOLVED]
    assert out[0].message == (f"mains frequency not resolved: 50 and 60 Hz hum fit the quiet baseline equally well "
                              f"and differ by {d * 2.0 * 1e3:.3g} mV under the contact (give daq.mains_hz)")


def test_difference_under_a_contact_that_starts_later():
    """Samples before the contact are not under it: only those from floor(start_u) to ceil(end_u) count."""
    base = np.zeros(N)
    other = np.zeros(N)
    other[:30] = 0.05  # before the contact
    other[30] = 0.002  # floor(30.4): the sample the contact starts after
    other[41] = 0.003  # ceil(40.2)
    other[42:] = 0.05  # after it
    out = _problems(_fit(base), 1.0, (60.0, 50.0, other), start_u=30.4, end_u=40.2)
    assert [p.message for p in out] == ["mains frequency not resolved: 60 and 50 Hz hum fit the quiet baseline "
                                        "equally well and differ by 6 mV under the contact (give daq.mains_hz)"]


@pytest.mark.parametrize("peak", [1.0, 0.5])
@pytest.mark.parametrize(("factor", "flagged"), [(2.0, True), (0.5, False)])
def test_hum_of_a_quiet_stretch_too_short_for_the_other_frequency(peak, factor, flagged):
    """The other frequency could not be fitted (no hum amplitudes): the hum itself against the peak."""
    hum = factor * MAINS_AMBIGUOUS_FRACTION * peak
    fit = _fit(np.zeros(N), hum_amplitudes=(0.75 * hum, 0.25 * hum), quiet=slice(10, 150))
    out = _problems(fit, peak, (60.0, 50.0, None))
    if not flagged:
        assert out == []
        return
    # quiet samples 10..149: they span 139 sample intervals, 13.9 ms
    assert [(p.kind, p.message) for p in out] == [(
        ProblemKind.MAINS_UNRESOLVED,
        f"mains frequency not resolved: the quiet baseline spans 13.9 ms, too short to tell 60 from 50 Hz hum of "
        f"{hum * 2.0 * 1e3:.3g} mV (give daq.mains_hz)")]


def test_no_ambiguity_no_problem():
    assert _problems(_fit(np.zeros(N)), 1.0, None) == []


# --- whole traces with known hum -------------------------------------------------------------

# 5 ms before the contact and 9.5 ms after it: an 18.5 ms record holds a full period of 60 Hz
# (16.7 ms) but not of 50 Hz (20 ms)
SHORT = dict(pre_s=5e-3, post_s=9.5e-3, noise_V=0.002, seed=3)


def _unresolved(c):
    return [p.message for p in c.problems
            if p.kind is ProblemKind.MAINS_UNRESOLVED and p.message.startswith("mains frequency not resolved")]


def test_short_record_with_60_hz_hum_and_no_mains_given_is_a_problem():
    """20 mV of 60 Hz hum (harmonics 0.3 and 0.5 of it: 36 mV in all) in 18.5 ms, daq.mains_hz not given."""
    v, fs, _ = make_trace(hum_V=0.02, mains_hz=60.0, **SHORT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        msgs = _unresolved(condition_voltage(v, fs, tau_s=math.inf))
    assert len(msgs) == 1, msgs
    m = re.fullmatch(r"mains frequency not resolved: the quiet baseline spans (\S+) ms, too short to tell 60 from 50 "
                     r"Hz hum of (\S+) mV \(give daq.mains_hz\)", msgs[0])
    assert m, msgs[0]
    assert_allclose(float(m[1]), 1e3 * (v.size - 1) / fs, rtol=0.01)  # the whole record is quiet but the contact
    assert_allclose(float(m[2]), 36.0, rtol=0.05)


@pytest.mark.parametrize("mains", [50.0, 60.0])
def test_short_record_with_the_mains_frequency_given_is_no_problem(mains):
    v, fs, _ = make_trace(hum_V=0.02, mains_hz=mains, **SHORT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _unresolved(condition_voltage(v, fs, mains_hz=mains, tau_s=math.inf)) == []


@pytest.mark.parametrize("given", [False, True])
def test_weak_50_hz_hum_under_noise_is_ambiguous_unless_given(given):
    """10 mV of 50 Hz hum under 50 mV of noise, 34 ms record: 50 and 60 Hz fit the quiet samples alike
    (BIC within 10) and differ under the contact by more than 0.1 % of the 5 V peak, unless daq.mains_hz says."""
    v, fs, _ = make_trace(pre_s=15e-3, post_s=15e-3, hum_V=0.01, mains_hz=50.0, noise_V=0.05, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        msgs = _unresolved(condition_voltage(v, fs, mains_hz=50.0 if given else "auto", tau_s=math.inf))
    if given:
        assert msgs == []
        return
    assert len(msgs) == 1, msgs
    m = re.fullmatch(r"mains frequency not resolved: 50 and 60 Hz hum fit the quiet baseline equally well and differ "
                     r"by (\S+) mV under the contact \(give daq.mains_hz\)", msgs[0])
    assert m, msgs[0]
    assert 5.0 < float(m[1]) < 100.0  # above 0.1 % of the 5 V peak; of the order of the noise, not of the peak


# --- other integrity checks -------------------------------------------------------------------


def test_baseline_step_before_the_contact_leaves_the_level_before_it_off_zero():
    """A DC step of -20 mV 3 ms before the contact (DC-coupled chain, no hum): the offset the baseline fit
    takes is an average, so the corrected signal just before the contact is off zero, by between 0 and -20 mV
    (-10.8 mV measured; the bound -5 mV keeps it clear of the noise)."""
    v, fs, _ = make_trace(seed=9, noise_V=0.002, start_phase=0.3)
    v = v.copy()
    v[int(round((0.030 - 3e-3) * fs)):] -= 0.02  # make_trace's contact starts after pre_s = 30 ms
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    off = [p.message for p in c.problems if p.kind is ProblemKind.BASELINE_OFF_ZERO]
    assert len(off) == 1, off
    m = re.fullmatch(r"corrected signal before the contact is (\S+) mV off zero \((\S+) % of the peak\): baseline or "
                     r"amplifier decay not removed", off[0])
    assert m, off[0]
    assert -20.0 < float(m[1]) < -5.0
    assert_allclose(float(m[2]), 100 * abs(float(m[1])) / 5000.0, rtol=0.05)  # the peak is 5 V


def test_too_few_samples_message_gives_the_count():
    """At 4 kHz a 4 ms contact (and its 0.1 ms cloth foot) spans about 16.4 samples, fewer than 20."""
    v, fs, truth = make_trace(sample_rate_hz=4000.0, seed=12, pre_s=0.05, post_s=0.05, cloth_s=0.1e-3,
                              cloth_fraction=0.015, offset_V=0.08, hum_V=0.02, noise_V=0.002)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = condition_voltage(v, fs)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.TOO_FEW_SAMPLES]
    assert len(msgs) == 1, msgs
    m = re.fullmatch(r"only (\S+) samples in the contact \(fewer than 20\): sample rate too low for the contact time",
                     msgs[0])
    assert m, msgs[0]
    assert_allclose(float(m[1]), truth.contact_time_s * fs, atol=1.0)


@pytest.mark.parametrize("n", [7, 9])
def test_spike_in_a_short_record_is_removed(n):
    """A 7-sample record is long enough for the spike test (three neighbours each side of the middle sample)."""
    v = np.zeros(n)
    v[n // 2] = 1.0
    out, idx = remove_spikes(v, noise_rms_V=1e-3)
    assert idx.tolist() == [n // 2]
    assert_allclose(out, np.zeros(n), atol=0.0)


@pytest.mark.parametrize("side", ["rise after", "fall before"])
def test_sample_two_before_a_steep_edge_is_not_taken_for_a_spike(side):
    """A sample standing out with a spike's neighbours (-h/2 either side) but two samples from the corner of a
    steep edge: a spike needs second differences of about 0 two and three samples away on both sides."""
    v = np.zeros(20)
    v[5] = 1.0
    v[8:] = 0.6 * np.arange(1, 13)  # the edge starts at sample 7: second difference -0.3 there, 0.3 h
    if side == "fall before":
        v = v[::-1].copy()
    out, idx = remove_spikes(v, noise_rms_V=1e-3)
    assert idx.size == 0
    assert_allclose(out, v, atol=0.0)


def test_negative_outliers_in_the_quiet_baseline_are_clipped_like_positive_ones():
    """30 dips of 3 samples at -0.1 V (50 noise deviations; 5 % of the pre-trigger): outliers, which the whiteness
    check of the quiet residual clips at ROBUST_SIGMA noise deviations on both sides, not an unexplained baseline."""
    v, fs, _ = make_trace(seed=3, noise_V=0.002)
    v = v.copy()
    for p in np.random.default_rng(0).choice(np.arange(50, int(0.025 * fs), 7), 30, replace=False):
        v[p:p + 3] -= 0.1
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert not [p.message for p in c.problems if p.kind is ProblemKind.BASELINE_RESIDUAL]


@pytest.mark.parametrize(("level_mV", "printed"), [(12.349, "12.3"), (-7.0, "-7")])
def test_level_off_zero_message_gives_the_level_in_mV(level_mV, printed):
    """The last 2 ms before the contact at a known level (scale 2 V per unit, peak 1 unit = 2 V): the message
    gives it in mV to 3 digits and as a percentage of the peak."""
    from ballimpact.signal.integrity import level_problems

    fs, n = 10_000.0, 400
    x = np.zeros(n)
    x[:200] = level_mV / 2.0e3
    pre = np.arange(n) < 200
    fit = BaselineFit(baseline=np.zeros(n), coef={}, kappa=0.0, kappa_se=0.0, has_post=False, noise=1e-5,
                       hum_amplitudes=(), bic=0.0, quiet=pre, pre=pre, post=np.zeros(n, dtype=bool))
    out = level_problems(x, fs, fit, 1.0, 2.0, n - 1.0)
    pct = 100 * abs(level_mV) / 2.0e3
    assert [(p.kind, p.message) for p in out] == [(
        ProblemKind.BASELINE_OFF_ZERO,
        f"corrected signal before the contact is {printed} mV off zero ({pct:.2g} % of the peak): baseline or "
        "amplifier decay not removed")]
