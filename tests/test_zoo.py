"""The trace zoo's truth checked against independent analytic cases (the zoo is tests/zoo.py, issue 9)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.optimize import curve_fit

import zoo
from ballimpact.gates import gate_speeds
from ballimpact.processing import ImpactResult
from ballimpact.session import read_session
from ballimpact.traces import read_trace

#: An ideal chain: DC-coupled, ideal plate, no hum, noise, offset, drift or spikes.
IDEAL = dict(tau_s=math.inf, plate_hz=None, hum_V=0.0, noise_V=0.0, offset_V=0.0, drift_V_s=0.0, spikes=())


def ideal(seed, **kw):
    return zoo.make_trace(np.random.default_rng(seed), "random", **{**IDEAL, "second": None, "truncate": "",
                                                                    "clip_factor": 0.0, **kw})


def lsb(tr):
    lo, hi = tr.rig.adc_range_v
    return (hi - lo) / 2**zoo.ADC_BITS


@pytest.mark.parametrize("seed", range(6))
def test_ideal_trace_integrates_to_the_true_impulse(seed):
    # impulse theorem: integral F dt = m (vin + vout), and V = F / kCAL. At 200 kHz the
    # samples resolve the model's 0.01 ms ramp at first contact, so their sum is the integral.
    tr = ideal(seed, sample_rate_hz=200e3)
    t = tr.truth
    impulse_V_s = np.sum(tr.voltage_V) / tr.sample_rate_hz * tr.rig.polarity
    assert_allclose(impulse_V_s * t.kcal_N_per_V, t.mass_kg * (t.vin_m_s + t.vout_m_s), rtol=1e-3)


@pytest.mark.parametrize("seed", range(4))
def test_plate_keeps_the_impulse(seed):
    # a plate of unit static gain only redistributes the force in time
    tr = ideal(seed, plate_hz=2000.0 + 5000.0 * seed, plate_zeta=0.05, post_s=0.2, sample_rate_hz=200e3)
    t = tr.truth
    impulse_V_s = np.sum(tr.voltage_V) / tr.sample_rate_hz * tr.rig.polarity
    assert_allclose(impulse_V_s * t.kcal_N_per_V, t.mass_kg * (t.vin_m_s + t.vout_m_s), rtol=1e-3)


@pytest.mark.parametrize("fs", [20e3, 67e3])
def test_antialias_filter_keeps_the_impulse_and_passes_only_below_its_stopband(fs):
    # the sigma-delta decimation filter of bench/antialias_map.py: unit DC gain, flat to its cut-off, 100 dB down
    # from 0.55 fs (the map's truth is the ball's force, so the filter must not change the impulse)
    tr = ideal(1, antialias_hz=0.45 * fs, post_s=0.05, sample_rate_hz=fs)
    t = tr.truth
    impulse_V_s = np.sum(tr.voltage_V) / tr.sample_rate_hz * tr.rig.polarity
    assert_allclose(impulse_V_s * t.kcal_N_per_V, t.mass_kg * (t.vin_m_s + t.vout_m_s), rtol=2e-4)
    h = 1.0 / (50 * fs)
    time = np.arange(40_000) * h
    for f_hz, gain in [(0.3 * fs, 1.0), (0.44 * fs, 1.0), (0.56 * fs, 0.0), (0.9 * fs, 0.0)]:
        out = zoo._antialias(np.sin(2 * np.pi * f_hz * time), 0.45 * fs, fs, h)[10_000:30_000]
        assert_allclose(np.sqrt(2 * np.mean(out**2)), gain, atol=2e-3, err_msg=f"{f_hz / fs:g} fs")


@pytest.mark.parametrize("residue", [-0.45, 0.3])
def test_plate_of_two_modes_keeps_the_impulse_and_rings_at_both(residue):
    # bench/two_mode_map.py's plates: a modal sum of unit static gain still only redistributes the force in time,
    # and what it adds to the force (the same trace on an ideal plate: the plate draws nothing from the generator)
    # rings at both modes
    fn1, fn2 = 6000.0, 17000.0
    fields = dict(plate_zeta=0.02, post_s=0.2, sample_rate_hz=200e3)
    tr = ideal(1, plate_hz=fn1, plate_modes=((fn2, 0.02, residue),), **fields)
    t = tr.truth
    impulse_V_s = np.sum(tr.voltage_V) / tr.sample_rate_hz * tr.rig.polarity
    assert_allclose(impulse_V_s * t.kcal_N_per_V, t.mass_kg * (t.vin_m_s + t.vout_m_s), rtol=1e-3)
    ringing = tr.voltage_V - ideal(1, plate_hz=None, **fields).voltage_V
    k = int(t.start_s * tr.sample_rate_hz)
    ringing = ringing[k:k + 2000]
    power = np.abs(np.fft.rfft(ringing * np.hanning(ringing.size))) ** 2
    f = np.fft.rfftfreq(ringing.size, 1.0 / tr.sample_rate_hz)
    lines = [f[np.argmax(np.where(abs(f - fn) < 2000.0, power, 0.0))] for fn in (fn1, fn2)]
    assert_allclose(lines, [fn1, fn2], atol=200.0)
    between = np.max(power[(f > 9e3) & (f < 14e3)])  # the trough between the two modes
    assert min(power[np.searchsorted(f, lines)]) > 10 * between


@pytest.mark.parametrize("seed", range(6))
def test_force_is_nonzero_exactly_between_truth_start_and_end(seed):
    tr = ideal(seed)
    t = np.arange(tr.voltage_V.size) / tr.sample_rate_hz
    v = tr.voltage_V * tr.rig.polarity
    inside = (t > tr.truth.start_s) & (t < tr.truth.end_s)
    well_inside = (t > tr.truth.start_s + 20e-6) & (t < tr.truth.end_s - 20e-6)
    assert np.all(v[inside] > 0.5 * lsb(tr))  # the force is positive between start and end ...
    assert np.all(v[well_inside] > 3 * lsb(tr))  # ... and above the ADC step away from them
    assert np.all(np.abs(v[~inside]) <= 0.5 * lsb(tr))  # and zero outside
    # the largest sampled force is at most the model's peak
    assert np.max(v) * tr.truth.kcal_N_per_V <= tr.truth.peak_N * (1 + 1e-3)


def test_truth_matches_the_model_speeds():
    tr = ideal(3)
    t = tr.truth
    assert_allclose(t.vout_m_s, t.model_vout_m_s, rtol=1e-4)
    # TC from the first non-zero force: shorter than the model's (from x = 0) by the cloth phase
    cloth_phase = t.model_tc_s - t.tc_s
    assert 0 < cloth_phase < 2.1e-3 / t.vin_m_s + zoo.TIME_STEP_S


@pytest.mark.parametrize("tau_s", [0.01, 0.1, 3.0, 100.0])
def test_highpass_step_response_decays_with_tau(tau_s):
    # input rising linearly from 0 to 1 over [0, h] and then held: for t >= h the
    # first-order high-pass gives y = (tau / h) (1 - exp(-h / tau)) exp(-(t - h) / tau)
    h = 1e-6
    n = int(3 * min(tau_s, 0.05) / h)
    q = np.ones(n)
    q[0] = 0.0
    y = zoo._highpass(q, tau_s, h)
    t = np.arange(n) * h
    expected = tau_s / h * -math.expm1(-h / tau_s) * np.exp(-(t[1:] - h) / tau_s)
    assert y[0] == 0.0
    assert_allclose(y[1:], expected, rtol=1e-9)


def test_undershoot_after_contact_follows_the_high_pass():
    # after the contact the high-pass output is -(1 / tau) sum_i exp(-(t - t_i) / tau) V_i dt,
    # V the DC-coupled voltage: for tau >> TC an undershoot of about -(integral V dt) / tau
    tau = 0.2
    tr = ideal(1, tau_s=tau, post_s=0.1, sample_rate_hz=200e3)
    dc = ideal(1, post_s=0.1, sample_rate_hz=200e3)  # same draw, DC-coupled
    fs = dc.sample_rate_hz
    t = np.arange(tr.voltage_V.size) / fs
    vdc = dc.voltage_V * dc.rig.polarity
    v = tr.voltage_V * tr.rig.polarity
    for delay in (1e-3, 20e-3, 80e-3):
        k = int(np.searchsorted(t, tr.truth.end_s + delay))
        expected = -np.sum(np.exp(-(t[k] - t[:k]) / tau) * vdc[:k]) / fs / tau
        assert_allclose(v[k], expected, rtol=2e-3, atol=lsb(tr))


@pytest.mark.parametrize("mains_hz, dev", [(50.0, 0.03), (60.0, -0.04)])
def test_hum_has_the_drawn_frequency(mains_hz, dev):
    tr = ideal(2, hum_V=0.02, harmonics=(), mains_hz=mains_hz, mains_dev_hz=dev, post_s=0.5)
    t = np.arange(tr.voltage_V.size) / tr.sample_rate_hz
    quiet = t > tr.truth.end_s + 1e-3
    sine = lambda t, a, f, ph: a * np.sin(2 * np.pi * f * t + ph)
    best = None
    for ph in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        p, _ = curve_fit(sine, t[quiet], tr.voltage_V[quiet], p0=(0.02, mains_hz, ph))
        r = np.sum((sine(t[quiet], *p) - tr.voltage_V[quiet]) ** 2)
        best = (r, p) if best is None or r < best[0] else best
    assert_allclose(abs(best[1][0]), 0.02, rtol=1e-2)
    assert_allclose(best[1][1], mains_hz + dev, atol=2e-3)


def test_plate_rings_at_its_damped_frequency():
    fn, zeta, h = 5000.0, 0.02, 1e-6
    b, a = zoo._plate_filter(fn, zeta, h)
    from scipy import signal

    y = signal.lfilter(b, a, np.ones(4000)) - 1.0
    crossings = np.flatnonzero(np.diff(np.sign(y)) != 0)
    period = 2 * np.mean(np.diff(crossings)) * h
    assert_allclose(1 / period, fn * math.sqrt(1 - zeta**2), rtol=2e-3)
    assert_allclose(np.sum(b) / np.sum(a), 1.0, rtol=1e-12)


@pytest.mark.parametrize("where", ["start", "end"])
def test_truncated_trace_starts_or_ends_inside_the_contact(where):
    tr = ideal(4, truncate=where, truncate_frac=0.4)
    v = tr.voltage_V * tr.rig.polarity
    t_last = (v.size - 1) / tr.sample_rate_hz
    assert tr.truth.fault == "truncated" and not tr.truth.measurable
    if where == "start":
        assert tr.truth.start_s < 0 < tr.truth.end_s
        assert v[0] > 10 * lsb(tr)
    else:
        assert tr.truth.start_s < t_last < tr.truth.end_s
        assert v[-1] > 10 * lsb(tr)


def test_clipped_trace_reaches_the_rail():
    tr = ideal(5, clip_factor=1.3)
    lo, hi = tr.rig.adc_range_v
    at_rail = (tr.voltage_V >= hi - lsb(tr)) | (tr.voltage_V <= lo + lsb(tr))
    assert at_rail.sum() >= 2
    assert tr.truth.fault == "clipped"


@pytest.mark.parametrize("level", [0.6, 0.9])
def test_a_saturating_amplifier_holds_the_record_at_its_level_and_is_a_fault(level):
    """bench/saturation_map.py's stage: the amplifier's output held at +-saturation_V (the noise all added after
    it, so the top is that level to within the noise's mean), far inside the ADC's range; not reached, no fault."""
    kw = dict(polarity=1, noise_V=1e-3)
    free = ideal(5, **kw)
    sat_V = level * float(np.max(free.voltage_V))
    tr = ideal(5, saturation_V=sat_V, daq_noise_fraction=1.0, **kw)
    top = tr.voltage_V[tr.voltage_V > sat_V - 6e-3]
    assert top.size > 20
    assert_allclose(np.median(top), sat_V, atol=4e-3 / math.sqrt(top.size) + lsb(tr))
    assert tr.truth.fault == "saturated" and not tr.truth.measurable
    assert np.max(np.abs(tr.voltage_V)) < 0.9 * tr.rig.adc_range_v[1]
    untouched = ideal(5, saturation_V=9.9, daq_noise_fraction=1.0, **kw)
    assert untouched.truth.fault == "" and untouched.truth.measurable


@pytest.mark.parametrize("fraction, fault", [(0.02, ""), (0.3, "second contact"), (1.0, "second contact")])
def test_second_contact_size_and_fault(fraction, fault):
    tr = ideal(6, second=(0.008, fraction, 12.0), post_s=0.08)
    t = np.arange(tr.voltage_V.size) / tr.sample_rate_hz
    v = tr.voltage_V * tr.rig.polarity * tr.truth.kcal_N_per_V
    later = t > tr.truth.end_s + 0.5e-3
    assert_allclose(np.max(v[later]) / tr.truth.peak_N, fraction, rtol=0.02, atol=2 * lsb(tr) * tr.truth.kcal_N_per_V / tr.truth.peak_N)
    assert tr.truth.fault == fault
    assert tr.truth.measurable == (fault == "")


def test_same_seed_same_trace():
    a, b = zoo.trace_for(7, 13), zoo.trace_for(7, 13)
    assert_array_equal(a.voltage_V, b.voltage_V)
    assert a.truth == b.truth
    assert not np.array_equal(a.voltage_V[:100], zoo.trace_for(7, 15).voltage_V[:100])


@pytest.mark.parametrize("mode", zoo.FACTORS)
def test_one_factor_draw_keeps_the_others_benign(mode):
    rig = zoo.draw_rig(np.random.default_rng(1), mode)
    for name, value in zoo._BENIGN.items():
        if name not in zoo._draw(np.random.default_rng(2), mode):
            assert getattr(rig, name) == value, name


@pytest.mark.parametrize("fmt", ["csv", "tdms"])
def test_session_folder_reads_back(tmp_path, fmt):
    tr = zoo.trace_for(0, 10)
    folder = zoo.write_session_folder(tr, tmp_path / "zoo-s", trace_format=fmt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        session = read_session(folder)
    row = session.impacts[0]
    vin, vout = gate_speeds(row.gate_in_1_s, row.gate_in_2_s, row.gate_out_2_s, row.gate_out_1_s,
                            session.meta.gate_spacing_m)
    assert_allclose([vin, vout], [tr.truth.vin_m_s, tr.truth.vout_m_s], rtol=1e-7)
    assert_allclose(row.mass_kg, tr.truth.mass_kg, rtol=1e-9)
    trace = read_trace(session.trace_path(row), session.meta.sample_rate_hz)
    assert_allclose(trace.sample_rate_hz, tr.sample_rate_hz, rtol=1e-12)
    assert_allclose(trace.voltage_V, tr.voltage_V, atol=1e-7)
    assert session.meta.polarity == tr.rig.polarity
    assert ("mains_hz" in session.meta.raw["daq"]) == tr.rig.mains_known
    assert ("time_constant_s" in session.meta.raw["plate"]) == (tr.rig.tau_known and math.isfinite(tr.rig.tau_s))


def _result(status="ok", tc_ms=4.0, kcal=200.0, peak=1000.0, reason="", withheld=()):
    r = ImpactResult(impact_id="x", ball="b", status=status, reason=reason)
    r.contact_time_ms, r.kcal_N_per_V, r.peak_force_N = tc_ms, kcal, peak
    for q in withheld:
        setattr(r, f"{q}_status", "withheld")
    return r


def _truth(fault="", marginal="", spike=False):
    # an impact's TC is judged against the model's (from the first contact), not the force's from its jump
    return zoo.ZooTruth(tc_s=3.9e-3, start_s=0.0101, end_s=0.014, kcal_N_per_V=200.0, peak_N=1000.0, peak_is_spike=spike,
                        time_to_peak_s=1e-3, vin_m_s=20.0, vout_m_s=12.0, mass_kg=0.057,
                        measurable=not fault, fault=fault, marginal=marginal, second_fraction=0.0,
                        model_tc_s=4e-3, model_vout_m_s=12.0)


@pytest.mark.parametrize("result, truth, category, wrong", [
    (_result(), _truth(), "ok_right", []),
    (_result(tc_ms=4.0 * 1.009, kcal=200 * 0.991, peak=1000 * 1.029), _truth(), "ok_right", []),
    (_result(tc_ms=4.0 * 1.011), _truth(), "ok_wrong", ["tc"]),
    (_result(kcal=200 * 0.989), _truth(), "ok_wrong", ["kcal"]),
    (_result(peak=1000 * 1.04), _truth(), "ok_wrong", ["peak"]),
    (_result(peak=1000 * 1.04), _truth(spike=True), "ok_right", []),
    (_result(peak=1000 * 0.94), _truth(spike=True), "ok_wrong", ["peak"]),
    (_result(tc_ms=math.nan), _truth(), "ok_wrong", ["tc"]),
    (_result(peak=math.nan), _truth(), "ok_wrong", ["peak"]),  # a missing peak reported ok
    (_result(peak=1000 * 1.04, withheld=("peak",)), _truth(), "ok_right", []),  # withheld: not reported
    (_result(tc_ms=4.0 * 1.011, withheld=("peak",)), _truth(), "ok_wrong", ["tc"]),
    (_result(kcal=200 * 1.02, withheld=("kcal", "peak")), _truth(), "ok_right", []),
    (_result(), _truth(fault="second contact"), "faulty_ok", []),
    (_result(tc_ms=5.0), _truth(marginal="plate resonance 900 Hz below 3000 Hz"), "ok_wrong", ["tc"]),
    (_result("excluded", reason="no contact found", withheld=("contact_time",)), _truth(), "excluded_measurable", []),
    (_result("excluded", reason="clipping at the ADC rails"), _truth(fault="clipped"), "excluded_faulty", []),
    (_result("excluded", reason="x", withheld=("contact_time",)), _truth(marginal="plate"), "excluded_measurable",
     []),
    (_result("excluded", reason="x", tc_ms=5.0, withheld=("contact_time",), kcal=250.0), _truth(), "ok_wrong",
     ["kcal"]),  # excluded, but its kCAL reported and wrong
])
def test_judge(result, truth, category, wrong):
    j = zoo.judge(result, truth)
    assert j.category == category
    assert j.wrong == wrong
    assert j.reason == result.reason


def test_judge_gives_each_quantity_its_outcome():
    j = zoo.judge(_result(tc_ms=4.0 * 1.02, kcal=200.0, withheld=("contact_time", "kcal")), _truth())
    assert j.outcomes == {"tc": "withheld_wrong", "kcal": "withheld_right", "peak": "ok_right"}


def test_band_counts_labels_each_band_and_counts_its_categories():
    values = [0.5, 1.0, 1.5, 2.5, 3.0, 9.0, 2.0]
    categories = ["ok_right", "ok_right", "ok_wrong", "ok_right", "excluded_measurable", "ok_right", "ok_right"]
    rows = zoo.band_counts(values, categories, (1.0, 2.0, 3.0), scale=0.5, unit=" x")
    assert rows == [("< 2 x", "ok_right 1"), ("2-4 x", "ok_right 1, ok_wrong 1"), ("4-6 x", "ok_right 2"),
                    (">= 6 x", "ok_right 1, excluded_measurable 1")]


def _square(job):
    return job * job


@pytest.mark.parametrize("workers", [1, 2])
def test_map_rows_keeps_the_jobs_order(workers):
    assert zoo.map_rows(_square, [3, 1, 2, 5, 4], workers) == [9, 1, 4, 25, 16]


def test_map_command_line_and_summary():
    ap = zoo.map_arguments("A map of something.\n\nMore.", n=600, seed=2)
    assert ap.description == "A map of something."
    a = ap.parse_args([])
    assert (a.n, a.seed, a.workers) == (600, 2, 2)
    assert ap.parse_args(["--n", "7", "--seed", "3", "--workers", "1"]).n == 7
    assert not hasattr(a, "show_ok")
    with_ok = zoo.map_arguments("A map.", show_ok=True)
    assert with_ok.parse_args(["--show-ok"]).show_ok
    assert "--show-ok" in with_ok.format_help()  # its help prints (a bare % in it once broke --help)
    line = zoo.category_summary(5, 3, "ideal plate", ["ok_wrong", "ok_right", "ok_right", "excluded_measurable",
                                                       "ok_right"])
    assert line == "5 rigs (seed 3, ideal plate): excluded_measurable 1, ok_right 3, ok_wrong 1"
    assert zoo.category_summary(1, 1, "", ["ok_right"]) == "1 rigs (seed 1): ok_right 1"


def test_map_report_lines():
    """The report a map prints: the summary, a line per band, the extra lines, the first reasons of the measurable
    traces excluded, then each ok-but-wrong or faulty-ok trace with its own text and errors."""
    rig = ideal(1).rig
    err = {"tc": 1.5, "kcal": -0.2, "peak": 0.0}
    rows = [(0, rig, 0.2, "ok_right", err, ""), (1, rig, 0.7, "ok_wrong", err, ""),
            (2, rig, 0.8, "excluded_measurable", err, "no contact found: nothing"), (3, rig, 0.9, "faulty_ok", err, "")]
    lines = zoo.map_report(rows, 4, "a draw", [r[2] for r in rows], (0.5,), lambda band: f"  x {band}",
                           lambda r: f"x = {r[2]}", extra=["  an extra line"])
    assert lines[:5] == [
        "4 rigs (seed 4, a draw): excluded_measurable 1, faulty_ok 1, ok_right 1, ok_wrong 1",
        "  x < 0.5: ok_right 1",
        "  x >= 0.5: ok_wrong 1, faulty_ok 1, excluded_measurable 1",
        "  an extra line",
        "  first reasons of the 1 measurable excluded: no contact found 1",
    ]
    assert len(lines) == 7
    assert lines[5].startswith("  ok_wrong 4:1: ") and "x = 0.7: TC +1.50 %, kCAL -0.20 %" in lines[5]
    assert lines[6].startswith("  faulty_ok 4:3: ") and "x = 0.9" in lines[6]
