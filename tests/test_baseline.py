"""Tests of the baseline fit (ballimpact.signal.baseline): the hum across the gap a contact leaves in a record of
about one mains period.

The records are built here with numpy alone: a 60 Hz hum with its harmonics 2 to 5 at random phases, an offset and
white noise; the contact's samples are simply left out of the fit (no force is added).
"""

from __future__ import annotations

import numpy as np
import pytest

from ballimpact.signal.baseline import baseline_integral_se, fit_baseline, mains_frequencies

FS = 125_000.0  # [Hz]
MAINS = 60.0  # [Hz]


def _hum(seed, n, hum_V=8e-3, noise_V=1e-3):
    """The record [V] and its hum without noise [V]: harmonics of random amplitudes (0-0.6 of the fundamental)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    rel = np.concatenate([[1.0], rng.uniform(0.0, 0.6, 4)])
    hum = sum(r * hum_V * np.sin(2 * np.pi * k * MAINS * t + rng.uniform(0, 2 * np.pi))
              for k, r in enumerate(rel, start=1))
    return hum + 0.1 + rng.normal(0.0, noise_V, n), hum + 0.1


@pytest.mark.parametrize("end_ms", [10.5, 12.4, 14.0])
@pytest.mark.parametrize("seed", range(6))
def test_hum_fitted_around_a_long_window_in_a_record_of_one_mains_period_stays_the_hums_size(seed, end_ms):
    # 17.8 ms of record (1.07 periods of the fundamental), the window from 3.8 ms to end_ms left out (a contact
    # window that has grown in the window and baseline iteration): five hum components, an offset and a drift can
    # nearly cancel on the quiet samples left and swing by volts under the window, which the contact search then
    # reads as force. The hum's prior keeps the fitted baseline there within a few times the hum's own size (at
    # most 27 mV here) of the truth.
    v, truth = _hum(seed, int(17.8e-3 * FS))
    start_u, end_u = 3.8e-3 * FS, end_ms * 1e-3 * FS
    fit = fit_baseline(v, FS, mains_frequencies(MAINS, 5, FS), start_u, end_u, 0.5e-3 * FS, 2e-3 * FS,
                       with_decay=True, kappa_given=0.0)
    window = slice(int(start_u), int(end_u))
    assert np.max(np.abs(fit.baseline[window] - truth[window])) < 0.1
    assert max(fit.hum_amplitudes) < 0.1


def test_the_baselines_integral_under_a_contact_is_known_to_its_standard_error():
    # 300 records of 17.8 ms, each with a hum of its own (harmonics of random size and phase) under white noise:
    # the fitted baseline's integral over the window left out is off the true hum's by no more, rms, than the
    # standard error baseline_integral_se gives from the fit's covariance (with the hum's prior: the posterior's,
    # which counts the prior's pull as well as the noise), and not by far less (it is no blanket).
    n = int(17.8e-3 * FS)
    start_u, end_u = 4.8e-3 * FS, 9.5e-3 * FS
    window = np.arange(int(np.ceil(start_u)), int(end_u) + 1)
    ratios = []
    for seed in range(300):
        v, truth = _hum(seed, n, noise_V=2e-3)
        fit = fit_baseline(v, FS, mains_frequencies(MAINS, 5, FS), start_u, end_u, 0.5e-3 * FS, 2e-3 * FS,
                           with_decay=True, kappa_given=0.0)
        se = baseline_integral_se({**fit.coef, "coef_cov": fit.cov, "t_mid_s": fit.t_mid}, FS, start_u, end_u)
        ratios.append(np.sum(fit.baseline[window] - truth[window]) / FS / se)
    rms = float(np.sqrt(np.mean(np.square(ratios))))
    assert 0.4 < rms < 1.15
