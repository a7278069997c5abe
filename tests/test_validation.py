"""Tests of session validation (file-level checks of a raw session folder)."""

import hashlib

import numpy as np
import pytest
import yaml
from nptdms import ChannelObject, GroupObject, TdmsWriter

from ballimpact.session import SessionError
from ballimpact.validation import ValidationReport, format_validation, validate_session

RATE_HZ = 66964.3  # [Hz] session default
TDMS_RATE_HZ = 100000.0  # [Hz]
HEADER = "impact_id,ball,trace,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s,mass_g,note"
GATES = "0.0,0.004,0.010,0.0145"

META = {
    "session_id": "s1",
    "date": "2026-11-21",
    "plate": {"polarity": 1},
    "daq": {"sample_rate_hz": RATE_HZ, "adc_range_v": [-10.0, 10.0]},
    "gates": {"spacing_m": 0.1, "resolution_s": 1.0e-6},
    "balls": {"pressurised": {"mass_g": 57.7}, "pressureless": {"mass_g": 57.0}},
}


def voltage(n=300):
    return np.where((np.arange(n) > 100) & (np.arange(n) < 150), 1.0, 0.0) + 0.01


def write_csv_trace(path, *, header="", time=False, body=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    v = voltage()
    if body is None:
        if time:
            body = "time_s,voltage_V\n" + "\n".join(f"{i / RATE_HZ!r},{x!r}" for i, x in enumerate(v.tolist()))
        else:
            body = "voltage_V\n" + "\n".join(repr(x) for x in v.tolist())
    path.write_text(header + body + "\n")


def write_tdms_trace(path, rate_hz=TDMS_RATE_HZ):
    path.parent.mkdir(parents=True, exist_ok=True)
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(
            [GroupObject("Impact"), ChannelObject("Impact", "voltage", voltage(), properties={"wf_increment": 1 / rate_hz})]
        )


def make_session(root, rows, meta=None):
    """Session folder s1 with the given impacts.csv rows (traces written by the caller)."""
    folder = root / "s1"
    (folder / "traces").mkdir(parents=True, exist_ok=True)
    (folder / "session.yaml").write_text(yaml.safe_dump(meta or META, sort_keys=False))
    (folder / "impacts.csv").write_text(HEADER + "\n" + "\n".join(rows) + "\n")
    return folder


def clean_session(root):
    folder = make_session(
        root,
        [
            f"p1,pressurised,traces/p1.csv,{GATES},,",
            f"p2,pressurised,traces/p2.csv,{GATES},,",
            f"p3,pressurised,traces/p3.tdms,{GATES},,",
            f"n1,pressureless,traces/n1.csv,{GATES},,",
        ],
    )
    write_csv_trace(folder / "traces" / "p1.csv")  # session default rate
    write_csv_trace(folder / "traces" / "p2.csv", header=f"# sample_rate_hz: {RATE_HZ}\n# units: V\n")
    write_tdms_trace(folder / "traces" / "p3.tdms")
    write_csv_trace(folder / "traces" / "n1.csv", time=True)
    return folder


def test_clean_session(tmp_path):
    report = validate_session(clean_session(tmp_path))
    assert isinstance(report, ValidationReport)
    assert report.session_id == "s1"
    assert report.n_impacts == 4
    assert report.impacts_per_ball == {"pressurised": 3, "pressureless": 1}
    assert set(report.sample_rates_hz) >= {RATE_HZ, TDMS_RATE_HZ}
    assert sum(report.sample_rates_hz.values()) == 4
    assert report.trace_formats == {"csv": 3, "tdms": 1}
    assert report.sample_rate_sources == {"header": 1, "session": 1, "time_s": 1, "wf_increment": 1}
    assert report.problems == []
    assert report.ok
    text = format_validation(report)
    assert text.splitlines()[0] == "Session s1: 4 impacts"
    assert "pressurised: 3, pressureless: 1" in text
    assert "66964.3 Hz" in text and "100000 Hz: 1" in text
    assert "csv: 3, tdms: 1" in text
    assert "Problems: none" in text
    # p3's own 100 kHz disagrees with session.yaml and the other three traces (raw-format v1.2: suspect)
    assert [w.split(":")[0] for w in report.warnings] == ["p3"], report.warnings
    assert text.splitlines()[-1] == "Verdict: OK, all 4 impacts passed the file-level checks; 1 warning(s)"


def faulty_session(root):
    folder = make_session(
        root,
        [
            f"ok1,pressurised,traces/ok1.csv,{GATES},,",
            "gap,pressurised,traces/gap.csv,0.0,,0.010,0.0145,,",
            f"lost,pressureless,traces/lost.csv,{GATES},,",
            f"bad,pressureless,traces/bad.csv,{GATES},,",
            f"mv,pressureless,traces/mv.csv,{GATES},,",
            f"esc,pressureless,../s1.csv,{GATES},,",
            f"short,pressurised,traces/short.csv,{GATES},,",
            f"ext,pressurised,traces/ext.txt,{GATES},,",
        ],
    )
    traces = folder / "traces"
    write_csv_trace(traces / "ok1.csv")
    write_csv_trace(traces / "gap.csv")
    write_csv_trace(traces / "bad.csv", body="voltage_V\n0.1\n0.2\nspike!\n" + "0.1\n" * 200)
    write_csv_trace(traces / "mv.csv", header="# units: mV\n")
    write_csv_trace(traces / "short.csv", body="voltage_V\n" + "0.1\n" * 20)
    (traces / "ext.txt").write_text("voltage_V\n0.1\n")
    (root / "s1.csv").write_text("voltage_V\n0.1\n")
    return folder


def test_problems_by_impact(tmp_path):
    folder = faulty_session(tmp_path)
    report = validate_session(folder)
    assert report.n_impacts == 8
    problems = dict(report.problems)
    assert len(problems) == len(report.problems) == 7  # one problem each
    assert "ok1" not in problems
    assert problems["gap"] == "missing gate time gate_in_2_s"
    assert problems["lost"] == "trace file not found: traces/lost.csv"
    assert problems["bad"] == f"{folder}/traces/bad.csv: line 4: non-numeric value 'spike!'"
    assert problems["mv"] == f"{folder}/traces/mv.csv: line 1: units must be 'V', got 'mV'"
    assert problems["esc"] == "trace path escapes the session folder: ../s1.csv"
    assert problems["short"].endswith("short.csv: truncated trace: only 20 samples (at least 100 required)")
    assert problems["ext"].endswith("ext.txt: unknown trace file extension '.txt' (expected .csv, .tdms, .lvm)")
    assert report.trace_formats == {"csv": 2}  # ok1 and gap were read
    assert report.impacts_with_problems == ["gap", "lost", "bad", "mv", "esc", "short", "ext"]
    assert not report.ok

    text = format_validation(report)
    lines = text.splitlines()
    assert "Problems (7):" in lines
    for impact_id, message in report.problems:
        assert f"  {impact_id}: {message}" in lines
    assert lines[-1] == "Verdict: PROBLEMS, 7 of 8 impacts will be excluded; 1 can be processed"


def test_several_problems_one_impact_counted_once(tmp_path):
    folder = make_session(tmp_path, ["x1,pressurised,traces/none.csv,0.0,,,0.0145,abc,"])
    report = validate_session(folder)
    assert [p[0] for p in report.problems] == ["x1"] * 4
    assert [p[1] for p in report.problems] == [
        "missing gate time gate_in_2_s",
        "missing gate time gate_out_2_s",
        "non-numeric mass_g: 'abc'",
        "trace file not found: traces/none.csv",
    ]
    assert format_validation(report).splitlines()[-1] == "Verdict: NOTHING TO PROCESS, all 1 impacts will be excluded"


def test_shared_trace_and_suspect_mass_are_warnings(tmp_path):
    meta = {**META, "balls": {"pressurised": {"mass_g": 80.0}, "pressureless": {"mass_g": 57.0}}}
    folder = make_session(
        tmp_path,
        [f"a,pressurised,traces/a.csv,{GATES},,", f"b,pressurised,traces/a.csv,{GATES},,"],
        meta=meta,
    )
    write_csv_trace(folder / "traces" / "a.csv")
    report = validate_session(folder)
    assert report.problems == []
    assert any("80 g" in w for w in report.warnings)
    assert any("trace traces/a.csv is also the trace of impact a" in w for w in report.warnings)
    text = format_validation(report)
    assert "Warnings (2):" in text
    assert text.splitlines()[-1].endswith("; 2 warning(s)")


def test_session_error_propagates(tmp_path):
    folder = make_session(tmp_path, [f"a,tennis,traces/a.csv,{GATES},,"])
    with pytest.raises(SessionError, match=r"s1/impacts\.csv: line 2: ball 'tennis' is not defined"):
        validate_session(folder)


def test_validation_does_not_modify_folder(tmp_path):
    folder = faulty_session(tmp_path)
    clean_session(tmp_path / "clean")

    def snapshot(root):
        return {
            str(p.relative_to(root)): (p.stat().st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
            for p in sorted(root.rglob("*"))
        if p.is_file()
        }

    before = snapshot(tmp_path)
    validate_session(folder)
    validate_session(tmp_path / "clean" / "s1")
    assert snapshot(tmp_path) == before


# ------------------------------------------------------------ plausibility checks (issue 14)


def test_gate_times_in_ms_give_speed_problems_and_a_units_hint(tmp_path):
    ms = "0.0,4.0,10.0,14.5"  # the GATES times written in ms: 0.025 m/s instead of 25 m/s
    folder = make_session(tmp_path, [f"a,pressurised,traces/a.csv,{ms},,", f"b,pressurised,traces/a.csv,{ms},,"])
    write_csv_trace(folder / "traces" / "a.csv")
    report = validate_session(folder)
    # 0.1 m / 4 s = 0.025 m/s (COR 4 / 4.5 = 0.889 is plausible): by hand, not by the code under test
    assert [m for i, m in report.problems if i == "a"] == [
        "inbound speed 0.025 m/s from the gate times is outside 2-80 m/s",
    ]
    assert any("are the gate times in ms instead of s? in s the speeds would be 25 m/s" in c
               for c in report.causes), report.causes


def test_the_units_hint_comes_before_the_per_impact_lines(tmp_path):
    """Issue 49: the gate-times-in-ms hint came last, after every per-impact speed line."""
    ms = "0.0,4.0,10.0,14.5"
    rows = [f"i{k},pressurised,traces/a.csv,{ms},," for k in range(8)]
    folder = make_session(tmp_path, rows)
    write_csv_trace(folder / "traces" / "a.csv")
    lines = format_validation(validate_session(folder)).splitlines()
    hint = next(k for k, line in enumerate(lines) if "gate times in ms instead of s" in line)
    first_problem = next(k for k, line in enumerate(lines) if "from the gate times is outside" in line)
    assert hint < first_problem, lines
    assert sum("from the gate times is outside" in line for line in lines) == 8  # one line per impact


@pytest.mark.parametrize(("gates", "expected"), [
    ("0.0,0.0625,0.2,0.3", ["inbound speed 1.6 m/s from the gate times is outside 2-80 m/s"]),  # 0.1 / 0.0625
    ("0.0,0.05,0.2,0.3", []),  # 2 m/s in, 1 m/s out (COR 0.5): processing takes it, so must validate
    ("0.0,0.004,0.2,0.4", ["COR 0.02 from the gate times (rebound 0.5 m/s) is outside 0.05-1"]),  # 25 in, 0.5 out
])
def test_validate_judges_speeds_with_the_bounds_processing_applies(gates, expected):
    """Issue 49: validate took 1-80 m/s for both speeds, processing 2-80 m/s inbound and a COR of 0.05-1."""
    from ballimpact.validation import gate_speed_problems

    assert gate_speed_problems(0.1, [float(g) for g in gates.split(",")]) == expected


@pytest.mark.parametrize(("rate", "expected"), [
    (50000.0, "daq.sample_rate_hz = 50000 Hz disagrees with the rate every trace gives itself (mostly 66964.3 Hz"),
    (66.9643, "daq.sample_rate_hz = 66.9643 Hz is outside the plausible 1000-1e+07 Hz (in kHz?"),
])
def test_sample_rate_is_compared_with_the_trace_headers(tmp_path, rate, expected):
    meta = {**META, "daq": {"sample_rate_hz": rate, "adc_range_v": [-10.0, 10.0]}}
    folder = make_session(tmp_path, [f"a,pressurised,traces/a.csv,{GATES},,"], meta=meta)
    write_csv_trace(folder / "traces" / "a.csv", header=f"# sample_rate_hz: {RATE_HZ}\n")
    report = validate_session(folder)
    assert any(expected in w for w in report.warnings), report.warnings


def test_sample_rate_agreeing_with_a_header_is_not_warned_about(tmp_path):
    folder = make_session(tmp_path, [f"a,pressurised,traces/a.csv,{GATES},,"])
    write_csv_trace(folder / "traces" / "a.csv", header=f"# sample_rate_hz: {RATE_HZ}\n")
    assert validate_session(folder).warnings == []


@pytest.mark.parametrize(("slow_rate", "bandwidth_hz", "warned"), [
    (25000.0, None, True),  # a trace's own rate below 60 kHz, no key: a plate above 12.5 kHz may alias
    (25000.0, 12000.0, False),  # the key rules it out (or refuses the rig, in processing)
    (RATE_HZ, None, False),  # every trace at 67 kHz: twice the 30 kHz plates
])
def test_slow_trace_rates_without_the_bandwidth_are_warned_of_aliasing(tmp_path, slow_rate, bandwidth_hz, warned):
    daq = {"sample_rate_hz": RATE_HZ, "adc_range_v": [-10.0, 10.0]}
    if bandwidth_hz is not None:
        daq["bandwidth_hz"] = bandwidth_hz
    folder = make_session(tmp_path, [f"a,pressurised,traces/a.csv,{GATES},,", f"b,pressurised,traces/b.csv,{GATES},,"],
                          meta={**META, "daq": daq})
    write_csv_trace(folder / "traces" / "a.csv", header=f"# sample_rate_hz: {RATE_HZ}\n")
    write_csv_trace(folder / "traces" / "b.csv", header=f"# sample_rate_hz: {slow_rate}\n")
    for read_traces in (True, False):
        aliasing = [w for w in validate_session(folder, read_traces=read_traces).warnings if "would alias" in w]
        if warned:
            assert len(aliasing) == 1, aliasing
            assert aliasing[0].startswith("1 trace(s) sampled below 60 kHz by their own rate, and daq.bandwidth_hz "
                                          "not given: at 25 kHz a plate resonance above 12.5 kHz"), aliasing[0]
        else:
            assert aliasing == []


@pytest.mark.parametrize("polarity", [1, -1])
def test_polarity_is_guessed_from_the_traces(tmp_path, polarity):
    meta = {**META, "plate": {"polarity": polarity}}
    folder = make_session(tmp_path, [f"a,pressurised,traces/a.csv,{GATES},,"], meta=meta)
    # a negative pulse: -1 V for 50 samples on a 0.01 V baseline
    write_csv_trace(folder / "traces" / "a.csv", body="voltage_V\n" + "\n".join(repr(-x) for x in voltage().tolist()))
    report = validate_session(folder)
    if polarity == 1:
        assert report.causes == ["1 of 1 traces show a negative pulse but plate.polarity is +1: is plate.polarity "
                                 "-1? (each such impact is excluded)"]
        assert report.problems == [("a", "pulse is negative: plate.polarity is +1")]
    else:
        assert report.causes == [] and report.problems == []


def test_validate_lists_every_session_level_problem(tmp_path):
    meta = {**META, "date": "yesterday", "gates": {"spacing_m": -0.1, "resolution_s": 1e-6}}
    folder = make_session(tmp_path, [f"a,tennis,traces/a.csv,{GATES},,"], meta=meta)
    with pytest.raises(SessionError) as info:
        validate_session(folder)
    assert len(info.value.problems) == 3
    assert [k for k in ("key 'date'", "key 'gates.spacing_m'", "ball 'tennis' is not defined")
            if any(k in p for p in info.value.problems)] == ["key 'date'", "key 'gates.spacing_m'",
                                                                "ball 'tennis' is not defined"]


# ------------------------------------------------------------ a session made by hand (issue 49)


@pytest.mark.parametrize("read_traces", [True, False])
def test_a_trace_rate_unlike_the_sessions_is_named(tmp_path, read_traces):
    """Issue 49: one trace's header said 25 kHz, session.yaml and the other traces 50 kHz; validate only listed the
    rates. The warning names the impact, its file, both rates and what the wrong one does to TC and kCAL."""
    from handmade import write_session

    folder = write_session(tmp_path / "hand")
    report = validate_session(folder, read_traces=read_traces)
    odd = [w for w in report.warnings if w.startswith("shot04:")]
    assert odd == ["shot04: trace traces/shot04.csv gives its own sample rate as 25000 Hz, but daq.sample_rate_hz and "
                   "the session's other 6 traces say 50000 Hz: read at 25000 Hz, its contact time comes out x2 and "
                   "its kCAL x0.5 of what 50000 Hz gives; correct the file's sample rate if it is wrong"], report.warnings
    assert not [w for w in report.warnings if w.startswith(("shot01", "shot02", "shot03", "shot05"))]


def test_a_hand_made_session_with_tdms_and_lvm_validates(tmp_path):
    """Issue 49: a session of CSV, DAQmx-style TDMS and LabVIEW LVM traces reads without a problem."""
    from handmade import write_session

    report = validate_session(write_session(tmp_path / "hand"))
    assert report.problems == []
    assert report.trace_formats == {"csv": 4, "lvm": 1, "tdms": 2}
    assert report.sample_rates_hz == {25000.0: 1, 50000.0: 6}


def test_validate_verdict_agrees_with_processing_on_polarity(tmp_path):
    """Issue 49: validate warned that every pulse was positive with plate.polarity -1, yet its verdict said 7 can be
    processed (exit 0); the run excluded every one. Each impact validate counts out, processing excludes."""
    import subprocess
    import sys
    import warnings
    from pathlib import Path

    from handmade import HandmadeSpec, write_session

    from ballimpact.processing import process_impact
    from ballimpact.session import read_session

    folder = write_session(tmp_path / "hand", HandmadeSpec(polarity_yaml=-1, header_rates_hz={}))
    report = validate_session(folder)
    assert report.impacts_with_problems == [f"shot{k:02d}" for k in range(1, 8)]
    assert format_validation(report).splitlines()[-1].startswith(
        "Verdict: NOTHING TO PROCESS, all 7 impacts will be excluded")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        session = read_session(folder)
        processed = {row.impact_id: process_impact(row, session) for row in session.impacts}
    for impact_id, message in report.problems:
        assert processed[impact_id].status == "excluded" and message in processed[impact_id].reason
    cli = Path(sys.executable).parent / "ballimpact"
    assert subprocess.run([str(cli), "validate", str(folder)], capture_output=True).returncode == 1
