"""Tests for ballimpact.signal.conditioning: offset, hum and charge-amplifier decay removal."""

import functools
import math
import re
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose
from tracekit import HUM_HARMONICS, make_trace

from ballimpact.calibration import voltage_impulse
from ballimpact.signal.baseline import SHORT_MIN_POST_S, SHORT_POST_GUARD_S
from ballimpact.signal.conditioning import ConditioningWarning, condition_voltage
from ballimpact.problems import ProblemKind

CHAIN = dict(cloth_s=0.1e-3, cloth_fraction=0.015, offset_V=0.08, hum_V=0.02, noise_V=0.002)


def _quiet(**kw):
    """Run condition_voltage turning any ConditioningWarning into an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConditioningWarning)
        return condition_voltage(**kw)


@pytest.mark.parametrize("polarity", [1, -1])
@pytest.mark.parametrize("fs", [66964.3, 50000.0])
def test_offset_and_hum_recovered(polarity, fs):
    v, fs, _ = make_trace(sample_rate_hz=fs, polarity=polarity, tau_s=0.5, seed=4, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs, polarity=polarity)
    # the baseline model is in the polarity-applied frame
    assert_allclose(c.offset_V, polarity * 0.08, atol=3e-4)
    expected = [rel * 0.02 for _, rel in HUM_HARMONICS]
    assert_allclose(c.hum_harmonic_amplitudes_V, expected, atol=5e-4)
    assert_allclose(c.hum_amplitude_V, 0.02, atol=5e-4)
    assert_allclose(c.noise_rms_V, 0.002, rtol=0.1)
    assert c.baseline_coefficients["hum_frequencies_hz"] == (50.0, 100.0, 150.0)


def test_corrected_voltage_matches_clean_voltage():
    v, fs, truth = make_trace(tau_s=0.3, seed=2, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    err = c.voltage_V - truth.clean_V
    inside = (truth.time_s > truth.start_s) & (truth.time_s < truth.end_s)
    after = truth.time_s > truth.end_s + 1e-3
    # over the contact and after it, only the white noise is left (no offset, hum or undershoot)
    assert np.sqrt(np.mean(err[inside] ** 2)) < 1.5 * 0.002
    assert abs(np.mean(err[inside])) < 0.5e-3
    assert abs(np.mean(c.voltage_V[after])) < 0.3e-3


@pytest.mark.parametrize("tau", [0.3, 1.0, 3.0])
def test_time_constant_estimated(tau):
    v, fs, truth = make_trace(tau_s=tau, seed=1, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    assert c.tau_source == "estimated"
    assert_allclose(c.tau_s, tau, rtol=0.1)
    # undershoot = impulse / tau (the amplifier's charge balance): a first-order high-pass
    # returns the pulse's area A [V s] as a tail of -A/tau just after a short pulse. tau is
    # estimated within 10 %, so the undershoot is too.
    assert c.undershoot_V > 5 * c.undershoot_se_V
    assert_allclose(c.undershoot_V, truth.impulse_V_s / tau, rtol=0.1)


@pytest.mark.parametrize("seed", range(3))
def test_impulse_not_biased_by_the_undershoot(seed):
    """Same force and noise, with and without the amplifier decay: the same impulse."""
    results = {}
    for tau in (None, 0.3):
        v, fs, truth = make_trace(tau_s=tau, seed=seed, **CHAIN)
        c = _quiet(voltage_V=v, sample_rate_hz=fs)
        results[tau] = voltage_impulse(truth.time_s, c.voltage_V, c.contact.start_s, c.contact.end_s)
    assert_allclose(results[0.3], results[None], rtol=5e-4)
    assert_allclose(results[0.3], truth.impulse_V_s, rtol=2e-3)
    # a wrong given time constant (no decay, for a 0.3 s amplifier) cannot return the
    # baseline to zero on both sides of the contact: the integrity check names it
    v, fs, truth = make_trace(tau_s=0.3, seed=seed, **CHAIN)
    raw = condition_voltage(v, fs, tau_s=math.inf)
    assert raw.tau_source == "given"
    assert any(p.kind is ProblemKind.BASELINE_OFF_ZERO and "off zero" in p.message for p in raw.problems)


def test_given_time_constant_used():
    v, fs, _ = make_trace(tau_s=0.5, seed=0, **CHAIN)
    c = condition_voltage(v, fs, tau_s=0.5)
    assert c.tau_source == "given" and c.tau_s == 0.5
    assert c.undershoot_V > 0


def test_no_hum_fitted_without_mains():
    v, fs, _ = make_trace(seed=0, cloth_s=0.1e-3, noise_V=0.002, offset_V=0.05)
    c = _quiet(voltage_V=v, sample_rate_hz=fs, mains_hz=None)
    assert c.hum_amplitude_V == 0.0 and c.hum_harmonic_amplitudes_V == ()
    assert_allclose(c.offset_V, 0.05, atol=3e-4)


def test_sixty_hertz_mains():
    v, fs, _ = make_trace(seed=0, mains_hz=60.0, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs, mains_hz=60.0)
    assert_allclose(c.hum_amplitude_V, 0.02, atol=5e-4)


def test_warns_when_post_contact_stretch_too_short():
    # 0.8 ms of record after the contact: less than SHORT_MIN_POST_S from SHORT_POST_GUARD_S after its end
    v, fs, _ = make_trace(tau_s=0.5, post_s=0.0008, seed=0, **CHAIN)
    # the message says how much quiet record there is after the contact and how much is needed, in ms
    with pytest.warns(ConditioningWarning) as record:
        c = condition_voltage(v, fs)
    msg = str(record[0].message)
    m = re.fullmatch(r"charge-amplifier decay not corrected: only (\S+) ms of quiet record after the contact "
                     r"\(at least (\S+) ms from (\S+) ms after its end needed\) to measure the undershoot", msg)
    assert m, msg
    assert float(m.group(1)) < float(m.group(2))
    # to whole samples (15 us at 67 kHz) and two digits
    assert_allclose([float(m.group(2)), float(m.group(3))], [SHORT_MIN_POST_S * 1e3, SHORT_POST_GUARD_S * 1e3],
                    rtol=0.05)
    assert c.tau_source == "none" and math.isinf(c.tau_s)
    assert c.contact.found and c.warnings


@pytest.mark.parametrize("tau", [0.02, 0.3, math.inf])
def test_decay_measured_in_a_record_ending_3_ms_after_the_contact(tau):
    # 3 ms after the contact hold only 1 ms after the 2 ms ringing guard; from SHORT_POST_GUARD_S on they
    # measure the undershoot: the impulse comes out unbiased for a short and a long time constant and a DC
    # amplifier (zoo traces 0:602, 1:794 were excluded for want of a 2 ms post stretch)
    v, fs, truth = make_trace(tau_s=None if math.isinf(tau) else tau, post_s=0.003, seed=5, **CHAIN)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        c = condition_voltage(v, fs, mains_hz=50.0)
    assert not c.problems, c.problems
    assert_allclose(voltage_impulse(truth.time_s, c.voltage_V, c.contact.start_s, c.contact.end_s),
                    truth.impulse_V_s, rtol=3e-3)
    if tau < 1:
        assert c.tau_source == "estimated"
        assert_allclose(c.tau_s, tau, rtol=0.1)


@pytest.mark.parametrize("seed", range(4))
def test_hum_harmonics_that_are_not_there_do_not_hide_the_undershoot(seed):
    # 3 ms pre-trigger, 15 ms post, 60 Hz given but no hum: fitted with 5 harmonics (10 columns over
    # 1.1 periods), the hum takes up the undershoot's step and its error hides a decay worth more than
    # 0.3 % of the impulse; the fit with fewer harmonics (here none), of least BIC, measures it (zoo
    # traces 1:742 and 0:1346 were excluded so)
    v, fs, truth = make_trace(tau_s=5.0, pre_s=0.003, post_s=0.015, hum_V=0.0, mains_hz=60.0, noise_V=0.002,
                              peak_V=1.0, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        c = condition_voltage(v, fs, mains_hz=60.0, n_harmonics=5)
    assert not c.problems, c.problems
    assert c.tau_source == "estimated" and c.baseline_coefficients["hum_frequencies_hz"] == ()
    assert_allclose(voltage_impulse(truth.time_s, c.voltage_V, c.contact.start_s, c.contact.end_s),
                    truth.impulse_V_s, rtol=2e-3)


def test_warns_when_undershoot_not_measurable():
    # small impulse, large noise, DC-coupled: an undetected decay could matter. The message
    # gives the undershoot [mV] with its standard error, and the bias a decay hidden in that
    # error could cause: a decay kappa = 1/tau left uncorrected loses about kappa T / 2 of an
    # impulse of duration T, and kappa can hide up to UNDERSHOOT_SIGNIFICANCE standard errors
    # (the undershoot's error divided by the impulse A).
    from ballimpact.signal.baseline import UNDERSHOOT_SIGNIFICANCE

    v, fs, truth = make_trace(peak_V=1.0, noise_V=0.02, seed=0)
    with pytest.warns(ConditioningWarning, match="undershoot not measurable") as record:
        c = condition_voltage(v, fs)
    assert c.contact.found
    msg = str(record[0].message)
    m = re.fullmatch(r"charge-amplifier undershoot not measurable \((\S+) \+/- (\S+) mV\): "
                     r"the impulse may be off by up to (\S+) %", msg)
    assert m, msg
    undershoot_mV, se_mV, bias_pct = (float(g) for g in m.groups())
    # printed to 3 and 2 significant digits
    assert_allclose(undershoot_mV, c.undershoot_V * 1e3, rtol=0.005)
    assert_allclose(se_mV, c.undershoot_se_V * 1e3, rtol=0.05)
    assert abs(undershoot_mV) < 4 * se_mV  # DC-coupled: no undershoot, within its error
    kappa_hidden = UNDERSHOOT_SIGNIFICANCE * c.undershoot_se_V / truth.impulse_V_s  # [1/s]
    assert_allclose(bias_pct, 100 * kappa_hidden * truth.contact_time_s / 2, rtol=0.05)
    # 0.6 %: above the 0.3 % that excludes the impact
    assert [(p.kind, p.message) for p in c.problems] == [(ProblemKind.UNDERSHOOT_NOT_MEASURABLE, msg)]


def test_warns_when_baseline_rises_after_contact():
    v, fs, truth = make_trace(noise_V=0.002, seed=0)
    v = v + 0.005 * (truth.time_s > truth.end_s)  # a shift up by 5 mV, not an undershoot
    with pytest.warns(ConditioningWarning, match="above the one before it") as record:
        c = condition_voltage(v, fs)
    assert math.isinf(c.tau_s) and c.tau_source == "none"
    msg = str(record[0].message)
    m = re.fullmatch(r"charge-amplifier decay not corrected: the baseline after the contact is (\S+) mV "
                     r"above the one before it \(expected an undershoot\)", msg)
    assert m, msg
    assert_allclose(float(m.group(1)), 5.0, rtol=0.05)  # the 5 mV step, within the noise
    # the decay's problem first; the step right after the contact also stands out of the noise as force after the
    # end (the tail check) and as a step in the baseline, which say the same baseline is wrong there
    assert [(p.kind, p.message) for p in c.problems][0] == (ProblemKind.DECAY_NOT_CORRECTED, msg)
    assert all(p.kind in (ProblemKind.DECAY_NOT_CORRECTED, ProblemKind.BASELINE_STEP)
               or "0.5 ms after it stands" in p.message for p in c.problems), c.problems


def test_short_post_contact_problem_says_what_to_give():
    v, fs, _ = make_trace(tau_s=0.5, post_s=0.0008, seed=0)
    with pytest.warns(ConditioningWarning):
        c = condition_voltage(v, fs)
    assert any(p.kind == ProblemKind.DECAY_NOT_CORRECTED
               and p.message.endswith("to measure the undershoot (give plate.time_constant_s)") for p in c.problems)


def test_quiet_dc_coupled_trace_gives_no_warning():
    v, fs, _ = make_trace(seed=0, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    assert c.contact.found and c.warnings == ()


def test_no_contact_does_not_raise():
    rng = np.random.default_rng(0)
    t = np.arange(5000) / 66964.3
    v = 0.1 + 0.02 * np.sin(2 * np.pi * 50 * t + 0.3) + rng.normal(0, 0.002, t.size)
    c = condition_voltage(v, 66964.3)
    assert not c.contact.found and math.isnan(c.tau_s)
    assert_allclose(c.offset_V, 0.1, atol=3e-4)
    assert_allclose(c.hum_amplitude_V, 0.02, atol=5e-4)
    assert abs(np.mean(c.voltage_V)) < 1e-3


@pytest.mark.parametrize("kwargs, match", [
    (dict(polarity=2), "polarity must be 1 or -1"),
    (dict(tau_s=-1.0), "tau_s must be positive"),
    (dict(mains_hz=-50.0), "mains_hz must be non-negative"),
    (dict(sample_rate_hz=0.0), "sample_rate_hz must be positive"),
])
def test_bad_arguments(kwargs, match):
    args = dict(voltage_V=np.zeros(100), sample_rate_hz=1000.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        condition_voltage(**args)


def test_non_finite_samples_rejected():
    with pytest.raises(ValueError, match="non-finite samples"):
        condition_voltage(np.array([0.0, 1.0, np.inf, 0.0]), 1000.0)


@settings(max_examples=150, deadline=None)
@given(
    x=arrays(np.float64, st.integers(3, 300), elements=st.floats(allow_nan=False, allow_infinity=False)),
    fs=st.floats(10.0, 1e6),
    polarity=st.sampled_from([1, -1]),
)
def test_condition_voltage_never_raises_on_finite_arrays(x, fs, polarity):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        c = condition_voltage(x, fs, polarity=polarity)
    assert c.voltage_V.shape == x.shape
    if c.contact.found:
        assert 0.0 <= c.contact.start_s < c.contact.end_s <= (x.size - 1) / fs * (1 + 1e-12)


# ------------------------------------------------------------------ issue 9: events before baseline, integrity


def _impulse(c, truth):
    return voltage_impulse(truth.time_s, c.voltage_V, c.contact.start_s, c.contact.end_s)


def test_single_sample_spikes_replaced_and_not_biasing():
    v, fs, truth = make_trace(tau_s=0.5, seed=3, **CHAIN)
    clean = condition_voltage(v, fs)
    i_base = int(0.010 * fs)  # in the pre-trigger
    i_contact = int(round((truth.start_s + 0.3 * truth.contact_time_s) * fs))
    spiky = v.copy()
    spiky[i_base] += 0.8
    spiky[i_contact] -= 1.5
    c = condition_voltage(spiky, fs)
    assert set(c.spike_indices) == {i_base, i_contact}
    assert_allclose(_impulse(c, truth), _impulse(clean, truth), rtol=2e-3)
    assert_allclose(c.contact.contact_time_s, clean.contact.contact_time_s, atol=0.5 / fs)


@pytest.mark.parametrize("fraction, delay_s", [(0.36, 0.008), (0.10, 0.0098), (0.08, 0.0045)])
def test_second_contact_found_with_its_delay_and_size(fraction, delay_s):
    second = {"delay_s": delay_s, "fraction": fraction, "duration_s": 3e-3}
    v, fs, truth = make_trace(tau_s=0.5, post_s=0.08, second_impact=second, seed=5, **CHAIN)
    c = condition_voltage(v, fs)
    assert c.contact.n_impacts == 2
    (start_rel, frac), = c.contact.other_impacts
    # the second run starts where its force first exceeds the threshold: a little after its true start
    assert truth.contact_time_s + delay_s <= start_rel < truth.contact_time_s + delay_s + 1e-3
    assert_allclose(frac, fraction, rtol=0.05)


def test_small_second_contact_does_not_bend_the_baseline():
    # 3 % of the peak, 6 ms after the end: no fault, and the main contact's impulse is unbiased
    second = {"delay_s": 0.006, "fraction": 0.03, "duration_s": 3e-3}
    v, fs, truth = make_trace(tau_s=0.5, post_s=0.06, second_impact=second, seed=6, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    assert c.contact.n_impacts == 1 and c.problems == ()
    assert_allclose(_impulse(c, truth), truth.impulse_V_s, rtol=2e-3)
    assert_allclose(c.tau_s, 0.5, rtol=0.1)


@pytest.mark.parametrize("mains", [50.0, 60.0])
def test_mains_frequency_detected(mains):
    v, fs, truth = make_trace(seed=7, mains_hz=mains, tau_s=0.5, **CHAIN)
    c = condition_voltage(v, fs)  # mains_hz="auto"
    assert c.baseline_coefficients["mains_hz"] == mains
    assert c.baseline_coefficients["mains_source"] == "detected"
    assert_allclose(c.hum_amplitude_V, 0.02, atol=1e-3)
    assert_allclose(_impulse(c, truth), truth.impulse_V_s, rtol=2e-3)


def test_no_hum_detected_when_there_is_none():
    v, fs, _ = make_trace(seed=8, cloth_s=0.1e-3, noise_V=0.002, offset_V=0.05)
    c = condition_voltage(v, fs)
    assert c.baseline_coefficients["mains_source"] == "none" and c.hum_amplitude_V == 0.0


def test_given_mains_used_exactly():
    v, fs, _ = make_trace(seed=7, mains_hz=60.0, **CHAIN)
    c = condition_voltage(v, fs, mains_hz=50.0)
    assert c.baseline_coefficients["hum_frequencies_hz"][0] == 50.0
    assert c.baseline_coefficients["mains_source"] == "given"


@pytest.mark.parametrize("tau", [0.01, 0.02, 0.05])
def test_short_time_constant_estimated_and_undone(tau):
    # the signal decays visibly during the contact: the exact model still recovers it
    v, fs, truth = make_trace(tau_s=tau, seed=9, post_s=0.06, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    assert c.tau_source == "estimated" and c.problems == ()
    assert_allclose(c.tau_s, tau, rtol=0.02)
    assert_allclose(_impulse(c, truth), truth.impulse_V_s, rtol=3e-3)
    assert_allclose(c.contact.contact_time_s, truth.contact_time_s, rtol=5e-3)


def test_given_short_time_constant_undone_exactly():
    v, fs, truth = make_trace(tau_s=0.02, seed=9, post_s=0.06, **CHAIN)
    c = condition_voltage(v, fs, tau_s=0.02)
    assert c.tau_source == "given" and c.problems == ()
    assert_allclose(_impulse(c, truth), truth.impulse_V_s, rtol=3e-3)


def test_wrong_given_time_constant_is_a_problem():
    # a decay that the given tau cannot undo leaves the corrected baseline off zero
    v, fs, _ = make_trace(tau_s=0.02, seed=9, post_s=0.06, **CHAIN)
    c = condition_voltage(v, fs, tau_s=0.2)
    assert any(p.kind is ProblemKind.BASELINE_OFF_ZERO and "off zero" in p.message for p in c.problems)


def test_baseline_step_after_contact_is_a_problem():
    v, fs, truth = make_trace(noise_V=0.002, seed=0)
    v = v + 0.005 * (truth.time_s > truth.end_s)  # a shift up, not an undershoot
    with pytest.warns(ConditioningWarning):
        c = condition_voltage(v, fs)
    assert any(p.kind is ProblemKind.DECAY_NOT_CORRECTED and "above the one before it" in p.message
               for p in c.problems)


def test_plate_ringing_in_the_contact_is_a_problem():
    v, fs, truth = make_trace(seed=10, ringing_fraction=0.1, ringing_hz=8000.0, ringing_decay_s=1.5e-3, **CHAIN)
    c = condition_voltage(v, fs, undo_plate=False)
    # its frequency read within 5 % of the 8 kHz put in (7.98 and 8.01 kHz as the contact's end moves by a sample)
    seen = [float(m.group(1)) for p in c.problems if p.kind is ProblemKind.PLATE_RINGING
            for m in [re.match(r"plate ringing at ([0-9.]+) kHz", p.message)] if m]
    assert seen and all(abs(f / 8.0 - 1.0) < 0.05 for f in seen), [p.message for p in c.problems]
    # with the resonance undone (the default): excluded, or right (this additive ringing is no plate's
    # response to the force, so the guards of the undoing may refuse it)
    c = condition_voltage(v, fs)
    assert c.problems or (abs(c.contact.peak_V / truth.peak_V - 1) < 0.01
                          and abs(c.contact.contact_time_s / truth.contact_time_s - 1) < 0.005), c
    v, fs, _ = make_trace(seed=10, **CHAIN)  # the same without ringing
    assert not any(p.kind is ProblemKind.PLATE_RINGING for p in condition_voltage(v, fs).problems)


def test_ringing_outlasting_the_contact_is_a_problem():
    v, fs, _ = make_trace(seed=11, ringing_fraction=0.2, ringing_hz=1500.0, ringing_decay_s=3e-3, **CHAIN)
    c = condition_voltage(v, fs)
    assert any(p.kind is ProblemKind.PLATE_RINGING and "outlasts the contact" in p.message for p in c.problems)


def test_too_few_samples_in_the_contact_is_a_problem():
    v, fs, _ = make_trace(sample_rate_hz=4000.0, seed=12, pre_s=0.05, post_s=0.05, **CHAIN)
    c = condition_voltage(v, fs)
    assert any(p.kind is ProblemKind.TOO_FEW_SAMPLES and "samples in the contact" in p.message for p in c.problems)


def test_clean_traces_have_no_problems():
    for seed in range(4):
        v, fs, _ = make_trace(seed=seed, tau_s=[0.3, 1.0, 5.0, None][seed], **CHAIN)
        assert condition_voltage(v, fs).problems == ()


def test_contact_end_in_the_noise_is_a_problem():
    # zoo trace 0:1021 (tests/zoo.py, ideal plate, punctured ball): the end's hinge fit walks
    # 25 samples into the noise after the low force tail (TC +13 %); the samples inside
    # that end hold no force, and the check names it
    import zoo

    tr = zoo.trace_for(0, 1021)
    fs = tr.rig.sample_rate_hz
    c = condition_voltage(tr.voltage_V, fs, polarity=tr.rig.polarity, n_harmonics=5, tau_s=tr.rig.tau_s,
                          mains_hz=tr.rig.mains_hz)
    assert c.contact.end_s > tr.truth.end_s + 10 / fs
    assert any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED and p.message.startswith("contact end not determined")
               for p in c.problems)
    # a clean trace of the same chain with a well-found end has no such problem
    v, fs, _ = make_trace(seed=3, **CHAIN)
    assert not any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED for p in condition_voltage(v, fs).problems)


# ------------------------------------------------------------------ what cannot be measured to 1 % (issue 9)


def _jump_trace(fs, phase=0.7, duration_s=3.0e-3):
    """A force that jumps from zero (0.4 of its scale) and returns to zero with a finite slope, in volts."""
    t = np.arange(int(round(40e-3 * fs))) / fs
    start = (int(20e-3 * fs) + phase) / fs
    u = (t - start) / duration_s
    f = np.where((u > 0) & (u < 1), 0.4 * (1.0 - u) + np.sin(np.pi * u), 0.0)
    return 2.0 * f + np.random.default_rng(1).normal(0.0, 1e-3, t.size)


def test_jump_located_to_half_a_sample_is_a_problem_when_that_exceeds_the_tolerance():
    # at 20 kHz half a sample is 25 us, 0.83 % of a 3 ms contact: TC not known to 1 %
    c = condition_voltage(_jump_trace(20e3), 20e3, mains_hz=None, tau_s=math.inf)
    assert any(p.kind is ProblemKind.CONTACT_JUMP_UNRESOLVED and p.message.startswith("contact start between two samples")
               for p in c.problems)
    # at 100 kHz it is 0.17 %
    c = condition_voltage(_jump_trace(100e3), 100e3, mains_hz=None, tau_s=math.inf)
    assert "start_jump" in c.contact.flags
    assert not any(p.kind is ProblemKind.CONTACT_JUMP_UNRESOLVED for p in c.problems)


def test_force_below_zero_after_the_contact_is_a_problem():
    # a plate that swings back after the ball has left: 2 % of the peak below zero, 0.3-0.9 ms after
    v, fs, truth = make_trace(seed=5, **CHAIN)
    c = condition_voltage(v, fs)
    assert not any(p.kind is ProblemKind.NEGATIVE_FORCE for p in c.problems)
    u = (truth.time_s - truth.end_s - 0.3e-3) / 0.6e-3
    swing = np.where((u > 0) & (u < 1), -0.02 * 5.0 * np.sin(np.pi * u), 0.0)
    c = condition_voltage(v + swing, fs)
    assert any(p.kind is ProblemKind.NEGATIVE_FORCE and p.message.startswith("force below zero after the contact: 2")
               for p in c.problems)


def test_peak_on_plate_ringing_is_a_problem():
    # 8 kHz ringing of 3 % of the peak that lasts through the peak: the peak moves with it
    # (the checks themselves: with the plate's resonance left in)
    v, fs, _ = make_trace(seed=6, ringing_fraction=0.03, ringing_hz=8e3, ringing_decay_s=10e-3, **CHAIN)
    assert any(p.kind is ProblemKind.PEAK_ON_RINGING and p.message.startswith("peak force on plate ringing")
               for p in condition_voltage(v, fs, undo_plate=False).problems)
    # the same ringing dying out long before the peak (2 ms after the start) leaves the peak alone
    v, fs, _ = make_trace(seed=6, ringing_fraction=0.03, ringing_hz=8e3, ringing_decay_s=0.15e-3, **CHAIN)
    assert not any(p.kind is ProblemKind.PEAK_ON_RINGING for p in condition_voltage(v, fs, undo_plate=False).problems)


@pytest.mark.parametrize("samples_per_period", [2.3, 2.8, 3.6])
def test_peak_on_ringing_of_two_to_four_samples_per_period_is_a_problem(samples_per_period):
    # a plate resonance near the Nyquist frequency: its swings are 1 and 2 samples apart, too irregular
    # for the turning points of an oscillation, but the peak sample then stands on a rise of the ringing
    # (zoo trace 0:552, a 20.7 kHz plate at 58.6 kHz, had its peak 10.5 % high and passed as ok)
    fs = 58.6e3
    v, fs, truth = make_trace(sample_rate_hz=fs, seed=7, ringing_fraction=0.10, ringing_hz=fs / samples_per_period,
                              ringing_decay_s=10e-3, **CHAIN)
    c = condition_voltage(v, fs, undo_plate=False)
    assert any(p.kind in (ProblemKind.PEAK_ON_RINGING, ProblemKind.PEAK_BETWEEN_SAMPLES) for p in c.problems), \
        c.problems
    # with the resonance undone (the default) the impact is excluded or right, never wrong
    c = condition_voltage(v, fs)
    assert c.problems or (abs(c.contact.peak_V / truth.peak_V - 1) < 0.01
                          and abs(c.contact.contact_time_s / truth.contact_time_s - 1) < 0.005), c


def test_hum_in_a_record_shorter_than_its_period_is_a_problem():
    # 16 ms of quiet samples hold less than one period of 60 Hz: no hum is fitted, and 20 mV of it bends the
    # baseline under the contact (zoo trace 1:1962 came out ok with TC +20 %); without hum, no such problem
    for hum, expected in ((0.02, True), (0.0, False)):
        v, fs, _ = make_trace(pre_s=4e-3, post_s=8e-3, hum_V=hum, mains_hz=60.0, noise_V=0.001, seed=3)
        c = condition_voltage(v, fs, mains_hz=60.0, tau_s=math.inf)
        assert any(p.kind is ProblemKind.MAINS_UNRESOLVED and p.message.startswith("mains hum not resolved")
                   for p in c.problems) is expected, (hum, c.problems)


def test_level_after_a_contact_too_close_to_the_record_end_for_the_fit_is_checked():
    # 2.5 ms after the contact: too short for the 2 ms ringing guard + 2 ms, so the post stretch of the
    # baseline fit starts 0.5 ms after the contact; a step of 1 % of the peak from there must still be seen
    v, fs, truth = make_trace(pre_s=20e-3, post_s=2.5e-3, noise_V=0.001, seed=4)
    t = np.arange(v.size) / fs
    assert not any(p.kind is ProblemKind.BASELINE_OFF_ZERO
                   for p in condition_voltage(v, fs, mains_hz=None, tau_s=math.inf).problems)
    stepped = v + np.where(t > truth.end_s + 0.5e-3, 0.01 * 5.0, 0.0)
    c = condition_voltage(stepped, fs, mains_hz=None, tau_s=math.inf)
    assert any(p.kind is ProblemKind.BASELINE_OFF_ZERO and re.match("corrected signal (just )?after the contact",
                                                                     p.message) for p in c.problems), c.problems


def _spike_trace(fs, phase):
    """A half-sine of 3 ms with the ball's pre-buckling spike, a ramp of 1.0 of its scale over 0.1 ms
    ending in a sudden drop 0.25 ms after the start (the largest force); in volts, and the true peak [V]."""
    t = np.arange(int(round(40e-3 * fs))) / fs
    start = (int(20e-3 * fs) + phase) / fs
    u = (t - start) / 3.0e-3
    base = np.where((u > 0) & (u < 1), np.sin(np.pi * np.clip(u, 0.0, 1.0)), 0.0)
    ramp = np.clip((t - start - 0.15e-3) / 0.1e-3, 0.0, 1.0) * (t < start + 0.25e-3)
    f = base + ramp
    true_peak = np.sin(np.pi * 0.25e-3 / 3.0e-3) + 1.0
    return 2.0 * f + np.random.default_rng(2).normal(0.0, 1e-3, t.size), 2.0 * true_peak


def test_peak_between_samples_is_a_problem_when_the_samples_do_not_pin_it():
    # at 25 kHz the spike's ramp rises by 0.4 (32 % of its top) per sample: the largest sample can miss
    # the top by that much; the phases put the drop just after a sample and just before the next; at
    # phase 0.5 the spike falls between samples so that the largest sample is the smooth maximum, and
    # the spike is a lower sampled maximum after a steep rise (zoo seed 4000 "sample_rate", once ok)
    for phase in (0.1, 0.5, 0.9):
        v, top = _spike_trace(25e3, phase)
        c = condition_voltage(v, 25e3, mains_hz=None, tau_s=math.inf)
        assert any(p.kind is ProblemKind.PEAK_BETWEEN_SAMPLES and p.message.startswith("peak force between samples")
                   for p in c.problems), (phase, c.problems)
        assert np.max(c.voltage_V) < 0.95 * top  # the largest sample does miss the true top by more than 5 %
    # at 400 kHz the ramp rises by 2 % of the top per sample: the largest sample is within it of the top
    v, top = _spike_trace(400e3, 0.5)
    c = condition_voltage(v, 400e3, mains_hz=None, tau_s=math.inf)
    assert not any(p.kind is ProblemKind.PEAK_BETWEEN_SAMPLES for p in c.problems)
    assert_allclose(np.max(c.voltage_V), top, rtol=0.02)
    # a smooth maximum is pinned by its samples even at 20 kHz
    v, fs, _ = make_trace(sample_rate_hz=20e3, seed=8, **CHAIN)
    assert not any(p.kind is ProblemKind.PEAK_BETWEEN_SAMPLES for p in condition_voltage(v, fs).problems)


def _ball_force(fs, tc_s=3.5e-3, spike=0.6):
    """Contact samples of a one-hump force: a half-sine of tc_s with the pre-buckling spike (a ramp of
    ``spike`` of its scale from 0.1 to 0.2 ms, then a drop)."""
    t = np.arange(int(round(tc_s * fs))) / fs
    ramp = np.clip((t - 0.1e-3) / 0.1e-3, 0.0, 1.0) * (t < 0.2e-3)
    return t, np.sin(np.pi * t / tc_s) + spike * ramp


def test_force_with_two_humps_is_a_problem():
    from ballimpact.signal.shape import second_hump

    # a ball's force has one hump after its spike (Eq. (14): kB x + (cB + cM) x' as x rises and falls once);
    # with the ringing of a plate resonance at 848 Hz (damping 0.22) that the spike set off, it falls after
    # its first maximum and rises again (zoo trace 3:1077 came out ok with TC -12 % and the peak +27 %)
    fs = 50e3
    t, f = _ball_force(fs)
    assert second_hump(f, fs, 1e-3, f.max()) == []
    wn, z = 2 * np.pi * 848.0, 0.22
    sensed = f + 0.5 * np.exp(-z * wn * t) * np.sin(wn * math.sqrt(1 - z * z) * t)
    problems = second_hump(sensed, fs, 1e-3, sensed.max())
    assert [p.kind for p in problems] == [ProblemKind.PLATE_RINGING]
    assert problems[0].message.startswith("force with two humps"), problems
    # a foot that flattens into a low plateau and then drops falls without rising again
    foot = np.concatenate([f[: f.size * 9 // 10], np.full(20, 0.01), np.linspace(0.01, 0.0, 3)])
    assert second_hump(foot, fs, 1e-3, foot.max()) == []
    # a dip and rise within the noise of the average are no second hump
    noisy = f + np.random.default_rng(0).normal(0.0, 0.05, f.size)
    assert second_hump(noisy, fs, 0.05, noisy.max()) == []


def test_largest_sample_at_the_jump_from_zero_is_a_problem():
    # zoo trace 0:952: an 8.7 kHz plate at 22.9 kHz overshoots the force's jump by 9 %, and the first sample
    # of the contact is the largest; a ball's force rises as it compresses, so that sample is no measured top
    fs = 22.9e3
    t = np.arange(int(40e-3 * fs)) / fs
    start = (int(20e-3 * fs) + 0.6) / fs
    u = (t - start) / 3.0e-3
    inside = (u > 0) & (u < 1)
    f = np.where(inside, 0.6 * (1.0 - u) + 0.4 * np.sin(np.pi * u), 0.0)
    over = np.where(inside, 0.5 * np.exp(-(t - start) / 0.05e-3) * np.cos(2 * np.pi * 8.7e3 * (t - start)), 0.0)
    noise = np.random.default_rng(3).normal(0.0, 1e-3, t.size)
    c = condition_voltage(2.0 * (f + over) + noise, fs, mains_hz=None, tau_s=math.inf)
    assert any(p.kind is ProblemKind.PEAK_BETWEEN_SAMPLES and "the first of the contact" in p.message
               for p in c.problems), c.problems
    # the same jump without the overshoot: its top comes later (the half-sine), and is measured
    c = condition_voltage(2.0 * (0.4 * f / 0.6 + 0.6 * np.where(inside, np.sin(np.pi * u), 0.0)) + noise, fs,
                          mains_hz=None, tau_s=math.inf)
    assert not any(p.kind is ProblemKind.PEAK_BETWEEN_SAMPLES for p in c.problems), c.problems


def test_contact_end_fading_into_the_noise_is_a_problem():
    # zoo trace 0:1550 (ideal plate, punctured ball at 34 m/s, 172 kHz): the last 0.3 ms of the
    # force are a tail of 1 % of the peak, 5 noise deviations, that curves into zero; fitted from
    # the samples above 4 noise deviations the end is 10 samples late (TC +1.6 %), and fitted
    # from those above 8 it moves: the check names it
    import zoo

    tr = zoo.trace_for(0, 1550)
    fs = tr.rig.sample_rate_hz
    c = condition_voltage(tr.voltage_V, fs, polarity=tr.rig.polarity, n_harmonics=5, tau_s=tr.rig.tau_s)
    assert any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED and p.message.startswith("contact end not determined to 1 %")
               for p in c.problems)
    v, fs, _ = make_trace(seed=3, **CHAIN)
    assert not any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED for p in condition_voltage(v, fs).problems)


def test_mains_not_resolved_in_a_short_record_is_a_problem():
    # zoo trace 0:1440 with 12 ms of pre-trigger: 5.4 mV of 60 Hz hum, no daq.mains_hz, a quiet
    # baseline that spans 18 ms (before the contact and from 0.5 ms after it): a full period of 60 Hz
    # but not of 50 Hz, so the two cannot be told apart; the same trace with its mains frequency given
    # has no such problem. (With its 17 ms of pre-trigger the quiet baseline spans more than 20 ms.)
    import zoo

    from ballimpact.problems import ProblemKind

    tr = zoo.trace_for(0, 1440, pre_s=0.012)
    fs, rig = tr.rig.sample_rate_hz, tr.rig
    kinds = [p.kind for p in condition_voltage(tr.voltage_V, fs, polarity=rig.polarity, n_harmonics=5).problems]
    assert ProblemKind.MAINS_UNRESOLVED in kinds
    given = condition_voltage(tr.voltage_V, fs, polarity=rig.polarity, n_harmonics=5, mains_hz=60.0)
    assert ProblemKind.MAINS_UNRESOLVED not in [p.kind for p in given.problems]


# ---------------------------------------------------------- found by the sampled mutation run


@pytest.mark.parametrize("tau", [0.003, 0.004])
def test_time_constant_below_the_plausible_bound_is_not_applied(tau):
    # a charge amplifier of 3-4 ms (below TAU_BOUNDS_S[0] = 5 ms, which no plate amplifier has):
    # the time constant is estimated (it is in the message, to the truth's 3 digits within 5 %)
    # but not applied, and the impact is a problem, with the warning said once
    from ballimpact.signal.baseline import TAU_BOUNDS_S

    v, fs, _ = make_trace(tau_s=tau, seed=9, post_s=0.06, **CHAIN)
    with pytest.warns(ConditioningWarning, match="below the plausible") as record:
        c = condition_voltage(v, fs)
    assert math.isinf(c.tau_s) and c.tau_source == "none"
    msg = [str(w.message) for w in record if "below the plausible" in str(w.message)]
    assert len(msg) == 1
    m = re.fullmatch(r"charge-amplifier decay not corrected: estimated time constant (\S+) s is below the "
                     r"plausible (\S+) s \(a baseline shift that is not the amplifier's decay\?\)", msg[0])
    assert m, msg[0]
    assert_allclose(float(m.group(1)), tau, rtol=0.05)
    assert float(m.group(2)) == TAU_BOUNDS_S[0]
    assert (ProblemKind.DECAY_NOT_CORRECTED, msg[0]) in [(p.kind, p.message) for p in c.problems]


@pytest.mark.parametrize("seed", [0, 2])
def test_dc_coupled_trace_undershoot_in_the_noise_applied_only_when_positive(seed):
    # no decay in the chain: the undershoot is noise (within 3 standard errors). A positive
    # one is applied as found (tau = impulse / undershoot, seed 0: about 200 s, a negligible
    # correction; unbiased on average), a negative one is not (seed 2: tau infinite, "none")
    v, fs, truth = make_trace(seed=seed, **CHAIN)
    c = _quiet(voltage_V=v, sample_rate_hz=fs)
    assert abs(c.undershoot_V) < 3 * c.undershoot_se_V
    if c.undershoot_V > 0:
        assert c.tau_source == "estimated"
        assert_allclose(c.tau_s, truth.impulse_V_s / c.undershoot_V, rtol=0.01)
    else:
        assert math.isinf(c.tau_s) and c.tau_source == "none"
    assert (c.undershoot_V > 0) == (seed == 0)  # both branches are taken


def test_force_below_zero_message_gives_depth_and_time_of_the_swing():
    # a swing of 2 % of the peak below zero, a half sine centred 1.0 ms after the contact end,
    # at 200 kHz (so that the 0.05 ms smoothing spans 10 samples): the message gives its depth,
    # its size in noise deviations (depth / (noise / sqrt(10))) and when it is deepest
    fs = 200_000.0
    v, fs, truth = make_trace(sample_rate_hz=fs, seed=5, **CHAIN)
    u = (truth.time_s - truth.end_s - 0.7e-3) / 0.6e-3
    v = v + np.where((u > 0) & (u < 1), -0.02 * truth.peak_V * np.sin(np.pi * u), 0.0)
    c = condition_voltage(v, fs)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.NEGATIVE_FORCE]
    assert len(msgs) == 1
    m = re.fullmatch(r"force below zero after the contact: (\S+) % of the peak \((\S+) noise deviations\) (\S+) ms "
                     r"after its end; the plate rings \(or the baseline is wrong\) and TC and the peak cannot be "
                     r"trusted", msgs[0])
    assert m, msgs[0]
    pct, n_dev, ms = (float(g) for g in m.groups())
    assert_allclose(pct, 2.0, rtol=0.05)
    assert_allclose(n_dev, 0.02 * truth.peak_V / (0.002 / math.sqrt(10)), rtol=0.1)
    assert_allclose(ms, 1.0, atol=0.03)  # printed to 2 digits; the end is located to about a sample


def test_peak_on_ringing_message_gives_the_ringing_frequency():
    # the 8 kHz ringing of test_peak_on_plate_ringing_is_a_problem: its frequency is read from
    # the spacing of the swings around the peak, to about one sample of a 8-sample period
    v, fs, _ = make_trace(seed=6, ringing_fraction=0.03, ringing_hz=8e3, ringing_decay_s=10e-3, **CHAIN)
    msgs = [p.message for p in condition_voltage(v, fs, undo_plate=False).problems
            if p.kind is ProblemKind.PEAK_ON_RINGING]
    assert len(msgs) == 1
    m = re.match(r"peak force on plate ringing: the force oscillates at about (\S+) kHz during the contact", msgs[0])
    assert m, msgs[0]
    assert_allclose(float(m.group(1)), 8.0, rtol=0.25)


def test_baseline_off_zero_message_names_the_stretch():
    # the wrong time constant of test_wrong_given_time_constant_is_a_problem: the corrected
    # signal is off zero just after the contact and later; the message gives the level [mV]
    # and that level as a percentage of the peak
    v, fs, truth = make_trace(tau_s=0.02, seed=9, post_s=0.06, **CHAIN)
    c = condition_voltage(v, fs, tau_s=0.2)
    found = {}
    for p in c.problems:
        m = re.fullmatch(r"corrected signal (before|just after|later after) the contact is (\S+) mV off zero "
                         r"\((\S+) % of the peak\): baseline or amplifier decay not removed", p.message)
        if p.kind is ProblemKind.BASELINE_OFF_ZERO:
            assert m, p.message
            found[m.group(1)] = (float(m.group(2)), float(m.group(3)))
    assert "just after" in found
    for mV, pct in found.values():
        assert_allclose(pct, 100 * abs(mV) / (truth.peak_V * 1e3), rtol=0.08)


def test_quiet_baseline_with_an_unmodelled_oscillation_is_a_problem():
    # 100 mV at 333 Hz (no mains harmonic) on the quiet baseline: offset, drift, hum and decay
    # cannot explain it; the same trace without it has no such problem
    v, fs, truth = make_trace(seed=5, **CHAIN)
    assert not any(p.kind is ProblemKind.BASELINE_RESIDUAL for p in condition_voltage(v, fs).problems)
    with pytest.warns(ConditioningWarning, match="undershoot not measurable"):
        c = condition_voltage(v + 0.1 * np.sin(2 * np.pi * 333.0 * truth.time_s + 0.4), fs)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.BASELINE_RESIDUAL]
    assert len(msgs) == 1
    assert re.fullmatch(r"quiet baseline not explained by offset, drift, hum and decay: \S+ mV rms above the white "
                        r"noise \(\S+ % of the peak; hum or drift not resolved\?\)", msgs[0]), msgs[0]


@pytest.mark.parametrize(("jump_at", "ends"), [("end", "end"), ("both", "start and end")])
def test_jump_at_the_end_or_both_ends_is_named_with_its_uncertainty(jump_at, ends):
    # a force that jumps from zero (0.4 of its scale) at its end, or at both ends, at 20 kHz:
    # each jump leaves TC uncertain by half a sample (25 us), more than JUMP_MAX_FRACTION (0.7 %)
    # of the 3 ms contact
    from ballimpact.signal.end_checks import JUMP_MAX_FRACTION

    fs, duration_s = 20e3, 3.0e-3
    t = np.arange(int(round(40e-3 * fs))) / fs
    u = (t - (int(20e-3 * fs) + 0.7) / fs) / duration_s
    step = 0.4 * u if jump_at == "end" else 0.4 * np.ones_like(u)
    v = 2.0 * np.where((u > 0) & (u < 1), step + np.sin(np.pi * u), 0.0) + np.random.default_rng(1).normal(0, 1e-3, t.size)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.CONTACT_JUMP_UNRESOLVED]
    assert len(msgs) == 1
    m = re.fullmatch(rf"contact {ends} between two samples: the force jumps from zero there, so TC is known to "
                     rf"\+-(\S+) us only, more than {100 * JUMP_MAX_FRACTION:.2g} % of (\S+) ms \(sample faster\)",
                     msgs[0])
    assert m, msgs[0]
    assert float(m.group(1)) == pytest.approx(len(ends.split(" and ")) * 0.5e6 / fs)
    assert_allclose(float(m.group(2)), duration_s * 1e3, rtol=0.02)


def test_contact_end_fading_into_the_noise_message_gives_the_move_in_us_and_percent_of_tc():
    # zoo trace 0:1550 of test_contact_end_fading_into_the_noise_is_a_problem: the message gives
    # how far the end moves when fitted again [us] and that move as a percentage of TC
    import zoo

    tr = zoo.trace_for(0, 1550)
    c = condition_voltage(tr.voltage_V, tr.rig.sample_rate_hz, polarity=tr.rig.polarity, n_harmonics=5,
                          tau_s=tr.rig.tau_s)
    msgs = [p.message for p in c.problems
            if p.kind is ProblemKind.CONTACT_END_UNDETERMINED and "to 1 %" in p.message]
    assert len(msgs) == 1
    m = re.fullmatch(r"contact end not determined to 1 %: fitted again from the samples above twice the noise "
                     r"threshold it moves by (\S+) us \((\S+) % of TC\); the force fades into the noise there",
                     msgs[0])
    assert m, msgs[0]
    moved_us, pct = float(m.group(1)), float(m.group(2))
    assert abs(moved_us) > 0.01 * c.contact.contact_time_s * 1e6  # more than 1 % of TC, as the message says
    assert_allclose(pct, 100 * moved_us * 1e-6 / c.contact.contact_time_s, rtol=0.05)


def test_contact_noise_reported_in_volts():
    # the contact's noise is reported in volts like the signal's: the trace's 2 mV
    v, fs, _ = make_trace(seed=3, **CHAIN)
    c = condition_voltage(v, fs)
    assert_allclose(c.contact.noise_rms_V, 0.002, rtol=0.1)


def test_event_before_the_contact_is_left_out_of_the_baseline():
    # a knock on the plate 15 ms before the contact (a 1 ms half sine of 10 % of the peak) is an
    # event, not baseline: the impulse and the contact time stay those of the trace without it
    v, fs, truth = make_trace(seed=3, **CHAIN)
    u = (truth.time_s - truth.start_s + 15e-3) / 1e-3
    knock = np.where((u > 0) & (u < 1), 0.1 * truth.peak_V * np.sin(np.pi * u), 0.0)
    plain, knocked = condition_voltage(v, fs), condition_voltage(v + knock, fs)
    assert_allclose(_impulse(knocked, truth), _impulse(plain, truth), rtol=2e-4)
    assert_allclose(knocked.contact.contact_time_s, plain.contact.contact_time_s, rtol=2e-3)
    assert_allclose(_impulse(knocked, truth), truth.impulse_V_s, rtol=3e-3)


@pytest.mark.parametrize("f_hz, fraction", [(3100.0, 1e-2), (3100.0, 1e-3), (10000.0, 1e-3)])
def test_a_ringing_line_is_found_above_the_force_spectrum_or_large_enough(f_hz, fraction):
    # the Goodwill & Haake force of a pressurised ball at 50 kHz plus a sinusoid of 1 % or 0.1 % of the peak
    # at 3.1 kHz (just above the band's edge, on the force's steep spectrum) or 0.1 % at 10 kHz: each is a
    # line, although the bumps of the force's own spectrum at the band's edge are not; the force alone has none
    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    from ballimpact.signal.ringing import _ringing_line

    p = BALLS["pressurised"].params
    sim = simulate_impact(20.0, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, record=True)
    fs = 5.0e4
    t = np.arange(0.0, float(sim.contact_time_s), 1.0 / fs)
    force = np.maximum(np.interp(t, sim.time_s, sim.force_N), 0.0)
    force /= force.max()
    noise = np.random.default_rng(3).normal(0.0, 1e-6, t.size)
    assert _ringing_line(force + noise, fs, 1e-6) is None
    found = _ringing_line(force + noise + fraction * np.sin(2 * np.pi * f_hz * t), fs, 1e-6)
    assert found is not None
    assert_allclose(found[0], f_hz, rtol=0.05)


def test_unstable_contact_window_message_names_the_windows():
    # zoo trace 1:164 (1.5 ms pre-trigger, hum and decay not given): the window goes back and forth between
    # the contact end (5.9 ms) and 2 ms later as the baseline fitted around it changes; the message says so
    import zoo

    tr = zoo.trace_for(1, 164)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        c = condition_voltage(tr.voltage_V, tr.sample_rate_hz, polarity=tr.rig.polarity, n_harmonics=5)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.CONTACT_UNSTABLE]
    assert len(msgs) == 1, c.problems
    m = re.search(r"still move by (\S+) samples after \d+ iterations \(last from (\S+)-(\S+) ms to (\S+)-(\S+) ms "
                  r"of the record: the decay, drift and hum fitted around each window move it\)$", msgs[0])
    assert m, msgs[0]
    moved, a0, b0, a1, b1 = (float(g) for g in m.groups())
    # the move is the larger of the two ends' moves, in samples (3 digits of ms: a sample is 0.038 ms)
    assert_allclose(moved, max(abs(a1 - a0), abs(b1 - b0)) * 1e-3 * tr.sample_rate_hz, rtol=0.1, atol=1.0)
    # both windows start at the contact (truth 1.54 ms) and end after it starts
    assert_allclose([a0, a1], tr.truth.start_s * 1e3, atol=0.05)
    assert min(b0, b1) > tr.truth.start_s * 1e3 + 1.0


def test_quiet_residual_after_the_contact_only_is_named_so():
    # a 500 Hz oscillation after the contact only (a lightly damped plate ringing on past the guard: 0.8 % of
    # the peak from 3.5 ms after the contact, decaying over 30 ms; under 6 noise deviations, else its swings are
    # masked as events): the reason says where it is; the 333 Hz oscillation on both sides in the test above
    # keeps "hum or drift not resolved?"
    v, fs, truth = make_trace(seed=5, tau_s=0.5, peak_V=1.0, noise_V=0.0015, offset_V=0.05, hum_V=0.01)
    after = truth.time_s - truth.end_s - 3.5e-3
    ring = np.where(after > 0, 0.008 * np.exp(-np.clip(after, 0, None) / 0.03) * np.sin(2 * np.pi * 500.0 * after),
                    0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        c = condition_voltage(v + ring, fs, tau_s=0.5)
    msgs = [p.message for p in c.problems if p.kind is ProblemKind.BASELINE_RESIDUAL]
    assert len(msgs) == 1, c.problems
    assert msgs[0].endswith("after the contact only: plate ringing that outlasts the guard, or a decay not "
                            "resolved?)"), msgs[0]
    # without it, no such problem
    assert not any(p.kind is ProblemKind.BASELINE_RESIDUAL for p in condition_voltage(v, fs, tau_s=0.5).problems)


def _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball="pressureless", vin=22.0, modes=()):
    """Samples at fs of the model's ball force (tests/zoo.py: its jump at 2 mm, spike and buckling drop)
    through a second-order plate (scipy's exact response to the piecewise-linear force; None = ideal plate),
    from the sample before the force's jump (at ``phase`` of a sample interval after it) [N]. ``modes``: further
    modes of the plate, (resonance [Hz], damping ratio [-], residue [-]) each, summed with the first, whose
    residue is 1 less theirs (unit static gain)."""
    from scipy import signal

    import zoo

    knots_t, knots_f, sim, _, _ = zoo.model_force(ball, (1.0, 1.0, 1.0, 1.0, 1.0), vin)
    n, m = int(knots_t[-1] * fs) + 40, int(math.ceil(2e6 / fs))  # a grid of m points a sample interval
    grid = (np.arange(n * m) / m - 1 + phase) / fs  # the first sample just before the jump
    force = np.interp(grid, knots_t, knots_f, left=0.0, right=0.0)
    if plate_hz is not None:
        sensed = np.zeros_like(force)
        for fn, z, r in ((plate_hz, zeta, 1.0 - sum(r for *_, r in modes)), *modes):
            wn = 2 * np.pi * fn
            sensed += r * signal.lsim(([wn * wn], [1.0, 2 * z * wn, wn * wn]), force, grid - grid[0])[1]
        force = sensed
    return force[::m], float(sim.peak_force_N)


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin, phase", [
    (146e3, 9.7e3, 0.17, "pressureless", 22.0, 0.1),  # zoo 3:700: the jump's overshoot is the peak, +7.9 %
    (146e3, 9.7e3, 0.17, "pressureless", 22.0, 0.5),
    (146e3, 9.7e3, 0.17, "pressureless", 22.0, 0.9),
    (21e3, 6.5e3, 0.24, "oversize", 32.0, 0.1),  # zoo 3:212: three samples a period, +10 %
    (21e3, 6.5e3, 0.24, "oversize", 32.0, 0.5),
    (21e3, 6.5e3, 0.24, "oversize", 32.0, 0.9),
    (23.6e3, 8.5e3, 0.26, "oversize", 27.0, 0.9),  # zoo 3:672: +5.6 % (+3.6 to +4.2 % at phases 0.1 and 0.5)
    (60e3, 8.0e3, 0.2, "pressurised", 30.0, 0.3),
])
def test_peak_on_the_plates_step_response_is_a_problem(fs, plate_hz, zeta, ball, vin, phase):
    from ballimpact.signal.shape import peak_on_step_response

    # a damped plate answers the force's jump (and the spike's drop) with one overshoot and a damped swing: a fall,
    # a bump and a fall again after a peak in the spike's phase; the ball's own force after its spike rises once
    # to its maximum (Eq. (14)). The overshoot makes the peak too high, with too little ringing for the other checks
    noise = 1.0
    rng = np.random.default_rng(int(fs) + int(10 * phase))
    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
    assert sensed.max() > 1.05 * true_peak  # the overshoot is what is at stake
    sensed = sensed + rng.normal(0.0, noise, sensed.size)
    problems = peak_on_step_response(sensed[1:], fs, noise, sensed.max(), 1.0 - phase)
    assert [p.kind for p in problems] == [ProblemKind.PEAK_ON_RINGING], (fs, plate_hz, phase)
    assert problems[0].message.startswith("peak force on the plate's step response"), problems
    f_seen = float(re.search(r"ringing at about (\S+) kHz", problems[0].message).group(1)) * 1e3
    assert_allclose(f_seen, plate_hz * math.sqrt(1 - zeta * zeta), rtol=0.25)  # a period read to a sample or two
    # the same force on an ideal plate: its jump, spike, drop and one hump pass
    ideal, _ = _plate_sensed_ball_force(fs, None, 0.0, phase, ball, vin)
    ideal = ideal + rng.normal(0.0, noise, ideal.size)
    assert peak_on_step_response(ideal[1:], fs, noise, ideal.max(), 1.0 - phase) == []


@pytest.mark.parametrize("fs", [20e3, 23.6e3, 50e3, 100e3, 200e3])
@pytest.mark.parametrize("ball, vin", [("pressurised", 35.0), ("punctured", 35.0), ("pressureless", 12.5),
                                       ("oversize", 25.0), ("pressurised", 10.0)])
def test_ball_force_on_an_ideal_plate_has_no_step_response(fs, ball, vin):
    from ballimpact.signal.shape import peak_on_slow_fall, peak_on_step_response

    # every ball of Table 2, slow and fast, at 20-200 kHz with noise of 0.1 % of the peak: the spike and its drop
    # (or none) and one hump are no plate's step response, wherever the jump falls between the samples; nor is the
    # spike's drop at buckling (or a later peak) a slow fall
    for phase in (0.05, 0.35, 0.65, 0.95):
        f, peak = _plate_sensed_ball_force(fs, None, 0.0, phase, ball, vin)
        f = f + np.random.default_rng(int(fs + 100 * phase)).normal(0.0, 1e-3 * peak, f.size)
        assert peak_on_step_response(f[1:], fs, 1e-3 * peak, f.max(), 1.0 - phase) == [], (phase, fs)
        assert peak_on_slow_fall(f[1:], fs, 1e-3 * peak, f.max(), 1.0 - phase) == [], (phase, fs)


@pytest.mark.parametrize("fs, plate_hz, zeta, mode, ball, vin", [
    # bench/two_mode_map.py's ok-but-wrong plates, balls and speeds (seeds 2 and 3), the balls unscaled
    (54.9e3, 10.6e3, 0.171, (24.7e3, 0.172, -0.445), "oversize", 18.9),  # 2:371: peak +12 %
    (93.7e3, 7.45e3, 0.175, (27.0e3, 0.173, 0.124), "pressurised", 34.6),  # 2:385: peak +15 %
    (141.7e3, 6.08e3, 0.278, (19.5e3, 0.084, -0.492), "pressurised", 25.7),  # 3:301: peak +28 %
])
@pytest.mark.parametrize("phase", [0.2, 0.7])
def test_peak_that_the_force_leaves_slowly_is_a_problem(fs, plate_hz, zeta, mode, ball, vin, phase):
    from ballimpact.signal.shape import peak_on_slow_fall

    # a plate of two modes answers the force's jump with an overshoot the one-mode fits do not recognise; the force
    # leaves that top over several samples, where the ball's drops at once at buckling (section 3.2.4)
    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin, modes=(mode,))
    assert sensed.max() > 1.03 * true_peak  # the lifted peak is what is at stake
    noise = 1e-3 * true_peak
    sensed = sensed + np.random.default_rng(int(fs) + int(10 * phase)).normal(0.0, noise, sensed.size)
    problems = peak_on_slow_fall(sensed[1:], fs, noise, sensed.max(), 1.0 - phase)
    assert [p.kind for p in problems] == [ProblemKind.PEAK_ON_RINGING], (fs, plate_hz, phase)
    assert "a ball's force drops at once as its wall buckles" in problems[0].message, problems


# ------------------------------------------------- an end from the force's curve, a convex end (issue 9)


def _model_trace(fs, ball, scale, vin, seed, peak_V=4.0, noise_V=1.0e-3):
    """A DC-coupled, hum-free record of the Goodwill & Haake force of one impact (tests/zoo.py's model force:
    its 0.01 ms steps, linear between them, its interpolated end), 20 ms pre-trigger, 60 ms in all, peak_V at
    the peak, normal noise (seeded): voltage [V] and the true start and end [s]."""
    import zoo

    knots_t, knots_f, _, _, _ = zoo.model_force(ball, scale, vin)
    t = np.arange(int(0.06 * fs)) / fs
    start = 0.02 + 0.37 / fs
    v = peak_V * np.interp(t - start, knots_t, knots_f / np.max(knots_f), left=0.0, right=0.0)
    return v + np.random.default_rng(seed).normal(0.0, noise_V, t.size), start, start + knots_t[-1]


PUNCTURED_30 = ("punctured", (1.0, 1.0, 1.0, 1.0, 1.0), 30.0)  # the force steepens into its end (concave)
CONVEX_2_1489 = ("punctured", (1.0093, 0.8681, 1.1831, 0.9941, 1.1973), 33.447)  # zoo trace 2:1489's ball: flattens


def test_end_taken_from_the_curve_where_the_refit_moves_it_later():
    """A punctured ball at 50 kHz whose end, refitted from the samples above twice the noise threshold, moves
    later by more than 0.5 % of TC (the force steepens into its end): the curve pins it, the contact's end is
    the curve's and TC is within 0.3 % of the model's; no problem is left."""
    from ballimpact.signal.end_checks import SPREAD_MAX_FRACTION

    fs = 50e3
    v, start, end = _model_trace(fs, *PUNCTURED_30, seed=2)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert c.contact.end_spread_s > SPREAD_MAX_FRACTION * c.contact.contact_time_s
    assert "end_curve" in c.contact.flags
    assert c.contact.end_s == c.contact.curve_end_s
    assert_allclose(c.contact.contact_time_s, end - start, rtol=3e-3)
    assert not c.problems, [p.message for p in c.problems]


@pytest.mark.parametrize("seed", [7, 8])
def test_end_not_taken_from_the_curve_below_33kHz(seed):
    """The same ball at 25 kHz, where a plate of up to 30 kHz could alias below the ringing checks' band: an end
    that moves when refitted stays a problem."""
    fs = 25e3
    v, _, _ = _model_trace(fs, *PUNCTURED_30, seed=seed)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert "end_curve" not in c.contact.flags
    assert any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED and "fitted again" in p.message for p in c.problems)


@pytest.mark.parametrize("seed", [0, 3, 9])
def test_convex_end_is_excluded(seed):
    """A force that flattens into its end (zoo trace 2:1489's ball, 1 mV on 4 V at 50 kHz): the line through its
    last samples meets zero early (TC 0.7-1.1 % short of the model's here), and its refit from higher samples
    earlier still, sometimes by less than 0.5 % of TC (seed 9); the force's curve puts the end later, or the
    refit moves it: the end is not determined, never the curve's."""
    fs = 50e3
    v, start, end = _model_trace(fs, *CONVEX_2_1489, seed=seed)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert c.contact.contact_time_s < (1 - 0.007) * (end - start)  # what would be reported: short
    assert "end_curve" not in c.contact.flags
    assert any(p.kind is ProblemKind.CONTACT_END_UNDETERMINED for p in c.problems), [p.message for p in c.problems]


def _plate_case(fs, fn_hz, zeta, noise, seed, foot=(0, 0.0)):
    """A force that jumps to 0.3 at ts = 500.37 samples, rises to 1 and falls to zero 4.2 ms later (with, before
    ts, a foot rising from zero over ``foot[0]`` samples to ``foot[1]``), through the continuous plate (the
    analytic responses of tests/test_plate.py), with white noise: (sensed, ts [samples], TC [samples], a baseline
    fit of that noise)."""
    from test_plate import sensed_force

    from ballimpact.signal.baseline import BaselineFit

    n = int(0.03 * fs)
    ts, tc = 500.37, 4.2e-3 * fs
    u = np.linspace(0.0, 1.0, 80)[1:]
    kt = np.concatenate([[ts, ts + 1e-9], ts + u * tc]) / fs
    kf = np.concatenate([[0.0, 0.3], np.sin(np.pi * u) + 0.3 * (1.0 - u) ** 2])
    kf[-1] = 0.0
    if foot[0]:
        kt = np.concatenate([[(ts - foot[0]) / fs], kt])
        kf = np.concatenate([[0.0, foot[1]], kf[1:]])
    x = sensed_force(kt, kf, np.arange(n) / fs, fn_hz, zeta) + np.random.default_rng(seed).normal(0.0, noise, n)
    every = np.ones(n, bool)
    return x, ts, tc + foot[0], BaselineFit(np.zeros(n), {}, 0.0, 0.0, True, noise, (), 0.0, every, every, every)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_undone_contact_fits_the_exact_forces_ends_through_the_plate(seed):
    # the sensed start read 6 samples early (as detect_contact's foot or edge fallback can, on a plate's first
    # overshoot): the exact undone force's start found on it is later, which alone refused it (a foot lost?).
    # Its ends fitted through the plate come back to the truth, and the sensed samples before them hold no foot
    from test_plate import _resonance

    from ballimpact.signal.undone import _undone_contact
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = 50e3, 12e3, 0.02
    x, ts, tc, fit = _plate_case(fs, fn, zeta, 1e-3, seed)
    got = _undone_contact(undo_plate_resonance(x, fs, fn, zeta), x, fs, fit, ts - 6.0, 0.0, math.inf,
                          _resonance(fn, zeta, fs), [])
    assert not isinstance(got, str), got
    c = got[0]
    assert_allclose(c.start_s * fs, ts, atol=0.1)
    assert_allclose((c.end_s - c.start_s) * fs, tc, rtol=2e-3)


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("foot", [(15, 0.005), (30, 0.004)])
def test_undone_contact_refuses_a_foot_lost_in_the_undone_noise(seed, foot):
    # a foot of 0.4-0.5 % of the peak over 15-30 samples, seen by the sensed start: lost in the undone force's
    # amplified noise, and not fitted back through the plate (a jump, a line and a parabola); the sensed samples
    # before the fitted start stand out of their noise, and the undone force is refused
    from test_plate import _resonance

    from ballimpact.signal.undone import _undone_contact
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = 50e3, 12e3, 0.02
    x, ts, tc, fit = _plate_case(fs, fn, zeta, 1e-3, seed, foot)
    got = _undone_contact(undo_plate_resonance(x, fs, fn, zeta), x, fs, fit, ts - foot[0], 0.0, math.inf,
                          _resonance(fn, zeta, fs), [])
    assert isinstance(got, str), (got[0].start_s * fs, ts - foot[0])


# ------------------------------------------------- the exact undone force read from fits (issue 9)


def _spike_through_plate(fs, fn, zeta, drop_at, noise, seed, fine=16):
    """The model's pre-buckling spike on a grid `fine` times the sample rate (a jump to 0.4 at first contact, a
    concave ramp to 1.0 at drop_at samples after it, a drop to 0.8, then a smooth top of 0.9 30 samples later),
    sensed through a second-order plate (fn [Hz], zeta [-]; exact on the fine grid for a force linear between
    its points), sampled at fs [Hz], with seeded white noise [V]: the sensed trace [V], the force at the samples
    [V] and the first contact [samples]."""
    from scipy import signal

    n = 300
    t = np.arange(n * fine) / (fs * fine)
    start = 100.3
    tau = t * fs - start  # [samples] since first contact
    ramp = 0.4 + 0.6 * (tau / drop_at) * (2.0 - tau / drop_at)
    after = 0.8 + 0.1 * (1.0 - ((tau - drop_at - 30.0) / 30.0) ** 2)
    force = np.where(tau < 0, 0.0, np.where(tau < drop_at, ramp, np.maximum(after, 0.0)))
    b, a = _fine_plate(fs * fine, fn, zeta)
    sensed = signal.lfilter(b, a, force)[::fine]
    return sensed + np.random.default_rng(seed).normal(0.0, noise, n), force[::fine], start


@functools.lru_cache(maxsize=4)
def _fine_plate(rate, fn, zeta):
    """A second-order plate (fn [Hz], zeta [-]) discretised on a grid at ``rate`` [Hz], exact for a force linear
    between its points (scipy's first-order hold): numerator and denominator [-]."""
    from scipy import signal

    wn = 2.0 * math.pi * fn
    b, a, _ = signal.cont2discrete(([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn]), 1.0 / rate, method="foh")
    return np.ravel(b), np.ravel(a)


SPIKE_PLATE = (100e3, 12e3, 0.05)  # sample rate [Hz], plate resonance [Hz], damping ratio [-]


def test_fitted_force_does_not_span_the_drop():
    """Read one-sided, the fits that reach past the pre-buckling drop do not hold: the samples after it keep
    their own value (NaN error), never a reading smoothed across the drop."""
    from ballimpact.signal.undone_peak import _fitted_force
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = SPIKE_PLATE
    sensed, truth, start = _spike_through_plate(fs, fn, zeta, 17.6, 1e-3, seed=1)
    exact = undo_plate_resonance(sensed, fs, fn, zeta)
    a, last = int(math.ceil(start)) + 1, int(math.floor(start + 17.6))
    _, error = _fitted_force(exact, fs, a, last + 4, last + 4 - a, 1e-3, PlateResonance(fn, zeta, 0.0, 0.0))
    assert np.all(np.isnan(error[last + 1 - a:]))
    assert np.all(np.isfinite(error[:last - 3 - a]))  # the ramp well before the drop is fitted


SPIKE_DROP_AT = 17.6  # the spike's drop this many samples after the start in the fitted-force tests [samples]


def _fitted_reads(read, noise, draws=40):
    """Misses of ``read(exact, start) -> (reading, its standard error, sample index)`` against the true force over
    ``draws`` noise draws of the spike through SPIKE_PLATE, and their mean reported error; asserts that the reported
    error is the scatter's (0.75-1.35 times) on at least 90 % of the draws."""
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = SPIKE_PLATE
    miss, error = [], []
    for seed in range(draws):
        sensed, truth, start = _spike_through_plate(fs, fn, zeta, SPIKE_DROP_AT, noise, seed=seed)
        reading, err, k = read(undo_plate_resonance(sensed, fs, fn, zeta), start)
        if np.isfinite(err):
            miss.append(reading - truth[k])
            error.append(err)
    assert len(miss) >= 0.9 * draws
    se = float(np.mean(error))
    assert 0.75 * se <= float(np.std(miss)) <= 1.35 * se
    return np.asarray(miss), se


def test_fitted_force_reads_the_ramps_top_with_an_honest_error():
    """The top of a ramp cut by a drop (the model's pre-buckling spike through a 12 kHz plate at 100 kHz, 0.2 %
    noise): read from the ramp's fit at its last sample over 40 noise draws, its scatter is the reported standard
    error (0.75-1.35 times), which is under a third of one undone sample's noise; its mean within 1.5 % of the
    true force there (above it: the drop's transient in the plate's inverse reaches back one sample)."""
    from ballimpact.signal.undone_peak import _fitted_force
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import undone_noise_gain

    fs, fn, zeta = SPIKE_PLATE
    noise = 2e-3

    def ramp_top(exact, start):
        a, last = int(math.ceil(start)) + 1, int(math.floor(start + SPIKE_DROP_AT))
        out, err = _fitted_force(exact, fs, a, last + 1, last + 1 - a, noise, PlateResonance(fn, zeta, 0.0, 0.0))
        return out[-1], err[-1], last

    miss, se = _fitted_reads(ramp_top, noise)
    assert se < noise * undone_noise_gain(fs, fn, zeta) / 3.0
    assert_allclose(np.mean(miss), 0.0, atol=0.015)


def test_fitted_force_reads_a_smooth_top_unbiased():
    """Centred fits read the smooth top after buckling (0.9 at 30 samples after the drop) without bias (within
    3 standard errors of the mean over 40 draws) and with their reported error (0.75-1.35 times)."""
    from ballimpact.signal.undone_peak import PEAK_FIT_S, _fitted_force
    from ballimpact.signal.plate import PlateResonance

    fs, fn, zeta = SPIKE_PLATE
    noise = 2e-3

    def smooth_top(exact, start):
        a = int(math.floor(start + SPIKE_DROP_AT)) + 4
        top = int(round(start + SPIKE_DROP_AT + 30.0))
        out, err = _fitted_force(exact, fs, a, a + 50, int(round(PEAK_FIT_S * fs)), noise,
                                 PlateResonance(fn, zeta, 0.0, 0.0), centred=True)
        return out[top - a], err[top - a], top

    miss, se = _fitted_reads(smooth_top, noise)
    assert abs(float(np.mean(miss))) <= 3.0 * se / math.sqrt(len(miss))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fit_noise_scale_finds_noise_the_stated_one_misses(seed):
    """White noise through the plate's inverse, 500 samples: stated right, the scale is about 1 (never below it);
    stated at half, the centred fits' residuals find it twice as large (1.7-2.3)."""
    from ballimpact.signal.undone_peak import _fit_noise_scale
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = SPIKE_PLATE
    plate = PlateResonance(fn, zeta, 0.0, 0.0)
    exact = undo_plate_resonance(np.random.default_rng(seed).normal(0.0, 1e-3, 600), fs, fn, zeta)
    assert 1.0 <= _fit_noise_scale(exact, fs, 50, 550, 20, 1e-3, plate) <= 1.15
    assert 1.7 <= _fit_noise_scale(exact, fs, 50, 550, 20, 0.5e-3, plate) <= 2.3


# ------------------------------------------------- a peak lifted by the plate's ringing from the jump (issue 9)


def _front_ringing_problems(fs, plate_hz, zeta, phase, ball, vin, seed):
    """peak_on_front_ringing on the model's force through a plate (None: ideal), 0.1 % of the peak of noise, ten
    quiet samples before it; the problems, the sensed trace and the true peak [N]."""
    from ballimpact.signal.peak import peak_on_front_ringing

    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
    noise = 1e-3 * true_peak
    x = np.concatenate([np.zeros(10), sensed]) + np.random.default_rng(seed).normal(0.0, noise, sensed.size + 10)
    start = 10 + 1.0 - phase  # the force's jump: (1 - phase) of a sample after the first sample of ``sensed``
    end = 10 + float(np.flatnonzero(sensed > 0.01 * true_peak)[-1])
    return peak_on_front_ringing(x, fs, noise, float(x.max()), start, end), x, true_peak


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin, phase", [
    (168e3, 13.7e3, 0.2, "pressureless", 32.5, 0.1),  # zoo 3:824: the spike's top on the ringing's second maximum
    (168e3, 13.7e3, 0.2, "pressureless", 32.5, 0.5),
    (168e3, 13.7e3, 0.2, "pressureless", 32.5, 0.9),
    (150e3, 11.0e3, 0.15, "oversize", 27.0, 0.5),
])
def test_peak_lifted_by_the_ringing_from_the_jump_is_a_problem(fs, plate_hz, zeta, ball, vin, phase):
    from ballimpact.signal.shape import peak_on_step_response

    # a damped plate rings from the force's jump and the pre-buckling spike's top lands on a later maximum of that
    # ringing: the largest sample is 5-14 % above the ball's peak, and the force has no bump or regular swings
    # for the other checks to see; a jump and a ramp through a plate explain the samples, through an ideal plate not
    problems, x, true_peak = _front_ringing_problems(fs, plate_hz, zeta, phase, ball, vin, seed=int(10 * phase))
    assert x.max() > 1.05 * true_peak  # what is at stake
    assert [p.kind for p in problems] == [ProblemKind.PEAK_ON_RINGING], problems
    assert problems[0].message.startswith("peak force on the plate's ringing"), problems
    lift = float(re.search(r"lifts the largest sample (\S+) % of the peak", problems[0].message).group(1))
    assert lift > 3.0
    if plate_hz == 13.7e3:  # the spike's top on the second maximum, 1.5 periods fitted: the plate is found
        assert_allclose(float(re.search(r"plate of about (\S+) kHz", problems[0].message).group(1)) * 1e3, plate_hz,
                        rtol=0.03)
        k0 = int(math.ceil(11 - phase))
        assert peak_on_step_response(x[k0:], fs, 1e-3 * true_peak, x.max(), k0 - (11 - phase)) == []


@pytest.mark.parametrize("fs", [100e3, 150e3, 200e3])
@pytest.mark.parametrize("ball, vin", [("pressurised", 35.0), ("punctured", 35.0), ("pressureless", 12.5),
                                       ("oversize", 25.0), ("pressureless", 32.5)])
def test_ball_force_on_an_ideal_plate_has_no_front_ringing(fs, ball, vin):
    # every ball of Table 2 at 100-200 kHz (enough samples in the spike's phase to fit): the jump, the ramp and the
    # spike's top through an ideal plate need no resonance, wherever the jump falls between the samples
    for phase in (0.2, 0.7):
        problems, _, _ = _front_ringing_problems(fs, None, 0.0, phase, ball, vin, seed=int(fs + 100 * phase))
        assert problems == [], (phase, [p.message for p in problems])


def _half_sine_with_foot(foot_fraction, foot_samples, fs=50e3, tc=4e-3, peak=2.0, noise_fraction=1e-3, seed=1):
    """A half-sine contact force of ``tc`` [s] on an ideal plate with a flat foot of ``foot_fraction`` of the
    peak for ``foot_samples`` samples before it (a cloth that carries a little load before the core does), white
    noise of ``noise_fraction`` of the peak: (voltage [V], sample rate [Hz], true start [s], true TC [s])."""
    t = np.arange(int(0.2 * fs)) / fs
    t0 = 0.05
    force = np.where((t >= t0) & (t < t0 + tc), peak * np.sin(np.pi * (t - t0) / tc), 0.0)
    force += np.where((t >= t0 - foot_samples / fs) & (t < t0), foot_fraction * peak, 0.0)
    noise = np.random.default_rng(seed).normal(0.0, noise_fraction * peak, t.size)
    return force + noise, fs, t0 - foot_samples / fs, tc + foot_samples / fs


@pytest.mark.parametrize("foot_fraction, foot_samples", [
    (0.0, 0),  # no foot: the control, TC to 1 %
    (0.003, 10),  # a flat foot of 3 noise deviations over 10 samples: was ok with TC -4.7 %, now named
    (0.003, 20),  # the same over 20 samples: was ok with TC -9.1 %
    (0.005, 10),  # 5 noise deviations over 10 samples: was ok with TC -1.4 %
    (0.01, 10),  # 1 % of the peak over 10 samples: was ok with TC +2.4 %, now named (the hinge's start not pinned)
])
def test_a_foot_before_the_rise_is_measured_or_named(foot_fraction, foot_samples):
    """A foot before the force's rise (a cloth that carries a little load first; the zoo's model force has none)
    is part of the contact: either TC comes out within 1 % of the true one, from the foot's start, or the impact
    shows a problem (the check of the corrected signal before the start, FOOT_CHECK_SIGMA, or the hinge's start
    uncertainty, END_SE_MAX_FRACTION)."""
    v, fs, start_s, tc_s = _half_sine_with_foot(foot_fraction, foot_samples)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = condition_voltage(v, fs, mains_hz=None)
    error = c.contact.contact_time_s / tc_s - 1.0
    assert c.problems or abs(error) <= 0.01, (f"ok with TC {100 * error:+.2f} %, start "
                                             f"{(c.contact.start_s - start_s) * fs:+.2f} samples off")


@pytest.mark.parametrize("level_sigma, n", [(2.0, 25), (1.0, 100), (3.0, 4)])
def test_foot_sigma_reads_a_level_in_standard_errors(level_sigma, n):
    """A flat level of ``level_sigma`` noise deviations over n samples before a start, no noise: level_sigma
    sqrt(n) standard errors (the level statistic's, the ramp's lower for a flat foot)."""
    from ballimpact.signal.end_checks import foot_sigma

    assert_allclose(foot_sigma(np.full(n, level_sigma * 1e-3), 1e-3), level_sigma * math.sqrt(n), rtol=1e-12)


def test_foot_sigma_on_white_noise_stays_below_the_check():
    """On white noise (500 draws of 25-100 samples) the statistic, a maximum over lengths and two shapes, exceeds
    FOOT_CHECK_SIGMA (5) at most once: the check's false alarms are rare."""
    from ballimpact.signal.end_checks import FOOT_CHECK_SIGMA, foot_sigma

    rng = np.random.default_rng(0)
    values = [foot_sigma(rng.normal(0.0, 1e-3, int(rng.integers(25, 101))), 1e-3) for _ in range(500)]
    assert sum(v > FOOT_CHECK_SIGMA for v in values) <= 1
    assert 1.0 < float(np.median(values)) < 3.0


@pytest.mark.parametrize("jump", [0.03, 0.1])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_end_that_jumps_is_no_convex_fade(jump, seed):
    """A half-sine force (4 V, 4 ms, 50 kHz, 1 mV noise, DC-coupled) cut off where it has fallen to 3 or 10 % of
    its peak: it jumps to zero. The end is located to half a sample from the jump; the force's curve, fitted
    there too, meets zero up to a sample and a half after it (no curve models a jump), which is not the
    convex fade the end check looks for: no problem, and TC within 0.5 % of the truth."""
    fs, tc_half_sine = 50e3, 4.0e-3
    start_s = (1000.3 + 0.113 * seed) / fs
    t = np.arange(int(0.08 * fs)) / fs
    phase = (t - start_s) / tc_half_sine
    cut = 1.0 - math.asin(jump) / math.pi  # the phase where the half-sine has fallen to ``jump`` of its peak
    force = np.where((phase > 0) & (phase < cut), 4.0 * np.sin(np.pi * np.clip(phase, 0.0, 1.0)), 0.0)
    v = force + np.random.default_rng(seed).normal(0.0, 1e-3, t.size)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert "end_jump" in c.contact.flags
    assert not c.problems, c.problems
    assert_allclose(c.contact.contact_time_s, cut * tc_half_sine, rtol=0.005)


# ------------------------------------------------- weighted fits of the exact undone force (issue 9, low-pass guard)


def test_weighted_fit_reads_a_smooth_top_with_half_the_error():
    """Centred fits weighted by the undone noise's covariance read the smooth top after buckling (0.9 at 30 samples
    after the drop, SPIKE_PLATE, 0.2 % noise) without bias (within 3 standard errors of the mean over 40 draws), with
    their reported error (0.75-1.35 times the scatter), and at most 0.6 times the unweighted fits' error and 0.4
    times the sensed noise (the undone sample's own noise is about 10 times the sensed noise)."""
    from ballimpact.signal.undone_peak import PEAK_FIT_S, _fitted_force
    from ballimpact.signal.plate import PlateResonance

    fs, fn, zeta = SPIKE_PLATE
    noise = 2e-3
    errors = {}
    for weighted in (False, True):
        def smooth_top(exact, start, weighted=weighted):
            a = int(math.floor(start + SPIKE_DROP_AT)) + 4
            top = int(round(start + SPIKE_DROP_AT + 30.0))
            out, err = _fitted_force(exact, fs, a, a + 50, int(round(PEAK_FIT_S * fs)), noise,
                                     PlateResonance(fn, zeta, 0.0, 0.0), centred=True, weighted=weighted)
            return out[top - a], err[top - a], top

        miss, errors[weighted] = _fitted_reads(smooth_top, noise)
        assert abs(float(np.mean(miss))) <= 3.0 * errors[weighted] / math.sqrt(len(miss))
    assert errors[True] <= 0.6 * errors[False]
    assert errors[True] <= 0.4 * noise


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_weighted_fit_does_not_hold_across_the_drop(seed):
    """No weighted centred fit whose window spans the pre-buckling drop (SPIKE_PLATE, 0.2 % noise) holds: its
    weighted residual sees the step, so the spike's top is never read smoothed across it; the fits well after
    the drop hold."""
    from ballimpact.signal.undone_peak import PEAK_FIT_S, _fitted_force
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import undo_plate_resonance

    fs, fn, zeta = SPIKE_PLATE
    sensed, _, start = _spike_through_plate(fs, fn, zeta, SPIKE_DROP_AT, 2e-3, seed=seed)
    exact = undo_plate_resonance(sensed, fs, fn, zeta)
    length = int(round(PEAK_FIT_S * fs)) | 1
    a = int(math.ceil(start)) + 1
    _, error = _fitted_force(exact, fs, a, a + 70, length, 2e-3, PlateResonance(fn, zeta, 0.0, 0.0), centred=True,
                             weighted=True)
    drop = start + SPIKE_DROP_AT - a  # [samples] from a
    spans = np.abs(np.arange(error.size) - drop) < 0.5 * length - 1.0  # the window around the sample holds the drop
    assert not np.any(np.isfinite(error[spans]))
    assert np.all(np.isfinite(error[int(drop) + length + 2:error.size - length]))


def _guarded_lowpass(force_knots, fs, fn, zeta, noise, seed):
    """A piecewise-linear force (knot times [s] and forces [V]) through the continuous plate (analytic ramp
    responses, test_plate.sensed_force) with seeded white noise [V], undone exactly and low-passed at twice fn:
    the low-pass guard's verdict (None: kept) and the low-passed peak over the force's [-]."""
    from test_plate import sensed_force

    from ballimpact.signal.undone_peak import lowpass_hides_peak
    from ballimpact.signal.contact import detect_contact
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import lowpass_zero_phase, undo_plate_resonance

    kt, kf = force_knots
    t = np.arange(int(0.030 * fs)) / fs
    sensed = sensed_force(kt, kf, t, fn, zeta) + np.random.default_rng(seed).normal(0.0, noise, t.size)
    exact = undo_plate_resonance(sensed, fs, fn, zeta)
    contact = detect_contact(lowpass_zero_phase(exact, fs, 2.0 * fn), fs)
    return (lowpass_hides_peak(exact, fs, noise, PlateResonance(fn, zeta, 0.0, 0.0), contact, 0.0),
            float(contact.peak_V) / float(np.max(kf)))


GUARD_T0 = 0.010 + 0.37 / 100e3  # the force's start in the low-pass guard's tests [s]


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_lowpass_guard_shows_a_smooth_top_kept(seed):
    """A smooth ball-like force (a jump to 0.15, a 4 ms hump of 1) through a 5 kHz plate (damping 0.03) at
    100 kHz with 0.4 % noise: its exact undone force's noise (the sensed noise times ``undone_noise_gain``) is
    tens of times the sensed noise, and the unweighted fits' errors are too large to show a loss of 4 %; the
    weighted fits after buckling show the low-pass at 10 kHz keeps the peak (it does, to 1 %: the force's truth)."""
    u = np.linspace(0.0, 1.0, 81)[1:]
    kt = np.concatenate([[GUARD_T0, GUARD_T0 + 1e-9], GUARD_T0 + u * 4.0e-3])
    kf = np.concatenate([[0.0, 0.15], np.sin(np.pi * u) ** 1.2 + 0.15 * (1.0 - u) ** 2])
    kf[-1] = 0.0
    why, kept = _guarded_lowpass((kt, kf), 100e3, 5e3, 0.03, 4e-3, seed)
    assert why is None
    assert_allclose(kept, 1.0, atol=0.01)


@pytest.mark.parametrize("noise", [2e-3, 5e-3, 1e-2])
@pytest.mark.parametrize("drop", [0.9, 0.95])
def test_lowpass_guard_refuses_to_flatten_the_buckling_drop(noise, drop):
    """The model's pre-buckling spike (a jump to 0.4, a ramp to 1 at 0.2 ms, a drop to ``drop`` - 0.05, a smooth
    rest) through the 5 kHz plate at 150 kHz with 0.2-1 % noise: the low-pass at 10 kHz takes 5-9 % of its top,
    and the guard refuses it for every noise draw (the weighted fits, which may hold across such a drop at 1 %
    noise and read it smoothed, are not used there)."""
    fs = 150e3
    t0 = 0.010 + 0.37 / fs
    td = t0 + 0.2e-3 + 0.4 / fs
    u = np.linspace(0.0, 1.0, 81)[1:]
    kt = np.concatenate([[t0, t0 + 1e-9, td, td + 1e-9], td + u * 3.8e-3])
    kf = np.concatenate([[0.0, 0.4, 1.0, drop - 0.05], drop - 0.05 + 0.04 * np.sin(np.pi * u) - (drop - 0.05) * u ** 3])
    kf[-1] = 0.0
    for seed in range(4):
        why, kept = _guarded_lowpass((kt, kf), fs, 5e3, 0.03, noise, seed)
        assert kept < 0.95
        assert why is not None and re.search(r"lowers the exact undone force|too noisy to show", why), why


@pytest.mark.parametrize("fs, fn, noise", [(150e3, 5e3, 1e-3), (100e3, 4e3, 2e-3), (60e3, 3.5e3, 5e-4)])
def test_plate_cutoffs_start_where_the_undone_noise_is_quiet_and_go_down_to_the_resonance(fs, fn, noise):
    """The low-passes tried on a refused undone force (peak 1): from the first cutoff that brings white noise
    through the plate's inverse and the low-pass to PLATE_LOWPASS_NOISE of the peak (measured on 20 000 seeded
    samples pushed through both), down in steps of sqrt(2), never below the resonance, at most PLATE_LOWPASS_TRIES
    of them (now six: which one passes every check depends on the force)."""
    from ballimpact.signal.undone import PLATE_LOWPASS_NOISE, PLATE_LOWPASS_TRIES, _plate_cutoffs
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import lowpass_zero_phase, undo_plate_resonance

    zeta = 0.03
    cutoffs = _plate_cutoffs(fs, PlateResonance(fn, zeta, 0.0, 0.0), noise, 1.0)
    assert 1 <= len(cutoffs) <= PLATE_LOWPASS_TRIES == 6
    assert min(cutoffs) >= fn
    assert_allclose(np.array(cutoffs[:-1]) / np.array(cutoffs[1:]), math.sqrt(2.0), rtol=1e-12)
    white = undo_plate_resonance(np.random.default_rng(0).normal(0.0, noise, 20000), fs, fn, zeta)

    def rms(cutoff):
        return float(np.std(lowpass_zero_phase(white, fs, cutoff)[100:-100]))

    assert rms(cutoffs[0]) <= 1.05 * PLATE_LOWPASS_NOISE
    if cutoffs[0] * math.sqrt(2.0) < 0.5 * fs:
        assert rms(cutoffs[0] * math.sqrt(2.0)) > 0.95 * PLATE_LOWPASS_NOISE


# ------------------------------------------------- a peak on the plate's first overshoot, a few samples a period (issue 9)


def _first_overshoot_problems(fs, plate_hz, zeta, phase, ball, vin, seed, noise_fraction=1e-3):
    """peak_on_first_overshoot on the model's force through a plate (None: ideal), ``noise_fraction`` of the peak
    of noise, ten quiet samples before it; the problems, the sensed trace and the true peak [N]."""
    from ballimpact.signal.peak import peak_on_first_overshoot

    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
    noise = noise_fraction * true_peak
    x = np.concatenate([np.zeros(10), sensed]) + np.random.default_rng(seed).normal(0.0, noise, sensed.size + 10)
    start = 10 + 1.0 - phase  # the force's jump: (1 - phase) of a sample after the first sample of ``sensed``
    end = 10 + float(np.flatnonzero(sensed > 0.01 * true_peak)[-1])
    return peak_on_first_overshoot(x, fs, noise, float(x.max()), start, end), x, true_peak


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin, phase", [
    (25.5e3, 8.5e3, 0.11, "pressureless", 30.0, 0.1),  # the class reported: 3 samples a period, peak +17 to +22 %
    (25.5e3, 8.5e3, 0.11, "pressureless", 30.0, 0.7),
    (25.5e3, 8.5e3, 0.11, "pressureless", 30.0, 0.95),
    (30.0e3, 12.9e3, 0.077, "pressureless", 34.0, 0.4),  # 2.3 samples a period: maybe an alias, no evidence
    (30.0e3, 12.9e3, 0.077, "pressureless", 34.0, 0.7),
    (65.0e3, 24.4e3, 0.037, "punctured", 13.0, 0.7),  # 2.7 samples a period, lightly damped
])
def test_peak_on_the_plates_first_overshoot_sampled_a_few_times_a_period_is_a_problem(fs, plate_hz, zeta, ball, vin,
                                                                                       phase):
    from ballimpact.signal.peak import OVERSHOOT_MIN_PERIOD, peak_on_front_ringing

    # the plate's first overshoot of the force's jump is the largest sample, 1-2 samples into the contact, and its
    # ringing is gone a period or two later; the front through a plate, with the drop at buckling, finds the plate
    problems, x, true_peak = _first_overshoot_problems(fs, plate_hz, zeta, phase, ball, vin, seed=int(10 * phase))
    assert x.max() > 1.1 * true_peak  # what is at stake
    if fs / plate_hz >= OVERSHOOT_MIN_PERIOD:  # evidence of the plate, undone where that passes every check
        assert [p.kind for p in problems] == [ProblemKind.PEAK_ON_RINGING], problems
        assert problems[0].message.startswith("peak force on plate ringing: the largest sample"), problems
    else:  # near fs / 2 a resonance above it rings the same through its alias: named, no evidence
        assert [p.kind for p in problems] == [ProblemKind.PEAK_BETWEEN_SAMPLES], problems
        assert problems[0].message.startswith("peak force between samples: the largest sample"), problems
        assert "seen through its alias" in problems[0].message
    assert_allclose(float(re.search(r"plate of about (\S+) kHz", problems[0].message).group(1)) * 1e3, plate_hz,
                    rtol=0.05)
    assert float(re.search(r"lifts the largest sample (\S+) % of the peak", problems[0].message).group(1)) > 3.0
    noise = 1e-3 * true_peak  # too few samples up to the largest for the front's own check
    assert peak_on_front_ringing(x, fs, noise, float(x.max()), 11 - phase, x.size - 20) == []


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin, phase, after, spike", [
    (25.5e3, 8.5e3, 0.11, "pressureless", 30.0, 0.3, 2, -0.1),  # the class reported above, the spike in a trough
])
def test_first_overshoot_is_seen_under_an_electrical_spike_on_the_ringing(fs, plate_hz, zeta, ball, vin, phase,
                                                                          after, spike):
    # an electrical spike of 10 % of the peak (50 noise deviations) on one sample of the ringing after the first
    # overshoot (added after the plate; remove_spikes cannot tell it from the ringing's swings): the front fits
    # neither through an ideal plate nor through a plate until the fits take a free spike (on 257a046 no problem was
    # found, as on python bench/spike_ends_map.py --n 400 --seed 2 trace 2:349, peak +5.0 % ok)
    from ballimpact.signal.peak import peak_on_first_overshoot

    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
    noise = 2e-3 * true_peak  # (at 1e-3 the fit with the spike leaves 42 noise variances of the model's misfit)
    x = np.concatenate([np.zeros(10), sensed]) + np.random.default_rng(1).normal(0.0, noise, sensed.size + 10)
    i = int(np.argmax(x))
    x[i + after] += spike * true_peak
    start = 10 + 1.0 - phase
    end = 10 + float(np.flatnonzero(sensed > 0.01 * true_peak)[-1])
    problems = peak_on_first_overshoot(x, fs, noise, float(x.max()), start, end)
    assert [p.kind for p in problems] == [ProblemKind.PEAK_ON_RINGING], problems
    seen = re.search(r"plate of about (\S+) kHz.* less a single-sample spike of (\S+) noise deviations (\S+) samples "
                     r"from the start", problems[0].message)
    assert seen, problems[0].message
    assert_allclose(float(seen.group(1)) * 1e3, plate_hz, rtol=0.05)
    assert_allclose(float(seen.group(2)), spike * true_peak / noise, rtol=0.1)
    assert_allclose(float(seen.group(3)), i + after - start, atol=0.01)


@pytest.mark.parametrize("fs", [20e3, 32e3])
@pytest.mark.parametrize("ball, vin", [("pressurised", 35.0), ("punctured", 28.0), ("pressureless", 12.5),
                                       ("oversize", 25.0), ("pressureless", 32.5)])
def test_ball_force_on_an_ideal_plate_has_no_first_overshoot(fs, ball, vin):
    # every ball of Table 2 at 20 and 32 kHz, its spike's top in the first samples and its drop at buckling sampled
    # anywhere, at 1e-3 and 5e-5 of the peak of noise: the front through an ideal plate needs no resonance
    for phase, noise_fraction in ((0.2, 1e-3), (0.7, 1e-3), (0.45, 5e-5)):
        problems, _, _ = _first_overshoot_problems(fs, None, 0.0, phase, ball, vin, seed=int(fs + 100 * phase),
                                                   noise_fraction=noise_fraction)
        assert problems == [], (phase, [p.message for p in problems])


# ------------------------------------------------- a contact front ringing near half the sample rate (issue 9)


def _fast_ringing_problems(fs, plate_hz, zeta, phase, ball, vin, seed, noise_fraction=2e-3):
    """_start_on_fast_ringing on the model's force through a plate (None: ideal), ``noise_fraction`` of the peak of
    noise, ten quiet samples before it, the contact from the force's true start to its true end; the problems, the
    sensed trace, the true start [samples] and TC [samples]."""
    from ballimpact.signal.ringing import _start_on_fast_ringing

    sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
    ideal, _ = _plate_sensed_ball_force(fs, None, 0.0, phase, ball, vin)
    noise = noise_fraction * true_peak
    x = np.concatenate([np.zeros(10), sensed]) + np.random.default_rng(seed).normal(0.0, noise, sensed.size + 10)
    start = 10 + 1.0 - phase  # the force's jump: (1 - phase) of a sample after the first sample of ``sensed``
    end = 10 + float(np.flatnonzero(ideal > 0)[-1]) + 0.5
    return _start_on_fast_ringing(x, fs, noise, float(x.max()), start, end), x, start, end - start


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin, phase, dip", [
    # as bench/overshoot_map.py 2:61 (24.3 m/s, a contact of 64 samples there: TC +1.4 %), at 35 m/s here (66)
    (20.6e3, 9.03e3, 0.087, "pressurised", 35.0, 0.4, False),
    (20.6e3, 9.03e3, 0.087, "pressurised", 35.0, 0.9, False),
    (20.0e3, 8.8e3, 0.05, "oversize", 35.0, 0.6, False),
    (36.4e3, 16.47e3, 0.045, "pressurised", 12.3, 0.1, True),  # map 2:113: a front sample back at zero, TC -1.7 %
    (55.1e3, 15.76e3, 0.106, "punctured", 11.5, 0.5, True),  # map 2:202: 3.5 samples a period, TC +1.5 %
])
def test_contact_front_ringing_near_half_the_sample_rate_is_a_problem(fs, plate_hz, zeta, ball, vin, phase, dip):
    from ballimpact.signal.ringing import FAST_RING_ZERO
    from ballimpact.signal.end_checks import JUMP_MAX_FRACTION
    from ballimpact.signal.peak import OVERSHOOT_MIN_PERIOD

    problems, x, start, tc = _fast_ringing_problems(fs, plate_hz, zeta, phase, ball, vin, seed=int(10 * phase))
    k0 = int(math.ceil(start))
    front = x[k0:k0 + 8]
    # what is at stake, on the signal itself: a front sample swung back to zero after the jump, or a contact so short
    # that half a sample is more than 0.7 % of it
    assert (float(front[np.argmax(front > 0.2 * x.max()):].min()) < FAST_RING_ZERO * x.max()) == dip
    assert dip or 0.5 > JUMP_MAX_FRACTION * tc
    assert len(problems) == 1, problems
    period = float(re.search(r"about (\S+) samples a period", problems[0].message).group(1))
    # the recursion of a sinusoid fitted with a cubic reads the plate's period to a few tenths of a sample (its decay
    # reads it nearer two samples, where it stops)
    assert_allclose(period, fs / plate_hz, atol=0.3)
    assert_allclose(float(re.search(r"samples a period, (\S+) kHz", problems[0].message).group(1)) * 1e3,
                    fs / period, rtol=0.01)
    if period >= OVERSHOOT_MIN_PERIOD:
        assert problems[0].kind is ProblemKind.PLATE_RINGING, problems  # evidence: the plate's undoing is tried
    else:  # near fs / 2 a resonance above it rings the same through its alias: named, no evidence
        assert problems[0].kind is ProblemKind.CONTACT_END_UNDETERMINED, problems
        assert "seen through its alias" in problems[0].message
    assert ("swings back below" in problems[0].message) == dip


@pytest.mark.parametrize("fs", [20.6e3, 36.4e3, 55.1e3])
@pytest.mark.parametrize("ball, vin", [("pressurised", 24.3), ("punctured", 11.5), ("pressureless", 32.0),
                                       ("oversize", 18.0)])
def test_ball_force_on_an_ideal_plate_has_no_fast_front_ringing(fs, ball, vin):
    # the ball's front (its jump, spike and drop at buckling) is smooth after buckling: nothing rings
    for phase in (0.1, 0.5, 0.9):
        problems, _, _, _ = _fast_ringing_problems(fs, None, 0.0, phase, ball, vin, seed=int(fs + 10 * phase))
        assert problems == [], (phase, [p.message for p in problems])


@pytest.mark.parametrize("phase", [0.2, 0.6])
def test_fast_front_ringing_that_leaves_the_start_is_no_problem(phase):
    from ballimpact.signal.ringing import FAST_RING_ZERO
    from ballimpact.signal.end_checks import JUMP_MAX_FRACTION

    # 2.6 samples a period on a contact of over 140 samples: the front rings (as on zoo trace 0:960, ok and right),
    # but never back to zero, and half a sample is well within 0.7 % of TC: the start is left as found
    problems, x, start, tc = _fast_ringing_problems(33.5e3, 12.9e3, 0.154, phase, "pressurised", 20.0, seed=3)
    k0 = int(math.ceil(start))
    front = x[k0:k0 + 8]
    assert float(front[np.argmax(front > 0.2 * x.max()):].min()) > 5 * FAST_RING_ZERO * x.max()
    assert 0.5 < JUMP_MAX_FRACTION * tc
    assert problems == []


def _ramp_cut_by_a_drop(fs, rise_frac, drop_phase, noise_frac=0.0, hump=0.9, seed=0):
    """Contact samples at fs: a straight ramp rising ``rise_frac`` of its top (1) per sample, cut by a drop to 75 %
    of it ``drop_phase`` of a sample after the ramp's last sample, then a smooth hump to ``hump`` of the top; the
    true top is 1 (the pre-buckling spike of section 3.2.4 in Goodwill & Haake 2004, idealised)."""
    t = np.arange(int(round(3e-3 * fs))) / fs
    n_ramp = 6
    t_drop = (n_ramp + drop_phase) / fs
    ramp = np.maximum(1.0 - rise_frac * (t_drop - t) * fs, 0.0)
    after = 0.75 + (hump - 0.75) * np.sin(np.pi * np.clip((t - t_drop) / (t[-1] - t_drop), 0.0, 1.0))
    f = np.where(t <= t_drop, ramp, after)
    return f + np.random.default_rng(seed).normal(0.0, noise_frac, t.size)


def test_peak_between_samples_judges_the_range_of_the_lifted_top():
    from ballimpact.calibration import force_top
    from ballimpact.signal.peak import peak_between_samples

    # a straight ramp of 10.4 % of the top per sample cut by a drop, noise 0.35 % of the top: half a rise less
    # two noise deviations of a difference is 4.7 %, but force_top lifts the largest sample by half the last
    # rise (5.2 %) and its top may be off by that much: with the drop just after the last ramp sample, 5.1 % high
    fs, noise = 25e3, 3.5e-3
    x = _ramp_cut_by_a_drop(fs, 0.104, 0.01)
    top, _, half = force_top(np.arange(x.size) / fs, x, noise)
    assert_allclose(half, 0.052, rtol=1e-9)
    assert abs(top - 1.0) <= half + 1e-12  # the analytic top within the lifted top's half range
    assert top - 1.0 > 0.05  # what is at stake
    problems = peak_between_samples(x, fs, noise)
    assert [p.kind for p in problems] == [ProblemKind.PEAK_BETWEEN_SAMPLES], problems
    assert "may miss the peak by 5.2 %" in problems[0].message
    # an undone force's largest sample is not lifted: judged by half a rise, less the noise, as before
    assert peak_between_samples(x, fs, noise, lifted=False) == []


#: zoo trace 11:617's force (25.7 kHz, ideal plate, punctured ball), a fraction of its true peak, the sample before
#: the contact first: the jump's sample on the spike's ramp, a lower maximum after it, the top (1.0) between it and
#: the drop, and the smooth hump's largest sample at 92 %
_SPIKE_AFTER_THE_JUMP = [0.0, 0.757, 0.9066, 0.8525, 0.7614, 0.7922, 0.8136, 0.8297, 0.8431, 0.8542, 0.8637, 0.8734,
                         0.8822, 0.8898, 0.8976, 0.9039, 0.91, 0.9144, 0.9173, 0.9197, 0.9208, 0.9203, 0.9187, 0.9165]


@pytest.mark.parametrize("jump, spike, flagged", [
    (0.757, 0.9066, True),   # half the rise from the jump's sample (7.5 %) above it: 6.4 % above the largest sample
    (0.757, 0.80, False),    # a lower spike: half its rise (2.2 %) leaves it below the hump's top
    (None, 0.9066, False),   # the jump from zero straight to the maximum (no sample on the ramp before it)
    (0.15, 0.90, False),     # a jump spread over two samples, the first low: no ramp (PEAK_RAMP_FLOOR)
])
def test_peak_between_samples_sees_a_spike_on_the_jumps_next_sample(jump, spike, flagged):
    """A lower maximum after the jump from zero and one rise on the ramp may hide the spike's top between samples:
    zoo trace 11:617 (25.7 kHz) was ok with the peak 7.9 % low, its true top 8.6 % above the largest sample. Only
    where the jump's sample is already at half the peak: a jump the sensor chain spreads over two samples rises as
    steeply, and counted, it excluded 66 right traces of zoo seeds 0-14."""
    from ballimpact.signal.peak import peak_between_samples

    x = np.array(_SPIKE_AFTER_THE_JUMP)
    x[2] = spike
    if jump is None:
        x = np.delete(x, 1)  # 0 -> 0.9066 -> 0.8525: one rise, from zero
    else:
        x[1] = jump
    problems = peak_between_samples(x, 25.7e3, 2.7e-4, lifted=False)
    assert bool(problems) is flagged, problems
    if flagged:
        assert problems[0].kind is ProblemKind.PEAK_BETWEEN_SAMPLES
        assert "a sampled maximum of 98.5 % of the largest sample" in problems[0].message


@pytest.mark.parametrize("fs, plate_hz, zeta, ball, vin", [
    (23.9e3, None, 0.0, "pressurised", 29.3),
    (35.5e3, None, 0.0, "pressureless", 31.0),
    (35.5e3, 12.9e3, 0.29, "pressurised", 29.6),  # a swing of ringing on the ramp (bench/spike_top_map.py 1:299)
    (40.0e3, 18.0e3, 0.3, "pressureless", 25.0),  # (a plate's first overshoot of the jump: peak_on_first_overshoot)
])
def test_peak_between_samples_passes_only_a_top_known_to_5_percent(fs, plate_hz, zeta, ball, vin):
    from ballimpact.calibration import force_top
    from ballimpact.signal.peak import peak_between_samples

    # the model's force (its spike the peak) through a known plate at ten sample phases, noise 0.3 % of the
    # peak: where the check passes, the top that processing reports (force_top's on the sensed force) is within
    # 5 % of the model's peak
    for phase in np.linspace(0.05, 0.95, 10):
        sensed, true_peak = _plate_sensed_ball_force(fs, plate_hz, zeta, phase, ball, vin)
        noise = 3e-3 * true_peak
        x = sensed + np.random.default_rng(int(100 * phase)).normal(0.0, noise, sensed.size)
        xc = x[1:int(np.flatnonzero(sensed > 0.01 * true_peak)[-1]) + 1]
        if peak_between_samples(xc, fs, noise) == []:
            assert abs(force_top(np.arange(xc.size) / fs, xc, noise)[0] / true_peak - 1.0) <= 0.05, phase


@pytest.mark.parametrize("start_se, end_se, flags, named", [
    (0.001, 0.001, (), False),  # TC known to +-0.28 % (twice the root sum of squares): no problem
    (0.002, 0.004, (), False),  # +-0.89 %
    (0.001, 0.0048, (), False),  # +-0.98 %
    (0.001, 0.006, (), True),  # +-1.2 %: not determined to 1 %
    (0.001, math.inf, (), True),  # the hinge's window allows any corner
    (0.001, 0.006, ("end_jump",), False),  # a jump's half sample is CONTACT_JUMP_UNRESOLVED's to judge
    (0.001, math.nan, (), False),  # no fit
])
def test_hinge_problems_name_tc_not_known_to_one_percent(start_se, end_se, flags, named):
    """``_hinge_problems``: twice the root sum of squares of the ends' standard uncertainties above 1 % of TC (here
    TC is 1 s, so the uncertainties are fractions of it) names the end with the larger one."""
    from ballimpact.signal.end_checks import _hinge_problems
    from ballimpact.signal.contact import ContactResult

    c = ContactResult(found=True, start_s=1.0, end_s=2.0, edge_start_s=1.0, edge_end_s=2.0, start_index=1,
                      end_index=2, peak_index=1, peak_V=1.0, n_impacts=1, noise_rms_V=1e-3, threshold_V=8e-3,
                      clipped=False, flags=flags, start_se_s=start_se, end_se_s=end_se)
    problems = _hinge_problems(c)
    assert bool(problems) == named, problems
    if problems:
        assert problems[0].kind == ProblemKind.CONTACT_END_UNDETERMINED
        assert problems[0].message.startswith("contact end not determined to 1 %"), problems[0].message


@pytest.mark.parametrize("where, offset", [("start", 2), ("start", -3), ("end", -3), ("end", 3), (None, 0)])
def test_a_spike_on_the_smooth_force_near_a_contact_end_is_replaced_and_the_end_kept(where, offset):
    # an electrical spike of 1.5 V added at a known sample a few samples from an end, where this trace's force is
    # smooth (its cloth foot, its half-sine's fade) or the baseline: the neighbours continue one curve, so it is
    # electrical and replaced, and the impulse and TC are the clean trace's; a third into the contact likewise (2
    # before the end to 1 after it the half-sine's slope breaks off between the neighbours: kept and judged there)
    v, fs, truth = make_trace(tau_s=0.5, seed=3, **CHAIN)
    clean = condition_voltage(v, fs)
    at = {"start": truth.start_s, "end": truth.end_s, None: truth.start_s + 0.3 * truth.contact_time_s}[where]
    k = int(round(at * fs)) + offset
    spiky = v.copy()
    spiky[k] += 1.5
    c = condition_voltage(spiky, fs)
    assert k in c.spike_indices
    assert [p.message for p in c.problems if "spike" in p.message] == []
    assert_allclose(_impulse(c, truth), _impulse(clean, truth), rtol=2e-3)
    assert_allclose(c.contact.contact_time_s, clean.contact.contact_time_s, atol=0.5 / fs)


@pytest.mark.parametrize("flags, curve_se, said", [
    ((), math.nan, "the line through its last samples meets zero within +-12 us only"),
    (("end_curve",), 0.006, "the force's curve before it meets zero within +-12 us only"),
])
def test_hinge_problems_say_which_fit_gave_the_end(flags, curve_se, said):
    """``_hinge_problems`` names the fit that gave the end: an end from the force's curve (``end_curve``) is not "the
    line through its last samples" (TC 1 ms: an end uncertain by 6 us, +-12 us at twice it, is 1.2 % of TC)."""
    from ballimpact.signal.end_checks import _hinge_problems
    from ballimpact.signal.contact import ContactResult

    c = ContactResult(found=True, start_s=1.0, end_s=1.001, edge_start_s=1.0, edge_end_s=1.001, start_index=1,
                      end_index=2, peak_index=1, peak_V=1.0, n_impacts=1, noise_rms_V=1e-3, threshold_V=8e-3,
                      clipped=False, flags=flags, start_se_s=1e-7, end_se_s=6e-6, curve_end_se_s=curve_se * 1e-3)
    problems = _hinge_problems(c)
    assert len(problems) == 1 and said in problems[0].message, problems


# ------------------------------------------------------------------ a low-pass in the sensor chain (issue 9)


def _lowpassed_jump_trace(fs, fn_hz=None, zeta=0.71, jump=0.4, duration_s=4.0e-3, phase=0.3, noise_fraction=1e-3):
    """A force that jumps from zero to ``jump`` of its scale, humps as a half-sine and fades linearly to zero,
    through a unit-gain second-order low-pass of ``fn_hz`` and damping ``zeta`` (an amplifier's filter; None:
    none), integrated exactly on a grid of about 1 us that holds every sample (scipy's lsim, the force linear
    between its points), sampled at ``fs`` with white noise of ``noise_fraction`` of the scale: (voltage [V], TC [s])."""
    from scipy import signal

    m = int(math.ceil(1e6 / fs))
    n = int(round(0.04 * fs))
    t = np.arange(n * m) / (fs * m)
    start = (int(0.02 * fs) + phase) / fs
    u = (t - start) / duration_s
    force = np.where((u > 0) & (u < 1), jump * (1.0 - u) + np.sin(np.pi * u), 0.0)
    if fn_hz is not None:
        wn = 2.0 * math.pi * fn_hz
        force = signal.lsim(([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn]), force, t)[1]
    v = 2.0 * force[::m] + np.random.default_rng(int(fs) + int(100 * phase)).normal(0.0, 2.0 * noise_fraction, n)
    return v, duration_s


@pytest.mark.parametrize("fs, fn_hz, zeta", [(100e3, 4e3, 0.71), (50e3, 3e3, 0.87), (200e3, 6e3, 0.5)])
def test_jump_spread_by_a_low_pass_is_a_problem(fs, fn_hz, zeta):
    # a second-order Butterworth (0.71), a Bessel (0.87) and a less damped filter: each delays the force by
    # 2 zeta / wn (56, 92 and 27 us: 1.4, 2.3 and 0.66 % of TC), and the contact's end comes late by about that
    v, tc = _lowpassed_jump_trace(fs, fn_hz, zeta)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    delay = 2.0 * zeta / (2.0 * math.pi * fn_hz)
    assert c.contact.contact_time_s - tc > 0.6 * delay, (c.contact.contact_time_s - tc, delay)
    assert c.problems, "a TC long by the filter's delay passed"
    # the check itself (run last, when nothing else excludes the trace; here the end's curve may already have)
    from ballimpact.signal.shape import front_lowpass

    found = front_lowpass(c.voltage_V, fs, c.noise_rms_V, float(c.contact.peak_V), c.contact.start_s * fs,
                           c.contact.end_s * fs, c.contact.contact_time_s)
    assert len(found) == 1 and found[0].kind is ProblemKind.CONTACT_END_UNDETERMINED, found
    assert "as through a low-pass" in found[0].message
    said = float(re.search(r"delays the force by about (\S+) us", found[0].message).group(1)) * 1e-6
    assert 0.5 * delay < said < 2.0 * delay, (said, delay)


@pytest.mark.parametrize("fs", [25e3, 50e3, 100e3, 200e3])
@pytest.mark.parametrize("jump", [0.0, 0.4])
def test_force_through_no_low_pass_shows_none(fs, jump):
    # the same force through an ideal chain, wherever its start falls between two samples, and a force that
    # starts without a jump (its rise spread by the force itself, not by a filter)
    from ballimpact.signal.shape import front_lowpass

    for phase in (0.1, 0.5, 0.9):
        v, _ = _lowpassed_jump_trace(fs, None, jump=jump, phase=phase)
        c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
        assert not any("low-pass" in p.message for p in c.problems), (phase, [p.message for p in c.problems])
        assert front_lowpass(c.voltage_V, fs, c.noise_rms_V, float(c.contact.peak_V), c.contact.start_s * fs,
                              c.contact.end_s * fs, c.contact.contact_time_s) == [], phase


# ------------------------------------------------------------------ a coarse ADC (issue 9)


def _coarse_adc_trace(fs, bits, noise_V, seed, peak_V=0.5):
    """A force that jumps to a fifth of ``peak_V``, humps as a half-sine and fades linearly to zero over 4 ms
    (continuous at its end), 20 ms into a 60 ms record, with white noise of ``noise_V``, recorded by an ADC of
    ``bits`` over +-10 V: (recorded voltage [V], its step [V], TC [s])."""
    step = 20.0 / 2**bits
    t = np.arange(int(0.06 * fs)) / fs
    u = (t - (int(0.02 * fs) + 0.3) / fs) / 4.0e-3
    force = np.where((u > 0) & (u < 1), 0.2 * (1.0 - u) + 0.8 * np.sin(np.pi * u), 0.0)
    v = peak_V * force + 0.013 + np.random.default_rng(seed).normal(0.0, noise_V, t.size)
    return -10.0 + np.round((v + 10.0) / step) * step, step, 4.0e-3


@pytest.mark.parametrize("fs, seed", [(50e3, 0), (100e3, 1), (137e3, 2), (33e3, 3)])
def test_a_coarse_adc_is_judged_by_its_step(fs, seed):
    # 12 bits (a step of 4.9 mV) under 0.08 mV of noise: the quiet record moves in whole steps and holds almost no
    # noise; its noise is taken as the step's error, step / sqrt(12), and the contact is right or excluded
    v, step, tc = _coarse_adc_trace(fs, 12, 8e-5, seed)
    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    assert c.noise_rms_V >= step / math.sqrt(12.0) * (1.0 - 1e-9)
    if not c.problems:
        assert_allclose(c.contact.contact_time_s, tc, rtol=0.01)


def test_a_fine_adc_leaves_the_noise_as_measured():
    # 16 bits (0.31 mV) under 1 mV of noise: the noise dithers the step, and is measured as it is
    v, step, _ = _coarse_adc_trace(50e3, 16, 1e-3, 4, peak_V=3.0)
    c = condition_voltage(v, 50e3, mains_hz=None, tau_s=math.inf)
    assert_allclose(c.noise_rms_V, math.sqrt(1e-6 + step * step / 12.0), rtol=0.1)


def _staircase_trace(fs, bits, noise_V, seed, tail_s, level_V=5e-3):
    """A half-sine of 0.5 V over 4 ms that, where it has fallen to ``level_V``, fades linearly to zero over
    ``tail_s`` instead (0: it ends as the half-sine does), 20 ms into a 60 ms record, white noise of ``noise_V``,
    recorded by an ADC of ``bits`` over +-10 V: recorded voltage [V]."""
    step = 20.0 / 2**bits
    t = np.arange(int(0.06 * fs)) / fs
    u = (t - (int(0.02 * fs) + 0.4) / fs) / 4.0e-3
    force = np.where((u > 0) & (u < 1), 0.5 * np.sin(np.pi * u), 0.0)
    if tail_s > 0:
        cut = 1.0 - math.asin(level_V / 0.5) / math.pi
        tail = np.clip(1.0 - (u - cut) * 4.0e-3 / tail_s, 0.0, 1.0)
        force = np.where(u >= cut, level_V * tail, force)
    v = force + 0.011 + np.random.default_rng(seed).normal(0.0, noise_V, t.size)
    return -10.0 + np.round((v + 10.0) / step) * step


def _staircase_check(v, fs):
    from ballimpact.signal.end_checks import adc_step_problems
    from ballimpact.signal.noise import quantization_step

    c = condition_voltage(v, fs, mains_hz=None, tau_s=math.inf)
    scale = float(np.max(np.abs(v)))
    return c, adc_step_problems(c.voltage_V / scale, fs, c.noise_rms_V / scale, quantization_step(v) / scale,
                                 c.contact, 0.0, scale)


@pytest.mark.parametrize("fs, seed", [(50e3, 0), (120e3, 1)])
def test_an_end_read_off_a_staircase_is_a_problem(fs, seed):
    # a slow fade at the end (from 5 mV, about one 12-bit step, to zero over 0.3 ms: 7 % of TC to cross a step)
    # under 0.1 mV of noise: the end is read off the ADC's staircase
    v = _staircase_trace(fs, 12, 1e-4, seed, 0.3e-3)
    c, found = _staircase_check(v, fs)
    assert c.problems
    assert [p.kind for p in found] == [ProblemKind.CONTACT_END_UNDETERMINED]
    assert "contact end not determined to 1 %" in found[0].message and "staircase" in found[0].message


@pytest.mark.parametrize("bits, noise, tail_s", [(16, 1e-3, 0.3e-3), (12, 1e-4, 0.0), (12, 4e-3, 0.3e-3)])
def test_a_dithered_step_or_a_steep_end_is_no_staircase(bits, noise, tail_s):
    # the same fade under noise that dithers the step (16 bits under 1 mV; 12 bits under 4 mV), or no slow fade: the
    # half-sine's own end crosses a 12-bit step in about 12 us (0.3 % of TC)
    v = _staircase_trace(50e3, bits, noise, 3, tail_s)
    _, found = _staircase_check(v, 50e3)
    assert found == []


# ------------------------------------------------------------------ a step in the baseline (issue 9)

def _with_step(v, fs, truth, at_s, height_V):
    """The trace ``v`` with its level shifted by ``height_V`` from ``at_s`` on (a DAQ's offset changing) [V]."""
    out = np.array(v, dtype=float)
    out[int(np.searchsorted(truth.time_s, at_s)):] += height_V
    return out


def _step_problems(c):
    return [p for p in c.problems if p.kind is ProblemKind.BASELINE_STEP]


@pytest.mark.parametrize("where, tau_given", [
    ("before", False),  # in the pre-trigger, 10 ms before the contact: the scan of instants
    ("after", False),  # 12 ms after the end, in the quiet record the decay is fitted on
    ("inside", True),  # within the contact with the time constant given: the levels either side differ
])
@pytest.mark.parametrize("seed", range(2))
def test_step_in_the_baseline_is_a_problem_naming_its_size(where, tau_given, seed):
    """A shift of 0.3 % of the peak (7.5 noise deviations) is named with its sign and where; without it, no problem."""
    v, fs, truth = make_trace(tau_s=0.5, seed=seed, **CHAIN)
    at_s = {"before": truth.start_s - 10e-3, "after": truth.end_s + 12e-3,
            "inside": 0.5 * (truth.start_s + truth.end_s)}[where]
    height = -0.003 * truth.peak_V
    tau = 0.5 if tau_given else None
    clean = condition_voltage(v, fs, tau_s=tau)
    assert not _step_problems(clean), [p.message for p in clean.problems]
    stepped = condition_voltage(_with_step(v, fs, truth, at_s, height), fs, tau_s=tau)
    found = _step_problems(stepped)
    assert len(found) == 1, [p.message for p in stepped.problems]
    shift_mV = float(re.search(r"shifts by (\S+) mV", found[0].message).group(1))
    # the residual's shift: the baseline fit's drift has taken up part of the step
    assert 0.4 <= shift_mV / (1e3 * height) <= 1.3, found[0].message
    first, last = (float(x) for x in re.search(r"between (\S+) and (\S+) ms", found[0].message).groups())
    assert first - 1.0 <= 1e3 * at_s <= last + 1.0, found[0].message


@pytest.mark.parametrize("where, height", [("before", -0.003), ("after", 0.002), ("before", 0.001)])
@pytest.mark.parametrize("seed", (0, 2, 3, 4))
def test_a_step_in_the_baseline_is_judged_by_the_level_it_can_leave_under_the_contact(where, height, seed):
    """A step's finding bounds what it does to TC: the contact found on the stepped trace moves from the true
    contact's length by no more than its estimated effect (signal.effects.level_effects of the step's size), and
    a step of 0.1 % of the peak leaves TC within its tolerance (no longer withheld for being seen). The
    amplifier's time constant is given: an estimated decay takes up a step next to the contact, and its effect is
    not known then (the last case). (Seed 1's end is read on a tail that falls slower than such a level over
    END_SLOPE_S: its effect is not known there.)"""
    from ballimpact.signal.effects import finding_effects
    v, fs, truth = make_trace(tau_s=0.5, seed=seed, **CHAIN)
    at_s = {"before": truth.start_s - 10e-3, "after": truth.end_s + 12e-3}[where]
    c = condition_voltage(_with_step(v, fs, truth, at_s, height * truth.peak_V), fs, tau_s=0.5)
    found = _step_problems(c)
    assert len(found) == 1, [p.message for p in c.problems]
    t0 = float(truth.time_s[0])
    s_u, e_u = (c.contact.start_s - t0) * fs, (c.contact.end_s - t0) * fs
    effects = finding_effects(found[0], c.problems, c.voltage_V, fs, s_u, e_u, c.noise_rms_V).effects
    assert all(math.isfinite(effects[q]) for q in ("contact_time", "kcal", "peak")), effects
    tc_error = abs(c.contact.contact_time_s / truth.contact_time_s - 1.0)
    assert tc_error <= effects["contact_time"] + 2.0 / (fs * truth.contact_time_s), (tc_error, effects)
    assert_allclose(effects["peak"], abs(height), rtol=0.7)
    if abs(height) <= 0.001:
        assert 2.0 * effects["contact_time"] / math.sqrt(3.0) < 0.01, effects
    estimated = condition_voltage(_with_step(v, fs, truth, at_s, height * truth.peak_V), fs)
    for p in _step_problems(estimated):
        assert not finding_effects(p, estimated.problems, estimated.voltage_V, fs, s_u, e_u, c.noise_rms_V).effects


def test_step_check_passes_bursts_spikes_and_a_step_within_the_noise():
    """The fits on residuals clipped at 5 noise deviations pass a burst of 5 samples of 30 noise deviations in the
    quiet record; a shift of 0.02 % of the peak (below BASELINE_STEP_FRACTION) is not a problem however many
    standard errors it is."""
    v, fs, truth = make_trace(tau_s=0.5, seed=3, **CHAIN)
    burst = np.array(v, dtype=float)
    k = int(np.searchsorted(truth.time_s, truth.start_s - 8e-3))
    burst[k:k + 5] += 30 * CHAIN["noise_V"] * np.array([1, -1, 1, -1, 1])
    assert not _step_problems(condition_voltage(burst, fs))
    small = _with_step(v, fs, truth, truth.start_s - 10e-3, 0.0002 * truth.peak_V)
    assert not _step_problems(condition_voltage(small, fs))


def test_step_within_the_contact_with_the_decay_estimated_is_taken_for_the_decay():
    """Documented limit: with the time constant estimated, a shift within the contact is what an amplifier's undershoot
    looks like to the fit (kappa takes it up); the step check cannot see it, and plate.time_constant_s can."""
    v, fs, truth = make_trace(tau_s=None, seed=1, **CHAIN)
    stepped = _with_step(v, fs, truth, 0.5 * (truth.start_s + truth.end_s), -0.01 * truth.peak_V)
    assert not _step_problems(condition_voltage(stepped, fs))
    assert _step_problems(condition_voltage(stepped, fs, tau_s=math.inf))


@pytest.mark.parametrize("seed", range(2))
def test_step_just_after_the_contact_taken_for_the_decay_leaves_a_plateau_that_is_a_problem(seed):
    """A step down of 3 % of the peak 1.5 ms after the end, the decay estimated: kappa takes it for the undershoot, and
    the correction lifts the 1.5 ms before it into a shelf of force; the contact's end on that plateau is a problem.
    Without the step, or with the time constant given (the step then seen as one), no plateau."""
    v, fs, truth = make_trace(tau_s=None, seed=seed, **CHAIN)
    plateau = re.compile("force is flat over the last")
    clean = condition_voltage(v, fs)
    assert not [p for p in clean.problems if plateau.search(p.message)]
    stepped = _with_step(v, fs, truth, truth.end_s + 1.5e-3, -0.03 * truth.peak_V)
    c = condition_voltage(stepped, fs)
    found = [p for p in c.problems if plateau.search(p.message)]
    assert found and found[0].kind is ProblemKind.CONTACT_END_UNDETERMINED, [p.message for p in c.problems]
    given = condition_voltage(stepped, fs, tau_s=math.inf)
    assert _step_problems(given) or any(p.kind is ProblemKind.BASELINE_OFF_ZERO for p in given.problems)


@pytest.mark.parametrize("seed", range(3))
def test_a_contact_found_only_after_a_baseline_through_it_is_unchecked_and_a_problem(seed):
    """A flat top (a saturated stage) under a 1 ms pre-trigger with its largest sample at the top's end: the record's
    level before that sample is the top's, nothing stands out of it, and the contact shows only once a baseline
    is fitted through the whole record, its own samples included. No check ran on it: that is a problem (it was
    none, and bench/saturation_map.py trace 2:320 came out ok with TC -19 % and kCAL +100 %)."""
    fs = 50e3
    v = np.concatenate([np.zeros(50), np.linspace(0.0, 2.0, 16)[1:], np.full(150, 2.0), np.linspace(2.0, 0.0, 16)[1:],
                        np.zeros(2000)])
    v = v + np.random.default_rng(seed).normal(0.0, 1e-3, v.size)
    v[50 + 15 + 149] += 0.01  # the largest sample at the top's end
    cond = condition_voltage(v, fs, polarity=1, mains_hz=None, tau_s=math.inf)
    assert cond.contact.found and cond.n_iterations == 0
    unstable = [p for p in cond.problems if p.kind is ProblemKind.CONTACT_UNSTABLE]
    assert unstable and "baseline under the contact is unknown" in unstable[0].message


@pytest.mark.parametrize("seed", range(4))
def test_kappa_refinement_slope_and_least_match_finite_differences_and_a_scan(seed):
    """The residual's first and second derivatives in kappa (Newton's refinement of the decay rate) against central
    differences of the residual itself, and the refined kappa against a fine scan of the residual."""
    from ballimpact.signal.baseline import _normal_equations, _refine_kappa, _rss_slope, _solve_kappa

    rng = np.random.default_rng(seed)
    n, p = 400, 4
    phi = rng.standard_normal((n, p))
    big_phi = np.cumsum(rng.standard_normal((n, p)), axis=0) / n
    iv = np.cumsum(rng.standard_normal(n)) / n
    y = phi @ rng.standard_normal(p) - 3.0 * (iv - big_phi @ rng.standard_normal(p)) + 0.1 * rng.standard_normal(n)
    ne = _normal_equations(phi, big_phi, y, iv, np.ones(n, dtype=bool))
    for k in (-2.0, 0.5, 3.0):
        h = 1e-4
        r = _solve_kappa(ne, np.array([k - h, k, k + h]))[0]
        d1, d2 = _rss_slope(ne, k)
        assert_allclose(d1, (r[2] - r[0]) / (2 * h), rtol=1e-5, atol=1e-9)
        assert_allclose(d2, (r[2] - 2 * r[1] + r[0]) / h ** 2, rtol=1e-4)
    scan = np.linspace(-20.0, 20.0, 400001)
    least = scan[int(np.argmin(_solve_kappa(ne, scan)[0]))]
    k = _refine_kappa(ne, least - 0.5, least + 0.5, least - 0.3, 1e-10)
    assert_allclose(k, least, atol=1e-4)
    assert abs(_rss_slope(ne, k)[0]) < 1e-9 * max(1.0, abs(_rss_slope(ne, least - 0.5)[0]))
    # a bracket the least is not in: its bound nearer the least, where the residual is least within it
    assert _refine_kappa(ne, least + 0.5, least + 1.0, least + 0.7, 1e-10) == least + 0.5
    assert _refine_kappa(ne, least - 1.0, least - 0.5, least - 0.7, 1e-10) == least - 0.5


@pytest.mark.parametrize("seed", range(3))
def test_correlation_factor_is_one_for_white_residuals_and_large_for_unmodelled_hum(seed):
    """kappa's standard error is widened by the scores' long-run variance over their white variance: about 1 for
    white residuals (never below), near the window's length for a hum the model left out (correlated over it)."""
    from ballimpact.signal.baseline import _correlation_factor

    rng = np.random.default_rng(seed)
    fs, n, lag = 66964.3, 4000, 134
    t = np.arange(n) / fs
    x = np.column_stack([np.ones(n), t - t.mean()])
    d = np.cumsum(np.exp(-t / 0.01)) / fs  # a running integral, as kappa's column is
    white = _correlation_factor(x, d, 1e-3 * rng.standard_normal(n), lag)
    assert 1.0 <= white < 1.3
    hum = 1e-3 * np.sin(2 * np.pi * 50.0 * t + rng.uniform(0, 2 * np.pi)) + 1e-5 * rng.standard_normal(n)
    assert _correlation_factor(x, d, hum, lag) > 0.5 * (lag + 1)
    assert _correlation_factor(x, d, np.zeros(n), lag) == 1.0
    assert _correlation_factor(x[:2], d[:2], np.ones(2), lag) == 1.0


@pytest.mark.parametrize("tau_s, mains", [(None, [50.0, 100.0, 150.0]), (0.5, []), (None, [])])
def test_baseline_fit_cache_returns_the_fit_of_the_same_quiet_samples(tau_s, mains):
    """The iteration's fit cache: a window moved by a fraction of a sample keeps its quiet samples and gets the
    same fit back; one moved by samples gets a new fit; each is the fit made without the cache."""
    from ballimpact.signal.baseline import fit_baseline

    v, fs, truth = make_trace(tau_s=2.0, hum_V=0.01, noise_V=0.001, offset_V=0.02, seed=7)
    s_u, e_u = truth.start_s * fs, truth.end_s * fs
    guards = (0.5e-3 * fs, 1.0e-3 * fs)
    kappa = None if tau_s is None else 1.0 / tau_s
    cache: dict = {}

    def fit(a, b, use_cache=True):
        return fit_baseline(v, fs, mains, a, b, *guards, None, True, kappa, cache=cache if use_cache else None)

    first = fit(s_u, e_u)
    # the quiet stretches start and end at whole samples: a move of 0.02 samples that crosses none of the
    # boundaries gives the same samples
    a, b = math.floor(s_u) + 0.3, math.floor(e_u) + 0.3
    assert fit(a, b) is fit(a + 0.02, b + 0.02)
    moved = fit(s_u + 3.0, e_u + 3.0)
    assert moved is not first
    for (x, y), cached in [((s_u, e_u), first), ((s_u + 3.0, e_u + 3.0), moved)]:
        fresh = fit(x, y, use_cache=False)
        assert_allclose(cached.baseline, fresh.baseline, rtol=0, atol=0)
        assert repr(cached.coef) == repr(fresh.coef)


def _sensed_through_plate(force, fs_fine, fs, fn, zeta):
    """A force on a fine grid [N] as a plate of resonance fn [Hz] and damping ratio zeta senses it, sampled at fs."""
    from scipy.signal import lsim

    wn = 2 * math.pi * fn
    t = np.arange(force.size) / fs_fine
    _, out, _ = lsim(([wn * wn], [1.0, 2 * zeta * wn, wn * wn]), force, t)
    step = int(round(fs_fine / fs))
    return out[::step]


@pytest.mark.parametrize("spike, flagged", [(0.0, False), (1.0, True)])
def test_undone_peak_spread_flags_a_spike_built_by_the_damping_term(spike, flagged):
    """The undone peak's dependence on the plate's damping ratio: a smooth half-sine's top (slope zero there) barely
    moves with it; a narrow spike's peak, undone from a heavily damped 4 kHz plate, is built by the damping term
    (2 zeta / wn) x' and moves by several per cent with the ratio 25 % off (zoo trace 7:265: -9.2 %)."""
    from ballimpact.signal.undone import PLATE_PEAK_SPREAD, undone_peak_spread
    from ballimpact.signal.contact import ContactResult
    from ballimpact.signal.plate import PlateResonance

    fs_fine, fs, fn, zeta = 2.0e6, 50.0e3, 4000.0, 0.25
    t = np.arange(int(0.012 * fs_fine)) / fs_fine
    t0, tc = 0.004, 0.004
    inside = (t >= t0) & (t <= t0 + tc)
    force = np.where(inside, np.sin(np.pi * (t - t0) / tc), 0.0)
    force += spike * np.exp(-0.5 * ((t - t0 - 0.3e-3) / 40e-6) ** 2)  # a pre-buckling spike, 0.1 ms wide, the peak
    x = _sensed_through_plate(force, fs_fine, fs, fn, zeta)
    wn = 2 * math.pi * fn
    pole = np.exp(complex(-zeta * wn, wn * math.sqrt(1 - zeta * zeta)) / fs)
    plate = PlateResonance(fn, zeta, 2 * pole.real, -abs(pole) ** 2)
    contact = ContactResult(found=True, start_s=t0, end_s=t0 + tc, edge_start_s=t0, edge_end_s=t0 + tc,
                            start_index=int(t0 * fs), end_index=int((t0 + tc) * fs), peak_index=0, peak_V=1.0,
                            n_impacts=1, noise_rms_V=1e-4, threshold_V=1e-3, clipped=False, flags=())
    problems = undone_peak_spread(x, fs, contact, plate, math.inf, 0.0)
    assert bool(problems) is flagged
    if flagged:
        assert problems[0].kind is ProblemKind.PEAK_ON_RINGING
        assert re.search(r"the peak moves by [\d.]+ % with the damping ratio 25 % off", problems[0].message)
    assert PLATE_PEAK_SPREAD == 0.015  # half the peak's 3 % tolerance (the docstring's reading)


def _spike_then_hump(fs, spike_top, hump_top, t0=0.004, tc=0.004, rise=0.12e-3):
    """A ball-like force sampled at fs [Hz]: a ramp from the contact's jump to the pre-buckling spike's top at
    ``rise`` [s], a sudden drop at buckling, then a smooth hump (half-sine) of ``hump_top`` (section 3.2.4 in
    Goodwill & Haake 2004); the contact from t0 to t0 + tc [s]."""
    t = np.arange(int(0.012 * fs)) / fs
    u = t - t0
    inside = (u >= 0) & (u <= tc)
    hump = hump_top * np.sin(np.pi * np.clip(u, 0, tc) / tc)
    ramp = np.where((u >= 0) & (u < rise), 0.3 * spike_top + 0.7 * spike_top * u / rise, 0.0)
    return np.where(inside, np.maximum(hump, ramp), 0.0), t0, tc


@pytest.mark.parametrize("spike_top, hump_top, cutoff_hz, flagged", [
    (1.0, 0.8, 12e3, True),        # the spike is the peak, low-passed: its top lowered by the kernel
    (1.0, 0.8, math.inf, False),   # the same spike, exact: the other checks judge its top
    (0.0, 1.0, 12e3, False),       # no spike: the smooth hump's top is the peak
    (0.8, 1.0, 12e3, False),       # a spike well below the hump (< LOWPASS_SPIKE_FRACTION of the peak)
])
def test_lowpassed_spike_is_not_a_known_peak(spike_top, hump_top, cutoff_hz, flagged):
    """A low-passed undone force whose maximum in the spike's phase is near its peak does not report that peak:
    the kernel lowers a ramp cut by a drop by an amount the samples cannot bound (zoo traces 11:784, 13:41,
    14:1538, 14:1632: 5.2-6.3 % low)."""
    from ballimpact.signal.undone import LOWPASS_SPIKE_FRACTION, lowpassed_spike
    from ballimpact.signal.contact import ContactResult
    from ballimpact.signal.plate import PlateResonance
    from ballimpact.signal.undo import lowpass_zero_phase

    fs = 100e3
    force, t0, tc = _spike_then_hump(fs, spike_top, hump_top)
    y = force if math.isinf(cutoff_hz) else lowpass_zero_phase(force, fs, cutoff_hz)
    if flagged:  # the physics the check rests on: the kernel takes more than a per cent off the spike's top
        assert np.max(y) < 0.99 * np.max(force)
    contact = ContactResult(found=True, start_s=t0, end_s=t0 + tc, edge_start_s=t0, edge_end_s=t0 + tc,
                            start_index=int(t0 * fs), end_index=int((t0 + tc) * fs), peak_index=0,
                            peak_V=float(np.max(y)), n_impacts=1, noise_rms_V=1e-4, threshold_V=1e-3, clipped=False,
                            flags=())
    problems = lowpassed_spike(y, fs, contact, PlateResonance(8000.0, 0.05, 0.0, 0.0), cutoff_hz, 0.0)
    assert bool(problems) is flagged
    if flagged:
        assert problems[0].kind is ProblemKind.PEAK_ON_RINGING
        assert re.search(r"low-passed at 12 kHz, the force's maximum [\d.]+ ms into the contact", problems[0].message)
    assert LOWPASS_SPIKE_FRACTION == 0.9


@pytest.mark.parametrize("tail_s, where, flagged", [
    (0.5e-3, "start", True),    # the fall of an impact the trigger came late for
    (0.0, "start", False),      # a quiet record's start
    (2 / 50e3, "start", False),  # two samples: shorter than EDGE_EVENT_MIN_S (a spike the spike check cannot reach)
    (0.5e-3, "end", False),     # after the contact the decay's correction wanders: not looked at
])
def test_edge_event_at_the_record_start_is_an_impact_cut_off(tail_s, where, flagged):
    from ballimpact.signal.integrity import edge_event_problems

    fs, noise, peak = 50e3, 1e-3, 1.0
    rng = np.random.default_rng(3)
    x = rng.normal(0.0, noise, int(0.03 * fs))
    t = np.arange(x.size) / fs
    s_u, e_u = 0.010 * fs, 0.014 * fs
    x += np.where((t >= 0.010) & (t <= 0.014), peak * np.sin(np.pi * (t - 0.010) / 0.004), 0.0)
    n_tail = int(round(tail_s * fs))
    fall = 0.02 * peak * np.linspace(1.0, 0.0, n_tail, endpoint=False)  # 2 % of the peak, falling to zero
    if where == "start":
        x[:n_tail] += fall
    else:
        x[x.size - n_tail:] += fall[::-1]
    problems = edge_event_problems(x, fs, noise, peak, s_u, 1.0)
    assert bool(problems) is flagged
    if flagged:
        assert problems[0].kind is ProblemKind.MULTIPLE_IMPACTS
        assert re.match(r"more than one impact in the trace: force at the record's start, [\d.]+ ms",
                        problems[0].message)


@pytest.mark.parametrize("shape, flagged", [
    ("rise", True),           # another impact's start, 0.1 ms of it rising to 5 % of the peak at the last sample
    ("fall", False),          # the same stretch falling at the end: its largest sample is not the last
    ("wander", False),        # a slow rise over 10 ms (longer than the contact): the decay's correction wandering
    ("quiet", False),         # a quiet record's end
    ("short", False),         # two samples: shorter than EDGE_EVENT_MIN_S
])
def test_end_event_rising_at_the_record_end_is_an_impact_cut_off(shape, flagged):
    """Force rising to the record's last sample, after a quiet stretch, no longer than the contact: another impact
    the record cut off (zoo trace 19:218, a faulty trace ok)."""
    from ballimpact.signal.integrity import end_event_problems

    fs, noise, peak = 50e3, 1e-3, 1.0
    x = np.random.default_rng(3).normal(0.0, noise, int(0.03 * fs))
    t = np.arange(x.size) / fs
    s_u, e_u = 0.005 * fs, 0.009 * fs
    x += np.where((t >= 0.005) & (t <= 0.009), peak * np.sin(np.pi * (t - 0.005) / 0.004), 0.0)
    n = {"rise": 5, "fall": 5, "wander": 500, "quiet": 0, "short": 2}[shape]
    ramp = 0.05 * peak * np.linspace(0.0, 1.0, n + 1)[1:]
    if shape == "fall":
        ramp = ramp[::-1]
    if n:
        x[x.size - n:] += ramp
    problems = end_event_problems(x, fs, noise, peak, e_u, e_u - s_u, 1.0)
    assert bool(problems) is flagged, problems
    if flagged:
        assert problems[0].kind is ProblemKind.MULTIPLE_IMPACTS
        assert re.match(r"more than one impact in the trace: force rising at the record's end, [\d.]+ ms",
                        problems[0].message)


@pytest.mark.parametrize("hum_V, flagged", [(0.03, False), (3.0, True)])
def test_baseline_bend_under_the_contact_beyond_a_tenth_of_the_peak(hum_V, flagged):
    """A 60 Hz hum of tens of mV bends the baseline under a 4 ms contact by a few mV; one fitted at volts (an
    unpinned fit, zoo trace 11:342) by more than a tenth of a 1 V peak."""
    from types import SimpleNamespace

    from ballimpact.signal.integrity import baseline_bend_problems

    fs = 50e3
    t = np.arange(int(0.03 * fs)) / fs
    fit = SimpleNamespace(baseline=hum_V * np.sin(2 * np.pi * 60.0 * t + 0.3), hum_amplitudes=(hum_V,))
    problems = baseline_bend_problems(fit, 1.0, 0.010 * fs, 0.014 * fs, 1.0)
    assert bool(problems) is flagged
    if flagged:
        assert problems[0].kind is ProblemKind.MAINS_UNRESOLVED
        assert problems[0].message.startswith("mains hum not resolved: the fitted baseline bends by")


@pytest.mark.parametrize("height, masked", [(0.013, True), (0.007, True), (0.004, False)])
def test_event_mask_takes_a_second_contact_with_its_shoulders(height, masked):
    """A second contact standing out as an event is left out of the baseline fit from where it rises out of the
    noise to where it falls back, with the guards beyond: its shoulders, left in the fit of a short record with
    hum, bent the hum under the contact (zoo trace 25:1094, 1.3 % of the peak, kCAL +1.2 %)."""
    from ballimpact.signal.window import EVENT_GUARD_AFTER_S, EVENT_GUARD_BEFORE_S, EVENT_SHOULDER_SIGMA, _event_mask
    from ballimpact.signal.contact import ContactResult

    fs, noise, peak = 100e3, 1e-4, 1.0
    t = np.arange(int(0.04 * fs)) / fs
    x = np.random.default_rng(11).normal(0.0, noise, t.size)
    t0, tc = 0.005, 0.004
    x += np.where((t >= t0) & (t <= t0 + tc), peak * np.sin(np.pi * (t - t0) / tc), 0.0)
    s0, d = 0.020, 0.006  # a broad second pulse: 6 ms, its shoulders far beyond the half-millisecond guard
    pulse = np.where((t >= s0) & (t <= s0 + d), height * peak * np.sin(np.pi * (t - s0) / d) ** 2, 0.0)
    x += pulse
    contact = ContactResult(found=True, start_s=t0, end_s=t0 + tc, edge_start_s=t0, edge_end_s=t0 + tc,
                            start_index=int(t0 * fs), end_index=int((t0 + tc) * fs), peak_index=int((t0 + tc / 2) * fs),
                            peak_V=peak, n_impacts=1, noise_rms_V=noise, threshold_V=0.03, clipped=False, flags=())
    mask = _event_mask(x, fs, noise, contact, 0.5e-3 * fs, 2e-3 * fs)
    out = np.flatnonzero(pulse > EVENT_SHOULDER_SIGMA * noise + 5 * noise)  # the pulse well out of the noise
    assert bool(mask[out].all()) is masked
    if masked:  # and no further than its shoulders and the guards
        held = np.flatnonzero(mask)
        assert t[held[0]] >= s0 - EVENT_GUARD_BEFORE_S - 2 / fs
        assert t[held[-1]] <= s0 + d + EVENT_GUARD_AFTER_S + 2 / fs
    else:
        assert not mask.any()


@pytest.mark.parametrize("second, n_fall, kinds", [
    # zoo trace 33:674: a 1.5 V electrical spike on the jump's second sample, the peak +32 %; its excess over its
    # neighbours' mean (1.58 V) is 0.7 % of the impulse: kCAL in doubt too
    (2.78, 120, [ProblemKind.PEAK_BETWEEN_SAMPLES, ProblemKind.IMPULSE_UNRESOLVED]),
    (2.78, 600, [ProblemKind.PEAK_BETWEEN_SAMPLES]),  # a longer contact: 0.2 % of its impulse, the peak alone
    (2.11, 120, []),   # 1 % above the ball's top (2.09 V): within PEAK_ALONE_FRACTION
    (1.30, 120, []),   # the jump's second sample on the way up: the ball's top later is the largest sample
])
def test_peak_between_samples_sees_a_single_sample_top_on_the_jump(second, n_fall, kinds):
    """The largest sample second in the jump from zero, standing alone above every other sample, is a single-sample
    top: the ball's spike with its ramp unsampled or an electrical spike riding on the jump (whose second differences
    there have no isolated spike's shape, so remove_spikes leaves it). Zoo trace 33:674 (50.7 kHz, ideal plate) was
    ok with such a spike taken for the peak, +32 %. Were it electrical, its excess is in the impulse as well."""
    from ballimpact.signal.peak import PEAK_ALONE_FRACTION, peak_between_samples
    from ballimpact.signal.spikes import SPIKE_END_IMPULSE

    # 33:674's front [V]: the sample before the contact, the jump's first sample (part-way), its second, and the
    # oversize ball's force after it: a jump to 1.43 V and a ramp to its top of 2.09 V at 1.05 ms, then the fall
    fs = 50.65e3
    x = np.concatenate([[0.005, 0.97, second], np.linspace(1.43, 2.09, 53), np.linspace(2.09, 0.05, n_fall)[1:]])
    problems = peak_between_samples(x, fs, 4.6e-3)
    assert [p.kind for p in problems] == kinds, problems
    if kinds:
        assert "the largest sample stands alone" in problems[0].message
        assert "rises from a sample at 35 % of it" in problems[0].message
        # the excess over every other sample, in per cent of the largest: (2.78 - 2.09) / 2.78
        assert_allclose(float(re.search(r"stands (\S+) % of it above", problems[0].message).group(1)),
                        100 * (2.78 - 2.09) / 2.78, atol=0.5)
        excess = (second - 0.5 * (0.97 + 1.43)) / np.sum(x[1:])
        assert bool(excess > SPIKE_END_IMPULSE) is (len(kinds) == 2)  # the two contacts either side of the bound
        if len(kinds) == 2:
            assert_allclose(float(re.search(r"impulse would be (\S+) % off", problems[1].message).group(1)),
                            100 * excess, rtol=0.02)
    assert 100 * (2.11 - 2.09) / 2.11 < 100 * PEAK_ALONE_FRACTION  # the third case is below the bound


def _front_33_674(first=0.97, second=1.27, third=1.43, n_fall=120):
    """Held-out zoo trace 33:674's front [V] after 20 quiet samples: the jump's first sample (part-way), the
    oversize ball's ramp to its top of 2.09 V, its fall; the contact starts at sample 19.5."""
    return np.concatenate([np.zeros(20), [first, second, third], np.linspace(1.57, 2.09, 50),
                           np.linspace(2.09, 0.05, n_fall)[1:]])


@pytest.mark.parametrize("second, start_u, flagged", [
    (-0.23, 19.5, True),   # a -1.5 V spike on the jump's second sample, the start found before the jump
    (-0.23, 21.5, True),   # ... or after the dip (the start found on the force's far side of it)
    (1.27, 19.5, False),   # the ball's front: no sample back near zero
    (0.60, 19.5, False),   # a dip to 29 % of the peak: a ball's buckling drops as far
])
def test_front_dip_names_a_sample_back_at_zero_after_the_jump(second, start_u, flagged):
    """No ball's force returns to zero after its jump before it leaves (section 3.2.4 in Goodwill & Haake 2004):
    a sample of the front back near zero is a negative electrical spike or a plate's swing, and the start is not
    known (zoo trace 33:674's rig with a -1.5 V spike there: ok, TC -1.2 %)."""
    from ballimpact.signal.peak import front_dip

    x = _front_33_674(second=second)
    problems = front_dip(x, 50.65e3, 2.09, start_u, x.size - 2.0)
    assert [p.kind for p in problems] == ([ProblemKind.CONTACT_END_UNDETERMINED] if flagged else []), problems
    if flagged:
        assert problems[0].message.startswith("contact start not determined")
        assert "falls back to -11 % of the peak" in problems[0].message
