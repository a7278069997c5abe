"""Trace file reader: one charge-amplifier voltage trace per impact (CSV, NI TDMS or LabVIEW LVM)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

__all__ = ["TraceError", "Trace", "read_trace", "trace_header_rate", "MIN_SAMPLES", "TRACE_FORMATS"]

MIN_SAMPLES = 100  # fewer samples than this is a truncated trace
UNIFORM_SAMPLING_RTOL = 0.01  # time_s steps may differ from the median step by this fraction
RATE_AGREEMENT_RTOL = 0.005  # header sample_rate_hz vs time_s column: largest relative difference
TRACE_FORMATS = {".csv": "csv", ".tdms": "tdms", ".lvm": "lvm"}
VOLTAGE_COLUMN = "voltage_V"
TIME_COLUMN = "time_s"
_TDMS_VOLT_UNITS = {"v", "volt", "volts"}  # accepted `unit_string` (TDMS) and `Y_Unit_Label` (LVM) values
_LVM_END = "***End_of_Header***"  # closes the file header and each segment header of an LVM file
_QUANTUM_PROBE_LINES = 50  # time_s strings looked at (each end) to find their printed resolution


class TraceError(ValueError):
    """Impact-level fault of a trace file; the message names the file (and line)."""


@dataclass
class Trace:
    """One recorded voltage trace."""

    voltage_V: np.ndarray  # [V] float64, as recorded (polarity NOT applied)
    sample_rate_hz: float  # [Hz]
    t0_s: float  # [s] time of the first sample
    metadata: dict  # header keys / TDMS properties
    path: Path
    format: str  # "csv", "tdms" or "lvm"
    sample_rate_source: str  # "header", "time_s", "wf_increment", "Delta_X", "X_Value" or "session"

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.voltage_V.size)

    @property
    def time_s(self) -> np.ndarray:
        """Sample times [s]: ``t0_s + i / sample_rate_hz``."""
        return self.t0_s + np.arange(self.voltage_V.size) / self.sample_rate_hz


def _positive_float(value) -> float | None:
    """Positive finite float of a number or numeric string, else None."""
    if isinstance(value, (bool, np.bool_)):
        return None
    try:
        number = float(value.strip() if isinstance(value, str) else value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) and number > 0 else None


def _read_bytes(path: Path, file: str) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise TraceError(f"{file}: cannot read: {exc.strerror or exc}") from None


def _check_samples(file: str, voltage: np.ndarray, where) -> None:
    """Non-finite values and too few samples; ``where(i)`` names sample i ('line 7')."""
    finite = np.isfinite(voltage)
    if not finite.all():
        i = int(np.argmin(finite))
        raise TraceError(f"{file}: {where(i)}: non-finite value {float(voltage[i])!r} (NaN/inf are not samples)")
    if voltage.size < MIN_SAMPLES:
        raise TraceError(f"{file}: truncated trace: only {voltage.size} samples (at least {MIN_SAMPLES} required)")


# ---------------------------------------------------------------------------- CSV


def _parse_header(lines: list[str], file: str) -> tuple[dict, dict, int]:
    """`# key: value` lines; returns metadata, the line of each key, index of the header row."""
    metadata: dict[str, str] = {}
    key_line: dict[str, int] = {}
    i = 0
    while i < len(lines):
        stripped = lines[i].strip()
        if not stripped:
            i += 1
            continue
        if not stripped.startswith("#"):
            break
        body = stripped[1:].strip()
        if body:
            key, sep, value = body.partition(":")
            key = key.strip()
            if not sep or not key:
                raise TraceError(f"{file}: line {i + 1}: header line must look like '# key: value', got {lines[i]!r}")
            if key in key_line:
                raise TraceError(f"{file}: line {i + 1}: header key {key!r} repeats line {key_line[key]}")
            metadata[key] = value.strip()
            key_line[key] = i + 1
        i += 1
    return metadata, key_line, i


def _fields_per_line(data: list[str], n_fields: int) -> bool:
    """True when every line has exactly n_fields comma-separated fields (vectorised)."""
    raw = np.frombuffer("\n".join(data).encode("utf-8"), dtype=np.uint8)
    newlines = np.flatnonzero(raw == ord("\n"))
    line_of_comma = np.searchsorted(newlines, np.flatnonzero(raw == ord(",")))
    commas = np.bincount(line_of_comma, minlength=len(data))
    return bool(np.all(commas == n_fields - 1))


def _fast_parse(data: list[str], n_fields: int) -> np.ndarray | None:
    """All samples as an (n, n_fields) float64 array, or None if any line is malformed."""
    try:
        if n_fields == 1:
            return np.array(data, dtype=np.float64).reshape(-1, 1)
        flat = ",".join(data).split(",")
        if len(flat) != n_fields * len(data) or not _fields_per_line(data, n_fields):
            return None
        return np.array(flat, dtype=np.float64).reshape(-1, n_fields)
    except (ValueError, TypeError):
        return None


def _raise_bad_line(data: list[str], columns: list[str], first_line: int, file: str) -> None:
    """Slow path after the fast parse failed: TraceError naming the first malformed line."""
    for k, text in enumerate(data):
        line = first_line + k
        if not text.strip():
            raise TraceError(f"{file}: line {line}: empty line among the samples")
        cells = text.split(",")
        if len(cells) != len(columns):
            hint = ""
            if len(cells) > len(columns) and re.search(r"\d,\d", text):
                hint = " (decimal commas? write numbers with a decimal point, e.g. 0.0021 not 0,0021)"
            elif ";" in text or "\t" in text:
                hint = " (the separator must be a comma, not ';' or a tab)"
            raise TraceError(
                f"{file}: line {line}: expected {len(columns)} field(s) ({','.join(columns)}), got {len(cells)}"
                + hint
            )
        for cell in cells:
            try:
                float(cell)
            except ValueError:
                raise TraceError(f"{file}: line {line}: non-numeric value {cell.strip()!r}") from None


def _decimal_quantum(texts: list[str]) -> float:
    """Median printing resolution of number strings ('0.000015' -> 1e-6), 0 if none."""
    quanta = []
    for text in texts:
        try:
            exponent = Decimal(text.strip()).as_tuple().exponent
        except InvalidOperation:
            continue
        if isinstance(exponent, int):
            quanta.append(10.0**exponent)
    return float(np.median(quanta)) if quanta else 0.0


def _time_column_rate(time: np.ndarray, time_texts: list[str], first_line: int, file: str) -> float:
    """Sample rate [Hz] from a time_s column; TraceError if not increasing or not uniform."""
    step = np.diff(time)
    bad = step <= 0
    if bad.any():
        k = int(np.argmax(bad))
        raise TraceError(
            f"{file}: line {first_line + k + 1}: time_s must be strictly increasing, "
            f"got {float(time[k + 1])!r} after {float(time[k])!r}"
        )
    median_step = float(np.median(step))
    # Values printed with few decimals jitter by up to one printed digit: allow for it.
    # (a robust value at each end: the end with the largest |t| has the coarsest digits
    # in %g formats, and an occasional short repr such as '0.0' must not count)
    quantum = max(
        _decimal_quantum(time_texts[:_QUANTUM_PROBE_LINES]), _decimal_quantum(time_texts[-_QUANTUM_PROBE_LINES:])
    )
    tolerance = UNIFORM_SAMPLING_RTOL * median_step + quantum
    off = np.abs(step - median_step) > tolerance
    if off.any():
        k = int(np.argmax(off))
        raise TraceError(
            f"{file}: line {first_line + k + 1}: non-uniform sampling: time step {step[k]:.6g} s differs "
            f"from the median step {median_step:.6g} s by more than {UNIFORM_SAMPLING_RTOL:.0%}"
        )
    # The mean step over the whole span is immune to the printing resolution.
    return (time.size - 1) / float(time[-1] - time[0])


def _read_csv(path: Path, file: str, default_sample_rate_hz: float) -> Trace:
    lines = _csv_lines(path, file)
    metadata, key_line, header_index = _parse_header(lines, file)
    columns = _csv_columns(lines, header_index, file)
    header_line = header_index + 1
    header_rate = _csv_header_rate(metadata, key_line, file)
    data = lines[header_index + 1 :]
    while data and not data[-1].strip():
        data.pop()
    if not data:
        raise TraceError(f"{file}: no samples after the header row (line {header_line})")
    first_line = header_line + 1
    values = _fast_parse(data, len(columns))
    if values is None:
        _raise_bad_line(data, columns, first_line, file)
        # every line is fine by Python's float(): numpy only differs on exotic input
        values = np.array([[float(c) for c in line.split(",")] for line in data], dtype=np.float64)
    voltage = np.ascontiguousarray(values[:, -1])
    _check_samples(file, voltage, lambda i: f"line {first_line + i}")

    t0_s = 0.0
    if len(columns) == 2:
        rate, t0_s = _csv_time_column_rate(values[:, 0], data, first_line, header_rate, key_line, file)
        source = "time_s"
    elif header_rate is not None:
        rate, source = header_rate, "header"
    else:
        rate, source = default_sample_rate_hz, "session"
    return Trace(
        voltage_V=voltage,
        sample_rate_hz=float(rate),
        t0_s=t0_s,
        metadata=metadata,
        path=path,
        format="csv",
        sample_rate_source=source,
    )


def _csv_lines(path: Path, file: str) -> list[str]:
    """The lines of a CSV trace, decoded (UTF-8, BOM allowed), any line ending."""
    data_bytes = _read_bytes(path, file)
    if not data_bytes.strip():
        raise TraceError(f"{file}: empty trace file (no header row, no samples)")
    try:
        text = data_bytes.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data_bytes[: exc.start].count(b"\n") + 1
        raise TraceError(f"{file}: line {line}: not valid UTF-8 (byte 0x{data_bytes[exc.start]:02x})") from None
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _csv_columns(lines: list[str], header_index: int, file: str) -> list[str]:
    """The columns of the header row: [voltage_V] or [time_s, voltage_V], else a TraceError."""
    if header_index >= len(lines):
        raise TraceError(f"{file}: no header row ({VOLTAGE_COLUMN}) and no samples")
    header_line = header_index + 1
    columns = [cell.strip().strip('"') for cell in lines[header_index].split(",")]
    if columns not in ([VOLTAGE_COLUMN], [TIME_COLUMN, VOLTAGE_COLUMN]):
        if VOLTAGE_COLUMN not in columns:
            raise TraceError(
                f"{file}: line {header_line}: missing {VOLTAGE_COLUMN} column (header row is {lines[header_index]!r})"
            )
        raise TraceError(
            f"{file}: line {header_line}: header row must be '{VOLTAGE_COLUMN}' or "
            f"'{TIME_COLUMN},{VOLTAGE_COLUMN}', got {lines[header_index]!r}"
        )
    return columns


def _csv_header_rate(metadata: dict, key_line: dict, file: str) -> float | None:
    """The ``# sample_rate_hz`` of a CSV header [Hz] (None when absent); checks ``# units``."""
    units = metadata.get("units")
    if units is not None and units != "V":
        raise TraceError(f"{file}: line {key_line['units']}: units must be 'V', got {units!r}")
    header_rate = None
    if "sample_rate_hz" in metadata:
        header_rate = _positive_float(metadata["sample_rate_hz"])
        if header_rate is None:
            raise TraceError(
                f"{file}: line {key_line['sample_rate_hz']}: sample_rate_hz must be a positive number, "
                f"got {metadata['sample_rate_hz']!r}"
            )
    return header_rate


def _csv_time_column_rate(time, data, first_line, header_rate, key_line, file) -> tuple[float, float]:
    """Sample rate [Hz] and first time [s] from a time_s column, which must agree with a header rate."""
    if not np.isfinite(time).all():
        i = int(np.argmin(np.isfinite(time)))
        raise TraceError(f"{file}: line {first_line + i}: non-finite time_s value {float(time[i])!r}")
    probe = data[:_QUANTUM_PROBE_LINES] + data[-_QUANTUM_PROBE_LINES:]
    time_texts = [line.split(",", 1)[0] for line in probe]
    rate = _time_column_rate(time, time_texts, first_line, file)
    if header_rate is not None and abs(rate - header_rate) > RATE_AGREEMENT_RTOL * header_rate:
        raise TraceError(
            f"{file}: line {key_line['sample_rate_hz']}: header sample_rate_hz {header_rate:g} Hz disagrees "
            f"with the time_s column ({rate:.6g} Hz) by {abs(rate / header_rate - 1):.2%} "
            f"(more than {RATE_AGREEMENT_RTOL:.1%})"
        )
    return rate, float(time[0])


# --------------------------------------------------------------------------- TDMS


def _plain(value):
    """TDMS property value as a plain Python object (for archives)."""
    if isinstance(value, np.datetime64):
        return str(value)
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_tdms(path: Path, file: str, default_sample_rate_hz: float) -> Trace:
    from nptdms import TdmsFile

    try:
        tdms = TdmsFile.read(path)
        groups = tdms.groups()
    except Exception as exc:  # npTDMS raises many types for a damaged file
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise TraceError(f"{file}: not a readable TDMS file: {detail}") from None
    if not groups:
        raise TraceError(f"{file}: empty trace: the TDMS file has no groups")
    channels = groups[0].channels()
    if not channels:
        raise TraceError(f"{file}: empty trace: TDMS group {groups[0].name!r} has no channels")
    channel = channels[0]
    try:
        voltage = np.array(channel[:], dtype=np.float64)
    except (TypeError, ValueError):
        raise TraceError(f"{file}: TDMS channel {channel.name!r} does not hold numbers") from None
    if voltage.size == 0:
        raise TraceError(f"{file}: empty trace: TDMS channel {channel.name!r} has no samples")
    _check_samples(file, voltage, lambda i: f"channel {channel.name!r} sample {i}")

    properties = {str(k): _plain(v) for k, v in channel.properties.items()}
    metadata = {"tdms_group": groups[0].name, "tdms_channel": channel.name, **properties}
    units = properties.get("unit_string")
    if units not in (None, "") and str(units).strip().lower() not in _TDMS_VOLT_UNITS:
        raise TraceError(f"{file}: channel {channel.name!r} unit_string must be 'V', got {units!r}")
    if "wf_increment" in properties:
        increment = _positive_float(properties["wf_increment"])
        if increment is None:
            raise TraceError(
                f"{file}: channel {channel.name!r} property wf_increment must be a positive number of "
                f"seconds, got {properties['wf_increment']!r}"
            )
        rate, source = 1.0 / increment, "wf_increment"
    else:
        rate, source = default_sample_rate_hz, "session"
    t0_s = 0.0
    if "wf_start_offset" in properties:
        offset = properties["wf_start_offset"]
        try:
            t0_s = float(offset)
        except (TypeError, ValueError):
            t0_s = math.nan
        if isinstance(offset, bool) or not math.isfinite(t0_s):
            raise TraceError(
                f"{file}: channel {channel.name!r} property wf_start_offset must be a number of seconds, "
                f"got {offset!r}"
            )
    return Trace(
        voltage_V=voltage,
        sample_rate_hz=float(rate),
        t0_s=t0_s,
        metadata=metadata,
        path=path,
        format="tdms",
        sample_rate_source=source,
    )


# ---------------------------------------------------------------------------- LVM


def _lvm_text(path: Path, file: str) -> str:
    """The text of an LVM file (UTF-8, else the Windows code page LabVIEW writes), checked to be one."""
    data = _read_bytes(path, file)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("cp1252", errors="replace")
    if not text.lstrip().startswith("LabVIEW Measurement"):
        first = text.strip().splitlines()[0][:60] if text.strip() else ""
        raise TraceError(f"{file}: not a LabVIEW Measurement file: its first line is {first!r}, "
                         "expected 'LabVIEW Measurement'")
    return text


def _lvm_channel(segment: dict) -> tuple[int, int | None, str]:
    """Column of the first data channel in a segment's data, column of its X values (None), its name."""
    names = [str(n).strip() for n in segment.get("Channel names", [])]
    for k, name in enumerate(names):
        if name not in ("X_Value", "Comment", ""):
            return k, (k - 1 if k > 0 and names[k - 1] == "X_Value" else None), name
    raise TraceError("no data channel")


def _lvm_value(segment: dict, key: str, index: int):
    """A per-channel header value of an LVM segment (``Delta_X``, ``X0``, ``Y_Unit_Label``), None if absent."""
    values = segment.get(key)
    if not isinstance(values, list) or index >= len(values):
        return None
    value = values[index]
    return value.strip() if isinstance(value, str) else value


def _lvm_samples(file: str, lvm: dict) -> tuple[np.ndarray, np.ndarray | None, dict, str]:
    """Voltage [V], X values [s] or None, the first segment's header and the channel's name."""
    voltage, xs, first = [], [], None
    for k in range(int(lvm.get("Segments", 0))):
        segment = lvm[k]
        try:
            column, x_column, name = _lvm_channel(segment)
        except TraceError:
            raise TraceError(f"{file}: LVM segment {k + 1} has no data channel") from None
        data = np.asarray(segment.get("data", np.empty((0, 0))), dtype=np.float64)
        if data.ndim != 2 or data.shape[1] <= column:
            raise TraceError(f"{file}: LVM segment {k + 1}: no samples for channel {name!r}")
        if first is None:
            first = (segment, name, _lvm_value(segment, "Delta_X", 0))
        elif _lvm_value(segment, "Delta_X", 0) != first[2]:
            raise TraceError(f"{file}: LVM segment {k + 1} has Delta_X {_lvm_value(segment, 'Delta_X', 0)!r}, "
                             f"segment 1 {first[2]!r}: one trace must have one sample rate")
        voltage.append(data[:, column])
        xs.append(data[:, x_column] if x_column is not None else None)
    if first is None:
        raise TraceError(f"{file}: LVM file without a data segment")
    x = np.concatenate(xs) if all(v is not None for v in xs) else None
    return np.concatenate(voltage), x, first[0], first[1]


def _read_lvm(path: Path, file: str, default_sample_rate_hz: float) -> Trace:
    import lvm_read

    text = _lvm_text(path, file)
    try:
        lvm = lvm_read.read_str(text)
    except Exception as exc:  # lvm_read raises ValueError, SyntaxError, KeyError, ... on a damaged file
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise TraceError(f"{file}: not a readable LabVIEW Measurement file: {detail}") from None
    voltage, x, segment, name = _lvm_samples(file, lvm)
    _check_samples(file, voltage, lambda i: f"channel {name!r} sample {i}")
    units = _lvm_value(segment, "Y_Unit_Label", 0)
    if units not in (None, "") and str(units).lower() not in _TDMS_VOLT_UNITS:
        raise TraceError(f"{file}: channel {name!r} Y_Unit_Label must be volts, got {units!r}")
    delta = _lvm_value(segment, "Delta_X", 0)
    increment = _positive_float(delta) if delta is not None else None
    if increment is not None:
        rate, source = 1.0 / increment, "Delta_X"
    elif x is not None and np.isfinite(x).all() and x.size > 1:
        rate, source = _time_column_rate(x, [], 1, f"{file}: X_Value column"), "X_Value"
    else:
        rate, source = default_sample_rate_hz, "session"
    x0 = _lvm_value(segment, "X0", 0)
    t0_s = float(x0) if isinstance(x0, (int, float)) and math.isfinite(x0) else 0.0
    metadata = {str(k): v for k, v in lvm.items() if isinstance(k, str) and isinstance(v, str)}
    metadata.update(lvm_channel=name, lvm_segments=int(lvm.get("Segments", 1)))
    return Trace(voltage_V=voltage, sample_rate_hz=float(rate), t0_s=t0_s, metadata=metadata, path=path,
                 format="lvm", sample_rate_source=source)


def _lvm_header_rate(path: Path) -> float | None:
    """``Delta_X`` of an LVM file's first channel as a rate [Hz], from its header lines alone."""
    separator, decimal, ends = "\t", ".", 0
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        for line in fh:
            line = line.rstrip("\r\n")
            if line.startswith("Separator") and len(line) > 9:
                separator = line[9]
            elif line.startswith("Decimal_Separator") and len(line) > 18:
                decimal = line[18]
            elif line.startswith(_LVM_END):
                ends += 1
                if ends == 2:
                    return None
            elif line.startswith("Delta_X") and ends == 1:
                fields = line.split(separator)
                increment = _positive_float(fields[1].replace(decimal, ".")) if len(fields) > 1 else None
                return None if increment is None else 1.0 / increment
    return None


# ------------------------------------------------------------------------- public


def read_trace(path, default_sample_rate_hz: float) -> Trace:
    """
    Read one voltage trace (CSV or NI TDMS), without writing anything.

    Parameters
    ----------
    path : str or Path
        Trace file, ``.csv`` (``# key: value`` header lines, then a ``voltage_V``
        column, optionally preceded by ``time_s``), ``.tdms`` (first channel of
        the first group; ``wf_increment`` [s] and ``wf_start_offset`` [s] used) or
        ``.lvm`` (LabVIEW Measurement text, read by ``lvm_read``: the first data
        channel; its ``Delta_X`` [s], else its X column [s], and ``X0`` [s] used;
        the segments of a file with several are joined).
    default_sample_rate_hz : float
        Sample rate [Hz] used when the file gives none (session.yaml's
        ``daq.sample_rate_hz``).

    Returns
    -------
    Trace
        Voltage [V] as recorded, sample rate [Hz], time of the first sample [s],
        metadata, format and where the sample rate came from.

    Raises
    ------
    TraceError
        Missing, unreadable or malformed file, with the file and line named.
    ValueError
        ``default_sample_rate_hz`` not a positive number.
    """
    if _positive_float(default_sample_rate_hz) is None or isinstance(default_sample_rate_hz, str):
        raise ValueError(f"default_sample_rate_hz must be a positive number, got {default_sample_rate_hz!r}")
    default_sample_rate_hz = float(default_sample_rate_hz)
    path = Path(path)
    file = str(path)
    if not path.exists():
        raise TraceError(f"{file}: trace file not found")
    if not path.is_file():
        raise TraceError(f"{file}: trace path is not a file")
    kind = TRACE_FORMATS.get(path.suffix.lower())
    if kind == "csv":
        return _read_csv(path, file, default_sample_rate_hz)
    if kind == "tdms":
        return _read_tdms(path, file, default_sample_rate_hz)
    if kind == "lvm":
        return _read_lvm(path, file, default_sample_rate_hz)
    raise TraceError(f"{file}: unknown trace file extension {path.suffix!r} (expected {', '.join(TRACE_FORMATS)})")


def trace_header_rate(path) -> float | None:
    """
    The sample rate a trace file gives itself, from its header alone (no samples read).

    Parameters
    ----------
    path : str or Path
        A ``.csv`` (``# sample_rate_hz: ...`` header line), ``.tdms`` (channel property
        ``wf_increment`` [s]) or ``.lvm`` trace (``Delta_X`` [s] of its first channel).

    Returns
    -------
    float or None
        [Hz]; None when the header states none (a CSV ``time_s`` column is not read).

    Raises
    ------
    OSError, ValueError
        The file cannot be read (:func:`read_trace` says why).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".tdms":
        from nptdms import TdmsFile

        groups = TdmsFile.read_metadata(path).groups()
        props = groups[0].channels()[0].properties if groups and groups[0].channels() else {}
        increment = _positive_float(props["wf_increment"]) if "wf_increment" in props else None
        return None if increment is None else 1.0 / increment
    if suffix == ".lvm":
        return _lvm_header_rate(path)
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        for line in fh:
            if not line.startswith("#"):
                return None
            key, _, value = line[1:].partition(":")
            if key.strip() == "sample_rate_hz":
                return _positive_float(value)
    return None
