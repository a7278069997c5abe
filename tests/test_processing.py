"""Per-impact processing against the ground truth of synthetic sessions (issue 3 accuracy targets)."""

import re

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from ballimpact import processing

from ballimpact.problems import Problem, ProblemKind
from ballimpact.processing import (
    IMPACT_COLUMNS,
    ImpactResult,
    apply_calibration_check,
    flag_calibration_outliers,
    iter_process,
)
from ballimpact.session import read_session


@pytest.fixture(scope="module", params=["synth_session", "synth_session_negative_tdms"])
def processed(request):
    session_dir, truth = request.getfixturevalue(request.param)
    session = read_session(session_dir)
    results = list(iter_process(session))
    apply_calibration_check(results)
    return session, results, truth


def test_every_raw_impact_has_a_result_in_raw_order(processed):
    session, results, truth = processed
    assert [r.impact_id for r in results] == [row.impact_id for row in session.impacts]
    assert all(set(r.row()) == set(IMPACT_COLUMNS) for r in results)


def test_faults_excluded_with_right_reason_and_good_ones_kept(processed):
    _, results, truth = processed
    for r in results:
        t = truth.loc[r.impact_id]
        if t.fault:
            assert r.status == "excluded", r.impact_id
            assert t.expected_reason in r.reason, (r.impact_id, r.reason)
        else:
            assert r.status == "ok", (r.impact_id, r.reason)
            assert r.reason == ""


# Tolerances: about 2x the largest error that `python bench/accuracy.py <session>` measures on
# these two fixtures, written by `ballimpact synth syn-mixed --seed 11 --impacts-per-ball 4
# --faults-per-kind 1 --format mixed` and `ballimpact synth syn-neg --seed 12 --impacts-per-ball 4
# --faults-per-kind 1 --polarity -1 --format tdms --sample-rate-hz 50000` (the same files as
# conftest.py's fixtures): TC 0.24 %, kCAL 0.057 %, COR 1e-4, largest displacement 0.88 %.
TC_RTOL = 0.005
KCAL_RTOL = 1.2e-3
COR_ATOL = 2e-4
DISPLACEMENT_RTOL = 0.018


def test_accuracy_against_truth(processed):
    _, results, truth = processed
    good = [r for r in results if r.status == "ok"]
    assert len(good) >= 16
    t = truth.loc[[r.impact_id for r in good]]
    get = lambda name: np.array([getattr(r, name) for r in good])
    assert_allclose(get("contact_time_ms"), t.contact_time_ms, rtol=TC_RTOL)
    assert_allclose(get("kcal_N_per_V"), t.kcal_N_per_V, rtol=KCAL_RTOL)
    # Peak force within 3 %. Exception: at high speed the model's largest force is the
    # spike just before buckling (kB drops from kCONST at 0.2 ms, section 3.2.4): a
    # ramp of ~5 N/us ending in a sudden drop, whose top falls between samples. At
    # 50 kHz (20 us) that alone can hide up to ~7 %; measured worst case 3.2 % over 120
    # impacts (bench/accuracy.py). Those impacts get 5 %; at 67 kHz every one is in 3 %.
    spike = (t.time_to_peak_ms < 0.25).to_numpy() & (np.array(get("sample_rate_hz")) < 60e3)
    peak, true_peak = get("peak_force_N"), t.peak_force_N.to_numpy()
    assert_allclose(peak[~spike], true_peak[~spike], rtol=0.03)
    assert_allclose(peak[spike], true_peak[spike], rtol=0.05)
    assert_allclose(get("cor"), t.cor, atol=COR_ATOL)
    assert_allclose(get("vin_m_s"), t.vin_m_s, rtol=1e-3)
    assert_allclose(get("max_displacement_mm"), t.max_displacement_mm, rtol=DISPLACEMENT_RTOL)


def test_force_integral_with_the_true_kcal_is_the_momentum_change(processed):
    # Impulse-momentum, independent of how the processing calibrates: the conditioned
    # voltage integrated over the detected contact (trapezoids, here), times the plate's TRUE
    # kCAL, must equal the momentum change m (vin + vout) of the simulated impact (truth).
    # This fails when the conditioning (baseline, decay correction) or the contact's ends
    # are wrong, which the kCAL = m (vin + vout) / integral identity alone cannot show.
    # The error is kCAL's, so the tolerance is KCAL_RTOL (measured 0.054 % at most).
    _, results, truth = processed
    good = [r for r in results if r.status == "ok"]
    assert len(good) >= 16
    t = truth.loc[[r.impact_id for r in good]]
    integral = np.array([np.trapezoid(r.voltage_V, r.time_s) for r in good])
    assert_allclose(t.kcal_N_per_V.to_numpy() * integral, t.impulse_N_s.to_numpy(), rtol=KCAL_RTOL)


def test_kelvin_voigt_stiffness_against_the_true_contact_time(processed):
    # Eq. (2) of Goodwill & Haake 2004, kB = m pi^2 / TC^2, with the TRUE contact time of the
    # simulated impact: kB ~ TC^-2 doubles TC's relative error (measured 0.24 %, so 0.48 %;
    # tolerance 2x that).
    _, results, truth = processed
    good = [r for r in results if r.status == "ok"]
    assert len(good) >= 16
    tc_true = truth.loc[[r.impact_id for r in good]].contact_time_ms.to_numpy() * 1e-3
    mass = np.array([r.mass_kg for r in good])
    kb = np.array([r.kv_stiffness_kN_m for r in good]) * 1e3
    assert_allclose(kb, mass * np.pi**2 / tc_true**2, rtol=2 * TC_RTOL)


def test_time_series_are_consistent(processed):
    _, results, truth = processed
    assert sum(r.status == "ok" for r in results) >= 16
    for r in results:
        if r.status != "ok":
            continue
        assert r.time_s[0] == 0.0
        assert_allclose(r.time_s[-1], r.contact_time_ms * 1e-3, rtol=1e-9)
        assert_allclose(r.velocity_m_s[0], r.vin_m_s, rtol=1e-12)
        assert r.displacement_m[0] == 0.0
        assert_allclose(np.max(r.displacement_m) * 1e3, r.max_displacement_mm, rtol=1e-12)
        # Newton's second law on the series: the velocity falls by the force integral / m
        # (trapezoids here), and the ball is at its deepest where the velocity changes sign.
        dv = np.concatenate([[0.0], np.cumsum(np.diff(r.time_s) * (r.force_N[1:] + r.force_N[:-1]) / 2)])
        assert_allclose(r.velocity_m_s, r.vin_m_s - dv / r.mass_kg, atol=1e-3 * r.vin_m_s)
        deepest = int(np.argmax(r.displacement_m))
        assert r.velocity_m_s[deepest - 1] > 0 >= r.velocity_m_s[min(deepest + 1, r.time_s.size - 1)]


def test_bad_impact_never_stops_the_others(synth_session, tmp_path):
    import shutil

    session_dir, truth = synth_session
    copy = tmp_path / session_dir.name
    shutil.copytree(session_dir, copy)
    victim = next(iid for iid in truth.index if truth.loc[iid].fault == "")
    (copy / "traces" / f"{victim}.csv").write_bytes(b"\xff\xfe garbage\n") if (copy / "traces" / f"{victim}.csv").exists() \
        else (copy / "traces" / f"{victim}.tdms").write_bytes(b"not a tdms file")
    session = read_session(copy)
    results = {r.impact_id: r for r in iter_process(session)}
    assert results[victim].status == "excluded" and "unreadable trace" in results[victim].reason
    others_ok = [r for iid, r in results.items() if iid != victim and truth.loc[iid].fault == ""]
    assert all(r.status == "ok" for r in others_ok)


def test_kcal_outlier_flagged():
    k = np.array([180.0, 182, 178, 181, 179, 240, np.nan])
    reasons, med, spread = flag_calibration_outliers(k, [True] * 6 + [False])
    assert "calibration factor 240.0 N/V" in reasons[5]
    assert all(r == "" for i, r in enumerate(reasons) if i != 5)
    assert_allclose(med, 180.5, rtol=1e-12)


def test_kcal_spread_of_a_few_percent_is_not_flagged():
    rng = np.random.default_rng(0)
    k = 180 * (1 + 0.03 * rng.standard_normal(40))
    reasons, _, _ = flag_calibration_outliers(k, np.ones(40, bool))
    assert not any(reasons)


def test_excluded_result_row_has_reason():
    r = ImpactResult(impact_id="x", ball="b").find(Problem(ProblemKind.NO_CONTACT, "no contact found"))
    r.find(Problem(ProblemKind.CLIPPING, "clipping at the ADC rails"))
    assert [p.kind for p in r.problems] == [ProblemKind.NO_CONTACT, ProblemKind.CLIPPING]
    assert r.row()["status"] == "excluded"
    assert r.row()["reason"] == "no contact found; clipping at the ADC rails"


_PEAK_MESSAGE = "peak force between samples: the force rises by 14 % of the peak in the 43 us before the largest sample"


def test_a_problem_of_the_peak_alone_withholds_the_peak_of_an_ok_impact():
    r = ImpactResult(impact_id="x", ball="b", peak_force_N=1500.0, time_to_peak_ms=0.1, contact_time_ms=4.0)
    r.find(Problem(ProblemKind.PEAK_BETWEEN_SAMPLES, _PEAK_MESSAGE))
    row = r.row()
    assert (row["status"], row["reason"], row["peak_note"]) == ("ok", "", _PEAK_MESSAGE)
    assert (row["peak_status"], row["contact_time_status"], row["kcal_status"]) == ("withheld", "ok", "ok")
    assert row["reason_code"] == "peak_between_samples" and row["withheld_note"] == f"peak: {_PEAK_MESSAGE}"
    assert row["peak_force_N"] == 1500.0  # the estimate is kept; impacts.csv empties its cell (tables.WITHHELD_CELLS)


def test_a_peak_problem_joins_the_reason_of_an_impact_a_fault_excludes():
    r = ImpactResult(impact_id="x", ball="b", peak_force_N=1500.0)
    r.find(Problem(ProblemKind.PEAK_ON_RINGING, "peak force on plate ringing: ..."))
    r.find(Problem(ProblemKind.NO_CALIBRATION, "no calibration: x"))
    assert r.status == "excluded" and r.reason == "no calibration: x"
    assert r.reason_code == "peak_on_ringing;no_calibration"
    assert r.peak_note == "" and r.peak_force_N == 1500.0
    assert [p.kind for p in r.problems] == [ProblemKind.PEAK_ON_RINGING, ProblemKind.NO_CALIBRATION]


@pytest.mark.parametrize("kind, excluded", [(ProblemKind.NO_CONTACT, True), (ProblemKind.PLATE_RINGING, True),
                                            (ProblemKind.ALIASING, False)])
def test_a_finding_excludes_only_where_it_withholds_tc_or_is_a_fault(kind, excluded):
    r = ImpactResult(impact_id="x", ball="b").find(Problem(kind, "something"))
    assert (r.status == "excluded") is excluded, r.reason_code


@pytest.mark.parametrize("bandwidth_hz, fs, free", [
    (None, 50e3, False), (25e3, 50e3, True), (24.9e3, 50e3, True), (25.1e3, 50e3, False), (30e3, 20e3, False),
])
def test_alias_free_needs_a_bandwidth_of_at_most_half_the_sample_rate(bandwidth_hz, fs, free):
    assert processing.alias_free(bandwidth_hz, fs) is free


@pytest.mark.parametrize("bandwidth_hz, fs, tc_s, plate_hz, withheld", [
    (None, 59.9e3, 4e-3, None, False),  # no key below twice v1.1's 30 kHz plates: aliasing not ruled out
    (None, 20e3, 4e-3, 9e3, False),  # ... whatever plate was undone
    (None, 60e3, 4e-3, None, True),  # no key, sampled fast enough for any v1.1 plate
    (None, 100e3, float("nan"), None, False),
    (60e3, 100e3, 4e-3, None, False),  # above fs/2, key or no key
    (60e3, 100e3, 4e-3, 60e3, False),
    (25e3, 50e3, 4e-3, None, True),  # rounds the front over 20 us = 0.5 % of TC
    (24e3, 50e3, 4e-3, None, False),  # 20.8 us: more
    (10e3, 21.5e3, 3.3e-3, None, False),  # bench/antialias_map.py 2:339's kind: 1.5 % of TC
    (8e3, 50e3, 4e-3, 8.7e3, True),  # the key is the undone plate's resonance: nothing left rounds the front
    (8e3, 50e3, 4e-3, 7.3e3, True),
    (8e3, 50e3, 4e-3, 8.9e3, False),  # 11 % off: another band limit (a filter) may round it
    (8e3, 50e3, 4e-3, float("nan"), False),
    (25e3, 50e3, float("nan"), None, False),
])
def test_peak_withheld_only_without_alias_and_with_a_front_rounded_over_little_of_tc(bandwidth_hz, fs, tc_s,
                                                                                       plate_hz, withheld):
    assert processing.peak_can_be_withheld(bandwidth_hz, fs, tc_s, plate_hz) is withheld


@pytest.mark.parametrize("bandwidth_hz, fs, ruled_out", [
    (None, 59.9e3, False), (None, 60e3, True), (None, 200e3, True), (None, float("nan"), False),
    (25e3, 50e3, True), (25.1e3, 50e3, False), (40e3, 200e3, True),
])
def test_aliasing_ruled_out_by_the_key_or_by_sampling_above_twice_the_highest_plate(bandwidth_hz, fs, ruled_out):
    assert processing.aliasing_ruled_out(bandwidth_hz, fs) is ruled_out


@pytest.mark.parametrize("factor, excluded", [(0.4, False), (0.6, True)])
def test_bandwidth_above_half_the_sample_rate_withholds_kcal_and_the_peak(synth_session, tmp_path, factor, excluded):
    import shutil

    session_dir, truth = synth_session
    copy = tmp_path / session_dir.name
    shutil.copytree(session_dir, copy)
    fs = read_session(copy).meta.sample_rate_hz
    text = (copy / "session.yaml").read_text(encoding="utf-8")
    (copy / "session.yaml").write_text(text.replace("daq:\n", f"daq:\n  bandwidth_hz: {factor * fs!r}\n", 1),
                                       encoding="utf-8")
    session = read_session(copy)
    assert session.meta.bandwidth_hz == pytest.approx(factor * fs, rel=1e-12)
    good = [r for r in iter_process(session) if truth.loc[r.impact_id].fault == ""]
    if excluded:  # an alias moves kCAL unseen; TC and COR stand on their own checks
        assert all(r.kcal_status == r.peak_status == "withheld" and any(p.kind is ProblemKind.ALIASING
                   for p in r.problems) and "above half the sample rate" in r.withheld_note + r.reason
                   for r in good), [r.reason for r in good]
        assert sum(r.status == "ok" for r in good) >= len(good) - 1, [r.reason for r in good]
    else:
        assert all(r.status == "ok" and r.peak_note == "" and np.isfinite(r.peak_force_N) for r in good), \
            [r.reason for r in good]


@pytest.mark.parametrize("kcal_range, excluded", [("[100, 300]", False), ("[250, 400]", True)])
def test_plate_kcal_range_from_session_yaml(synth_session, tmp_path, kcal_range, excluded):
    import shutil

    session_dir, truth = synth_session
    copy = tmp_path / session_dir.name
    shutil.copytree(session_dir, copy)
    text = (copy / "session.yaml").read_text(encoding="utf-8")
    (copy / "session.yaml").write_text(
        text.replace("plate:\n", f"plate:\n  kcal_range_N_per_V: {kcal_range}\n", 1), encoding="utf-8")
    session = read_session(copy)
    good = [r for r in iter_process(session) if truth.loc[r.impact_id].fault == ""]
    reasons = [r.reason for r in good]
    if excluded:  # the synthetic plate's kCAL is about 180 N/V: a symptom that can bias every quantity
        assert all(r.status == "excluded" and "outside the plate's range [250, 400] N/V" in r.reason
                   for r in good), reasons
    else:
        assert all(r.status == "ok" for r in good), reasons


def test_bad_kcal_range_is_a_session_fault(synth_session, tmp_path):
    import shutil

    from ballimpact.session import SessionError

    session_dir, _ = synth_session
    copy = tmp_path / session_dir.name
    shutil.copytree(session_dir, copy)
    text = (copy / "session.yaml").read_text(encoding="utf-8")
    (copy / "session.yaml").write_text(text.replace("plate:\n", "plate:\n  kcal_range_N_per_V: [300, 100]\n", 1),
                                       encoding="utf-8")
    with pytest.raises(SessionError, match=r"session.yaml: key 'plate.kcal_range_N_per_V' must be two numbers"):
        read_session(copy)


# ------------------------------------------------------------ how each trace was conditioned


def test_conditioning_recorded_against_the_sensor_chain(processed):
    # Both fixtures use SensorChain()'s amplifier, hum and noise (synth.py's defaults, written
    # in session.yaml only as daq.mains_hz): 0.8 s, 12 mV of 50 Hz hum, 1.5 mV of white noise.
    from ballimpact.synth import SensorChain

    chain = SensorChain()
    _, results, _ = processed
    good = [r for r in results if r.status == "ok"]
    get = lambda name: np.array([getattr(r, name) for r in good])  # noqa: E731
    assert {r.tau_source for r in good} == {"estimated"}
    tau, se = get("tau_s"), get("tau_se_s")
    assert np.all(se > 0) and np.all(se < 0.02 * chain.amplifier_time_constant_s)
    # an honest standard error: the estimates scatter about the truth by about one of them
    z = (tau - chain.amplifier_time_constant_s) / se
    assert np.all(np.abs(z) < 4.5), z
    assert 0.6 < np.sqrt(np.mean(z**2)) < 1.8  # 16 draws of N(0, 1): 0.65-1.35 at 99 %
    assert {r.mains_source for r in good} == {"given"}
    assert_allclose(get("mains_hz"), chain.mains_hz, rtol=0)
    assert_allclose(get("hum_amplitude_V"), chain.hum_V, rtol=0.05)
    assert_allclose(get("noise_rms_V"), chain.noise_V, rtol=0.1)


def test_given_time_constant_is_used_and_mains_found_without_daq_mains_hz(synth_session):
    import dataclasses

    from ballimpact.synth import SensorChain

    session_dir, truth = synth_session
    session = read_session(session_dir)
    chain = SensorChain()
    session.meta = dataclasses.replace(session.meta, time_constant_s=chain.amplifier_time_constant_s, mains_hz=None)
    good = [i for i in truth.index if not truth.loc[i, "fault"]][:3]
    results = list(iter_process(session, impact_ids=good))
    assert [r.status for r in results] == ["ok"] * 3, [r.reason for r in results]
    for r in results:
        assert (r.tau_source, r.tau_s) == ("given", chain.amplifier_time_constant_s)
        assert np.isnan(r.tau_se_s)
        assert (r.mains_source, r.mains_hz) == ("detected", chain.mains_hz)


# ------------------------------------------------------------ wrong plate.polarity (issue 14)


@pytest.mark.parametrize("fixture", ["synth_session", "synth_session_negative_tdms"])
def test_wrong_polarity_is_named_as_the_reason(request, tmp_path, fixture):
    import dataclasses

    session_dir, truth = request.getfixturevalue(fixture)
    session = read_session(session_dir)
    true_polarity = session.meta.polarity
    session.meta = dataclasses.replace(session.meta, polarity=-true_polarity)  # the user's mistake
    good = [i for i in truth.index if not truth.loc[i, "fault"]][:3]
    results = list(iter_process(session, impact_ids=good))
    sign = "negative" if true_polarity == -1 else "positive"
    expected = f"pulse is {sign}: plate.polarity is {-true_polarity:+d}"
    assert [(r.status, r.reason) for r in results] == [("excluded", expected)] * len(good)


# ------------------------------------------------ speeds at the plate (issue 13)


def _drag_session(root, orientation):
    import pandas as pd

    from ballimpact.balls import BALLS
    from ballimpact.synth import SensorChain, SynthConfig, write_session

    config = SynthConfig(
        session_id="drag", seed=13, balls={"pressurised": BALLS["pressurised"].params},
        labels={"pressurised": "Ball 1"}, impacts_per_ball=6, faults_per_kind=0, vin_range_m_s=(5.0, 30.0),
        flight_drag=True, rig_orientation=orientation, chain=SensorChain(gate_to_plate_m=0.25),
    )
    session_dir, truth_csv = write_session(root / "drag", config)
    return session_dir, pd.read_csv(truth_csv).set_index("impact_id")


@pytest.mark.parametrize("orientation", ["horizontal", "vertical"])
def test_speeds_corrected_to_the_plate_recover_cor(tmp_path, orientation):
    import shutil

    import yaml

    session_dir, truth = _drag_session(tmp_path / "a", orientation)
    results = list(iter_process(read_session(session_dir)))
    assert all(r.status == "ok" for r in results), [r.reason for r in results]
    t = truth.loc[[r.impact_id for r in results]]
    get = lambda name: np.array([getattr(r, name) for r in results])
    # corrected: the COR at the plate (the model's, in the truth) within 0.002, speeds within 0.1 %
    assert np.max(np.abs(get("cor") - t.cor.to_numpy())) < 0.002
    assert_allclose(get("vin_m_s"), t.vin_m_s, rtol=1e-3)
    assert_allclose(get("vout_m_s"), t.vout_m_s, rtol=1e-3)
    assert_allclose(get("kcal_N_per_V"), t.kcal_N_per_V, rtol=0.01)
    if orientation == "horizontal":  # drag only: faster in at the gates, slower out
        assert np.all(get("vin_gate_m_s") > get("vin_m_s"))
        assert np.all(get("vout_gate_m_s") < get("vout_m_s"))
    # the same session read without gates.distance_to_plate_m: the gate speeds, measurably off
    plain = tmp_path / "b" / "drag"
    shutil.copytree(session_dir, plain)
    doc = yaml.safe_load((plain / "session.yaml").read_text())
    del doc["gates"]["distance_to_plate_m"]
    (plain / "session.yaml").write_text(yaml.safe_dump(doc))
    uncorrected = list(iter_process(read_session(plain)))
    cor_gate = np.array([r.cor for r in uncorrected])
    assert_allclose([r.vin_m_s for r in uncorrected], get("vin_gate_m_s"), rtol=1e-12)
    assert np.max(np.abs(cor_gate - t.cor.to_numpy())) > 0.005
    if orientation == "horizontal":  # about 1 % low at every speed (the estimate)
        assert np.all(cor_gate < t.cor.to_numpy() - 0.004)


# ------------------------------------------------------------ the session's time constant (issue 9)

def _taus(tau_s, tau_se_s, tc_ms=3.7, ok=None):
    n = len(tau_s)
    return processing.flag_time_constant_outliers(tau_s, tau_se_s, [tc_ms] * n, [True] * n if ok is None else ok)


def test_time_constant_unlike_the_sessions_is_flagged_with_what_it_costs():
    rng = np.random.default_rng(0)
    tau = list(0.8 + 0.005 * rng.standard_normal(9)) + [0.0796]
    reasons, median = _taus(tau, [0.005] * 9 + [1e-4])
    assert reasons[:9] == [""] * 9
    # kappa 12.56 against 1.25 per s: the impulse moves by 11.3 x 3.7 ms / 2 = 2.1 %
    assert re.match(r"charge-amplifier time constant 0.0796 s estimated, unlike the session's 0.8\d* s \(10 impacts; "
                    r"\d+ standard errors\): the impulse and kCAL may be off by 2.1 %", reasons[9]), reasons[9]
    assert_allclose(median, 0.8, rtol=0.01)


@pytest.mark.parametrize("tau_out, se_out, flagged", [
    (0.7, 1e-4, False),  # 1000 standard errors, but kappa differs by 0.18 per s: 0.03 % of the impulse
    (0.3, 1e-4, True),  # 2.1 per s: 0.39 % of the impulse
    (0.3, 0.3, False),  # as far, but within its own standard error (kappa se 3.3 per s)
])
def test_time_constant_check_needs_both_significance_and_an_effect(tau_out, se_out, flagged):
    reasons, _ = _taus([0.8] * 5 + [tau_out], [0.005] * 5 + [se_out])
    assert bool(reasons[5]) is flagged, reasons[5]


def test_time_constant_check_skips_sessions_with_fewer_than_three_estimates_and_excluded_impacts():
    assert _taus([0.8, 0.08], [0.005, 1e-4]) == ([""] * 2, pytest.approx(np.nan, nan_ok=True))
    # an excluded impact is neither typical nor judged; NaN (given or not estimated) are left out
    reasons, median = _taus([0.8, 0.8, 0.08, 0.08, np.nan], [0.005, 0.005, 1e-4, 1e-4, np.nan],
                            ok=[True, True, False, False, True])
    assert reasons == [""] * 5 and np.isnan(median)


@pytest.mark.parametrize("kwargs, match", [
    ({"tau_se_s": [0.1, 0.1]}, r"one value per impact, got 3, 2, 3 and 3"),
    ({"max_z": 0.0}, r"max_z and max_impulse must be positive, got 0.0 and 0.003"),
])
def test_time_constant_check_validates_its_input(kwargs, match):
    args = {"tau_s": [0.8] * 3, "tau_se_s": [0.01] * 3, "contact_time_ms": [4.0] * 3, "ok": [True] * 3, **kwargs}
    with pytest.raises(ValueError, match=match):
        processing.flag_time_constant_outliers(**args)


@given(tau=st.floats(0.01, 100.0), n=st.integers(3, 40), rel_se=st.floats(1e-4, 0.3), tc_ms=st.floats(2.0, 8.0),
       spread=st.floats(1.0, 100.0), seed=st.integers(0, 2**32 - 1))
@settings(max_examples=200)
def test_time_constant_check_passes_a_session_of_honest_estimates(tau, n, rel_se, tc_ms, spread, seed):
    """One true time constant, each impact's kappa off by at most 3.5 of its own standard error, standard errors
    spread over a factor ``spread`` between impacts: nothing is flagged."""
    rng = np.random.default_rng(seed)
    kappa_se = rel_se / tau * np.exp(rng.uniform(0.0, np.log(spread), n))
    kappa = 1.0 / tau + np.clip(rng.standard_normal(n), -3.5, 3.5) * kappa_se
    assume(np.all(kappa > 0))
    reasons, _ = processing.flag_time_constant_outliers(1.0 / kappa, kappa_se / kappa**2, [tc_ms] * n, [True] * n)
    assert reasons == [""] * n
