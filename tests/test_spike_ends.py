"""Single-sample spikes at a contact's ends (issue 9): the force's own sample at its jump, or an electrical spike.

An analytic force sampled at 50 kHz, as the zoo's model force is at its start (tests/zoo.py; zoo traces 0:1635 and
1:1331): it jumps from zero (section 3.2.4 in Goodwill & Haake 2004), its first sample falls on the jump's ramp, its
second on the ball's pre-buckling spike (shorter than a sample at 12 m/s), its third after the drop at buckling; then
a half-sine to zero. On a DC-coupled amplifier without hum, so the conditioned voltage is the force's.
"""

import math
import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ballimpact.signal.spikes import _spike_kink, remove_spikes
from ballimpact.signal.conditioning import condition_voltage
from ballimpact.problems import ProblemKind

FS = 50e3  # sample rate [Hz]
START_U = 1000.95  # the force's jump, in samples from the record's first [samples]
RAMP_U = 0.5  # the jump's ramp from zero to the spike's level [samples]
SPIKE_U = 1.6  # the spike ends (drops at buckling) this long after the jump [samples]
SPIKE_V = 2.6  # the spike's level [V]
PEAK_V = 4.0  # the half-sine's peak [V]
TC_U = 200.0  # contact time [samples] (4 ms)
LEAD_U = 21.0  # the half-sine starts this long before the jump (0.29 of its peak there) [samples]
N = 3300  # record [samples]: 20 ms before the contact, 42 ms after it
NOISE_V = 1e-3  # white noise [V]


def _force(u):
    """The analytic force [V] at sample times u [samples]: ramp, spike, then the half-sine to zero at the end."""
    t = np.asarray(u, dtype=float) - START_U
    sine = PEAK_V * np.sin(np.pi * (t + LEAD_U) / (TC_U + LEAD_U))
    f = np.where(t < RAMP_U, SPIKE_V * t / RAMP_U, np.where(t < SPIKE_U, SPIKE_V, sine))
    return np.where((t >= 0.0) & (t < TC_U), f, 0.0)


def _trace(seed=1):
    u = np.arange(N, dtype=float)
    clean = _force(u)
    return clean, clean + np.random.default_rng(seed).normal(0.0, NOISE_V, N)


def _condition(v):
    return condition_voltage(v, FS, mains_hz=None, tau_s=math.inf)


K_SPIKE = int(math.ceil(START_U + RAMP_U))  # the sample on the ball's spike (1002: 1001 is on the ramp)
K_END = int(math.floor(START_U + TC_U))  # the contact's last sample (1200)


def test_the_analytic_force_is_sampled_as_meant():
    # the premises of the cases below, from the force itself: a ramp sample, the spike's sample, the drop
    clean, _ = _trace()
    assert 0.0 < clean[K_SPIKE - 1] < SPIKE_V and clean[K_SPIKE] == SPIKE_V > clean[K_SPIKE + 1]
    assert clean[K_END] > 0.0 and clean[K_END + 1] == 0.0


def test_spike_kink_is_zero_on_a_line_and_a_quarter_of_a_jump_at_it():
    k = 10
    line = 0.3 + 0.01 * np.arange(21)
    line[k] += 2.0  # an electrical spike on a straight force
    assert_allclose(_spike_kink(line, k), 0.0, atol=1e-12)
    jump = np.zeros(21)
    jump[k + 1:] = 1.6  # the force jumps from zero at sample k (its sample there higher still)
    jump[k] = 2.5
    assert_allclose(_spike_kink(jump, k), 1.6 / 4.0, rtol=1e-12)
    with pytest.raises(ValueError, match="two samples either side of sample 1"):
        _spike_kink(line, 1)


def test_remove_spikes_keeps_the_samples_it_is_told_to():
    v = np.zeros(40)
    v[10] = v[25] = 1.0
    out, idx = remove_spikes(v, noise_rms_V=1e-3, keep=(10,))
    assert idx.tolist() == [25]
    assert out[10] == 1.0 and out[25] == 0.0


def test_the_balls_spike_at_the_jump_is_kept():
    # no electrical spike: the sample on the ball's spike has a spike's shape but its neighbours continue the
    # baseline before it and the force after it; kept, the conditioned force there is the force's (replaced, it
    # was its neighbours' mean, 1.1 V low, and the start was not determined)
    clean, v = _trace()
    c = _condition(v)
    assert K_SPIKE not in c.spike_indices
    assert_allclose(c.voltage_V[K_SPIKE - 1:K_SPIKE + 2], clean[K_SPIKE - 1:K_SPIKE + 2], atol=5 * NOISE_V)
    assert [p.message for p in c.problems if "spike" in p.message] == []
    assert_allclose(c.contact.start_s * FS, START_U, atol=0.5)


@pytest.mark.parametrize("k", [K_END - 3, K_END + 3])
def test_an_electrical_spike_near_the_end_is_replaced_and_the_end_kept(k):
    # 1.5 V planted on the half-sine's fade 3.8 samples before its end, or on the baseline 2.2 samples after it:
    # the neighbours continue one curve, so the sample is electrical and replaced by their mean, and the end is
    # the clean trace's
    clean, v = _trace()
    spiky = v.copy()
    spiky[k] += 1.5
    c, ref = _condition(spiky), _condition(v)
    assert k in c.spike_indices
    assert_allclose(c.voltage_V[k], clean[k], atol=0.01)  # the fade's curvature over two samples: 0.4 mV
    assert [p.message for p in c.problems if "spike" in p.message] == []
    assert_allclose(c.contact.end_s, ref.contact.end_s, atol=0.05 / FS)


def test_an_electrical_spike_riding_on_the_jump_is_not_told_from_the_force():
    # 4 V more on the spike's sample: kept like the ball's own, but were it electrical the impulse would be off by
    # its excess over its neighbours' mean (1.0 %); the start is then not determined
    clean, v = _trace()
    spiky = v.copy()
    spiky[K_SPIKE] += 4.0
    c = _condition(spiky)
    assert K_SPIKE not in c.spike_indices
    said = [p for p in c.problems if "spike" in p.message]
    assert [p.kind for p in said] == [ProblemKind.CONTACT_END_UNDETERMINED]
    excess = SPIKE_V + 4.0 - 0.5 * (clean[K_SPIKE - 1] + clean[K_SPIKE + 1])
    share = 100 * excess / float(np.sum(clean) + 4.0)  # of the impulse the sample is in
    assert share > 0.5  # 1.0 %
    m = said[0].message
    offset = re.match(r"contact start not determined: the sample (\S+) samples from it", m)
    assert offset, m
    assert_allclose(float(offset[1]), K_SPIKE - START_U, atol=0.5)  # where the start is found within its sample
    said_share = re.search(r"the impulse would be (\S+) % off \(more than 0.5 %\)", m)
    assert said_share, m
    assert_allclose(float(said_share[1]), share, atol=0.05)  # two digits


@pytest.mark.parametrize("outer_V, said", [(0.0, "it is the contact's outermost sample"), (0.5, None)])
def test_a_kept_sample_that_is_the_contacts_first_leaves_the_start_undetermined(outer_V, said):
    # the judgement alone, on a force of 1 V (100 samples, 1 mV noise) from sample 10 whose sample 11 stands 0.4 V
    # (0.4 % of the impulse) above its neighbours: with sample 10 at zero the start rests on sample 11, which may be
    # electrical; with sample 10 at 0.5 V the start rests on sample 10, and the excess is within the impulse's share
    from ballimpact.signal.spikes import second_differences, spikes_at_ends
    from ballimpact.signal.contact import ContactResult

    x = np.zeros(200)
    x[10:110] = 1.0
    x[10] = outer_V
    x[11] += 0.4 + 0.5 * (outer_V - 1.0)  # 0.4 above the mean of samples 10 and 12
    contact = ContactResult(found=True, start_s=9.5 / FS, end_s=109.5 / FS, edge_start_s=9.5 / FS,
                            edge_end_s=109.5 / FS, start_index=10, end_index=109, peak_index=11, peak_V=1.4,
                            n_impacts=1, noise_rms_V=1e-3, threshold_V=8e-3, clipped=False, flags=())
    problems, keep = spikes_at_ends(x, second_differences(x), (), (11,), contact, x, 1e-3, FS, 0.0, 1.0)
    assert keep == ()
    if said is None:
        assert problems == []
    else:
        assert [p.kind for p in problems] == [ProblemKind.CONTACT_END_UNDETERMINED]
        assert problems[0].message.startswith("contact start not determined: the sample +1.5 samples from it"), \
            problems[0].message
        assert said in problems[0].message, problems[0].message


@pytest.mark.parametrize("k", [K_END - 3, K_END - 6])
def test_a_lower_electrical_spike_in_the_ends_fit_is_replaced(k):
    # -13 mV (about 11 noise deviations of the second difference, below the record's threshold of 12) on the fade 3.8
    # or 6.8 samples before the end, among the samples the end's hinge is fitted to: replaced, and the end is the
    # clean trace's (on main it stayed, and 79-185 mV ones moved the end by -1.8 % of TC on bench/spike_ends_map.py)
    clean, v = _trace()
    spiky = v.copy()
    spiky[k] -= 0.013
    c, ref = _condition(spiky), _condition(v)
    assert k in c.spike_indices and k not in ref.spike_indices
    assert_allclose(c.voltage_V[k], clean[k], atol=5 * NOISE_V)
    assert_allclose(c.contact.end_s, ref.contact.end_s, atol=0.05 / FS)
