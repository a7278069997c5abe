"""Tests of the trace file reader (CSV and NI TDMS)."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from nptdms import ChannelObject, GroupObject, TdmsWriter

from ballimpact.traces import MIN_SAMPLES, Trace, TraceError, read_trace

RATE_HZ = 66964.3  # [Hz] the rig's DAQ rate
SESSION_RATE_HZ = 50000.0  # [Hz] a different "session default", to see which one is used


def signal(n=500):
    """A known test voltage [V]: a half-sine pulse on a small offset."""
    t = np.arange(n)
    return 0.01 + np.where((t > 100) & (t < 200), np.sin(np.pi * (t - 100) / 100.0), 0.0)


def write_csv(path, voltage, *, header=None, time_s=None, fmt=repr, newline="\n"):
    """Write a CSV trace; header is a dict of `# key: value` lines."""
    lines = [f"# {k}: {v}" for k, v in (header or {}).items()]
    if time_s is None:
        lines.append("voltage_V")
        lines += [fmt(float(v)) for v in voltage]
    else:
        lines.append("time_s,voltage_V")
        lines += [f"{fmt(float(t))},{fmt(float(v))}" for t, v in zip(time_s, voltage)]
    path.write_bytes((newline.join(lines) + newline).encode("utf-8"))
    return path


def write_tdms(path, voltage, properties=None, extra_channels=()):
    """Write a TDMS trace: group 'Impact', first channel 'voltage' then extra channels."""
    channels = [ChannelObject("Impact", "voltage", np.asarray(voltage), properties=properties or {})]
    channels += [ChannelObject("Impact", name, np.asarray(data)) for name, data in extra_channels]
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([GroupObject("Impact"), *channels])
    return path


# ----------------------------------------------------------------------- CSV


def test_csv_header_rate(tmp_path):
    v = signal()
    path = write_csv(tmp_path / "a.csv", v, header={"sample_rate_hz": RATE_HZ, "units": "V", "channel": "amp out"})
    trace = read_trace(path, SESSION_RATE_HZ)
    assert isinstance(trace, Trace)
    assert trace.voltage_V.dtype == np.float64
    np.testing.assert_allclose(trace.voltage_V, v, rtol=0, atol=0)
    assert trace.sample_rate_hz == RATE_HZ
    assert trace.sample_rate_source == "header"
    assert trace.t0_s == 0.0
    assert trace.format == "csv"
    assert trace.path == path
    assert trace.metadata["channel"] == "amp out"


def test_csv_session_default_rate(tmp_path):
    path = write_csv(tmp_path / "a.csv", signal())
    trace = read_trace(path, SESSION_RATE_HZ)
    assert trace.sample_rate_hz == SESSION_RATE_HZ
    assert trace.sample_rate_source == "session"
    assert trace.metadata == {}


def test_csv_with_time_column(tmp_path):
    v = signal()
    t = 0.002 + np.arange(v.size) / RATE_HZ
    path = write_csv(tmp_path / "a.csv", v, time_s=t)
    trace = read_trace(path, SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.voltage_V, v, rtol=0, atol=0)
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=1e-9)
    np.testing.assert_allclose(trace.t0_s, 0.002, rtol=1e-12)
    assert trace.sample_rate_source == "time_s"


def test_csv_time_column_printed_in_microseconds(tmp_path):
    # At 67 kHz a time step is 14.93 us: printed to 1 us the steps are 14 or 15 us.
    v = signal(5000)
    t = np.arange(v.size) / RATE_HZ
    path = write_csv(tmp_path / "a.csv", v, time_s=t, fmt=lambda x: f"{x:.6f}")
    trace = read_trace(path, SESSION_RATE_HZ)
    # span of 4999 steps known to +-1 us -> relative error < 1e-6 / 0.0746 s
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=2e-5)


@pytest.mark.parametrize("fmt", ["{:.5g}", "{:.7e}", "{:.9f}"])
def test_csv_time_column_other_formats_and_negative_start(tmp_path, fmt):
    v = signal(2000)
    t = -0.005 + np.arange(v.size) / RATE_HZ  # pre-trigger: the first sample before t = 0
    trace = read_trace(write_csv(tmp_path / "a.csv", v, time_s=t, fmt=fmt.format), SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=1e-4)
    np.testing.assert_allclose(trace.t0_s, -0.005, rtol=1e-4)


def test_csv_time_column_agrees_with_header(tmp_path):
    v = signal()
    t = np.arange(v.size) / RATE_HZ
    path = write_csv(tmp_path / "a.csv", v, time_s=t, header={"sample_rate_hz": RATE_HZ * 1.004})
    trace = read_trace(path, SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=1e-9)
    assert trace.sample_rate_source == "time_s"


def test_csv_time_column_disagrees_with_header(tmp_path):
    v = signal()
    t = np.arange(v.size) / RATE_HZ
    path = write_csv(tmp_path / "a.csv", v, time_s=t, header={"sample_rate_hz": RATE_HZ * 1.01})
    with pytest.raises(TraceError, match=r"a\.csv: line 1: header sample_rate_hz .* disagrees with the time_s column"):
        read_trace(path, SESSION_RATE_HZ)


def test_csv_time_not_increasing(tmp_path):
    v = signal()
    t = np.arange(v.size) / RATE_HZ
    t[300] = t[299]
    path = write_csv(tmp_path / "a.csv", v, time_s=t)
    # header row is line 1, sample i is on line i + 2
    with pytest.raises(TraceError, match=r"a\.csv: line 302: time_s must be strictly increasing"):
        read_trace(path, SESSION_RATE_HZ)


def test_csv_time_non_uniform(tmp_path):
    v = signal()
    t = np.arange(v.size) / RATE_HZ
    t[250:] += 0.5 / RATE_HZ  # one step 50 % too long
    path = write_csv(tmp_path / "a.csv", v, time_s=t)
    with pytest.raises(TraceError, match=r"a\.csv: line 252: non-uniform sampling"):
        read_trace(path, SESSION_RATE_HZ)


def test_csv_time_small_jitter_accepted(tmp_path):
    rng = np.random.default_rng(1)
    v = signal()
    t = (np.arange(v.size) + rng.uniform(-0.002, 0.002, v.size)) / RATE_HZ  # 0.4 % step jitter at most
    trace = read_trace(write_csv(tmp_path / "a.csv", v, time_s=t), SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=1e-4)


def test_csv_crlf_bom_and_trailing_blank_lines(tmp_path):
    v = signal()
    path = tmp_path / "a.csv"
    text = "\ufeff# units: V\r\n\r\nvoltage_V\r\n" + "\r\n".join(repr(float(x)) for x in v) + "\r\n\r\n  \r\n"
    path.write_bytes(text.encode("utf-8"))
    trace = read_trace(path, SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.voltage_V, v, rtol=0, atol=0)
    assert trace.metadata == {"units": "V"}


def test_csv_units_must_be_volt(tmp_path):
    path = write_csv(tmp_path / "a.csv", signal(), header={"sample_rate_hz": RATE_HZ, "units": "mV"})
    with pytest.raises(TraceError, match=r"a\.csv: line 2: units must be 'V', got 'mV'"):
        read_trace(path, SESSION_RATE_HZ)


def test_exactly_min_samples_is_enough(tmp_path):
    trace = read_trace(write_csv(tmp_path / "a.csv", signal(MIN_SAMPLES)), SESSION_RATE_HZ)
    assert trace.voltage_V.size == MIN_SAMPLES == 100


def sample_lines(n=150):
    return [repr(float(x)) for x in signal(n)]


CSV_FAULTS = [
    (b"", r"a\.csv: empty trace file"),
    (b"\n \n", r"a\.csv: empty trace file"),
    (b"# units: V\n", r"a\.csv: no header row \(voltage_V\) and no samples"),
    (b"# units: V\nvoltage_V\n\n", r"a\.csv: no samples after the header row \(line 2\)"),
    ("current_A\n" + "\n".join(sample_lines()), r"a\.csv: line 1: missing voltage_V column \(header row is 'current_A'\)"),
    ("\n".join(sample_lines()), r"a\.csv: line 1: missing voltage_V column"),
    ("voltage_V,time_s\n" + "\n".join(sample_lines()), r"a\.csv: line 1: header row must be 'voltage_V' or 'time_s,voltage_V'"),
    ("voltage_V\n" + "\n".join(sample_lines()[:40] + ["0.1x"] + sample_lines()[40:]), r"a\.csv: line 42: non-numeric value '0\.1x'"),
    ("voltage_V\n" + "\n".join(sample_lines()[:40] + ["", "0.1"] + sample_lines()[40:]), r"a\.csv: line 42: empty line among the samples"),
    ("voltage_V\n" + "\n".join(sample_lines()[:9] + ["0.1,0.2"] + sample_lines()[9:]), r"a\.csv: line 11: expected 1 field\(s\) \(voltage_V\), got 2"),
    ("time_s,voltage_V\n0,1\n1\n" + "\n".join(f"{i},0.1" for i in range(2, 200)), r"a\.csv: line 3: expected 2 field\(s\)"),
    ("voltage_V\n" + "\n".join(sample_lines()[:7] + ["nan"] + sample_lines()[7:]), r"a\.csv: line 9: non-finite value nan"),
    ("voltage_V\n" + "\n".join(sample_lines()[:7] + ["-inf"] + sample_lines()[7:]), r"a\.csv: line 9: non-finite value -inf"),
    ("voltage_V\n" + "\n".join(sample_lines(99)), r"a\.csv: truncated trace: only 99 samples \(at least 100 required\)"),
    ("# sample_rate_hz: 0\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 1: sample_rate_hz must be a positive number, got '0'"),
    ("# units: V\n# sample_rate_hz: -5\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 2: sample_rate_hz must be a positive number, got '-5'"),
    ("# sample_rate_hz: fast\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 1: sample_rate_hz must be a positive number, got 'fast'"),
    ("# sample_rate_hz: nan\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 1: sample_rate_hz must be a positive number"),
    ("# units: V\n# no colon here\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 2: header line must look like '# key: value'"),
    ("# units: V\n# units: V\nvoltage_V\n" + "\n".join(sample_lines()), r"a\.csv: line 2: header key 'units' repeats line 1"),
    (b"# units: V\nvoltage_V\n0.1\n0.\xff2\n", r"a\.csv: line 4: not valid UTF-8 \(byte 0xff\)"),
]


@pytest.mark.parametrize(("content", "message"), CSV_FAULTS)
def test_csv_fault(tmp_path, content, message):
    path = tmp_path / "a.csv"
    path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    with pytest.raises(TraceError, match=message) as info:
        read_trace(path, SESSION_RATE_HZ)
    assert str(info.value).startswith(str(path))
    assert "\n" not in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(TraceError, match=r"nope\.csv: trace file not found"):
        read_trace(tmp_path / "nope.csv", SESSION_RATE_HZ)


def test_unknown_extension(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("voltage_V\n0.1\n")
    with pytest.raises(TraceError, match=r"a\.txt: unknown trace file extension '\.txt' \(expected \.csv, \.tdms, "
                                         r"\.lvm\)"):
        read_trace(path, SESSION_RATE_HZ)


def test_uppercase_extension_accepted(tmp_path):
    trace = read_trace(write_csv(tmp_path / "a.CSV", signal()), SESSION_RATE_HZ)
    assert trace.format == "csv"


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, "66964"])
def test_bad_default_rate_is_value_error(tmp_path, bad):
    path = write_csv(tmp_path / "a.csv", signal())
    with pytest.raises(ValueError, match="default_sample_rate_hz must be a positive number"):
        read_trace(path, bad)


# ---------------------------------------------------------------------- TDMS


def test_tdms_rate_from_wf_increment(tmp_path):
    v = signal()
    path = write_tdms(
        tmp_path / "a.tdms",
        v,
        properties={"wf_increment": 1.0 / RATE_HZ, "wf_start_offset": -0.0015, "unit_string": "V"},
        extra_channels=[("trigger", np.zeros(v.size))],
    )
    trace = read_trace(path, SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.voltage_V, v, rtol=0, atol=0)
    np.testing.assert_allclose(trace.sample_rate_hz, RATE_HZ, rtol=1e-12)
    np.testing.assert_allclose(trace.t0_s, -0.0015, rtol=1e-12)
    assert trace.sample_rate_source == "wf_increment"
    assert trace.format == "tdms"
    assert trace.metadata["tdms_group"] == "Impact"
    assert trace.metadata["tdms_channel"] == "voltage"
    assert trace.metadata["unit_string"] == "V"


def test_tdms_float32_and_session_default(tmp_path):
    v = signal().astype(np.float32)
    trace = read_trace(write_tdms(tmp_path / "a.tdms", v), SESSION_RATE_HZ)
    assert trace.voltage_V.dtype == np.float64
    np.testing.assert_allclose(trace.voltage_V, v.astype(np.float64), rtol=0, atol=0)
    assert trace.sample_rate_hz == SESSION_RATE_HZ
    assert trace.sample_rate_source == "session"


@pytest.mark.parametrize(
    ("voltage", "properties", "message"),
    [
        (signal(), {"wf_increment": 0.0}, r"property wf_increment must be a positive number of seconds, got 0\.0"),
        (signal(), {"wf_increment": -1e-5}, r"property wf_increment must be a positive number"),
        (signal(), {"wf_increment": "fast"}, r"property wf_increment must be a positive number"),
        (signal(), {"wf_start_offset": "soon"}, r"property wf_start_offset must be a number of seconds"),
        (signal(), {"unit_string": "mV"}, r"unit_string must be 'V', got 'mV'"),
        (signal(50), {}, r"truncated trace: only 50 samples"),
        (np.array([], dtype=np.float64), {}, r"empty trace: TDMS channel 'voltage' has no samples"),
        (np.r_[signal(), np.nan], {}, r"sample 500: non-finite value nan"),
    ],
)
def test_tdms_fault(tmp_path, voltage, properties, message):
    path = write_tdms(tmp_path / "a.tdms", voltage, properties)
    with pytest.raises(TraceError, match=r"a\.tdms: (channel 'voltage' )?" + message):
        read_trace(path, SESSION_RATE_HZ)


def test_tdms_garbage_file(tmp_path):
    path = tmp_path / "a.tdms"
    path.write_bytes(b"this is not a TDMS file at all" * 4)
    with pytest.raises(TraceError, match=r"a\.tdms: not a readable TDMS file"):
        read_trace(path, SESSION_RATE_HZ)


def test_tdms_without_channels(tmp_path):
    path = tmp_path / "a.tdms"
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([GroupObject("Impact")])
    with pytest.raises(TraceError, match=r"a\.tdms: empty trace: TDMS group 'Impact' has no channels"):
        read_trace(path, SESSION_RATE_HZ)


def test_read_does_not_write(tmp_path):
    write_csv(tmp_path / "a.csv", signal(), header={"units": "V"})
    write_tdms(tmp_path / "b.tdms", signal(), {"wf_increment": 1 / RATE_HZ})
    before = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in tmp_path.iterdir()}
    read_trace(tmp_path / "a.csv", SESSION_RATE_HZ)
    read_trace(tmp_path / "b.tdms", SESSION_RATE_HZ)
    assert {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in tmp_path.iterdir()} == before


# ------------------------------------------------------------------ properties

_LINE_TEXT = st.characters(codec="utf-8", exclude_characters="\n\r")
_KEY = st.text(_LINE_TEXT, min_size=1, max_size=12).map(str.strip).filter(
    lambda k: k and ":" not in k and k not in ("units", "sample_rate_hz")
)
_VALUE = st.text(_LINE_TEXT, max_size=20).map(str.strip)
_FINITE = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    values=st.lists(_FINITE, min_size=MIN_SAMPLES, max_size=300),
    metadata=st.dictionaries(_KEY, _VALUE, max_size=5),
    with_rate=st.booleans(),
)
def test_property_csv_round_trip(tmp_path, values, metadata, with_rate):
    header = dict(metadata)
    if with_rate:
        header["sample_rate_hz"] = RATE_HZ
    path = write_csv(tmp_path / "p.csv", values, header=header)
    trace = read_trace(path, SESSION_RATE_HZ)
    np.testing.assert_allclose(trace.voltage_V, np.array(values), rtol=1e-12, atol=0)
    for key, value in metadata.items():
        assert trace.metadata[key] == value
    assert trace.sample_rate_hz == (RATE_HZ if with_rate else SESSION_RATE_HZ)


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


_GARBAGE = st.text(_LINE_TEXT, min_size=1, max_size=20).filter(
    lambda g: g.strip() and not g.strip().startswith("#") and not _is_number(g) and "voltage_V" not in g
)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    garbage=st.lists(_GARBAGE, min_size=1, max_size=3),
    data=st.data(),
    with_time=st.booleans(),
    n_header=st.integers(0, 3),
)
def test_property_garbage_lines_give_trace_error_naming_the_line(tmp_path, garbage, data, with_time, n_header):
    v = signal(120)
    header = {f"key{i}": f"value {i}" for i in range(n_header)}
    path = write_csv(tmp_path / "g.csv", v, header=header, time_s=np.arange(v.size) / RATE_HZ if with_time else None)
    lines = path.read_text().split("\n")[:-1]
    positions = sorted(data.draw(st.lists(st.integers(0, len(lines)), min_size=len(garbage), max_size=len(garbage))))
    inserted = []
    for offset, (pos, text) in enumerate(zip(positions, garbage)):
        lines.insert(pos + offset, text)
        inserted.append(pos + offset + 1)  # 1-based line number of this garbage line
    path.write_bytes(("\n".join(lines) + "\n").encode("utf-8"))
    with pytest.raises(TraceError) as info:
        read_trace(path, SESSION_RATE_HZ)
    message = str(info.value)
    assert message.startswith(f"{path}: line {inserted[0]}:"), message


# ---------------------------------------------------------------- LabVIEW LVM (raw-format v1.2)
# The files are written here in LabVIEW's Measurement text format (tests/handmade.py), not by the reader's library.


@pytest.mark.parametrize(("x_column", "decimal"), [(True, "."), (False, "."), (True, ",")])
def test_lvm_voltage_and_rate_from_delta_x(tmp_path, x_column, decimal):
    from handmade import write_lvm

    v = signal()
    path = tmp_path / "shot.lvm"
    write_lvm(path, v, 50_000.0, x_column=x_column, decimal=decimal)
    trace = read_trace(path, SESSION_RATE_HZ)
    assert trace.format == "lvm" and trace.sample_rate_source == "Delta_X"
    np.testing.assert_allclose(trace.sample_rate_hz, 50_000.0, rtol=1e-6)  # Delta_X printed to 8 digits
    np.testing.assert_allclose(trace.voltage_V, v, atol=5.1e-7)  # written with 6 decimals
    assert trace.t0_s == 0.0


def test_lvm_without_delta_x_takes_the_x_column(tmp_path):
    from handmade import write_lvm

    path = tmp_path / "shot.lvm"
    write_lvm(path, signal(), 20_000.0)
    text = "\n".join(line for line in path.read_text().splitlines() if not line.startswith("Delta_X"))
    path.write_text(text + "\n")
    trace = read_trace(path, SESSION_RATE_HZ)
    assert trace.sample_rate_source == "X_Value"
    np.testing.assert_allclose(trace.sample_rate_hz, 20_000.0, rtol=1e-6)


def test_lvm_header_rate_read_without_the_samples(tmp_path):
    from handmade import write_lvm

    from ballimpact.traces import trace_header_rate

    path = tmp_path / "shot.lvm"
    write_lvm(path, signal(), 25_000.0, decimal=",")
    np.testing.assert_allclose(trace_header_rate(path), 25_000.0, rtol=1e-6)


def test_lvm_never_writes_beside_the_trace(tmp_path):
    """lvm_read.read() caches a .pkl next to the file by default: raw/ must never be written."""
    from handmade import write_lvm

    write_lvm(tmp_path / "shot.lvm", signal(), 50_000.0)
    read_trace(tmp_path / "shot.lvm", SESSION_RATE_HZ)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shot.lvm"]


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace("Y_Unit_Label\tVolts", "Y_Unit_Label\tNewtons"), r"channel 'Voltage' Y_Unit_Label must be volts, got 'Newtons'"),
    (lambda t: t.replace("LabVIEW Measurement", "Measurement"), r"not a LabVIEW Measurement file"),
    (lambda t: t.replace("\t0.100000\n", "\tabc\n", 1), r"channel 'Voltage' sample 150: non-finite value"),
])
def test_lvm_fault(tmp_path, edit, message):
    from handmade import write_lvm

    path = tmp_path / "shot.lvm"
    v = signal()
    v[150] = 0.1
    write_lvm(path, v, 50_000.0)
    path.write_text(edit(path.read_text()))
    with pytest.raises(TraceError, match=rf"shot\.lvm: {message}"):
        read_trace(path, SESSION_RATE_HZ)
