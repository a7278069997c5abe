"""Tests of the benchmarks' arithmetic: bench/run.py's extrapolation, bench/robustness.py's exclusion table."""

from __future__ import annotations

import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from ballimpact.problems import ProblemKind
from workflow_helpers import bench_module


def _bench():
    return bench_module("run")


@pytest.mark.parametrize(("ns", "t0", "per"), [((2, 4, 8), 12.0, 3.5), ((1, 3), 0.0, 7.25)])
def test_extrapolation_recovers_a_straight_line(ns, t0, per):
    value, slope, intercept, residual = _bench().extrapolate_linear(ns, [t0 + per * n for n in ns], 100)
    assert_allclose([value, slope, intercept], [t0 + per * 100, per, t0], rtol=1e-9, atol=1e-9)
    assert residual < 1e-9


def test_extrapolation_reports_the_misfit_of_a_curve():
    # wall time that bends upwards (e.g. swapping): the line's misfit at the measured sizes says so
    _, _, _, residual = _bench().extrapolate_linear([1, 2, 4], [1.0, 4.0, 16.0], 100)
    assert residual > 1.0


@pytest.mark.parametrize("ns", [(4,), (4, 4)])
def test_extrapolation_needs_two_sizes(ns):
    with pytest.raises(ValueError, match="at least two distinct sizes"):
        _bench().extrapolate_linear(ns, [10.0] * len(ns), 100)


def _rec(labels, tc, kcal="ok_right", peak="ok_right", category="ok_right", measurable=True, codes=""):
    status = "ok" if category in ("ok_right", "ok_wrong", "faulty_ok") else "excluded"
    return {"labels": labels, "category": category, "measurable": measurable, "status": status, "codes": codes,
            "tc_outcome": tc, "kcal_outcome": kcal, "peak_outcome": peak}


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")  # the script's BLAS setting, numpy already loaded
def test_factor_table_counts_each_quantity_s_outcomes_on_non_faulty_traces():
    robustness = bench_module("robustness")
    records = [
        _rec("all|mode one factor|plate ideal", "ok_right"),
        _rec("all|mode one factor|plate ideal", "withheld_right", category="excluded_measurable", codes="x"),
        _rec("all|mode random|plate 3-10 kHz", "ok_wrong", kcal="withheld_right", category="ok_wrong"),
        _rec("all|mode random|clipped", "withheld_wrong", category="faulty_ok", measurable=False),
    ]
    order, rows = robustness.table(records)
    assert order[0] == "all"
    assert rows["all"]["n"] == 4 and rows["all"]["measurable"] == 3 and rows["all"]["faulty_used"] == 1
    assert (rows["all"]["tc_ok_right"], rows["all"]["tc_ok_wrong"], rows["all"]["tc_withheld_right"]) == (1, 1, 1)
    assert rows["all"]["kcal_withheld_right"] == 1 and rows["all"]["used"] == 2
    text = robustness.markdown(records, "t").splitlines()
    assert text[2].startswith("| factor class | n | faulty used | non-faulty | used in fit | tc ok right |")
    assert "| all | 4 | 1 | 3 | 2 | 1 | 1 | 1 | 2 | 0 | 1 | 3 | 0 | 0 |" in text


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_targets_split_one_factor_from_random_rigs_by_plate():
    robustness = bench_module("robustness")
    records = [
        _rec("all|mode one factor|plate ideal", "ok_right"),
        _rec("all|mode one factor|plate < 3 kHz", "withheld_right"),
        _rec("all|mode random|plate ideal", "ok_right"),
        _rec("all|mode random|plate 3-10 kHz", "withheld_wrong"),
        _rec("all|mode random|plate < 3 kHz", "withheld_right"),
    ]
    text = robustness.targets(records)
    assert "| one factor | 2 | 1 (50.0 %) | >= 98 % |" in text
    assert "| random, ideal plate or >= 3 kHz | 2 | 1 (50.0 %) | >= 85 % |" in text
    assert "| random, plate < 3 kHz | 1 | 0 (0.0 %) | - |" in text
    assert "ok but wrong: tc 0, kcal 0, peak 0; faulty used in a fit: 0" in text


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_withheld_by_code_counts_right_tcs_lost_under_each_code():
    robustness = bench_module("robustness")
    records = [
        _rec("all", "withheld_right", codes="plate_ringing;peak_on_ringing"),
        _rec("all", "withheld_right", codes="plate_ringing"),
        _rec("all", "withheld_wrong", codes="plate_ringing"),  # wrong: withholding it was right
        _rec("all", "withheld_right", codes=""),  # its budget alone
    ]
    lines = robustness.withheld_by_code(records, 10).splitlines()
    assert lines.index("| plate_ringing | 2 |") < lines.index("| peak_on_ringing | 1 |")
    assert "| budget | 1 |" in lines
    assert robustness.withheld_by_code(records[2:3], 10) == ""


def _tau(category, source, true, tau, se):
    return {"category": category, "tau_source": source, "tau_true_s": true, "tau_s": tau, "tau_se_s": se}


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_time_constant_table_judges_the_standard_errors_in_kappa():
    robustness = bench_module("robustness")
    inf, nan = float("inf"), float("nan")
    # kappa = 1 / tau, se(kappa) = se(tau) / tau^2: 1/0.05 = 20 per s, the estimate 1/0.04 = 25 per s with
    # se(kappa) = 0.0004 / 0.0016 = 0.25 per s -> z = 20
    records = [
        _tau("ok_right", "estimated", 0.05, 0.04, 0.0004),  # z = 20
        _tau("ok_wrong", "estimated", 0.05, 0.05, 0.001),  # z = 0
        _tau("ok_right", "estimated", inf, 10.0, 50.0),  # DC rig: kappa 0.1 per s, se 0.5 -> z = 0.2
        _tau("excluded_measurable", "estimated", 0.5, 0.4, 0.001),  # not ok: not counted
        _tau("ok_right", "given", 0.5, 0.5, nan),  # given: not counted
        _tau("ok_right", "none", 200.0, inf, nan),  # not corrected: not counted
    ]
    table = robustness.time_constants(records).splitlines()
    assert f"| 0.01-0.1 s | 2 | {(20.0**2 / 2) ** 0.5:.2f} | 1 |" in table
    assert "| DC | 1 | 0.20 | 0 |" in table
    assert not any(line.startswith(("| 0.1-1 s", "| 1-100 s")) for line in table)
    assert robustness.time_constants(records[3:]) == ""


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_wander_map_noise_is_one_over_f_meeting_the_white_at_the_corner():
    import numpy as np

    wander = bench_module("wander_map")
    rng = np.random.default_rng(0)
    fs, n, white, corner = 10_000.0, 2**14, 0.002, 100.0
    power = np.mean([np.abs(np.fft.rfft(wander.pink_noise(n, fs, white, corner, rng))) ** 2 for _ in range(40)],
                    axis=0)
    f = np.fft.rfftfreq(n, 1.0 / fs)
    # white noise of rms s has E|X_k|^2 = n s^2 in every bin: the 1/f noise n s^2 corner / f, the white's at f = corner
    for lo, hi in [(5.0, 20.0), (80.0, 125.0), (800.0, 1250.0)]:
        band = (f >= lo) & (f < hi)
        assert_allclose(np.mean(power[band] * f[band]) / (n * white**2 * corner), 1.0, rtol=0.1)
    assert power[0] == pytest.approx(0.0, abs=1e-20)  # no mean: the zoo's offset stays the rig's


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_antialias_map_states_a_bandwidth_below_half_the_sample_rate_and_runs_each_trace_twice():
    from ballimpact.processing import alias_free

    antialias = bench_module("antialias_map")
    for index in range(20):
        rig, _ = antialias.rig_for(1, index)
        assert 20e3 <= rig.sample_rate_hz <= 100e3 and rig.plate_hz is None
        assert antialias.CUTOFF_FS[0] <= rig.antialias_hz / rig.sample_rate_hz <= antialias.CUTOFF_FS[1]
        assert rig.bandwidth_hz == rig.antialias_hz and alias_free(rig.bandwidth_hz, rig.sample_rate_hz)
    index, rig, _, runs = antialias.run_one((1, 0))
    assert index == 0 and [len(r) for r in runs] == [4, 4]
    assert runs[0][3] == ""  # without the key no peak is withheld


def test_known_plate_runs_a_trace_of_its_class_twice_and_tabulates_by_outcome():
    known = bench_module("known_plate")
    assert known.run_one((704, 0, "one factor")) is None  # 704:0 is a random rig
    r = known.run_one((704, 294, "random, ideal plate or >= 3 kHz"))  # 6.8 kHz plate at 30 kHz
    assert r["id"] == "704:294" and not r["aliases"]
    assert {r["keyless"], r["stated"]} <= set(known.OUTCOMES) and r["stated"] == "ok_right"
    rows = [{"aliases": False, "keyless": "withheld_right", "stated": "ok_right"},
            {"aliases": False, "keyless": "withheld_right", "stated": "withheld_right"},
            {"aliases": True, "keyless": "ok_right", "stated": "ok_right"}]
    lines = known.table(rows).splitlines()
    assert lines[2] == "| below fs / 2 | withheld right | 2 | 1 | 0 | 1 | 0 |"
    assert lines[3] == "| above fs / 2 | ok right | 1 | 1 | 0 | 0 | 0 |" and len(lines) == 4


def _trace_rows(spec):
    """Per-trace CSV rows as bench/robustness.py writes them: (index, category, TC, kCAL, peak error in %)."""
    return [{"seed": 3, "index": i, "id": f"3:{i}", "category": cat, "reason": "" if cat.startswith("ok") else
             f"contact end not determined to 1 %: trace {i}", "tc_err_pct": tc, "kcal_err_pct": kcal,
             "peak_err_pct": peak, "process_s": 0.01 * i} for i, cat, tc, kcal, peak in spec]


def test_compare_robustness_names_each_changed_trace_and_the_errors_of_those_ok_in_both(tmp_path, capsys):
    import pandas as pd
    compare = bench_module("compare_robustness")
    old = _trace_rows([(0, "ok_right", 0.2, 0.1, 1.0), (1, "ok_wrong", 1.4, 0.0, 0.0),
                       (2, "excluded_measurable", 0.3, 0.2, 0.1), (3, "ok_right", -0.6, 0.3, 0.5),
                       (4, "excluded_faulty", float("nan"), float("nan"), float("nan"))])
    new = _trace_rows([(0, "ok_right", 0.4, 0.1, 1.0), (1, "excluded_measurable", 1.4, 0.0, 0.0),
                       (2, "ok_right", 0.1, 0.2, 0.1), (3, "ok_right", -0.2, 0.3, 0.5),
                       (4, "excluded_faulty", float("nan"), float("nan"), float("nan"))])
    for side, rows in (("old", old), ("new", new)):
        (tmp_path / side).mkdir()
        pd.DataFrame(rows).to_csv(tmp_path / side / "robustness-s3-n5.csv", index=False)
    assert compare.main([str(tmp_path / "old"), str(tmp_path / "new")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "  ok_wrong: 1 -> 0" in out and "  excluded_measurable: 1 -> 1" in out and "  ok_right: 2 -> 3" in out
    assert "  category changed: 2" in out
    assert any(l.startswith("    3:1: ok_wrong -> excluded_measurable; TC +1.40 % -> +1.40 %") and
               "contact end not determined to 1 %: trace 1" in l for l in out)
    assert any(l.startswith("    3:2: excluded_measurable -> ok_right") for l in out)
    assert "  ok in both: 2" in out  # traces 0 and 3
    # TC of the two ok in both: (0.2, -0.6) -> (0.4, -0.2); one beyond 0.5 % before, none after
    tc = next(l for l in out if l.startswith("    TC error"))
    assert "mean -0.2000 -> +0.1000 %" in tc and "beyond 0.5 %: 1 -> 0" in tc
    assert "largest change of one trace 0.4 %" in tc
    assert out[-1] == ("all: ok_right 2 -> 3, ok_wrong 1 -> 0, excluded_measurable 1 -> 1, excluded_faulty 1 -> 1")


@pytest.mark.parametrize("mangle, message", [
    (lambda df: df.iloc[:-1], "hold different traces"),
    (lambda df: df.drop(columns="kcal_err_pct"), "lacks the columns \\['kcal_err_pct'\\]"),
])
def test_compare_robustness_refuses_runs_it_cannot_pair(tmp_path, mangle, message):
    import pandas as pd
    compare = bench_module("compare_robustness")
    rows = _trace_rows([(0, "ok_right", 0.2, 0.1, 1.0), (1, "ok_right", 0.1, 0.0, 0.0)])
    pd.DataFrame(rows).to_csv(tmp_path / "a.csv", index=False)
    mangle(pd.DataFrame(rows)).to_csv(tmp_path / "b.csv", index=False)
    with pytest.raises(SystemExit, match=message):
        compare.main([str(tmp_path / "a.csv"), str(tmp_path / "b.csv")])


def test_compare_robustness_says_whether_every_other_column_is_identical_to_the_last_bit(tmp_path, capsys):
    import pandas as pd
    compare = bench_module("compare_robustness")
    old = pd.DataFrame(_trace_rows([(0, "ok_right", 0.2, 0.1, 1.0), (1, "excluded_measurable", 0.3, float("nan"),
                                                                    0.1)]))
    old.loc[1, "reason"] = "unreadable trace: /tmp/zoo-bench-abc/zoo-x1/traces/zoo-1.tdms: truncated"
    same = old.copy()
    same["process_s"] += 1.0  # the timing columns do not count
    same.loc[1, "reason"] = "unreadable trace: /tmp/zoo-bench-def/zoo-y2/traces/zoo-1.tdms: truncated"  # nor the tmp
    moved = old.copy()
    moved.loc[0, "tc_err_pct"] = float(np.nextafter(0.2, 1.0))  # one bit
    moved.loc[1, "reason"] = "unreadable trace: /tmp/zoo-bench-def/zoo-y2/traces/zoo-2.tdms: truncated"
    for name, df in (("old", old), ("same", same), ("moved", moved)):
        df.to_csv(tmp_path / f"{name}.csv", index=False)
    compare.main([str(tmp_path / "old.csv"), str(tmp_path / "same.csv")])
    assert "  every other column identical to the last bit" in capsys.readouterr().out.splitlines()
    compare.main([str(tmp_path / "old.csv"), str(tmp_path / "moved.csv")])
    out = capsys.readouterr().out
    assert "  differ: reason on 1 traces (e.g. 3:1); tc_err_pct on 1 traces (e.g. 3:0)" in out.splitlines()


def test_time_against_gives_each_commits_median_and_its_ratio_to_the_first():
    rows = bench_module("time_against").summarise({"base": [0.007, 0.006, 0.008],
                                                   "new": [0.010, 0.011, 0.009, 0.0095]})
    assert [r["rev"] for r in rows] == ["base", "new"]
    assert_allclose([rows[0]["median_ms"], rows[1]["median_ms"]], [7.0, 9.75], rtol=1e-12)
    assert_allclose([rows[0]["ratio"], rows[1]["ratio"]], [1.0, 9.75 / 7.0], rtol=1e-12)
    assert_allclose([rows[1]["min_ms"], rows[1]["max_ms"]], [9.0, 11.0], rtol=1e-12)


@pytest.mark.parametrize("times", [{}, {"base": [0.007], "new": []}])
def test_time_against_needs_a_run_of_every_commit(times):
    with pytest.raises(ValueError, match="at least one run"):
        bench_module("time_against").summarise(times)


def test_front_spike_sweep_puts_its_spike_on_the_fronts_sample_and_judges_it():
    """bench/front_spike_sweep.py: one run, 2:1847 with a spike of minus its peak voltage on the jump's second
    sample, which was ok with TC -1.19 % on 8738d3e (the start taken after the spike); excluded since."""
    sweep = bench_module("front_spike_sweep")
    seed, index, offset, amplitude, category, errors, reason = sweep.run_one((2, 1847, 1, -1.0))
    assert (seed, index, offset, amplitude) == (2, 1847, 1, -1.0)
    assert category == "excluded_measurable", (errors, reason)
    assert "contact start not determined" in reason


def _rigs():
    rigs = bench_module("rigs")
    return rigs, rigs.rig_zoo  # imported by name (its dataclasses need a module in sys.modules)


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_rig_zoo_samples_the_force_over_kcal_on_an_ideal_quiet_rig():
    import dataclasses

    _, rig_zoo = _rigs()
    rig = dataclasses.replace(rig_zoo.draw_rig(1000, 1), plate_hz=None, antialias_hz=None, tau_s=1e12, hum_V=0.0,
                              noise_V=0.0, offset_V=0.0, drift_V_s=0.0, spikes=False, kcal_spread=0.0, polarity=-1)
    ball = rig.balls[0]
    volts, truth = rig_zoo.render_impact(rig, ball, 21.7, "", "x-1", np.random.default_rng(5))
    knots_t, knots_f, _ = rig_zoo.force_knots(ball, 21.7)
    fs = rig.sample_rate_hz
    lsb = 2 * rig.rail_V / 2**rig_zoo.ADC_BITS
    pre = int(rig.pre_s * fs) - 2
    assert np.ptp(volts[:pre]) <= lsb  # a flat baseline: the trace's own offset alone
    volts = volts - np.median(volts[:pre])
    force = -volts * truth.kcal_N_per_V  # polarity -1
    assert np.max(np.abs(force)) == pytest.approx(truth.peak_N, rel=0.05)
    # the impulse of the samples is m (vin + vout) of the truth, and the contact lasts TC
    assert np.sum(force) / fs == pytest.approx(ball.mass_kg * (truth.vin_m_s + truth.vout_m_s), rel=2e-3)
    above = np.flatnonzero(np.abs(volts) > lsb)
    assert (above[-1] - above[0]) / fs == pytest.approx(truth.contact_time_s, abs=2.5 / fs)
    assert truth.contact_time_s == pytest.approx(knots_t[-1]) and truth.fault == ""


def test_rig_zoo_calls_a_clean_impact_on_the_rail_inside_its_contact_clipped():
    """An impact drawn clean whose peak the ADC's rail cuts (here a rail of 0.4 of the peak's volts) is a fault
    (issue 45: clipping inside the contact), and one below the rail stays clean; the class of aliasing ruled out
    takes a stated bandwidth at fs / 2 or below only."""
    import dataclasses

    _, rig_zoo = _rigs()
    rig = dataclasses.replace(rig_zoo.draw_rig(1000, 1), plate_hz=None, antialias_hz=None, offset_V=0.0,
                              drift_V_s=0.0, spikes=False, kcal_spread=0.0)
    ball = rig.balls[0]
    _, truth = rig_zoo.render_impact(rig, ball, 21.7, "", "x-1", np.random.default_rng(5))
    assert truth.fault == ""
    rail = 0.4 * truth.peak_N / truth.kcal_N_per_V
    _, cut = rig_zoo.render_impact(dataclasses.replace(rig, rail_V=rail), ball, 21.7, "", "x-1",
                                   np.random.default_rng(5))
    assert cut.fault == "clipped"
    slow = dataclasses.replace(rig, sample_rate_hz=40e3, antialias_hz=None, plate_hz=25e3, stated=("bandwidth",))
    assert not slow.aliasing_ruled_out and not slow.clear_class
    assert dataclasses.replace(slow, plate_hz=19e3).aliasing_ruled_out


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_rigs_score_reads_the_v12_verdicts_and_falls_back_to_status():
    import pandas as pd

    rigs, _ = _rigs()
    truth = pd.DataFrame({"impact_id": ["a", "b", "c"], "fault": ["", "", "clipped"],
                          "contact_time_ms": [4.0, 4.0, 4.0], "kcal_N_per_V": [200.0] * 3,
                          "peak_force_N": [1000.0] * 3, "peak_is_spike": [False, True, False], "cor": [0.6] * 3})
    old = pd.DataFrame({"impact_id": ["c", "b", "a"], "ball": "x", "vin_m_s": ["20", "21", "22"],
                        "status": ["ok", "ok", "ok"], "reason": ["", "", ""],
                        "used_in_fit": ["true", "true", "false"], "contact_time_ms": ["4.0", "4.1", "4.0"],
                        "kcal_N_per_V": ["200", "200", "200"], "peak_force_N": ["1000", "1045", ""],
                        "cor": ["0.6", "0.6", "0.6025"]})
    s = rigs.score_impacts(old, truth)
    # b's TC is 2.5 % off (its peak 4.5 % is within the spike's 5 %); a's empty peak is withheld; its COR is off
    assert sorted((i, q) for i, q, _ in s["wrong"]) == [("a", "cor"), ("b", "tc")]
    assert (s["clean"], s["used"], s["used_right"], s["faulty_used"]) == (2, 1, 0, [("c", "clipped")])
    assert [rigs._reason_head(x) for x in s["lost_reasons"]] == ["left out of the fit"]  # a: ok, not used
    assert s["speeds"] == {"x": (20.0, 21.0)}  # of the impacts used in the fit, c (faulty) among them
    new = old.assign(contact_time_status=["ok", "withheld", "ok"], kcal_status="ok",
                     peak_status=["ok", "ok", "withheld"], cor_status=["ok", "ok", "withheld"])
    s = rigs.score_impacts(new, truth)
    assert s["wrong"] == [] and s["used"] == 1  # the withheld quantities are not given as ok
    s = rigs.score_impacts(new.assign(status=["ok", "excluded", "ok"], used_in_fit=["true", "false", "false"],
                                      reason_code=["", "contact_end;aliasing", ""]), truth)
    assert sorted(s["lost_reasons"]) == ["TC withheld [contact_end, aliasing]", "left out of the fit: "]
    s = rigs.score_impacts(new.assign(peak_status="ok"), truth)
    assert [(i, q) for i, q, _ in s["wrong"]] == [("a", "peak")]  # ok, yet no value: not right


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_rigs_runs_a_tiny_ideal_plate_session_through_the_workflow(capsys):
    rigs, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(1000, 1, (8, 8))
    assert rig.plate_hz is None and rig.sample_rate_hz < 60e3 and not rig.clear_class
    assert rigs.main(["--n", "2", "--seed", "1000", "--jobs", "1", "--impacts", "8", "8", "--only", "1"]) == 0
    out = capsys.readouterr().out
    assert "rig-1000-001 [other]" in out and "CRASH" not in out
    line = next(x for x in out.splitlines() if x.startswith("  clean used"))
    n_faulty = len(rig.faults)
    assert line.startswith(f"  clean used {8 - n_faulty}/{8 - n_faulty} (right {8 - n_faulty}); ok but wrong 0; "
                           f"faulty used 0/{n_faulty};")


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_start_read_behind_an_antialias_filter_s_ringing_is_completed_and_right(tmp_path):
    """Rig 1000:8 (an ideal plate behind a linear-phase anti-aliasing filter at 26 kHz): the filter rings ahead of
    the force's jump and hid the cloth's foot before it, and TC came out ok and 1.5-1.7 % short on e47051e, then
    withheld (41d1c01). Its start is now the jump less the cloth's 2 mm at the inbound speed (signal.cloth): every
    clean impact's TC within half its tolerance of the truth (the model's, from the first contact), and all but one
    ok at most."""
    import dataclasses

    from ballimpact import processing
    from ballimpact.problems import ProblemKind
    from ballimpact.session import read_session

    _, rig_zoo = _rigs()
    rig = dataclasses.replace(rig_zoo.draw_rig(1000, 8, (8, 8)), spikes=False)
    truths = rig_zoo.write_session(rig, tmp_path)
    session = read_session(tmp_path / rig.session_id)
    clean = [(row, t) for row, t in zip(session.impacts, truths) if not t.fault]
    assert len(clean) >= 5
    kept = 0
    for row, truth in clean:
        result = processing.process_impact(row, session)
        error = result.contact_time_ms / (1e3 * truth.contact_time_s) - 1.0
        assert abs(error) < 0.005, (row.impact_id, error)  # ok or withheld, TC is right
        assert any(p.kind is ProblemKind.CLOTH_PHASE_COMPLETED for p in result.problems), row.impact_id
        kept += result.contact_time_status == "ok"
    assert kept >= len(clean) - 1, kept  # (the filter's ringing may stand above the noise before the first contact)


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_low_plate_s_long_kernel_leaves_no_tc_ok_and_wrong(tmp_path):
    """Rig 6:173 (a 1.53 kHz plate, damping 0.134, at 82.4 kHz, its resonance stated): quieting the undone force
    takes a low-pass near the resonance, whose kernel spreads each end over 10-13 % of TC, and the ends fitted
    through it made the TCs of ball1-010 and ball2-020 1.5-1.6 % long, ok (f31ffcb, held-out rig seed 6). Such a
    kernel is refused now, saying so: TC withheld or within its tolerance of the truth."""
    from ballimpact import processing
    from ballimpact.session import read_session

    _, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(6, 173)
    truths = {t.impact_id: t for t in rig_zoo.write_session(rig, tmp_path)}
    session = read_session(tmp_path / rig.session_id)
    for row in session.impacts:
        if row.impact_id not in ("ball1-010", "ball2-020"):
            continue
        result = processing.process_impact(row, session)
        error = result.contact_time_ms / (1e3 * truths[row.impact_id].contact_time_s) - 1.0
        assert result.contact_time_status != "ok" or abs(error) <= 0.01, (row.impact_id, error)
        assert "spreads each end over" in result.reason + result.withheld_note, result.reason


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_the_session_s_plate_keeps_a_tc_its_own_trace_could_not_undo(tmp_path):
    """Rig 1001:023 (a 6.7 kHz plate, damping 0.12, at 123 kHz, nothing of it stated): ball2-001's trace alone
    identifies the plate too poorly to undo it (TC withheld for the plate's ringing); the plate the session
    identifies from all its 34 impacts, within 1 %, undoes it, and TC is kept, right (ballimpact.session_plate)."""
    table, truths = _rig_session_table(tmp_path, 1001, 23)
    row = table.loc["ball2-001"]
    assert row["contact_time_status"] == "ok", row["reason"]
    assert abs(row["contact_time_ms"] / (1e3 * truths["ball2-001"].contact_time_s) - 1.0) <= 0.005
    for impact_id, r in table.iterrows():  # and nothing ok is wrong
        t = truths[impact_id]
        if r["contact_time_status"] == "ok" and not t.fault:
            assert abs(r["contact_time_ms"] / (1e3 * t.contact_time_s) - 1.0) <= 0.01, impact_id


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_stated_plate_too_noisy_to_undo_keeps_its_tcs_fitted_through_it(tmp_path):
    """Rig 1001:014 (a 4.87 kHz plate, damping 0.048, at 194 kHz, its resonance stated): undoing it amplifies the
    noise to 5-7 % of the peak, and the low-passes that quiet it leave ends no fit pins; TC was withheld for the
    plate's ringing on all four (eef9dc6). The contact's ends fitted through the plate in the sensed force keep
    them, each within 0.5 % of the truth (ballimpact.signal.sensed_ends); kCAL and the peak stay withheld."""
    from ballimpact import processing
    from ballimpact.session import read_session

    _, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(1001, 14)
    truths = {t.impact_id: t for t in rig_zoo.write_session(rig, tmp_path)}
    session = read_session(tmp_path / rig.session_id)
    wanted = ("ball2-001", "ball4-004", "ball1-012", "ball4-017")
    for row in session.impacts:
        if row.impact_id not in wanted:
            continue
        result = processing.process_impact(row, session)
        error = result.contact_time_ms / (1e3 * truths[row.impact_id].contact_time_s) - 1.0
        assert result.contact_time_status == "ok", (row.impact_id, result.reason)
        assert abs(error) <= 0.005, (row.impact_id, error)
        assert result.kcal_status != "ok" and result.peak_status != "ok"
        assert "fitted through the plate in the sensed force" in result.withheld_note + result.reason


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_second_contact_under_a_plates_swing_is_not_used(tmp_path):
    """Rig 9:000 (a 3.85 kHz plate, damping 0.05, at 51 kHz, not stated; held-out rig seed 9 on c8a48f0, looked at
    since): ball1-006's second contact is 4.9 % of the sensed peak, which stands on the plate's swing, and no
    contact search saw it; the session's plate, used in the impact, fitted its ends through the plate and kept TC
    and COR: a faulty impact in the fit. The force undone from the plate and low-passed at its resonance shows the
    second contact, and the ends are not fitted through the plate then."""
    table, truths = _rig_session_table(tmp_path, 9, 0)
    assert truths["ball1-006"].fault == "second contact"
    for impact_id, r in table.iterrows():
        if truths[impact_id].fault:
            assert not (r["contact_time_status"] == "ok" and r["cor_status"] == "ok"), impact_id


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_faint_plate_behind_a_stated_bandwidth_keeps_its_tcs(tmp_path):
    """Rig 1000:026 (a 20.9 kHz plate, damping 0.06, at 69 kHz, no filter, daq.bandwidth_hz its resonance; dev rig
    seed 1000): a line of 0.06 % of the peak at the plate, a peak on its ringing and between samples; no resonance
    stands out of the noise to undo. TC was withheld on 4afeade: the plate's refusal had no bound beside a peak on
    ringing, and the band limit's one rounding of the front was charged twice, once by each peak problem. The
    refusal bounded by the larger of the line's and a ringing hidden in the noise, the rounding charged once: each
    TC ok and within 0.5 % of the truth."""
    wanted = ("ball2-002", "ball1-005", "ball2-010", "ball2-011", "ball2-015", "ball1-017")
    for impact_id, (result, truth) in _rig_impacts(tmp_path, 1000, 26, wanted).items():
        error = result.contact_time_ms / (1e3 * truth.contact_time_s) - 1.0
        assert result.contact_time_status == "ok", (impact_id, result.reason)
        assert abs(error) <= 0.005, (impact_id, error)
        rounding = [p for p in result.problems if "contact_time" in p.data.get("also_biases", ())]
        assert len(rounding) == 1, (impact_id, [p.kind for p in rounding])


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
@pytest.mark.parametrize("seed, index, balls", [(1001, 13, ("ball1", "ball3")), (1001, 19, ("ball3",)),
                                                (1001, 48, ("ball2",))])
def test_impacts_exactly_true_are_not_fit_outliers_of_a_model_that_is_not_the_ball(tmp_path, seed, index, balls):
    """Dev rigs 1001:013, 019 and 048: each ball type's true inbound speeds, TCs and CORs (the rig zoo's ball, the
    model with a cloth force, at its session's speeds) put through the fit-outlier search. The model fitted is not
    that ball to a part in 10^4, and on 4afeade one impact of each was left out, 0.1-0.8 % off the fit of the
    others at 6-28 of their deviations; the others' scatter taken as at least a quarter of each tolerance, none
    is. A COR off by ten times its tolerance (3 %, a rebound off line) still is."""
    from ballimpact.fitting_outliers import detect_fit_outliers

    _, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(seed, index)
    truths = [t for t in rig_zoo.write_session(rig, tmp_path) if not t.fault]
    for ball in rig.balls:
        rows = [t for t in truths if t.ball == ball.key]
        vin = np.array([t.vin_m_s for t in rows])
        tc = np.array([t.contact_time_s for t in rows])
        cor = np.array([t.vout_m_s / t.vin_m_s for t in rows])
        found = detect_fit_outliers(vin, tc, cor, np.full(vin.size, ball.mass_kg))
        assert found.used.all(), (ball.key, [n for n in found.notes if n])
        if ball.key in balls:
            off = cor.copy()
            off[vin.size // 2] -= 10 * 0.002
            found = detect_fit_outliers(vin, tc, off, np.full(vin.size, ball.mass_kg))
            assert np.flatnonzero(~found.used).tolist() == [vin.size // 2], found.notes


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_jump_read_before_its_steepest_rise_bounds_the_completed_start(tmp_path):
    """Rig 17:154 ball3-014 (a 6.2 kHz plate and a 12.7 kHz filter at 38 kHz, both stated; held-out rig seed 17,
    looked at since): on the force undone from the plate the start was read at the jump 2.8 samples before its
    steepest rise, the cloth's phase completed from the earlier of the two, and TC came out ok and 1.8 % long
    (20e4105). The two readings of one jump disagree: their distance is TC's effect, and TC is withheld."""
    (result, truth), = _rig_impacts(tmp_path, 17, 154, ("ball3-014",)).values()
    error = result.contact_time_ms / (1e3 * truth.contact_time_s) - 1.0
    assert result.contact_time_status != "ok" or abs(error) <= 0.01, (error, result.reason)
    completed = [p for p in result.problems if p.kind is ProblemKind.CLOTH_PHASE_COMPLETED]
    assert completed and completed[0].effects["contact_time"] >= 0.01, completed
    assert "before the steepest rise" in completed[0].message


def _rig_session_table(tmp_path, seed: int, index: int):
    """bench/rigs.py's rig ``seed:index`` written and run through the library: its impacts.csv (by impact id) and
    the truth of each impact."""
    import pandas as pd

    rigs, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(seed, index)
    raw, results = tmp_path / "raw", tmp_path / "results"
    truths = {t.impact_id: t for t in rig_zoo.write_session(rig, raw)}
    rigs.run_library(raw, results, rig.session_id)
    return pd.read_csv(results / rig.session_id / "impacts.csv").set_index("impact_id"), truths


def _rig_impacts(tmp_path, seed: int, index: int, wanted):
    """bench/rigs.py's rig ``seed:index`` written, and the impacts ``wanted`` processed alone: {id: (result, truth)}."""
    from ballimpact import processing
    from ballimpact.session import read_session

    _, rig_zoo = _rigs()
    rig = rig_zoo.draw_rig(seed, index)
    truths = {t.impact_id: t for t in rig_zoo.write_session(rig, tmp_path)}
    session = read_session(tmp_path / rig.session_id)
    return {row.impact_id: (processing.process_impact(row, session), truths[row.impact_id])
            for row in session.impacts if row.impact_id in wanted}


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_record_of_one_mains_period_keeps_its_tcs_with_the_hums_prior(tmp_path):
    """Rig 9:013 (18 ms records at 125 kHz under 8 mV of 60 Hz hum with harmonics 2-5, the time constant and a
    24 kHz plate stated; held-out rig seed 9, looked at since): the five hum components fitted around a window
    that had grown swung by volts under it, and the window never settled (0b80251). The hum's prior in the
    baseline fit (signal.baseline) keeps each TC within 0.5 % of the truth."""
    for impact_id, (result, truth) in _rig_impacts(tmp_path, 9, 13, ("ball2-001", "ball1-002", "ball1-017")).items():
        error = result.contact_time_ms / (1e3 * truth.contact_time_s) - 1.0
        assert result.contact_time_status == "ok", (impact_id, result.reason)
        assert abs(error) <= 0.005, (impact_id, error)


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_decay_not_measurable_leaves_no_level_after_a_short_records_contact(tmp_path):
    """Rig 9:162 (21 ms records at 130 kHz, the amplifier's time constant of 12 s not stated; held-out rig seed
    9, looked at since): the undershoot's kappa, fitted with the hum over 14 ms after the contact, came out below
    zero and was not applied, but the baseline it was fitted with stayed, and put the record after the contact
    above zero: the window ran to the record's end, two clean impacts were excluded as truncated and the others'
    windows never settled (0b80251). The baseline is fitted again without the decay then, and where the kappa
    flips with each window it is left out (signal.window): each TC within 0.5 % of the truth."""
    got = _rig_impacts(tmp_path, 9, 162, ("ball1-003", "ball3-012", "ball3-014"))
    for impact_id, (result, truth) in got.items():
        error = result.contact_time_ms / (1e3 * truth.contact_time_s) - 1.0
        assert result.status != "excluded" and result.contact_time_status == "ok", (impact_id, result.reason)
        assert abs(error) <= 0.005, (impact_id, error)


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_stated_plate_not_undone_says_what_its_sensed_ends_gave(tmp_path):
    """Rig 1001:012 (a 1.18 kHz plate, its resonance stated, at 31 kHz): not undone; its contact's ends, refused as
    too far from the contact found on 9b72d8a, are fitted through the plate since it is measured in the trace's
    free ringing (e2e7d03). TC stays withheld, its budget just above the tolerance, and the reason says why: the
    undoing refused, the ends fitted through the plate with the bound they charge, TC's expanded uncertainty."""
    result, j = _rig_impacts(tmp_path, 1001, 12, ("ball2-003",))["ball2-003"]
    assert result.contact_time_status == "withheld"
    assert re.search(r"not undone: .*; its contact's ends fitted through the plate in the sensed force instead \(TC "
                     r"moves by up to [\d.]+ %", result.reason), result.reason
    assert "contact time uncertain: expanded uncertainty" in result.reason


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_impacts_whose_hum_their_record_did_not_resolve_use_the_sessions_mains(tmp_path):
    """Rig 9:186 (60 Hz hum of 5 mV, no key stated; held-out rig seed 9, looked at since): four clean impacts of 24
    could not tell 50 from 60 Hz on their own quiet record, and their TC was withheld (mains_unresolved) while
    the other twenty found 60 Hz (5578e54). Processed again with the mains the session identified, each TC is
    kept and within 0.5 % of the truth (ballimpact.session_plate.session_mains)."""
    table, truths = _rig_session_table(tmp_path, 9, 186)
    for impact_id in ("ball3-006", "ball3-013", "ball1-022", "ball1-028"):
        row = table.loc[impact_id]
        assert row["contact_time_status"] == "ok" and "mains_unresolved" not in str(row["reason_code"]), impact_id
        assert abs(row["contact_time_ms"] / (1e3 * truths[impact_id].contact_time_s) - 1.0) <= 0.005, impact_id


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_the_sessions_plate_charges_its_own_damping_ratio_interval(tmp_path):
    """Rig 9:089 (a 1.24 kHz plate, damping ratio 0.118, at 34 kHz, nothing stated; held-out rig seed 9, looked at
    since): the session identifies the damping ratio to 0.7 %, yet the contact's ends fitted through its plate
    charged TC for 25 % off (a stated plate's), and 2 of 36 clean impacts were used (5578e54). Charged twice its
    interval, at least 10 % (session_plate.session_plate_uncertainty), ten more are, each TC within 1 % of the
    truth; no TC ok is wrong."""
    table, truths = _rig_session_table(tmp_path, 9, 89)
    for impact_id in ("ball1-003", "ball2-004", "ball1-008", "ball1-014", "ball2-021", "ball1-038"):
        assert table.loc[impact_id, "contact_time_status"] == "ok", impact_id
    for impact_id, r in table.iterrows():
        t = truths[impact_id]
        if r["contact_time_status"] == "ok" and not t.fault:
            assert abs(r["contact_time_ms"] / (1e3 * t.contact_time_s) - 1.0) <= 0.01, impact_id
