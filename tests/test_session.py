"""Tests of the raw session reader (session.yaml + impacts.csv)."""

import copy
import hashlib
import math
import os
import re
import warnings

import numpy as np
import pytest
import yaml

from ballimpact.problems import Problem, ProblemKind, kind_of_message
from ballimpact.session import (
    BallType,
    ImpactRow,
    Session,
    SessionError,
    SessionMeta,
    SessionWarning,
    file_sha256,
    read_session,
)

HEADER = "impact_id,ball,trace,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s,mass_g,note"

BASE_META = {
    "session_id": "s1",
    "date": "2026-11-21",
    "operator": "A. Tester",
    "description": "unit test session",
    "plate": {"polarity": 1},
    "daq": {"sample_rate_hz": 66964.3, "adc_range_v": [-10.0, 10.0]},
    "gates": {"spacing_m": 0.1, "resolution_s": 1.0e-6},
    "balls": {
        "pressurised": {"label": "Ball 1: pressurised", "mass_g": 57.7, "diameter_mm": 65.4, "kb0_kN_m": 21},
        "pressureless": {"mass_g": 57.0},
    },
}

GOOD_ROWS = [
    "b1-01,pressurised,traces/b1-01.csv,0.0,0.004,0.010,0.0145,,first",
    "b1-02,pressurised,traces/b1-02.csv,1.0,1.004,1.010,1.0145,58.1,",
    "b2-01,pressureless,traces/b2-01.csv,2.0,2.004,2.010,2.0145,,",
]


def write_trace(path, n=200):
    """A small valid CSV trace."""
    path.parent.mkdir(parents=True, exist_ok=True)
    values = np.sin(np.arange(n) / 10.0)
    path.write_text("# units: V\nvoltage_V\n" + "\n".join(repr(float(v)) for v in values) + "\n")


def make_session(root, *, session_id="s1", meta=None, yaml_text=None, rows=None, csv_text=None, traces=True):
    """Build a session folder under root and return its path."""
    folder = root / session_id
    folder.mkdir(parents=True, exist_ok=True)
    if yaml_text is None:
        yaml_text = yaml.safe_dump(BASE_META if meta is None else meta, sort_keys=False)
    if yaml_text is not False:
        (folder / "session.yaml").write_text(yaml_text)
    if csv_text is None:
        csv_text = HEADER + "\n" + "\n".join(GOOD_ROWS if rows is None else rows) + "\n"
    if csv_text is not False:
        if isinstance(csv_text, bytes):
            (folder / "impacts.csv").write_bytes(csv_text)
        else:
            (folder / "impacts.csv").write_text(csv_text)
    if traces:
        for name in ("b1-01", "b1-02", "b2-01", "b2-02", "x"):
            write_trace(folder / "traces" / f"{name}.csv")
    return folder


def patched(path, value):
    """BASE_META with the dotted key set to value (or removed when value is DELETE)."""
    meta = copy.deepcopy(BASE_META)
    *parents, last = path.split(".")
    node = meta
    for key in parents:
        node = node[key]
    if value is DELETE:
        del node[last]
    else:
        node[last] = value
    return meta


DELETE = object()


def row_with(**cells):
    """One impacts.csv row (b1-01 defaults) with some cells replaced."""
    base = dict(
        impact_id="b1-01",
        ball="pressurised",
        trace="traces/b1-01.csv",
        gate_in_1_s="0.0",
        gate_in_2_s="0.004",
        gate_out_2_s="0.010",
        gate_out_1_s="0.0145",
        mass_g="",
        note="",
    )
    base.update(cells)
    return ",".join(base[c] for c in HEADER.split(","))


# ----------------------------------------------------------------- good session


def test_read_good_session(tmp_path):
    folder = make_session(tmp_path)
    session = read_session(folder)
    assert isinstance(session, Session)
    meta = session.meta
    assert isinstance(meta, SessionMeta)
    assert meta.session_id == "s1"
    assert meta.date == "2026-11-21"
    assert meta.operator == "A. Tester"
    assert meta.polarity == 1
    assert meta.sample_rate_hz == pytest.approx(66964.3, rel=1e-12)
    assert meta.adc_range_v == (-10.0, 10.0)
    assert meta.gate_spacing_m == pytest.approx(0.1, rel=1e-12)
    assert meta.gate_resolution_s == pytest.approx(1e-6, rel=1e-12)
    assert meta.mains_hz is None  # v1.1: absent = find it in each trace
    assert meta.time_constant_s is None
    assert meta.bandwidth_hz is None  # absent: unknown (at 67 kHz no v1.1 plate aliases: processing.aliasing_ruled_out)
    assert meta.synthetic is False
    assert list(meta.balls) == ["pressurised", "pressureless"]
    ball = meta.balls["pressurised"]
    assert isinstance(ball, BallType)
    assert ball.label == "Ball 1: pressurised"
    np.testing.assert_allclose(ball.mass_kg, 0.0577, rtol=1e-12)
    np.testing.assert_allclose(ball.diameter_m, 0.0654, rtol=1e-12)
    np.testing.assert_allclose(ball.kb0_N_m, 21000.0, rtol=1e-12)
    plain = meta.balls["pressureless"]
    assert plain.label == "pressureless"
    assert plain.diameter_m is None and plain.kb0_N_m is None
    assert meta.raw["balls"]["pressurised"]["mass_g"] == 57.7

    assert [r.impact_id for r in session.impacts] == ["b1-01", "b1-02", "b2-01"]
    first = session.impacts[0]
    assert isinstance(first, ImpactRow)
    assert first.line == 2 and session.impacts[2].line == 4
    assert first.problems == []
    assert first.note == "first"
    assert (first.gate_in_1_s, first.gate_in_2_s, first.gate_out_2_s, first.gate_out_1_s) == (0.0, 0.004, 0.010, 0.0145)
    np.testing.assert_allclose(first.mass_kg, 0.0577, rtol=1e-12)
    np.testing.assert_allclose(session.impacts[1].mass_kg, 0.0581, rtol=1e-12)  # row override
    np.testing.assert_allclose(session.impacts[2].mass_kg, 0.0570, rtol=1e-12)
    assert session.trace_path(first) == folder / "traces" / "b1-01.csv"


def test_optional_keys_and_unknown_keys_kept(tmp_path):
    meta = copy.deepcopy(BASE_META)
    meta["daq"]["mains_hz"] = 60
    meta["daq"]["bandwidth_hz"] = 20000
    meta["plate"]["time_constant_s"] = 0.02
    meta["synthetic"] = True
    meta["rig"] = {"plate": "Kistler 9281", "notes": [1, 2]}
    with pytest.warns(SessionWarning, match=r"unknown key\(s\) 'rig\.plate', 'rig\.notes'"):  # rig: v1.1 section
        session = read_session(make_session(tmp_path, meta=meta))
    assert session.meta.mains_hz == 60.0
    assert session.meta.time_constant_s == 0.02
    assert session.meta.bandwidth_hz == 20000.0
    assert session.meta.synthetic is True
    assert session.meta.raw["rig"] == {"plate": "Kistler 9281", "notes": [1, 2]}


@pytest.mark.parametrize("rate_hz, bandwidth_hz, warned", [
    (50_000.0, None, True), (20_000.0, None, True), (50_000.0, 20_000.0, False), (50_000.0, 40_000.0, False),
    (60_000.0, None, False), (66_964.3, None, False),
])
def test_slow_daq_without_its_bandwidth_is_warned_of_aliasing(tmp_path, rate_hz, bandwidth_hz, warned):
    import warnings

    meta = copy.deepcopy(BASE_META)
    meta["daq"]["sample_rate_hz"] = rate_hz
    if bandwidth_hz is not None:
        meta["daq"]["bandwidth_hz"] = bandwidth_hz
    folder = make_session(tmp_path, meta=meta)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        session = read_session(folder)
    aliasing = [str(w.message) for w in caught if "would alias" in str(w.message)]
    assert bool(aliasing) is warned, aliasing
    if warned:
        assert issubclass(caught[0].category, SessionWarning)
        assert re.search(rf"session\.yaml: daq\.bandwidth_hz not given: at {rate_hz / 1e3:g} kHz a plate "
                         rf"resonance above {rate_hz / 2e3:g} kHz would alias", aliasing[0]), aliasing[0]
    assert session.meta.bandwidth_hz == bandwidth_hz


def test_bandwidth_warning_is_short_and_says_where_to_find_the_number(tmp_path):
    """Issue 49: the daq.bandwidth_hz warning took 60 words; it must be short and name the data sheet and the tap
    test (what a lab reads the number from)."""
    import warnings

    meta = copy.deepcopy(BASE_META)
    meta["daq"]["sample_rate_hz"] = 50_000.0
    folder = make_session(tmp_path, meta=meta)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_session(folder)
    (message,) = [str(w.message).split(": ", 1)[1] for w in caught if "bandwidth_hz" in str(w.message)]
    assert len(message.split()) <= 35, (len(message.split()), message)
    assert "data sheet" in message and "tap test" in message, message
    assert "25 kHz" in message, message  # what it risks: a resonance above half the 50 kHz


def test_unquoted_date_and_exponent_without_dot(tmp_path):
    # YAML 1.1 reads `1e-6` as a string and `2026-11-21` as a date: both must work.
    text = yaml.safe_dump(patched("gates.resolution_s", DELETE), sort_keys=False)
    text = text.replace("date: '2026-11-21'", "date: 2026-11-21")
    text = text.replace("gates:\n", "gates:\n  resolution_s: 1e-6\n")
    session = read_session(make_session(tmp_path, yaml_text=text))
    assert session.meta.date == "2026-11-21"
    assert session.meta.gate_resolution_s == pytest.approx(1e-6, rel=1e-12)


def test_negative_polarity(tmp_path):
    session = read_session(make_session(tmp_path, meta=patched("plate.polarity", -1)))
    assert session.meta.polarity == -1


def test_meta_is_frozen(tmp_path):
    session = read_session(make_session(tmp_path))
    with pytest.raises(AttributeError):
        session.meta.polarity = -1


def test_crlf_bom_quoted_note_and_blank_lines(tmp_path):
    rows = ['b1-01,pressurised,traces/b1-01.csv,0.0,0.004,0.010,0.0145,,"note, with comma"', "", GOOD_ROWS[2]]
    text = "\ufeff" + "\r\n".join([HEADER, *rows]) + "\r\n\r\n"
    session = read_session(make_session(tmp_path, csv_text=text.encode("utf-8")))
    assert [r.impact_id for r in session.impacts] == ["b1-01", "b2-01"]
    assert session.impacts[0].note == "note, with comma"
    assert session.impacts[1].line == 4


def test_optional_columns_absent_and_reordered(tmp_path):
    text = "ball,impact_id,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s,trace\n"
    text += "pressureless,b2-01,0,0.004,0.01,0.0145,traces/b2-01.csv\n"
    session = read_session(make_session(tmp_path, csv_text=text))
    row = session.impacts[0]
    assert (row.impact_id, row.ball, row.note) == ("b2-01", "pressureless", "")
    np.testing.assert_allclose(row.mass_kg, 0.057, rtol=1e-12)


def test_mass_outside_typical_range_warns(tmp_path):
    with pytest.warns(SessionWarning, match=r"session\.yaml: key 'balls\.pressurised\.mass_g' = 90 g"):
        read_session(make_session(tmp_path, meta=patched("balls.pressurised.mass_g", 90)))


def test_mass_override_outside_typical_range_warns(tmp_path):
    with pytest.warns(SessionWarning, match=r"impacts\.csv: line 2: mass_g 30"):
        session = read_session(make_session(tmp_path, rows=[row_with(mass_g="30")]))
    assert session.impacts[0].problems == []
    np.testing.assert_allclose(session.impacts[0].mass_kg, 0.030, rtol=1e-12)


def test_unknown_ball_key_warns(tmp_path):
    with pytest.warns(SessionWarning, match=r"balls\.pressurised\.kb0"):
        read_session(make_session(tmp_path, meta=patched("balls.pressurised.kb0", 21)))


# ---------------------------------------------------------- session-level faults

REQUIRED_KEYS = [
    "session_id",
    "date",
    "plate.polarity",
    "daq.sample_rate_hz",
    "daq.adc_range_v",
    "gates.spacing_m",
    "gates.resolution_s",
    "balls",
    "balls.pressureless.mass_g",
]


@pytest.mark.parametrize("key", REQUIRED_KEYS)
def test_missing_required_key(tmp_path, key):
    folder = make_session(tmp_path, meta=patched(key, DELETE))
    with pytest.raises(SessionError, match=rf"s1/session\.yaml: missing required key '{re.escape(key)}'$"):
        read_session(folder)


@pytest.mark.parametrize("section", ["plate", "daq", "gates"])
def test_missing_section(tmp_path, section):
    folder = make_session(tmp_path, meta=patched(section, DELETE))
    with pytest.raises(SessionError, match=rf"session\.yaml: missing required key '{section}'"):
        read_session(folder)


BAD_VALUES = [
    ("plate.polarity", 2, r"key 'plate\.polarity' must be 1 or -1, got 2"),
    ("plate.polarity", 0, r"key 'plate\.polarity' must be 1 or -1, got 0"),
    ("plate.polarity", "up", r"key 'plate\.polarity' must be 1 or -1, got 'up'"),
    ("daq.sample_rate_hz", 0, r"key 'daq\.sample_rate_hz' must be a positive number, got 0"),
    ("daq.sample_rate_hz", -100.0, r"key 'daq\.sample_rate_hz' must be a positive number, got -100\.0"),
    ("daq.sample_rate_hz", "fast", r"key 'daq\.sample_rate_hz' must be a positive number, got 'fast'"),
    ("daq.sample_rate_hz", True, r"key 'daq\.sample_rate_hz' must be a positive number, got True"),
    ("daq.adc_range_v", [10.0, -10.0], r"key 'daq\.adc_range_v' must be two numbers \[lo, hi\] with lo < hi"),
    ("daq.adc_range_v", [1.0], r"key 'daq\.adc_range_v' must be two numbers"),
    ("daq.adc_range_v", [-1.0, "x"], r"key 'daq\.adc_range_v' must be two numbers"),
    ("daq.adc_range_v", 10, r"key 'daq\.adc_range_v' must be two numbers"),
    ("daq.mains_hz", -50, r"key 'daq\.mains_hz' must be a positive number, got -50"),
    ("daq.bandwidth_hz", 0, r"key 'daq\.bandwidth_hz' must be a positive number, got 0"),
    ("daq.bandwidth_hz", "25 kHz", r"key 'daq\.bandwidth_hz' must be a positive number, got '25 kHz'"),
    ("gates.spacing_m", "abc", r"key 'gates\.spacing_m' must be a positive number, got 'abc'"),
    ("gates.spacing_m", -0.1, r"key 'gates\.spacing_m' must be a positive number, got -0\.1"),
    ("gates.resolution_s", 0, r"key 'gates\.resolution_s' must be a positive number, got 0"),
    ("gates.resolution_s", 0.01, r"key 'gates\.resolution_s' must be much smaller than the gate transit time"),
    ("balls", {}, r"key 'balls' must be a mapping of ball types"),
    ("balls", ["pressurised"], r"key 'balls' must be a mapping of ball types"),
    ("balls.pressurised", 57.7, r"key 'balls\.pressurised' must be a mapping"),
    ("balls.pressurised.mass_g", 0.5, r"key 'balls\.pressurised\.mass_g' must be in \(1, 1000\) g, got 0\.5"),
    ("balls.pressurised.mass_g", 1500, r"key 'balls\.pressurised\.mass_g' must be in \(1, 1000\) g, got 1500"),
    ("balls.pressurised.mass_g", "heavy", r"key 'balls\.pressurised\.mass_g' must be a number, got 'heavy'"),
    ("balls.pressurised.kb0_kN_m", -21, r"key 'balls\.pressurised\.kb0_kN_m' must be a positive number, got -21"),
    ("balls.pressurised.diameter_mm", 0, r"key 'balls\.pressurised\.diameter_mm' must be a positive number, got 0"),
    ("session_id", "s2", r"key 'session_id' is 's2' but the session folder is named 's1'"),
    ("date", "21/11/2026", r"key 'date' must be an ISO date YYYY-MM-DD, got '21/11/2026'"),
    ("date", "2026-13-01", r"key 'date' must be an ISO date YYYY-MM-DD, got '2026-13-01'"),
    ("synthetic", "yes", r"key 'synthetic' must be true or false, got 'yes'"),
]


@pytest.mark.parametrize(("key", "value", "message"), BAD_VALUES)
def test_bad_value(tmp_path, key, value, message):
    folder = make_session(tmp_path, meta=patched(key, value))
    with pytest.raises(SessionError, match=r"s1/session\.yaml: " + message):
        read_session(folder)


def test_example_message_is_exact(tmp_path):
    folder = make_session(tmp_path / "raw", meta=patched("gates.spacing_m", "abc"))
    with pytest.raises(SessionError) as info:
        read_session(folder)
    assert str(info.value) == f"{folder}/session.yaml: key 'gates.spacing_m' must be a positive number, got 'abc'"


@pytest.mark.parametrize(
    ("yaml_text", "message"),
    [
        ("session_id: s1\ndate: [2026\nplate: {polarity: 1}\n", r"session\.yaml: line \d+: invalid YAML: "),
        ("session_id: s1\n  date: x\n", r"session\.yaml: line 2: invalid YAML: "),
        ("- a\n- b\n", r"session\.yaml: top level must be a mapping of keys"),
        ("", r"session\.yaml: file is empty"),
        ("session_id: s1\nsession_id: s1\n", r"session\.yaml: line 2: invalid YAML: duplicate key 'session_id'"),
    ],
)
def test_malformed_yaml(tmp_path, yaml_text, message):
    folder = make_session(tmp_path, yaml_text=yaml_text)
    with pytest.raises(SessionError, match=message) as info:
        read_session(folder)
    assert "\n" not in str(info.value)


def test_missing_session_yaml(tmp_path):
    folder = make_session(tmp_path, yaml_text=False)
    with pytest.raises(SessionError, match=r"s1/session\.yaml: file not found"):
        read_session(folder)


def test_missing_folder(tmp_path):
    with pytest.raises(SessionError, match=r"nope: session folder not found"):
        read_session(tmp_path / "nope")


def test_non_utf8_session_yaml(tmp_path):
    folder = make_session(tmp_path)
    text = (folder / "session.yaml").read_bytes()
    (folder / "session.yaml").write_bytes(text.replace(b"A. Tester", b"A. T\xe9ster"))
    line = text[: text.index(b"A. Tester")].count(b"\n") + 1
    with pytest.raises(SessionError, match=rf"s1/session\.yaml: line {line}: not valid UTF-8 \(byte 0xe9\)"):
        read_session(folder)


def test_missing_impacts_csv(tmp_path):
    folder = make_session(tmp_path, csv_text=False)
    with pytest.raises(SessionError, match=r"s1/impacts\.csv: file not found"):
        read_session(folder)


CSV_FAULTS = [
    ("", r"impacts\.csv: file is empty"),
    ("\n\n", r"impacts\.csv: file is empty"),
    (HEADER + "\n", r"impacts\.csv: no impact rows \(only the header\)"),
    (
        "impact_id,ball,gate_in_1_s,gate_in_2_s,gate_out_2_s\nb1-01,pressurised,0,1,2\n",
        r"impacts\.csv: line 1: missing required column\(s\): trace, gate_out_1_s",
    ),
    (
        HEADER + "\n" + "\n".join(GOOD_ROWS + [row_with(impact_id="b1-02")]) + "\n",
        r"impacts\.csv: line 5: impact_id 'b1-02' duplicates line 3$",
    ),
    (HEADER + "\n" + row_with(impact_id="b 1") + "\n", r"impacts\.csv: line 2: impact_id 'b 1' is not valid"),
    (HEADER + "\n" + row_with(impact_id="b1/01") + "\n", r"impacts\.csv: line 2: impact_id 'b1/01' is not valid"),
    (HEADER + "\n" + GOOD_ROWS[0] + "\n" + row_with(impact_id="") + "\n", r"impacts\.csv: line 3: impact_id '' is not valid"),
    (
        HEADER + "\n" + GOOD_ROWS[0] + "\n" + GOOD_ROWS[1] + "\n" + GOOD_ROWS[2] + "\n"
        + row_with(impact_id="b3-01", ball="pressurized") + "\n",
        r"impacts\.csv: line 5: ball 'pressurized' is not defined in session\.yaml balls "
        r"\(valid: pressurised, pressureless\)$",
    ),
    (HEADER + "\n" + GOOD_ROWS[0] + "\nb1-02,pressurised,traces/b1-02.csv,0,1,2,3\n",
     r"impacts\.csv: line 3: expected 9 fields, got 7"),
    (HEADER + "\n" + GOOD_ROWS[0] + ",extra\n", r"impacts\.csv: line 2: expected 9 fields, got 10"),
    (HEADER + ",note\n" + GOOD_ROWS[0] + ",x\n", r"impacts\.csv: line 1: duplicate column\(s\) in header: note"),
    (HEADER + "\n" + GOOD_ROWS[0] + '\nb1-02,"pressurised"x,t.csv,0,1,2,3,,\n', r"impacts\.csv: line 3: malformed CSV: "),
]


@pytest.mark.parametrize(("csv_text", "message"), CSV_FAULTS)
def test_impacts_csv_fault(tmp_path, csv_text, message):
    folder = make_session(tmp_path, csv_text=csv_text)
    with pytest.raises(SessionError, match=r"s1/" + message) as info:
        read_session(folder)
    assert "\n" not in str(info.value)


def test_non_utf8_impacts_csv(tmp_path):
    data = (HEADER + "\n" + GOOD_ROWS[0] + "\n" + row_with(impact_id="b1-02", note="caf\udce9") + "\n").encode(
        "utf-8", "surrogateescape"
    )
    folder = make_session(tmp_path, csv_text=data)
    with pytest.raises(SessionError, match=r"s1/impacts\.csv: line 3: not valid UTF-8 \(byte 0xe9\)"):
        read_session(folder)


def test_undefined_ball_lists_valid_keys_exactly(tmp_path):
    folder = make_session(tmp_path, rows=[GOOD_ROWS[0], row_with(impact_id="x1", ball="pressurized")])
    with pytest.raises(SessionError) as info:
        read_session(folder)
    assert str(info.value) == (
        f"{folder}/impacts.csv: line 3: ball 'pressurized' is not defined in session.yaml balls "
        "(valid: pressurised, pressureless)"
    )


# ---------------------------------------------------------- impact-level faults

IMPACT_FAULTS = [
    (dict(gate_in_2_s=""), ["missing gate time gate_in_2_s"]),
    (dict(gate_out_1_s="  "), ["missing gate time gate_out_1_s"]),
    (dict(gate_in_1_s="x1"), ["non-numeric gate time gate_in_1_s: 'x1'"]),
    (dict(gate_in_1_s="nan"), ["non-finite gate time gate_in_1_s: 'nan'"]),
    (dict(gate_in_1_s="-0.001"), ["negative gate time gate_in_1_s: -0.001"]),
    (
        dict(gate_in_1_s="0.005"),
        ["gate times out of order: gate_in_1_s (0.005) must be earlier than gate_in_2_s (0.004)"],
    ),
    (
        dict(gate_in_2_s="0.004", gate_out_2_s="0.003", gate_in_1_s="0.001"),
        ["gate times out of order: gate_in_2_s (0.004) must be no later than gate_out_2_s (0.003)"],
    ),
    (
        dict(gate_out_1_s="0.010"),
        ["gate times out of order: gate_out_2_s (0.010) must be earlier than gate_out_1_s (0.010)"],
    ),
    (dict(mass_g="heavy"), ["non-numeric mass_g: 'heavy'"]),
    (dict(mass_g="0"), ["non-positive mass_g: 0"]),
    (dict(mass_g="-57"), ["non-positive mass_g: -57"]),
    (dict(mass_g="1500"), ["implausible mass_g: 1500 (must be in (1, 1000) g)"]),
    (dict(mass_g="inf"), ["non-finite mass_g: 'inf'"]),
    (dict(trace=""), ["missing trace path"]),
    (dict(trace="../x.csv"), ["trace path escapes the session folder: ../x.csv"]),
    (dict(trace="traces/../../x.csv"), ["trace path escapes the session folder: traces/../../x.csv"]),
    (dict(trace="/etc/passwd"), ["trace path escapes the session folder (absolute path): /etc/passwd"]),
    (dict(trace="traces/missing.csv"), ["trace file not found: traces/missing.csv"]),
    (dict(trace="traces"), ["trace path is not a file: traces"]),
    (
        dict(gate_in_2_s="", mass_g="abc", trace="traces/nope.csv"),
        ["missing gate time gate_in_2_s", "non-numeric mass_g: 'abc'", "trace file not found: traces/nope.csv"],
    ),
]


@pytest.mark.parametrize(("cells", "problems"), IMPACT_FAULTS)
def test_impact_level_fault(tmp_path, cells, problems):
    folder = make_session(tmp_path, rows=[GOOD_ROWS[1], row_with(**cells), GOOD_ROWS[2]])
    session = read_session(folder)
    assert [r.impact_id for r in session.impacts] == ["b1-02", "b1-01", "b2-01"]
    faulty = session.impacts[1]
    assert [p.message for p in faulty.problems] == problems
    assert [p.kind for p in faulty.problems] == [kind_of_message(m) for m in problems]
    assert session.impacts[0].problems == [] and session.impacts[2].problems == []
    assert faulty.line == 3


def test_missing_gate_is_nan(tmp_path):
    session = read_session(make_session(tmp_path, rows=[row_with(gate_out_2_s="")]))
    row = session.impacts[0]
    assert math.isnan(row.gate_out_2_s)
    assert row.gate_in_1_s == 0.0 and row.gate_out_1_s == 0.0145


def test_bad_mass_override_gives_nan_mass(tmp_path):
    session = read_session(make_session(tmp_path, rows=[row_with(mass_g="abc")]))
    assert math.isnan(session.impacts[0].mass_kg)


def test_symlink_escaping_session_is_caught(tmp_path):
    outside = tmp_path / "elsewhere" / "t.csv"
    write_trace(outside)
    folder = make_session(tmp_path, rows=[row_with(trace="traces/link.csv")])
    os.symlink(outside, folder / "traces" / "link.csv")
    session = read_session(folder)
    assert session.impacts[0].problems == [
        Problem(ProblemKind.TRACE_PATH_ESCAPES, "trace path escapes the session folder: traces/link.csv")]


def test_backslash_trace_path(tmp_path):
    folder = make_session(tmp_path, rows=[row_with(trace="traces\\b1-01.csv")])
    session = read_session(folder)
    row = session.impacts[0]
    assert row.problems == []
    assert row.trace == "traces\\b1-01.csv"
    assert session.trace_path(row) == folder / "traces" / "b1-01.csv"


# --------------------------------------------------------------- read-only, hash


def snapshot(folder):
    return {
        str(p.relative_to(folder)): (p.stat().st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    } | {"__dirs__": sorted(str(p) for p in folder.rglob("*") if p.is_dir())}


def test_read_session_does_not_modify_folder(tmp_path):
    folder = make_session(tmp_path, rows=GOOD_ROWS + [row_with(impact_id="z1", trace="traces/missing.csv")])
    before = snapshot(folder)
    dir_mtime = folder.stat().st_mtime_ns
    read_session(folder)
    assert snapshot(folder) == before
    assert folder.stat().st_mtime_ns == dir_mtime
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s1"]


def test_file_sha256_known_vector(tmp_path):
    path = tmp_path / "abc.bin"
    path.write_bytes(b"abc")
    # FIPS 180-2 test vector for "abc"
    assert file_sha256(path) == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    big = tmp_path / "big.bin"
    payload = bytes(range(256)) * 20000  # > 1 chunk
    big.write_bytes(payload)
    assert file_sha256(str(big)) == hashlib.sha256(payload).hexdigest()


# --------------------------------------------------------------- every problem at once (issue 14)


def test_every_session_level_problem_is_reported_at_once(tmp_path):
    meta = copy.deepcopy(BASE_META)
    meta["date"] = "21.11.2026"
    meta["daq"]["sample_rate_hz"] = -5
    meta["balls"]["pressureless"]["mass_g"] = 0.0577
    rows = GOOD_ROWS + ["b1-01,pressurised,traces/x.csv,3.0,3.004,3.010,3.0145,,",
                        "b9-01,nosuchball,traces/x.csv,4.0,4.004,4.010,4.0145,,"]
    folder = make_session(tmp_path, meta=meta, rows=rows)
    with pytest.raises(SessionError) as info:
        read_session(folder)
    problems = info.value.problems
    assert str(info.value).splitlines() == problems
    expected = ["key 'date'", "key 'daq.sample_rate_hz'", "key 'balls.pressureless.mass_g'",
                "impact_id 'b1-01' duplicates line 2"]
    for fragment in expected:
        assert sum(fragment in p for p in problems) == 1, (fragment, problems)
    # the ball of the last row is defined in no readable ball type: also reported
    assert any("'nosuchball' is not defined" in p for p in problems), problems


def test_one_problem_stays_one_line(tmp_path):
    folder = make_session(tmp_path, meta=patched("plate.polarity", 2))
    with pytest.raises(SessionError) as info:
        read_session(folder)
    assert info.value.problems == [str(info.value)]
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("present", "expected"), [("session.yml", "session.yaml"), ("Session.yaml", "session.yaml"),
                                                   ("impacts.CSV", "impacts.csv")])
def test_near_miss_file_name_is_named(tmp_path, present, expected):
    folder = make_session(tmp_path)
    (folder / expected).rename(folder / present)
    if present.lower() == expected and (folder / expected).exists():
        pytest.skip("case-insensitive file system")
    with pytest.raises(SessionError, match=rf"{re.escape(expected)}: file not found, but '{re.escape(present)}' "
                                           rf"is there: rename it to '{re.escape(expected)}'"):
        read_session(folder)


def test_semicolon_separated_impacts_csv_gets_a_separator_hint(tmp_path):
    text = HEADER.replace(",", ";") + "\n" + "\n".join(r.replace(",", ";") for r in GOOD_ROWS) + "\n"
    folder = make_session(tmp_path, csv_text=text)
    with pytest.raises(SessionError, match="missing required column.*separated by semicolons: save impacts.csv "
                                           "comma-separated"):
        read_session(folder)


def test_decimal_commas_in_impacts_csv_get_a_hint(tmp_path):
    rows = ['b1-01,pressurised,traces/b1-01.csv,0,0,0,004,0,010,0,0145,,']
    folder = make_session(tmp_path, rows=rows)
    with pytest.raises(SessionError, match=r"line 2: expected 9 fields, got 13 \(decimal commas\?"):
        read_session(folder)


def test_key_typo_names_the_key_it_misses(tmp_path):
    meta = copy.deepcopy(BASE_META)
    meta["balls"]["pressureless"]["kb0_kn_m"] = 21  # the lab's typo: kB(0) silently extrapolated
    folder = make_session(tmp_path, meta=meta)
    with pytest.warns(SessionWarning, match=r"unknown key\(s\) 'balls.pressureless.kb0_kn_m'.*did you mean "
                                            r"'balls.pressureless.kb0_kN_m'\? 'balls.pressureless.kb0_kn_m' has no "
                                            r"effect"):
        session = read_session(folder)
    assert session.meta.balls["pressureless"].kb0_N_m is None


def test_top_level_typo_names_the_key_it_resembles(tmp_path):
    """raw-format v1.2: a misspelt top-level key (descripton:) is warned about with the key it resembles."""
    meta = copy.deepcopy(BASE_META)
    meta.pop("description", None)
    meta["descripton"] = "Four ball types"
    meta["lab_notes"] = "kept"
    folder = make_session(tmp_path, meta=meta)
    with pytest.warns(SessionWarning, match=r"unknown key\(s\) 'descripton', 'lab_notes'.*did you mean "
                                            r"'description'\? 'descripton' has no effect") as caught:
        session = read_session(folder)
    assert session.meta.description == ""
    assert session.meta.raw["lab_notes"] == "kept"
    assert not any("'lab_notes' has no effect" in str(w.message) for w in caught)


def test_known_top_level_keys_give_no_unknown_key_warning(tmp_path):
    meta = copy.deepcopy(BASE_META)
    meta.update(operator="A. Tester", description="x", synthetic=False,
                rig={"orientation": "horizontal"})
    folder = make_session(tmp_path, meta=meta)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_session(folder)
    assert not [w for w in caught if "unknown key" in str(w.message)]


# --------------------------------------------------------- v1.1 flight and ITF keys


def test_v1_1_flight_and_itf_keys(tmp_path):
    meta = copy.deepcopy(BASE_META)
    meta["gates"]["distance_to_plate_m"] = 0.25
    meta["rig"] = {"orientation": "vertical", "air_density_kg_m3": 1.15}
    meta["balls"]["pressurised"]["itf_rebound_cm"] = 138.9
    session = read_session(make_session(tmp_path, meta=meta))
    assert session.meta.distance_to_plate_m == 0.25
    assert session.meta.rig_orientation == "vertical"
    assert session.meta.air_density_kg_m3 == 1.15
    assert session.meta.balls["pressurised"].itf_rebound_cm == 138.9
    assert session.meta.balls["pressureless"].itf_rebound_cm is None


def test_v1_1_keys_absent_mean_no_correction(tmp_path):
    session = read_session(make_session(tmp_path))
    assert session.meta.distance_to_plate_m is None
    assert session.meta.rig_orientation == "horizontal"
    assert session.meta.air_density_kg_m3 == 1.2


@pytest.mark.parametrize(("key", "value", "message"), [
    ("gates.distance_to_plate_m", -0.2, r"key 'gates\.distance_to_plate_m' must be a positive number, got -0\.2"),
    ("gates.distance_to_plate_m", 0.05,
     r"key 'gates\.distance_to_plate_m' \(0\.05 m\) must exceed the diameter of ball 'pressurised' \(65\.4 mm\)"),
    ("rig", "vertical", r"key 'rig' must be a mapping"),
    ("rig", {"orientation": "upwards"}, r"key 'rig\.orientation' must be one of horizontal, vertical, got 'upwards'"),
    ("rig", {"air_density_kg_m3": 1200}, r"key 'rig\.air_density_kg_m3' must be in \[0\.5, 1\.5\] kg/m\^3"),
    ("balls.pressurised.itf_rebound_cm", 1389, r"key 'balls\.pressurised\.itf_rebound_cm' must be below the 254 cm"),
    ("balls.pressurised.itf_rebound_cm", "high", r"key 'balls\.pressurised\.itf_rebound_cm' must be a positive number"),
])
def test_v1_1_bad_values(tmp_path, key, value, message):
    folder = make_session(tmp_path, meta=patched(key, value))
    with pytest.raises(SessionError, match=r"s1/session\.yaml: " + message):
        read_session(folder)
