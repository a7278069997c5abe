"""The cloth's phase: the force's jump located on analytic fronts, and the first contact the model puts before it."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import signal as sps

from ballimpact.model import CLOTH_DISPLACEMENT_M
from ballimpact.signal.cloth import first_contact, hidden_cloth_phase, steep_edge

FS = 50e3
TC_S = 4e-3


def _front(jump_s, *, jump=0.4, cloth=0.0, vin=20.0, n=1200):
    """A ball's force [peak 1] sampled at FS: a cloth ramp from the first contact, then at ``jump_s`` a step of
    ``jump`` and a half-sine rise to 1 at the middle of TC, back to zero at its end (as the model, section 3.2.4)."""
    t = np.arange(n) / FS
    first = jump_s - CLOTH_DISPLACEMENT_M / vin
    u = (t - jump_s) / (TC_S - (jump_s - first))
    f = np.where((u >= 0) & (u <= 1), jump + (1 - jump) * np.sin(np.pi * np.clip(u, 0, 1)), 0.0)
    f = np.where((u >= 0.5) & (u <= 1), np.sin(np.pi * np.clip(u, 0, 1)), f)  # falls back to zero smoothly
    ramp = (t >= first) & (t < jump_s)
    return t, np.where(ramp, cloth * (t - first) / (jump_s - first), f)


@pytest.mark.parametrize("offset", [0.0, 0.13, 0.5, 0.77])
def test_a_sampled_jump_is_located_within_half_a_sample(offset):
    jump_s = (200 + offset) / FS
    _, x = _front(jump_s)
    edge = steep_edge(x, 195.0, int(np.argmax(x)), 1e-3, TC_S * FS)
    assert edge is not None
    assert abs(edge.at_u - jump_s * FS) <= 0.5 + 1e-9
    assert_allclose(edge.se_u, 1 / math.sqrt(12), rtol=1e-12)  # a uniform half sample


@pytest.mark.parametrize("offset", [0.0, 0.3, 0.6])
@pytest.mark.parametrize("cutoff", [0.3, 0.45])
def test_a_jump_rounded_by_a_linear_phase_filter_is_located_at_its_instant(offset, cutoff):
    # a zero-phase low-pass (a linear-phase anti-aliasing filter, its delay removed) of a jump sampled 8 times finer
    jump_s = (200 + offset) / FS
    t = np.arange(8 * 1200) / (8 * FS)
    u = (t - jump_s) / TC_S
    fine = np.where((u >= 0) & (u <= 1), np.maximum(0.4, np.sin(np.pi * np.clip(u, 0, 1))), 0.0)
    taps = sps.firwin(401, cutoff * FS, fs=8 * FS)
    x = sps.filtfilt(taps, [1.0], fine)[::8]
    edge = steep_edge(x, 195.0, int(np.argmax(x)), 1e-3, TC_S * FS)
    assert edge is not None
    assert abs(edge.at_u - jump_s * FS) <= 0.15, edge


@pytest.mark.parametrize("shape", ["half-sine", "hertz", "small jump"])
def test_a_smooth_force_has_no_jump(shape):
    t = np.arange(1200) / FS
    u = np.clip((t - 0.004) / TC_S, 0, 1)
    x = {"half-sine": np.sin(np.pi * u),
         "hertz": np.sin(np.pi * u) ** 1.5,
         "small jump": np.where(u > 0, 0.05 + 0.95 * np.sin(np.pi * u), 0.0)}[shape]
    assert steep_edge(x, 0.004 * FS, int(np.argmax(x)), 1e-3, TC_S * FS) is None


def test_a_jump_within_the_noise_is_not_taken():
    _, x = _front(200 / FS, jump=0.4)
    assert steep_edge(x, 195.0, int(np.argmax(x)), 0.05, TC_S * FS) is None  # 0.4 is 8 noise deviations


def test_the_first_contact_is_the_jump_less_the_cloth_s_phase_at_the_inbound_speed():
    # the model's force is zero for the first 2 mm of compression, crossed at the inbound speed (section 3.2.4)
    assert_allclose(first_contact(300.0, FS, 20.0), 300.0 - 2e-3 / 20.0 * FS, rtol=1e-12)
    assert_allclose(first_contact(300.0, FS, 20.0, cloth_displacement_m=1e-3), 300.0 - 2.5, rtol=1e-12)
    assert math.isnan(first_contact(300.0, FS, math.nan))
    assert math.isnan(first_contact(300.0, FS, 0.0))


def test_the_model_s_force_starts_its_jump_two_millimetres_after_the_first_contact():
    from ballimpact.balls import get_ball
    from ballimpact.model import simulate_impact

    p = get_ball("pressurised").params
    for vin in (12.0, 30.0):
        sim = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, record=True, dt_s=1e-6)
        f = sim.force_N.ravel()
        x = f / f.max()
        edge = steep_edge(x, 0.0, int(np.argmax(x)), 1e-6, float(sim.contact_time_s) * 1e6)
        assert edge is not None
        # the first contact is t = 0 of the simulation, to a step
        assert_allclose(first_contact(edge.at_u, 1e6, vin), 0.0, atol=1.5)


def test_hidden_cloth_phase_is_its_length_over_tc():
    assert_allclose(hidden_cloth_phase(20.0, 4e-3), 2e-3 / 20.0 / 4e-3, rtol=1e-12)
    assert math.isnan(hidden_cloth_phase(math.nan, 4e-3))


def test_a_steeper_rise_after_the_jump_is_not_taken_for_it():
    # an electrical spike three samples after the jump is steeper than the jump: the jump is the first rise through
    # STEEP_MIN_RISE of the peak, located at its instant all the same
    _, x = _front(200 / FS)
    x[203] += 1.5
    edge = steep_edge(x, 199.5, int(np.argmax(x)), 1e-3, TC_S * FS)
    assert edge is not None and abs(edge.at_u - 199.5) <= 0.15, edge


@pytest.mark.parametrize("offset", np.arange(0.0, 1.0, 0.1))
def test_a_jump_is_found_before_a_plate_s_swing_steeper_than_it(offset):
    """A plate of 27 kHz sampled at 97 kHz (zoo trace 804:1222) answers the jump with swings at 3.6 samples a
    period, some steeper than the jump itself; the jump is still the contact's, at its instant within a sample (the
    plate's lag), at every phase of the sampling."""
    from scipy import signal

    fs, fn, zeta = 96.6e3, 26.5e3, 0.12
    dt = 1e-7
    t = np.arange(0, 6e-3, dt)
    jump_s = (100 + offset) / fs
    u = t - jump_s  # a jump, a ramp to the pre-buckling spike at 0.2 ms, and the hump
    force = np.where((u >= 0) & (u <= TC_S), np.where(u < 0.2e-3, 0.35 + 0.65 * np.clip(u / 0.25e-3, 0, 1),
                                                       0.1 + 0.75 * np.sin(np.pi * np.clip(u / TC_S, 0, 1))), 0.0)
    wn = 2 * np.pi * fn
    _, sensed, _ = signal.lsim(signal.lti([wn ** 2], [1.0, 2 * zeta * wn, wn ** 2]), force, t)
    x = np.interp(np.arange(int(6e-3 * fs)) / fs, t, sensed)
    edge = steep_edge(x, jump_s * fs - 0.5, int(np.argmax(x)), 1e-3, TC_S * fs)
    assert edge is not None and abs(edge.at_u - jump_s * fs) <= 1.0, (edge, jump_s * fs)
