"""Bad-input suite: every way the raw format (docs/raw-format.md) can be broken, and a few more.

One small valid synthetic session is made per module; every case copies it,
breaks one thing and checks the contract of the spec's "Errors" section:

* a session-level fault raises ``SessionError`` from ``read_session`` with a
  one-line message naming the file and the row or key, and
  ``ballimpact validate`` exits 2 with that one line on stderr (no traceback);
* an impact-level fault leaves every impact processed by ``iter_process``,
  exactly the broken impact excluded with a reason naming the problem, every
  other impact ok.

Every case also checks that the raw folder is byte-for-byte unchanged (content
hashes and mtimes) and that raw files are only ever opened read-only.
"""

from __future__ import annotations

import builtins
import csv
import hashlib
import io
import os
import shutil
import subprocess
import sys
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import yaml

from ballimpact.balls import BALLS
from ballimpact.cli import main as cli_main
from ballimpact.processing import iter_process
from ballimpact.session import SessionError, read_session
from ballimpact.synth import SynthConfig, write_session
from ballimpact.validation import validate_session

BALLIMPACT = str(Path(sys.executable).parent / "ballimpact")
SESSION_ID = "s"
BALL_KEYS = ("pressurised", "punctured")
VICTIM = 1  # index of the impact row that is broken (data line 3 of impacts.csv)
VICTIM_LINE = VICTIM + 2  # its 1-based line number in impacts.csv (the header is line 1)
VICTIM_TRACE = "punctured-002.csv"  # its trace file (write_session with the default seed 0)
REQUIRED_COLUMNS = ("impact_id", "ball", "trace", "gate_in_1_s", "gate_in_2_s", "gate_out_2_s", "gate_out_1_s")
WRITE_MODE_CHARS = set("wax+")
WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def base_session(tmp_path_factory) -> Path:
    """A valid session: two Table 2 balls, two impacts each, no faults (all four impacts ok)."""
    root = tmp_path_factory.mktemp("bad_input_base")
    config = SynthConfig(session_id=SESSION_ID, balls={k: BALLS[k].params for k in BALL_KEYS},
                         impacts_per_ball=2, faults_per_kind=0)
    session_dir, _ = write_session(root / SESSION_ID, config)
    results = list(iter_process(read_session(session_dir)))
    assert [r.status for r in results] == ["ok"] * 4, [r.reason for r in results]
    assert read_rows(session_dir)[VICTIM + 1][2] == "traces/" + VICTIM_TRACE
    return session_dir


@pytest.fixture
def session_copy(base_session, tmp_path) -> Path:
    """A fresh copy of the base session, named like it (the folder name is the session id)."""
    return Path(shutil.copytree(base_session, tmp_path / SESSION_ID))


# ----------------------------------------------------------------------------- file helpers


def read_rows(d: Path) -> list[list[str]]:
    with open(d / "impacts.csv", newline="", encoding="utf-8") as fh:
        return list(csv.reader(fh))


def write_rows(d: Path, rows: list[list[str]]) -> None:
    with open(d / "impacts.csv", "w", newline="", encoding="utf-8") as fh:
        csv.writer(fh, lineterminator="\n").writerows(rows)


def set_cell(column: str, value: str, row: int = VICTIM):
    """Breaker: set one cell of one impact row."""
    def breaker(d: Path) -> None:
        rows = read_rows(d)
        rows[row + 1][rows[0].index(column)] = value
        write_rows(d, rows)
    return breaker


def victim_trace(d: Path) -> Path:
    rows = read_rows(d)
    return d / rows[VICTIM + 1][rows[0].index("trace")]


def victim_id(d: Path) -> str:
    return read_rows(d)[VICTIM + 1][0]


def trace_lines(d: Path) -> tuple[list[str], list[str]]:
    """The victim trace as (header lines including the column row, sample lines)."""
    lines = victim_trace(d).read_text(encoding="utf-8").splitlines()
    k = lines.index("voltage_V") + 1
    return lines[:k], lines[k:]


def write_trace_lines(d: Path, header: list[str], samples: list[str]) -> None:
    victim_trace(d).write_text("\n".join(header + samples) + "\n", encoding="utf-8")


def edit_trace(fn: Callable[[list[str], list[str]], tuple[list[str], list[str]]]):
    """Breaker: edit the victim trace's header and sample lines."""
    def breaker(d: Path) -> None:
        header, samples = trace_lines(d)
        write_trace_lines(d, *fn(list(header), list(samples)))
    return breaker


def trace_bytes(data: bytes):
    """Breaker: replace the victim trace's bytes."""
    def breaker(d: Path) -> None:
        victim_trace(d).write_bytes(data)
    return breaker


def replace_sample(index: int, text: str):
    def fn(header, samples):
        samples[index] = text
        return header, samples
    return edit_trace(fn)


def insert_sample_line(index: int, text: str):
    def fn(header, samples):
        samples.insert(index, text)
        return header, samples
    return edit_trace(fn)


def set_header_key(key: str, value: str | None):
    """Breaker: set (or, with None, remove) a `# key: value` line of the victim trace."""
    def fn(header, samples):
        header = [h for h in header if not h.startswith(f"# {key}:")]
        if value is not None:
            header.insert(0, f"# {key}: {value}")
        return header, samples
    return edit_trace(fn)


def contact_start_index(d: Path) -> int:
    """First sample of the victim's contact (the synthetic pre-trigger is 25 ms)."""
    from ballimpact.traces import read_trace

    trace = read_trace(victim_trace(d), 66964.3)
    v = trace.voltage_V - np.median(trace.voltage_V[:1000])
    return int(np.argmax(v > 0.1 * v.max()))


def cut_in_contact(d: Path) -> None:
    """Breaker: the trace ends 1 ms into the contact (the DAQ stopped mid-impact)."""
    header, samples = trace_lines(d)
    start = contact_start_index(d)
    write_trace_lines(d, header, samples[: start + 67])


def all_zeros(d: Path) -> None:
    header, samples = trace_lines(d)
    write_trace_lines(d, header, ["0.0"] * len(samples))


def non_utf8_trace(d: Path) -> None:
    data = victim_trace(d).read_bytes()
    lines = data.split(b"\n")
    lines[2000] = b"0.01\xff\xfe"
    victim_trace(d).write_bytes(b"\n".join(lines))


def time_column(decreasing_at: int | None = None):
    """Breaker: add a time_s column (optionally with a step back in time at one sample)."""
    def breaker(d: Path) -> None:
        header, samples = trace_lines(d)
        t = np.arange(len(samples)) / 66964.3
        if decreasing_at is not None:
            t[decreasing_at] = t[decreasing_at - 2]
        header[-1] = "time_s,voltage_V"
        write_trace_lines(d, header, [f"{ti:.8f},{v}" for ti, v in zip(t, samples)])
    return breaker


def point_trace_at(relative_or_absolute: Callable[[Path], str], make_file: Callable[[Path], None] | None = None):
    """Breaker: make the victim row's trace cell some other path (creating a file first if asked)."""
    def breaker(d: Path) -> None:
        if make_file is not None:
            make_file(d)
        set_cell("trace", relative_or_absolute(d))(d)
    return breaker


def copy_victim_outside(d: Path) -> None:
    """A perfectly good trace, but outside the session folder (beside it)."""
    shutil.copyfile(victim_trace(d), d.parent / "outside.csv")


def fake_tdms(content: bytes):
    def make(d: Path) -> None:
        (d / "traces" / "fake.tdms").write_bytes(content)
    return make


def yaml_edit(fn: Callable[[dict], None]):
    """Breaker: parse session.yaml, change the document, write it back."""
    def breaker(d: Path) -> None:
        doc = yaml.safe_load((d / "session.yaml").read_text(encoding="utf-8"))
        fn(doc)
        (d / "session.yaml").write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return breaker


def yaml_set(dotted: str, value):
    def fn(doc):
        *parents, last = dotted.split(".")
        node = doc
        for key in parents:
            node = node[key]
        node[last] = value
    return yaml_edit(fn)


def yaml_delete(dotted: str):
    def fn(doc):
        *parents, last = dotted.split(".")
        node = doc
        for key in parents:
            node = node[key]
        del node[last]
    return yaml_edit(fn)


def write_file(name: str, data: bytes | str):
    def breaker(d: Path) -> None:
        target = d / name
        if isinstance(data, bytes):
            target.write_bytes(data)
        else:
            target.write_text(data, encoding="utf-8")
    return breaker


def remove_file(name: str):
    def breaker(d: Path) -> None:
        (d / name).unlink()
    return breaker


def replace_bytes(name: str, old: bytes, new: bytes):
    def breaker(d: Path) -> None:
        data = (d / name).read_bytes()
        assert old in data, (name, old)
        (d / name).write_bytes(data.replace(old, new, 1))
    return breaker


def drop_column(column: str):
    def breaker(d: Path) -> None:
        rows = read_rows(d)
        k = rows[0].index(column)
        write_rows(d, [r[:k] + r[k + 1:] for r in rows])
    return breaker


def header_only(d: Path) -> None:
    write_rows(d, read_rows(d)[:1])


def duplicate_id(d: Path) -> None:
    rows = read_rows(d)
    rows[VICTIM + 1][0] = rows[VICTIM][0]
    write_rows(d, rows)


def swap_cells(a: str, b: str):
    def breaker(d: Path) -> None:
        rows = read_rows(d)
        r = rows[VICTIM + 1]
        i, j = rows[0].index(a), rows[0].index(b)
        r[i], r[j] = r[j], r[i]
        write_rows(d, rows)
    return breaker


def negate_cell(column: str):
    def breaker(d: Path) -> None:
        rows = read_rows(d)
        k = rows[0].index(column)
        rows[VICTIM + 1][k] = "-" + rows[VICTIM + 1][k]
        write_rows(d, rows)
    return breaker


def extra_field(d: Path) -> None:
    rows = read_rows(d)
    rows[VICTIM + 1].append("surplus")
    write_rows(d, rows)


def unterminated_quote(d: Path) -> None:
    text = (d / "impacts.csv").read_text(encoding="utf-8")
    (d / "impacts.csv").write_text(text.rstrip("\n") + '"an open quote\n', encoding="utf-8")


def crlf(name: str):
    def breaker(d: Path) -> None:
        data = (d / name).read_bytes().replace(b"\n", b"\r\n")
        (d / name).write_bytes(data)
    return breaker


def bom(name: str):
    def breaker(d: Path) -> None:
        (d / name).write_bytes(b"\xef\xbb\xbf" + (d / name).read_bytes())
    return breaker


def compose(*breakers):
    def breaker(d: Path) -> None:
        for b in breakers:
            b(d)
    return breaker


# ----------------------------------------------------------------------------- cases


@dataclass(frozen=True)
class SessionCase:
    """A session-level fault: SessionError naming ``file`` and every one of ``where``."""

    id: str
    breaker: Callable[[Path], None]
    file: str  # "session.yaml" or "impacts.csv" (or the folder for a missing folder)
    where: tuple[str, ...]  # substrings naming the key/row and what is wrong


Y, C = "session.yaml", "impacts.csv"
L = f"line {VICTIM_LINE}"
REQUIRED_YAML_KEYS = ("session_id", "date", "plate", "plate.polarity", "daq", "daq.sample_rate_hz",
                      "daq.adc_range_v", "gates", "gates.spacing_m", "gates.resolution_s", "balls",
                      "balls.pressurised.mass_g")

SESSION_CASES = [
    # session.yaml: presence, syntax, shape
    SessionCase("yaml-missing", remove_file(Y), Y, ("file not found",)),
    SessionCase("yaml-empty-0-bytes", write_file(Y, b""), Y, ("empty",)),
    SessionCase("yaml-malformed-flow", write_file(Y, "session_id: s\nplate: [1, 2\ndaq: {}\n"), Y,
                ("line", "invalid YAML")),
    SessionCase("yaml-malformed-indent", write_file(Y, "session_id: s\n date: 2026-11-21\n  plate:\n"), Y,
                ("line", "invalid YAML")),
    SessionCase("yaml-tab-indent", write_file(Y, "session_id: s\nplate:\n\tpolarity: 1\n"), Y,
                ("line", "invalid YAML")),
    SessionCase("yaml-duplicate-key", replace_bytes(Y, b"session_id: s\n", b"session_id: s\nsession_id: s\n"),
                Y, ("line", "duplicate key 'session_id'")),
    SessionCase("yaml-top-level-list", write_file(Y, "- session_id: s\n- date: 2026-11-21\n"), Y,
                ("top level must be a mapping", "list")),
    SessionCase("yaml-top-level-scalar", write_file(Y, "just some text\n"), Y, ("top level must be a mapping",)),
    SessionCase("yaml-non-utf8", replace_bytes(Y, b"SYNTHETIC DATA", b"SYNTH\xe9TIC DATA"), Y,
                ("line", "not valid UTF-8", "0xe9")),
    # session.yaml: every required key missing in turn
    *[SessionCase(f"yaml-missing-{key}", yaml_delete(key), Y, (f"missing required key '{key}'",))
      for key in REQUIRED_YAML_KEYS],
    # session.yaml: wrong types and values
    SessionCase("polarity-up", yaml_set("plate.polarity", "up"), Y, ("'plate.polarity'", "'up'")),
    SessionCase("polarity-2", yaml_set("plate.polarity", 2), Y, ("'plate.polarity'", "1 or -1")),
    SessionCase("sample-rate-fast", yaml_set("daq.sample_rate_hz", "fast"), Y, ("'daq.sample_rate_hz'", "'fast'")),
    SessionCase("sample-rate-zero", yaml_set("daq.sample_rate_hz", 0), Y, ("'daq.sample_rate_hz'", "positive")),
    SessionCase("sample-rate-negative", yaml_set("daq.sample_rate_hz", -66964.3), Y,
                ("'daq.sample_rate_hz'", "positive")),
    SessionCase("sample-rate-empty", replace_bytes(Y, b"sample_rate_hz: 66964.3", b"sample_rate_hz:"), Y,
                ("'daq.sample_rate_hz'",)),
    SessionCase("spacing-negative", yaml_set("gates.spacing_m", -1), Y, ("'gates.spacing_m'", "positive", "-1")),
    SessionCase("resolution-in-us", yaml_set("gates.resolution_s", 1.0), Y, ("'gates.resolution_s'",)),
    SessionCase("adc-range-reversed", yaml_set("daq.adc_range_v", [10, -10]), Y, ("'daq.adc_range_v'", "lo < hi")),
    SessionCase("adc-range-scalar", yaml_set("daq.adc_range_v", 10), Y, ("'daq.adc_range_v'",)),
    SessionCase("adc-range-text", yaml_set("daq.adc_range_v", ["-10 V", "10 V"]), Y, ("'daq.adc_range_v'",)),
    SessionCase("daq-not-mapping", yaml_set("daq", "NI USB-6251"), Y, ("'daq'", "mapping")),
    SessionCase("balls-empty", yaml_set("balls", {}), Y, ("'balls'",)),
    SessionCase("ball-not-mapping", yaml_set("balls.pressurised", 57.7), Y, ("'balls.pressurised'",)),
    SessionCase("ball-mass-text", yaml_set("balls.pressurised.mass_g", "heavy"), Y,
                ("'balls.pressurised.mass_g'", "'heavy'")),
    SessionCase("ball-mass-in-kg", yaml_set("balls.pressurised.mass_g", 0.0577), Y, ("'balls.pressurised.mass_g'",)),
    SessionCase("date-not-iso", yaml_set("date", "21/11/2026"), Y, ("'date'", "ISO")),
    SessionCase("session-id-mismatch", yaml_set("session_id", "other"), Y, ("'session_id'", "'other'")),
    SessionCase("mains-negative", yaml_set("daq.mains_hz", -50), Y, ("'daq.mains_hz'",)),
    # impacts.csv: presence, encoding, emptiness
    SessionCase("csv-missing", remove_file(C), C, ("file not found",)),
    SessionCase("csv-empty-0-bytes", write_file(C, b""), C, ("empty",)),
    SessionCase("csv-whitespace-only", write_file(C, b"\n \n\t\n"), C, ("empty",)),
    SessionCase("csv-header-only", header_only, C, ("no impact rows",)),
    SessionCase("csv-non-utf8", replace_bytes(C, b"punctured,traces", b"punctur\xe9,traces"), C,
                (L, "not valid UTF-8", "0xe9")),
    # impacts.csv: columns
    *[SessionCase(f"csv-missing-column-{col}", drop_column(col), C, ("line 1", "missing required column", col))
      for col in REQUIRED_COLUMNS],
    SessionCase("csv-duplicate-column", replace_bytes(C, b",note\n", b",ball\n"), C, ("line 1", "duplicate column")),
    # impacts.csv: rows
    SessionCase("csv-unknown-ball", set_cell("ball", "golf"), C, (L, "'golf'", "not defined")),
    SessionCase("csv-duplicate-impact-id", duplicate_id, C, (L, "duplicates line 2")),
    SessionCase("csv-bad-impact-id", set_cell("impact_id", "impact 2!"), C, (L, "'impact 2!'")),
    SessionCase("csv-empty-impact-id", set_cell("impact_id", ""), C, (L, "impact_id")),
    SessionCase("csv-extra-field", extra_field, C, (L, "expected 9 fields, got 10")),
    SessionCase("csv-unterminated-quote", unterminated_quote, C, ("line", "malformed CSV")),
    # the folder itself
    SessionCase("folder-is-a-file", lambda d: (shutil.rmtree(d), d.write_text("not a folder")), SESSION_ID,
                ("session folder not found",)),
]


@dataclass(frozen=True)
class ImpactCase:
    """An impact-level fault: the victim excluded with a reason holding every one of ``reason``."""

    id: str
    breaker: Callable[[Path], None]
    reason: tuple[str, ...]
    file_level: bool = True  # validate_session reports it too (False: judged only by processing)


IMPACT_CASES = [
    # gate times
    ImpactCase("gate-empty", set_cell("gate_out_1_s", ""), ("missing gate time gate_out_1_s",)),
    ImpactCase("gate-non-numeric", set_cell("gate_in_2_s", "12:03:04.5"), ("non-numeric gate time gate_in_2_s",)),
    ImpactCase("gate-nan-text", set_cell("gate_in_1_s", "nan"), ("gate_in_1_s",)),
    ImpactCase("gate-negative", negate_cell("gate_in_1_s"), ("negative gate time gate_in_1_s",)),
    ImpactCase("gates-inbound-swapped", swap_cells("gate_in_1_s", "gate_in_2_s"),
               ("gate times out of order", "gate_in_1_s")),
    ImpactCase("gates-outbound-swapped", swap_cells("gate_out_2_s", "gate_out_1_s"),
               ("gate times out of order", "gate_out_2_s")),
    ImpactCase("gates-out-before-in", swap_cells("gate_in_2_s", "gate_out_2_s"), ("gate times out of order",)),
    ImpactCase("mass-override-text", set_cell("mass_g", "57,7 g"), ("non-numeric mass_g",)),
    ImpactCase("mass-override-negative", set_cell("mass_g", "-57.7"), ("mass_g",)),
    # trace path
    ImpactCase("trace-cell-empty", set_cell("trace", ""), ("missing trace path",)),
    ImpactCase("trace-file-missing", lambda d: victim_trace(d).unlink(), ("trace file not found",)),
    ImpactCase("trace-dotdot", point_trace_at(lambda d: "../outside.csv", copy_victim_outside),
               ("trace path escapes the session folder", "../outside.csv")),
    ImpactCase("trace-dotdot-inside-first", point_trace_at(lambda d: "traces/../../outside.csv", copy_victim_outside),
               ("trace path escapes the session folder",)),
    ImpactCase("trace-absolute", point_trace_at(lambda d: str(d.parent / "outside.csv"), copy_victim_outside),
               ("trace path escapes the session folder", "absolute")),
    ImpactCase("trace-absolute-inside", point_trace_at(lambda d: str(victim_trace(d).resolve())),
               ("trace path escapes the session folder", "absolute")),
    ImpactCase("trace-symlink-out", point_trace_at(lambda d: "traces/link.csv", lambda d: (
        copy_victim_outside(d), (d / "traces" / "link.csv").symlink_to(d.parent / "outside.csv"))),
               ("trace path escapes the session folder", "traces/link.csv")),
    ImpactCase("trace-windows-drive", set_cell("trace", r"C:\daq\trace.csv"), ("trace path escapes the session folder",)),
    ImpactCase("trace-is-folder", set_cell("trace", "traces"), ("trace path is not a file",)),
    ImpactCase("trace-is-session-folder", set_cell("trace", "."), ("trace path escapes the session folder",)),
    ImpactCase("trace-unknown-extension", point_trace_at(lambda d: "traces/x.txt",
                                                         lambda d: shutil.copyfile(victim_trace(d), d / "traces/x.txt")),
               ("unknown trace file extension", "'.txt'")),
    ImpactCase("trace-name-too-long", set_cell("trace", "traces/" + "x" * 300 + ".csv"), ("trace path",)),
    ImpactCase("trace-name-nul-byte", set_cell("trace", "traces/pun\x00ctured-002.csv"), ("trace path",)),
    # trace content
    ImpactCase("trace-nan", replace_sample(1000, "nan"), ("non-finite value nan", VICTIM_TRACE, "line")),
    ImpactCase("trace-inf", replace_sample(1700, "-inf"), ("non-finite value", VICTIM_TRACE)),
    ImpactCase("trace-few-samples", edit_trace(lambda h, s: (h, s[:50])), ("truncated trace", "50 samples")),
    ImpactCase("trace-cut-in-contact", cut_in_contact, ("contact not entirely inside the trace",), file_level=False),
    ImpactCase("trace-garbage-line", insert_sample_line(2000, "ERROR: buffer overrun"),
               ("non-numeric value", "ERROR: buffer overrun", VICTIM_TRACE)),
    ImpactCase("trace-two-fields", replace_sample(10, "0.01,0.02"), ("expected 1 field(s)",)),
    ImpactCase("trace-blank-line", insert_sample_line(500, ""), ("empty line among the samples",)),
    ImpactCase("trace-units-mV", set_header_key("units", "mV"), ("units must be 'V'", "'mV'")),
    ImpactCase("trace-rate-zero", set_header_key("sample_rate_hz", "0"), ("sample_rate_hz must be a positive number",)),
    ImpactCase("trace-rate-fast", set_header_key("sample_rate_hz", "fast"), ("sample_rate_hz", "'fast'")),
    ImpactCase("trace-rate-empty", set_header_key("sample_rate_hz", ""), ("sample_rate_hz",)),
    ImpactCase("trace-rate-negative", set_header_key("sample_rate_hz", "-66964.3"), ("sample_rate_hz",)),
    ImpactCase("trace-bad-header-line", edit_trace(lambda h, s: (["# no colon in this header line"] + h, s)),
               ("header line must look like",)),
    ImpactCase("trace-no-voltage-column", edit_trace(lambda h, s: (h[:-1] + ["volts"], s)), ("missing voltage_V",)),
    ImpactCase("trace-time-not-increasing", time_column(decreasing_at=3000), ("time_s must be strictly increasing",)),
    ImpactCase("trace-empty-0-bytes", trace_bytes(b""), ("empty trace file",)),
    ImpactCase("trace-whitespace-only", trace_bytes(b"\n\n  \n"), ("empty trace file",)),
    ImpactCase("trace-header-no-samples", edit_trace(lambda h, s: (h, [])), ("no samples",)),
    ImpactCase("trace-non-utf8", non_utf8_trace, ("not valid UTF-8", "0xff")),
    ImpactCase("trace-binary-junk", trace_bytes(bytes(range(256)) * 40), (VICTIM_TRACE,)),
    ImpactCase("trace-all-zeros", all_zeros, ("no contact found",), file_level=False),
    ImpactCase("tdms-not-tdms", point_trace_at(lambda d: "traces/fake.tdms", fake_tdms(b"voltage_V\n0.1\n" * 200)),
               ("not a readable TDMS file", "fake.tdms")),
    ImpactCase("tdms-bad-lead-in", point_trace_at(lambda d: "traces/fake.tdms",
                                                  fake_tdms(b"TDSm" + bytes(range(256)) * 8)),
               ("TDMS", "fake.tdms")),
    ImpactCase("tdms-empty", point_trace_at(lambda d: "traces/fake.tdms", fake_tdms(b"")), ("fake.tdms",)),
]

BENIGN_CASES = {
    # variations the spec allows: nothing may be excluded
    "csv-crlf": crlf(C),
    "yaml-crlf": crlf(Y),
    "csv-bom": bom(C),
    "yaml-bom": bom(Y),
    "trace-crlf-bom": lambda d: (crlf("traces/" + VICTIM_TRACE)(d), bom("traces/" + VICTIM_TRACE)(d)),
    "trace-without-rate-header": set_header_key("sample_rate_hz", None),
    "trace-without-any-header": edit_trace(lambda h, s: (["voltage_V"], s)),
    "trace-with-time-column": time_column(),
    "trace-extra-metadata": set_header_key("operator note", "plate re-tightened: 2 Nm"),
    "csv-blank-lines-and-unknown-column": compose(
        replace_bytes(C, b",note\n", b",note,humidity_pct\n"),
        lambda d: (d / C).write_text(
            "\n".join(line + ",45" if i else line
                      for i, line in enumerate((d / C).read_text(encoding="utf-8").splitlines())) + "\n\n\n",
            encoding="utf-8"),
    ),
    "csv-optional-columns-absent": compose(drop_column("note"), drop_column("mass_g")),
    "csv-columns-reordered": lambda d: write_rows(d, [r[::-1] for r in read_rows(d)]),
    "csv-quoted-note-with-comma": set_cell("note", 'ball "B7", re-used, 2nd day'),
    "trace-backslash-path": set_cell("trace", "traces\\" + VICTIM_TRACE),
}


# ----------------------------------------------------------------------------- contract checks


def snapshot(folder: Path) -> dict:
    """Every file and folder under ``folder``: sha256, size and mtime (files), mtime (folders)."""
    state = {}
    for p in sorted(folder.rglob("*")):
        st = p.lstat()
        if p.is_file():
            state[str(p.relative_to(folder))] = (hashlib.sha256(p.read_bytes()).hexdigest(), st.st_size,
                                                 st.st_mtime_ns)
        else:
            state[str(p.relative_to(folder)) + "/"] = (st.st_mtime_ns,)
    state["."] = (folder.lstat().st_mtime_ns,)
    return state


class OpenSpy:
    """Records every open of a path under ``root``; a write/append/create/update mode is a violation."""

    def __init__(self, root: Path):
        self.root = root.resolve()
        self.opened: list[tuple[Path, str]] = []
        self.violations: list[tuple[Path, str]] = []

    def _under_root(self, file) -> Path | None:
        if isinstance(file, int):
            return None
        try:
            p = Path(os.fsdecode(file)).resolve()
        except (TypeError, ValueError, OSError):
            return None
        return p if p == self.root or p.is_relative_to(self.root) else None

    def check(self, file, mode: str) -> None:
        p = self._under_root(file)
        if p is not None:
            self.opened.append((p, mode))
            if WRITE_MODE_CHARS & set(mode):
                self.violations.append((p, mode))

    def check_flags(self, file, flags: int) -> None:
        p = self._under_root(file)
        if p is not None:
            self.opened.append((p, f"os.open flags {flags:#o}"))
            if flags & WRITE_FLAGS:
                self.violations.append((p, f"os.open flags {flags:#o}"))


@contextmanager
def read_only_guard(monkeypatch, root: Path):
    """Patch builtins.open, io.open, Path.open and os.open to record the modes used under root."""
    spy = OpenSpy(root)
    real_open, real_io_open, real_path_open, real_os_open = builtins.open, io.open, Path.open, os.open

    def guarded_open(file, mode="r", *args, **kwargs):
        spy.check(file, mode)
        return real_open(file, mode, *args, **kwargs)

    def guarded_io_open(file, mode="r", *args, **kwargs):
        spy.check(file, mode)
        return real_io_open(file, mode, *args, **kwargs)

    def guarded_path_open(self, mode="r", *args, **kwargs):
        spy.check(self, mode)
        return real_path_open(self, mode, *args, **kwargs)

    def guarded_os_open(path, flags, *args, **kwargs):
        spy.check_flags(path, flags)
        return real_os_open(path, flags, *args, **kwargs)

    with monkeypatch.context() as m:
        m.setattr(builtins, "open", guarded_open)
        m.setattr(io, "open", guarded_io_open)
        m.setattr(Path, "open", guarded_path_open)
        m.setattr(os, "open", guarded_os_open)
        yield spy


def run_everything(session_dir: Path, monkeypatch):
    """read_session + iter_process + validate_session under the read-only guard; the folder must not change.

    Returns (session, results, report, spy); session/results/report are None when
    read_session raised SessionError (the error is returned in place of the session).
    """
    before = snapshot(session_dir)
    session = results = report = None
    with read_only_guard(monkeypatch, session_dir) as spy, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SessionWarning / ConditioningWarning are allowed here
        try:
            session = read_session(session_dir)
        except SessionError as exc:
            session = exc
        else:
            results = list(iter_process(session))
            report = validate_session(session_dir)
    assert snapshot(session_dir) == before, "the raw session folder changed"
    assert not spy.violations, f"raw files opened for writing: {spy.violations}"
    return session, results, report, spy


def run_cli_validate(session_dir: Path) -> subprocess.CompletedProcess:
    return subprocess.run([BALLIMPACT, "validate", str(session_dir)], capture_output=True, text=True, timeout=60)


# ----------------------------------------------------------------------------- tests


def test_base_session_is_good_and_untouched(base_session, monkeypatch):
    session, results, report, spy = run_everything(base_session, monkeypatch)
    assert [r.status for r in results] == ["ok"] * 4
    assert report.ok and report.n_impacts == 4
    opened = {p for p, _ in spy.opened}
    assert base_session.resolve() / "session.yaml" in opened
    assert base_session.resolve() / "impacts.csv" in opened
    for row in session.impacts:  # every trace was read, and only read
        assert session.trace_path(row).resolve() in opened


@pytest.mark.parametrize("case", SESSION_CASES, ids=lambda c: c.id)
def test_session_level_fault(case, session_copy, monkeypatch):
    case.breaker(session_copy)
    if session_copy.is_dir():
        error, results, _, _ = run_everything(session_copy, monkeypatch)
        assert results is None
    else:
        with pytest.raises(SessionError) as info:
            read_session(session_copy)
        error = info.value
    assert isinstance(error, SessionError), f"read_session accepted the broken session ({case.id})"
    message = str(error)
    assert "\n" not in message and message.strip() == message, repr(message)
    assert case.file in message, message
    for part in case.where:
        assert part in message, (part, message)
    # validate_session raises it too
    with pytest.raises(SessionError):
        validate_session(session_copy)
    # the command line: exit 2, exactly that one line on stderr, no traceback, nothing written
    before = snapshot(session_copy) if session_copy.is_dir() else session_copy.read_bytes()
    r = run_cli_validate(session_copy)
    assert (snapshot(session_copy) if session_copy.is_dir() else session_copy.read_bytes()) == before
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines() == [f"error: {message}"]
    assert r.stdout == ""


@pytest.mark.parametrize("case", IMPACT_CASES, ids=lambda c: c.id)
def test_impact_level_fault(case, session_copy, monkeypatch):
    ids = [row[0] for row in read_rows(session_copy)[1:]]
    victim = victim_id(session_copy)
    case.breaker(session_copy)
    session, results, report, _ = run_everything(session_copy, monkeypatch)
    assert not isinstance(session, SessionError), f"impact-level fault stopped the session: {session}"
    assert [r.impact_id for r in results] == ids, "every impact must be listed, in raw order"
    for r in results:
        if r.impact_id == victim:
            assert r.status == "excluded", f"{case.id}: broken impact was not excluded"
            assert r.reason, "an excluded impact needs a reason"
            for part in case.reason:
                assert part in r.reason, (part, r.reason)
        else:
            assert r.status == "ok", (r.impact_id, r.reason)
            assert r.reason == ""
    if case.file_level:
        assert report.impacts_with_problems == [victim], report.problems
    else:
        assert report.impacts_with_problems == [], report.problems


@pytest.mark.parametrize("name", list(BENIGN_CASES))
def test_allowed_variation_is_not_a_fault(name, session_copy, monkeypatch):
    BENIGN_CASES[name](session_copy)
    session, results, report, _ = run_everything(session_copy, monkeypatch)
    assert not isinstance(session, SessionError), str(session)
    assert [(r.impact_id, r.status, r.reason) for r in results] == [(r.impact_id, "ok", "") for r in results]
    assert report.ok, report.problems


@pytest.mark.parametrize("cell", ["12:03:04.5", "nan", "inf"])
def test_unreadable_gate_time_is_not_called_missing(cell, session_copy):
    """A gate cell with text in it was not missed by the timer: the reason must not say so."""
    set_cell("gate_in_2_s", cell)(session_copy)
    result = list(iter_process(read_session(session_copy)))[VICTIM]
    assert result.status == "excluded"
    assert "gate time gate_in_2_s" in result.reason and "missing" not in result.reason, result.reason


def test_many_faults_at_once_each_impact_judged_alone(session_copy, monkeypatch):
    """One fault on each of three impacts: three exclusions with their own reasons, the fourth ok."""
    rows = read_rows(session_copy)
    ids = [r[0] for r in rows[1:]]
    set_cell("gate_in_1_s", "", row=0)(session_copy)
    replace_sample(1000, "nan")(session_copy)  # row 1
    set_cell("trace", "../outside.csv", row=2)(session_copy)
    copy_victim_outside(session_copy)
    _, results, report, _ = run_everything(session_copy, monkeypatch)
    by_id = {r.impact_id: r for r in results}
    assert "missing gate time gate_in_1_s" in by_id[ids[0]].reason
    assert "non-finite value" in by_id[ids[1]].reason
    assert "escapes the session folder" in by_id[ids[2]].reason
    assert by_id[ids[3]].status == "ok" and by_id[ids[3]].reason == ""
    assert [by_id[i].status for i in ids[:3]] == ["excluded"] * 3
    assert report.impacts_with_problems == ids[:3]


def test_cli_validate_on_impact_faults_lists_them_and_changes_nothing(session_copy):
    """The real command on a session with impact-level faults: exit 0, problems listed, folder unchanged."""
    set_cell("gate_out_2_s", "abc")(session_copy)
    set_header_key("units", "mV")(session_copy)
    before = snapshot(session_copy)
    r = run_cli_validate(session_copy)
    assert snapshot(session_copy) == before
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    assert "non-numeric gate time gate_out_2_s" in r.stdout and "units must be 'V'" in r.stdout
    r = subprocess.run([BALLIMPACT, "validate", "--strict", str(session_copy)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 1
    assert snapshot(session_copy) == before


def test_cli_validate_in_process_session_fault(session_copy, capsys):
    """main() returns 2 and prints one line to stderr (no exception escapes)."""
    yaml_set("plate.polarity", "up")(session_copy)
    assert cli_main(["validate", str(session_copy)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert len(captured.err.strip().splitlines()) == 1
    assert "session.yaml" in captured.err and "plate.polarity" in captured.err


def test_read_only_guard_catches_a_write(session_copy, monkeypatch):
    """The guard itself works: a write under the session folder is recorded, a read is not a violation."""
    with read_only_guard(monkeypatch, session_copy) as spy:
        with open(session_copy / "impacts.csv", "rb"):
            pass
        with (session_copy / "probe.txt").open("w") as fh:
            fh.write("x")
        os.close(os.open(session_copy / "probe2.txt", os.O_WRONLY | os.O_CREAT))
    assert [mode for _, mode in spy.violations][:1] == ["w"]
    assert len(spy.violations) >= 2
    assert any(mode == "rb" for _, mode in spy.opened)
