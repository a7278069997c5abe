"""Raw session reader: session.yaml and impacts.csv of one test session folder."""

from __future__ import annotations

import csv
import datetime
import hashlib
import io
import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath, PureWindowsPath

import yaml

from .problems import Problem, ProblemKind

__all__ = [
    "SessionError",
    "SessionWarning",
    "BallType",
    "SessionMeta",
    "ImpactRow",
    "Session",
    "read_session",
    "SessionPlan",
    "plan_session",
    "file_sha256",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "GATE_COLUMNS",
    "near_miss_name",
    "alias_risk",
]

SESSION_FILE = "session.yaml"
IMPACTS_FILE = "impacts.csv"

GATE_COLUMNS = ("gate_in_1_s", "gate_in_2_s", "gate_out_2_s", "gate_out_1_s")
REQUIRED_COLUMNS = ("impact_id", "ball", "trace") + GATE_COLUMNS
OPTIONAL_COLUMNS = ("mass_g", "note")

IMPACT_ID_PATTERN = re.compile(r"[A-Za-z0-9_-]+")
ISO_DATE_PATTERN = re.compile(r"\d{4}-\d{2}-\d{2}")

MASS_MIN_G = 1.0  # [g] exclusive lower bound of a plausible ball mass
MASS_MAX_G = 1000.0  # [g] exclusive upper bound of a plausible ball mass
MASS_TYPICAL_MIN_G = 40.0  # [g] below this a warning (tennis balls are 56-59.4 g)
MASS_TYPICAL_MAX_G = 70.0  # [g] above this a warning
DEFAULT_MAINS_HZ = None  # `daq.mains_hz` absent: found in each trace (v1.1)
#: The highest plate resonance labs have (raw-format v1.1: "plate resonances from below 1 kHz to 30 kHz") [Hz]:
#: slower than twice this, without `daq.bandwidth_hz`, a plate's ringing may reach the samples through its alias.
PLATE_RESONANCE_MAX_HZ = 30_000.0
FAST_BALL_SPEED_M_S = 50.0  # [m/s] faster than any ball on the rig; sets the timer sanity bound
MAX_GATE_SPACING_M = 2.0  # [m] a larger spacing is almost surely given in mm: warning

_KNOWN_SECTION_KEYS = {
    "plate": {"polarity", "kcal_range_N_per_V", "time_constant_s", "resonance_hz", "damping_ratio"},
    "daq": {"sample_rate_hz", "adc_range_v", "mains_hz", "bandwidth_hz"},
    "gates": {"spacing_m", "resolution_s", "distance_to_plate_m"},
    "rig": {"orientation", "air_density_kg_m3"},
}
_KNOWN_BALL_KEYS = {"label", "mass_g", "diameter_mm", "kb0_kN_m", "itf_rebound_cm"}
#: The top-level keys of session.yaml (raw-format.md): any other is kept, and warned about.
_KNOWN_TOP_KEYS = {"session_id", "date", "operator", "description", "synthetic", "plate", "daq", "gates", "rig",
                   "balls"}
#: File names a lab may give session.yaml / impacts.csv by mistake (near misses).
_NEAR_MISS_NAMES = {
    SESSION_FILE: ("session.yml", "Session.yaml", "SESSION.yaml", "session.YAML", "session.yaml.txt",
                   "session.txt", "Session.yml", "session_yaml"),
    IMPACTS_FILE: ("Impacts.csv", "IMPACTS.csv", "impacts.CSV", "impacts.csv.txt", "impacts.txt",
                   "impact.csv", "impacts.tsv", "impacts.xlsx"),
}
RIG_ORIENTATIONS = ("horizontal", "vertical")  # `rig.orientation` (v1.1); horizontal is the default
DEFAULT_AIR_DENSITY_KG_M3 = 1.2  # [kg/m^3] default `rig.air_density_kg_m3`
AIR_DENSITY_RANGE_KG_M3 = (0.5, 1.5)  # [kg/m^3] plausible air (sea level to ~5 km); outside = error
DEFAULT_BALL_DIAMETER_M = 0.0654  # [m] ball diameter when `balls.<key>.diameter_mm` is not given
ITF_REBOUND_MAX_CM = 254.0  # [cm] a rebound cannot exceed the 254 cm drop


class SessionError(ValueError):
    """Session-level fault; ``str(e)`` is the message for the user, one line per problem.

    ``problems`` lists every session-level problem found (one line each): the reader
    collects them all instead of stopping at the first, so that one round of
    ``ballimpact validate`` shows everything to fix.
    """

    def __init__(self, message: str, problems: list[str] | None = None):
        self.problems = list(problems) if problems else [str(message)]
        super().__init__(message)


MAX_REPORTED_PROBLEMS = 30  # session-level problems listed in full; the rest are counted


def _raise_collected(problems: list[str]) -> None:
    """Raise one SessionError holding every problem (no-op when there is none)."""
    if not problems:
        return
    shown = problems[:MAX_REPORTED_PROBLEMS]
    if len(problems) > len(shown):
        shown = shown + [f"... and {len(problems) - len(shown)} more session-level problem(s) of the same kinds"]
    raise SessionError("\n".join(shown), shown)


class _Collector:
    """Runs independent checks, keeping the SessionError of each instead of stopping."""

    def __init__(self):
        self.problems: list[str] = []
        self.balls: dict | None = None  # ball types of session.yaml, when they could be read

    def __call__(self, check, *args, **kwargs):
        try:
            return check(*args, **kwargs)
        except SessionError as exc:
            self.problems.extend(exc.problems)
            return None


class SessionWarning(UserWarning):
    """Usable but suspect session metadata (e.g. a ball mass outside 40-70 g)."""


@dataclass(frozen=True)
class BallType:
    """One ball type of a session (a key of ``balls`` in session.yaml)."""

    key: str
    label: str
    mass_kg: float  # [kg]
    diameter_m: float | None  # [m], None when not given
    kb0_N_m: float | None  # [N/m] fixed kB(0) of the model, None = estimate it
    itf_rebound_cm: float | None = None  # [cm] measured ITF 254 cm drop-test rebound (v1.1), None when not given


@dataclass(frozen=True)
class SessionMeta:
    """Rig and ball metadata of a session (session.yaml)."""

    session_id: str
    date: str  # ISO date, YYYY-MM-DD
    operator: str
    description: str
    polarity: int  # +1: compressive force gives positive voltage, -1: negative
    sample_rate_hz: float  # [Hz] default for traces without one
    adc_range_v: tuple[float, float]  # [V] ADC input range (lo, hi)
    gate_spacing_m: float  # [m] distance between gate 1 and gate 2
    gate_resolution_s: float  # [s] timer resolution
    balls: dict[str, BallType]
    mains_hz: float | None  # [Hz] mains frequency, optional `daq.mains_hz`; None = find it in each trace
    synthetic: bool  # optional top-level `synthetic`, default False
    raw: dict  # the parsed YAML, for the archive
    kcal_range_N_per_V: tuple[float, float] | None = None  # [N/V] optional `plate.kcal_range_N_per_V`
    distance_to_plate_m: float | None = None  # [m] optional `gates.distance_to_plate_m` (v1.1): gate 2 to plate
    rig_orientation: str = "horizontal"  # optional `rig.orientation` (v1.1): horizontal or vertical
    air_density_kg_m3: float = DEFAULT_AIR_DENSITY_KG_M3  # [kg/m^3] optional `rig.air_density_kg_m3` (v1.1)
    time_constant_s: float | None = None  # [s] optional `plate.time_constant_s`; None = estimate it per trace
    bandwidth_hz: float | None = None  # [Hz] optional `daq.bandwidth_hz`: highest frequency at the ADC; None = unknown
    # v1.2: ([Hz], [-]) optional `plate.resonance_hz` and `plate.damping_ratio` (a tap test); None = identify them
    plate_resonance: tuple[float, float] | None = None


@dataclass
class ImpactRow:
    """One row of impacts.csv."""

    impact_id: str
    ball: str
    trace: str  # trace path as written, relative to the session folder
    gate_in_1_s: float  # [s] NaN when empty or unreadable
    gate_in_2_s: float  # [s]
    gate_out_2_s: float  # [s]
    gate_out_1_s: float  # [s]
    mass_kg: float  # [kg] row override (mass_g column) or the ball type's mass
    note: str
    line: int  # 1-based line number in impacts.csv (header is line 1)
    problems: list[Problem] = field(default_factory=list)  # impact-level faults, empty if none


@dataclass
class Session:
    """A raw session folder: metadata and the impact rows."""

    path: Path
    meta: SessionMeta
    impacts: list[ImpactRow]

    def trace_path(self, row: ImpactRow) -> Path:
        """
        Path of an impact's trace file.

        Parameters
        ----------
        row : ImpactRow
            An impact of this session.

        Returns
        -------
        Path
            ``self.path / row.trace`` (backslashes in the written path are
            taken as folder separators).
        """
        return self.path / _normalise_trace(row.trace)


# --------------------------------------------------------------------------- YAML


class _SessionYamlLoader(yaml.SafeLoader):
    """Safe loader that keeps dates as strings and rejects duplicate keys."""


_SessionYamlLoader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:timestamp"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}


def _construct_mapping_no_duplicates(loader, node):
    loader.flatten_mapping(node)
    seen: dict = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        try:
            first = seen.get(key)
        except TypeError:  # unhashable key: construct_mapping reports it
            continue
        if first is not None:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (first given on line {first})", key_node.start_mark
            )
        seen[key] = key_node.start_mark.line + 1
    return loader.construct_mapping(node, deep=True)


_SessionYamlLoader.add_constructor("tag:yaml.org,2002:map", _construct_mapping_no_duplicates)


def _decode_utf8(data: bytes, file: str) -> str:
    """Decode UTF-8 (a BOM is dropped); SessionError naming the line of a bad byte."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise SessionError(
            f"{file}: line {line}: not valid UTF-8 (byte 0x{data[exc.start]:02x}); save the file as UTF-8"
        ) from None


def near_miss_name(folder: Path, expected: str) -> str | None:
    """
    A file in ``folder`` whose name is a likely mistake for ``expected`` (e.g. session.yml).

    Parameters
    ----------
    folder : Path
        The session folder.
    expected : str
        The file name the format requires (``session.yaml`` or ``impacts.csv``).

    Returns
    -------
    str or None
        The name found, None when there is none.
    """
    try:
        names = {p.name for p in Path(folder).iterdir() if p.is_file()}
    except OSError:
        return None
    if expected in names:
        return None
    for name in _NEAR_MISS_NAMES.get(expected, ()):
        if name in names:
            return name
    lower = {n.lower(): n for n in names}
    stem = expected.rsplit(".", 1)[0]
    for low, name in sorted(lower.items()):
        if low != expected and low.startswith(stem) and low.split(".")[0] == stem:
            return name
    return None


def _read_bytes(path: Path, file: str, what: str) -> bytes:
    if not path.exists():
        other = near_miss_name(path.parent, path.name) if path.parent.is_dir() else None
        if other is not None:
            raise SessionError(f"{file}: file not found, but {other!r} is there: rename it to {path.name!r}")
        raise SessionError(f"{file}: file not found ({what})")
    if not path.is_file():
        raise SessionError(f"{file}: is not a file ({what})")
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise SessionError(f"{file}: cannot read: {exc.strerror or exc}") from None


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _load_yaml(path: Path, file: str) -> dict:
    text = _decode_utf8(_read_bytes(path, file, "every session folder needs a session.yaml"), file)
    try:
        data = yaml.load(text, Loader=_SessionYamlLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}: " if mark is not None else ""
        problem = exc.problem or exc.context or "syntax error"
        raise SessionError(f"{file}: {where}invalid YAML: {_one_line(problem)}") from None
    except yaml.YAMLError as exc:
        raise SessionError(f"{file}: invalid YAML: {_one_line(exc)}") from None
    if data is None:
        raise SessionError(
            f"{file}: file is empty (expected a mapping with session_id, date, plate, daq, gates, balls)"
        )
    if not isinstance(data, dict):
        raise SessionError(
            f"{file}: top level must be a mapping of keys (session_id, date, ...), got a {type(data).__name__}"
        )
    return data


# ------------------------------------------------------------------ value checks


def _require(mapping: dict, key: str, dotted: str, file: str):
    if key not in mapping or mapping[key] is None:
        raise SessionError(f"{file}: missing required key '{dotted}'")
    return mapping[key]


def _section(data: dict, key: str, file: str) -> dict:
    value = _require(data, key, key, file)
    if not isinstance(value, dict):
        raise SessionError(f"{file}: key '{key}' must be a mapping, got {value!r}")
    return value


def _to_float(value) -> float | None:
    """Float of a YAML number (or a numeric string such as '1e-6'); None if not numeric/finite."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str):
        try:
            number = float(value.strip())
        except ValueError:
            return None
    else:
        return None
    return number if math.isfinite(number) else None


def _number(value, dotted: str, file: str, *, positive: bool = False) -> float:
    number = _to_float(value)
    if number is None or (positive and number <= 0):
        kind = "a positive number" if positive else "a number"
        raise SessionError(f"{file}: key '{dotted}' must be {kind}, got {value!r}")
    return number


def _text(value, dotted: str, file: str) -> str:
    if value is None:
        return ""
    if isinstance(value, (dict, list)):
        raise SessionError(f"{file}: key '{dotted}' must be text, got {value!r}")
    return str(value)


def _warn_unknown(mapping: dict, known: set[str], prefix: str, file: str) -> None:
    """Warn of the keys of ``mapping`` that are not in ``known``, naming the known key each resembles.

    ``prefix`` is the dotted path of the mapping ("" for the top level of session.yaml).
    """
    dotted = (lambda k: f"{prefix}.{k}") if prefix else str
    unknown = [str(k) for k in mapping if k not in known]
    if unknown:
        import difflib

        lowered = {k.lower(): k for k in known}
        hints = []
        for k in unknown:  # a near miss, e.g. kb0_kn_m for kb0_kN_m: say what it silently changes
            close = lowered.get(k.lower()) or next(iter(difflib.get_close_matches(k, sorted(known), 1, 0.8)), None)
            if close is not None:
                hints.append(f"did you mean '{dotted(close)}'? '{dotted(k)}' has no effect")
        warnings.warn(
            f"{file}: unknown key(s) {', '.join(repr(dotted(k)) for k in unknown)} "
            f"(kept in raw, not used; known: {', '.join(sorted(known))})"
            + "".join(f"; {h}" for h in hints),
            SessionWarning,
            stacklevel=4,
        )


def _parse_ball(key: str, spec, file: str) -> BallType:
    prefix = f"balls.{key}"
    if not isinstance(spec, dict):
        raise SessionError(f"{file}: key '{prefix}' must be a mapping with at least mass_g, got {spec!r}")
    mass_g = _number(_require(spec, "mass_g", f"{prefix}.mass_g", file), f"{prefix}.mass_g", file)
    if not MASS_MIN_G < mass_g < MASS_MAX_G:
        raise SessionError(
            f"{file}: key '{prefix}.mass_g' must be in ({MASS_MIN_G:g}, {MASS_MAX_G:g}) g, got {spec['mass_g']!r}"
        )
    if not MASS_TYPICAL_MIN_G <= mass_g <= MASS_TYPICAL_MAX_G:
        warnings.warn(
            f"{file}: key '{prefix}.mass_g' = {mass_g:g} g is outside the usual "
            f"{MASS_TYPICAL_MIN_G:g}-{MASS_TYPICAL_MAX_G:g} g of a tennis ball",
            SessionWarning,
            stacklevel=3,
        )
    diameter_m = None
    if spec.get("diameter_mm") is not None:
        diameter_m = _number(spec["diameter_mm"], f"{prefix}.diameter_mm", file, positive=True) / 1000.0
    kb0_N_m = None
    if spec.get("kb0_kN_m") is not None:
        kb0_N_m = _number(spec["kb0_kN_m"], f"{prefix}.kb0_kN_m", file, positive=True) * 1000.0
    itf_rebound_cm = None
    if spec.get("itf_rebound_cm") is not None:
        itf_rebound_cm = _number(spec["itf_rebound_cm"], f"{prefix}.itf_rebound_cm", file, positive=True)
        if itf_rebound_cm >= ITF_REBOUND_MAX_CM:
            raise SessionError(
                f"{file}: key '{prefix}.itf_rebound_cm' must be below the {ITF_REBOUND_MAX_CM:g} cm drop height "
                f"(a rebound in cm), got {spec['itf_rebound_cm']!r}"
            )
    label = _text(spec.get("label"), f"{prefix}.label", file) or key
    _warn_unknown(spec, _KNOWN_BALL_KEYS, prefix, file)
    return BallType(key=key, label=label, mass_kg=mass_g / 1000.0, diameter_m=diameter_m, kb0_N_m=kb0_N_m,
                    itf_rebound_cm=itf_rebound_cm)


def _parse_session_id(data: dict, folder_name: str, file: str) -> str:
    session_id_value = _require(data, "session_id", "session_id", file)
    if isinstance(session_id_value, (dict, list, bool)):
        raise SessionError(f"{file}: key 'session_id' must be text, got {session_id_value!r}")
    session_id = str(session_id_value)
    if session_id != folder_name:
        hint = " (quote it in the YAML)" if not isinstance(session_id_value, str) else ""
        raise SessionError(
            f"{file}: key 'session_id' is {session_id!r} but the session folder is named {folder_name!r}; "
            f"they must be equal{hint}"
        )
    return session_id


def _parse_date(data: dict, file: str) -> str:
    date_value = _require(data, "date", "date", file)
    date = str(date_value).strip() if isinstance(date_value, str) else None
    ok = date is not None and ISO_DATE_PATTERN.fullmatch(date) is not None
    if ok:
        try:
            datetime.date.fromisoformat(date)
        except ValueError:
            ok = False
    if not ok:
        raise SessionError(f"{file}: key 'date' must be an ISO date YYYY-MM-DD, got {date_value!r}")
    return date


def _parse_plate(data: dict, file: str) -> tuple[int, tuple[float, float] | None, float | None, tuple | None]:
    plate = _section(data, "plate", file)
    polarity_value = _require(plate, "polarity", "plate.polarity", file)
    polarity_number = _to_float(polarity_value)
    if polarity_number not in (1.0, -1.0):
        raise SessionError(f"{file}: key 'plate.polarity' must be 1 or -1, got {polarity_value!r}")
    kcal_range = None
    if plate.get("kcal_range_N_per_V") is not None:
        value = plate["kcal_range_N_per_V"]
        bounds = [_to_float(v) for v in value] if isinstance(value, (list, tuple)) else []
        if len(bounds) != 2 or None in bounds or not 0 < bounds[0] < bounds[1]:
            raise SessionError(
                f"{file}: key 'plate.kcal_range_N_per_V' must be two numbers [lo, hi] with 0 < lo < hi, "
                f"got {value!r}"
            )
        kcal_range = (bounds[0], bounds[1])
    time_constant_s = None
    if plate.get("time_constant_s") is not None:
        time_constant_s = _number(plate["time_constant_s"], "plate.time_constant_s", file, positive=True)
    stated = [plate.get(k) is not None for k in ("resonance_hz", "damping_ratio")]
    resonance = None
    if any(stated):
        if not all(stated):
            given, missing = ("resonance_hz", "damping_ratio") if stated[0] else ("damping_ratio", "resonance_hz")
            raise SessionError(f"{file}: key 'plate.{given}' is given without 'plate.{missing}': a tap test gives "
                               "both (state both, or neither to identify the plate from the session)")
        fn = _number(plate["resonance_hz"], "plate.resonance_hz", file, positive=True)
        zeta = _number(plate["damping_ratio"], "plate.damping_ratio", file, positive=True)
        if not zeta < 1.0:
            raise SessionError(f"{file}: key 'plate.damping_ratio' must be below 1 (a resonance rings), "
                               f"got {plate['damping_ratio']!r}")
        resonance = (fn, zeta)
    _warn_unknown(plate, _KNOWN_SECTION_KEYS["plate"], "plate", file)
    return int(polarity_number), kcal_range, time_constant_s, resonance


def alias_risk(sample_rate_hz: float) -> str:
    """
    What a rig sampled below twice PLATE_RESONANCE_MAX_HZ risks without `daq.bandwidth_hz`, and where to find it.

    The text of the warnings of :func:`read_session` (daq.sample_rate_hz) and of
    ``ballimpact.validation.validate_session`` (a trace's own rate).

    Parameters
    ----------
    sample_rate_hz : float
        Sample rate [Hz].

    Returns
    -------
    str
        One sentence, starting "at ... kHz".
    """
    return (f"at {sample_rate_hz / 1e3:g} kHz a plate resonance above {sample_rate_hz / 2e3:g} kHz would alias "
            "into the force unseen; give the anti-aliasing filter's cut-off or the plate's highest resonance "
            "(data sheet, or a tap test)")


def _parse_daq(data: dict, file: str) -> tuple[float, tuple[float, float], float | None, float | None]:
    daq = _section(data, "daq", file)
    sample_rate_hz = _number(
        _require(daq, "sample_rate_hz", "daq.sample_rate_hz", file), "daq.sample_rate_hz", file, positive=True
    )
    adc_value = _require(daq, "adc_range_v", "daq.adc_range_v", file)
    adc = [_to_float(v) for v in adc_value] if isinstance(adc_value, (list, tuple)) else []
    if len(adc) != 2 or None in adc or not adc[0] < adc[1]:
        raise SessionError(
            f"{file}: key 'daq.adc_range_v' must be two numbers [lo, hi] with lo < hi, got {adc_value!r}"
        )
    mains_hz = DEFAULT_MAINS_HZ
    if daq.get("mains_hz") is not None:
        mains_hz = _number(daq["mains_hz"], "daq.mains_hz", file, positive=True)
    bandwidth_hz = None
    if daq.get("bandwidth_hz") is not None:
        bandwidth_hz = _number(daq["bandwidth_hz"], "daq.bandwidth_hz", file, positive=True)
    elif sample_rate_hz < 2.0 * PLATE_RESONANCE_MAX_HZ:
        warnings.warn(f"{file}: daq.bandwidth_hz not given: {alias_risk(sample_rate_hz)}",
                      SessionWarning, stacklevel=3)
    _warn_unknown(daq, _KNOWN_SECTION_KEYS["daq"], "daq", file)
    return sample_rate_hz, (adc[0], adc[1]), mains_hz, bandwidth_hz


def _parse_gates(data: dict, file: str) -> tuple[float, float, float | None]:
    gates = _section(data, "gates", file)
    spacing_m = _number(_require(gates, "spacing_m", "gates.spacing_m", file), "gates.spacing_m", file, positive=True)
    if spacing_m > MAX_GATE_SPACING_M:
        warnings.warn(
            f"{file}: key 'gates.spacing_m' = {spacing_m:g} m is larger than {MAX_GATE_SPACING_M:g} m "
            "(is it given in mm?)",
            SessionWarning,
            stacklevel=3,
        )
    resolution_s = _number(
        _require(gates, "resolution_s", "gates.resolution_s", file), "gates.resolution_s", file, positive=True
    )
    # A ball at FAST_BALL_SPEED_M_S crosses the gate spacing in spacing/speed; a timer
    # tick as long as that cannot time anything (this is a unit mistake, e.g. us as s).
    transit_fast_s = spacing_m / FAST_BALL_SPEED_M_S
    if resolution_s >= transit_fast_s:
        raise SessionError(
            f"{file}: key 'gates.resolution_s' must be much smaller than the gate transit time "
            f"(< {transit_fast_s:g} s for spacing {spacing_m:g} m), got {gates['resolution_s']!r}"
        )
    if resolution_s > 0.01 * transit_fast_s:
        warnings.warn(
            f"{file}: key 'gates.resolution_s' = {resolution_s:g} s gives more than 1 % speed error "
            f"for a {FAST_BALL_SPEED_M_S:g} m/s ball over {spacing_m:g} m",
            SessionWarning,
            stacklevel=3,
        )
    distance_to_plate_m = None
    if gates.get("distance_to_plate_m") is not None:
        distance_to_plate_m = _number(gates["distance_to_plate_m"], "gates.distance_to_plate_m", file, positive=True)
        if distance_to_plate_m > MAX_GATE_SPACING_M:
            warnings.warn(
                f"{file}: key 'gates.distance_to_plate_m' = {distance_to_plate_m:g} m is larger than "
                f"{MAX_GATE_SPACING_M:g} m (is it given in mm?)",
                SessionWarning,
                stacklevel=3,
            )
    _warn_unknown(gates, _KNOWN_SECTION_KEYS["gates"], "gates", file)
    return spacing_m, resolution_s, distance_to_plate_m


def _parse_rig(data: dict, file: str) -> tuple[str, float]:
    """Optional `rig` section (v1.1): orientation and air density [kg/m^3]."""
    rig = data.get("rig") or {}
    if not isinstance(rig, dict):
        raise SessionError(f"{file}: key 'rig' must be a mapping (orientation, air_density_kg_m3), got {rig!r}")
    orientation = rig.get("orientation") or "horizontal"
    if orientation not in RIG_ORIENTATIONS:
        raise SessionError(
            f"{file}: key 'rig.orientation' must be one of {', '.join(RIG_ORIENTATIONS)}, got {rig['orientation']!r}"
        )
    air_density = DEFAULT_AIR_DENSITY_KG_M3
    if rig.get("air_density_kg_m3") is not None:
        air_density = _number(rig["air_density_kg_m3"], "rig.air_density_kg_m3", file, positive=True)
        lo, hi = AIR_DENSITY_RANGE_KG_M3
        if not lo <= air_density <= hi:
            raise SessionError(
                f"{file}: key 'rig.air_density_kg_m3' must be in [{lo:g}, {hi:g}] kg/m^3 (air), "
                f"got {rig['air_density_kg_m3']!r}"
            )
    _warn_unknown(rig, _KNOWN_SECTION_KEYS["rig"], "rig", file)
    return orientation, air_density


def _parse_balls(data: dict, file: str, collect: _Collector | None = None) -> dict[str, BallType]:
    balls_value = _require(data, "balls", "balls", file)
    if not isinstance(balls_value, dict) or not balls_value:
        raise SessionError(
            f"{file}: key 'balls' must be a mapping of ball types (key: {{mass_g: ...}}), got {balls_value!r}"
        )
    balls: dict[str, BallType | None] = {}
    outer, collect = collect, _Collector()
    for key_value, spec in balls_value.items():
        key = str(key_value)
        if not IMPACT_ID_PATTERN.fullmatch(key):
            collect.problems.append(f"{file}: ball key {key!r} under 'balls' must match [A-Za-z0-9_-]+")
            continue
        if key in balls:
            collect.problems.append(f"{file}: ball key {key!r} is given twice under 'balls'")
            continue
        balls[key] = collect(_parse_ball, key, spec, file)  # None when unusable
    if outer is not None:
        outer.balls = balls  # every key, for the checks of impacts.csv
    _raise_collected(collect.problems)
    return balls


def _check_distance_to_plate(distance_to_plate_m: float | None, balls: dict, file: str) -> None:
    """Gate 2 must be further from the plate than a ball is wide [m]."""
    if distance_to_plate_m is None:
        return
    for ball in balls.values():
        diameter_m = ball.diameter_m if ball.diameter_m is not None else DEFAULT_BALL_DIAMETER_M
        if distance_to_plate_m <= diameter_m:
            raise SessionError(
                f"{file}: key 'gates.distance_to_plate_m' ({distance_to_plate_m:g} m) must exceed the diameter "
                f"of ball '{ball.key}' ({diameter_m * 1000:g} mm): gate 2 would be blocked during the contact"
            )


def _parse_synthetic(data: dict, file: str) -> bool:
    synthetic = data.get("synthetic", False)
    if synthetic is None:
        synthetic = False
    if not isinstance(synthetic, bool):
        raise SessionError(f"{file}: key 'synthetic' must be true or false, got {synthetic!r}")
    return synthetic


def _parse_meta(data: dict, folder_name: str, file: str, collect: _Collector | None = None) -> SessionMeta | None:
    """SessionMeta of session.yaml; every independent problem is collected first.

    With ``collect`` given, problems are appended to it and None is returned when there
    is any (the ball types parsed so far are in ``collect.balls``); without, one
    SessionError holding all of them is raised.
    """
    own = collect is None
    collect = collect or _Collector()
    n_before = len(collect.problems)
    session_id = collect(_parse_session_id, data, folder_name, file)
    date = collect(_parse_date, data, file)
    plate = collect(_parse_plate, data, file)
    daq = collect(_parse_daq, data, file)
    gates = collect(_parse_gates, data, file)
    rig = collect(_parse_rig, data, file)
    balls = collect(_parse_balls, data, file, collect)
    if gates is not None and balls is not None:
        collect(_check_distance_to_plate, gates[2], balls, file)
    synthetic = collect(_parse_synthetic, data, file)
    operator = collect(_text, data.get("operator"), "operator", file)
    description = collect(_text, data.get("description"), "description", file)
    _warn_unknown(data, _KNOWN_TOP_KEYS, "", file)
    if len(collect.problems) > n_before:
        if own:
            _raise_collected(collect.problems)
        return None
    polarity, kcal_range, time_constant_s, resonance = plate
    sample_rate_hz, adc, mains_hz, bandwidth_hz = daq
    spacing_m, resolution_s, distance_to_plate_m = gates
    orientation, air_density = rig
    return SessionMeta(
        session_id=session_id,
        date=date,
        operator=operator,
        description=description,
        polarity=polarity,
        sample_rate_hz=sample_rate_hz,
        adc_range_v=adc,
        gate_spacing_m=spacing_m,
        gate_resolution_s=resolution_s,
        balls=balls,
        mains_hz=mains_hz,
        synthetic=synthetic,
        raw=data,
        kcal_range_N_per_V=kcal_range,
        distance_to_plate_m=distance_to_plate_m,
        rig_orientation=orientation,
        air_density_kg_m3=air_density,
        time_constant_s=time_constant_s,
        bandwidth_hz=bandwidth_hz,
        plate_resonance=resonance,
    )


# ------------------------------------------------------------------ impacts.csv


def _normalise_trace(trace: str) -> str:
    return trace.replace("\\", "/")


def _parse_gate(cell: str, column: str, problems: list[Problem]) -> float:
    text = cell.strip()
    if not text:
        problems.append(Problem(ProblemKind.GATE_TIME_MISSING, f"missing gate time {column}"))
        return math.nan
    try:
        value = float(text)
    except ValueError:
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"non-numeric gate time {column}: {text!r}"))
        return math.nan
    if not math.isfinite(value):
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"non-finite gate time {column}: {text!r}"))
        return math.nan
    if value < 0:
        problems.append(Problem(ProblemKind.GATE_TIME_INVALID, f"negative gate time {column}: {text}"))
    return value


def _check_gate_order(gates: dict[str, float], cells: dict[str, str], problems: list[Problem]) -> None:
    pairs = (
        ("gate_in_1_s", "gate_in_2_s", True),
        ("gate_in_2_s", "gate_out_2_s", False),
        ("gate_out_2_s", "gate_out_1_s", True),
    )
    for first, second, strict in pairs:
        a, b = gates[first], gates[second]
        if math.isnan(a) or math.isnan(b):
            continue
        if (a >= b) if strict else (a > b):
            relation = "earlier than" if strict else "no later than"
            problems.append(Problem(
                ProblemKind.GATE_ORDER,
                f"gate times out of order: {first} ({cells[first].strip()}) must be {relation} "
                f"{second} ({cells[second].strip()})",
            ))


def _parse_mass(cell: str, ball: BallType, problems: list[Problem], where: str) -> float:
    text = cell.strip()
    if not text:
        return ball.mass_kg
    try:
        mass_g = float(text)
    except ValueError:
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-numeric mass_g: {text!r}"))
        return math.nan
    if not math.isfinite(mass_g):
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-finite mass_g: {text!r}"))
        return math.nan
    if mass_g <= 0:
        problems.append(Problem(ProblemKind.MASS_INVALID, f"non-positive mass_g: {text}"))
        return math.nan
    if not MASS_MIN_G < mass_g < MASS_MAX_G:
        problems.append(Problem(ProblemKind.MASS_INVALID,
                                f"implausible mass_g: {text} (must be in ({MASS_MIN_G:g}, {MASS_MAX_G:g}) g)"))
        return math.nan
    if not MASS_TYPICAL_MIN_G <= mass_g <= MASS_TYPICAL_MAX_G:
        warnings.warn(
            f"{where}: mass_g {text} g is outside the usual {MASS_TYPICAL_MIN_G:g}-{MASS_TYPICAL_MAX_G:g} g "
            "of a tennis ball",
            SessionWarning,
            stacklevel=5,
        )
    return mass_g / 1000.0


def _check_trace(cell: str, session_dir: Path, problems: list[Problem]) -> None:
    trace = cell.strip()
    if not trace:
        problems.append(Problem(ProblemKind.TRACE_PATH_MISSING, "missing trace path"))
        return
    normalised = _normalise_trace(trace)
    if PurePosixPath(normalised).is_absolute() or PureWindowsPath(trace).drive:
        problems.append(Problem(ProblemKind.TRACE_PATH_ESCAPES,
                                f"trace path escapes the session folder (absolute path): {trace}"))
        return
    root = session_dir.resolve()
    # ValueError: a NUL byte in the cell; OSError also covers a file name too long
    # for the OS (ENAMETOOLONG), which Path.exists() re-raises. Both are faults of
    # this one row, not of the session (bad-input suite: tests/test_bad_input.py).
    try:
        full = (root / normalised).resolve()
    except (OSError, RuntimeError, ValueError) as exc:  # symlink loops, NUL bytes
        problems.append(Problem(ProblemKind.TRACE_PATH_UNRESOLVABLE,
                                f"trace path cannot be resolved: {trace!r} ({exc})"))
        return
    if full == root or not full.is_relative_to(root):
        problems.append(Problem(ProblemKind.TRACE_PATH_ESCAPES, f"trace path escapes the session folder: {trace}"))
        return
    try:
        exists, is_file = full.exists(), full.is_file()
    except (OSError, ValueError) as exc:  # e.g. [Errno 36] File name too long
        problems.append(Problem(ProblemKind.TRACE_PATH_UNRESOLVABLE,
                                f"trace path cannot be resolved: {trace!r} ({exc.strerror or exc})"))
        return
    if not exists:
        problems.append(Problem(ProblemKind.TRACE_NOT_FOUND, f"trace file not found: {trace}"))
    elif not is_file:
        problems.append(Problem(ProblemKind.TRACE_NOT_A_FILE, f"trace path is not a file: {trace}"))


def _separator_hint(header: list[str]) -> str:
    """Why a header lacks the required columns, when the cause is the separator."""
    joined = ",".join(header)
    for sep, name in ((";", "semicolons"), ("\t", "tabs"), ("|", "'|'")):
        if sep in joined and sum(c in joined for c in REQUIRED_COLUMNS) >= 3:
            return (
                f"; the columns are separated by {name}: save {IMPACTS_FILE} comma-separated "
                "(in a spreadsheet: CSV, comma as separator, point as decimal mark)"
            )
    return ""


def _read_impacts(session_dir: Path, meta) -> list[ImpactRow]:
    """Impact rows; ``meta`` is a SessionMeta or None (session.yaml unusable: the rows'
    structure is still checked, every session-level problem collected)."""
    balls = meta.balls if meta is not None else None
    session_problems: list[str] = []
    path = session_dir / IMPACTS_FILE
    file = str(path)
    data = _read_bytes(path, file, "every session folder needs an impacts.csv")
    if not data.strip():
        raise SessionError(
            f"{file}: file is empty (expected a header row with columns {', '.join(REQUIRED_COLUMNS)})"
        )
    text = _decode_utf8(data, file)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    rows: list[ImpactRow] = []
    first_line: dict[str, int] = {}
    header: list[str] | None = None
    index: dict[str, int] = {}
    previous_line_num = 0
    while True:
        line = previous_line_num + 1
        try:
            record = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise SessionError(f"{file}: line {reader.line_num}: malformed CSV: {exc}") from None
        previous_line_num = reader.line_num
        if not record or all(not cell.strip() for cell in record) and len(record) <= 1:
            continue  # blank line
        if header is None:
            header = _impacts_header(record, file, line)
            index = {name: i for i, name in enumerate(header)}
            continue
        if len(record) != len(header):
            hint = ""
            if len(record) > len(header) and re.search(r"\d,\d", ",".join(record)):
                hint = " (decimal commas? write gate times with a decimal point, e.g. 4.219063 not 4,219063)"
            session_problems.append(f"{file}: line {line}: expected {len(header)} fields, got {len(record)}{hint}")
            continue
        cells = {name: record[i] for name, i in index.items()}
        row = _impact_row(cells, line, file, balls, first_line, session_problems, session_dir)
        if row is not None:
            rows.append(row)
    if header is None:
        raise SessionError(
            f"{file}: file is empty (expected a header row with columns {', '.join(REQUIRED_COLUMNS)})"
        )
    _raise_collected(session_problems)
    if not rows and balls is not None:
        raise SessionError(f"{file}: no impact rows (only the header)")
    return rows


def _impacts_header(record: list[str], file: str, line: int) -> list[str]:
    """The header row of impacts.csv: no duplicate, every required column; warns of unknown ones."""
    header = [cell.strip() for cell in record]
    duplicated = sorted({c for c in header if header.count(c) > 1})
    if duplicated:
        raise SessionError(f"{file}: line {line}: duplicate column(s) in header: {', '.join(duplicated)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise SessionError(
            f"{file}: line {line}: missing required column(s): {', '.join(missing)} "
            f"(header has: {_one_line(', '.join(header))})" + _separator_hint(header)
        )
    unknown = [c for c in header if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:
        warnings.warn(
            f"{file}: line {line}: unknown column(s) ignored: {', '.join(unknown)}",
            SessionWarning,
            stacklevel=4,
        )
    return header


def _impact_row(cells: dict[str, str], line: int, file: str, balls, first_line: dict[str, int],
                session_problems: list[str], session_dir: Path) -> ImpactRow | None:
    """One data row of impacts.csv as an ImpactRow with its impact-level problems, or None:
    a session-level fault (bad or duplicate impact_id, undefined ball) is appended to
    ``session_problems``; ``balls`` None (session.yaml unusable) checks only the structure."""
    impact_id = cells["impact_id"].strip()
    if not IMPACT_ID_PATTERN.fullmatch(impact_id):
        session_problems.append(
            f"{file}: line {line}: impact_id {impact_id!r} is not valid "
            "(allowed: letters, digits, '_' and '-', at least one)"
        )
        return None
    if impact_id in first_line:
        session_problems.append(
            f"{file}: line {line}: impact_id {impact_id!r} duplicates line {first_line[impact_id]}"
        )
        return None
    first_line[impact_id] = line
    ball_key = cells["ball"].strip()
    if balls is None:
        return None  # session.yaml balls unusable: only the structure of the rows is checked
    if ball_key in balls and balls[ball_key] is None:
        return None  # a ball type with problems of its own in session.yaml
    if ball_key not in balls:
        session_problems.append(
            f"{file}: line {line}: ball {ball_key!r} is not defined in {SESSION_FILE} balls "
            f"(valid: {', '.join(balls)})"
        )
        return None
    problems: list[Problem] = []
    gates = {column: _parse_gate(cells[column], column, problems) for column in GATE_COLUMNS}
    _check_gate_order(gates, cells, problems)
    mass_kg = _parse_mass(cells.get("mass_g", ""), balls[ball_key], problems, f"{file}: line {line}")
    trace = cells["trace"].strip()
    _check_trace(trace, session_dir, problems)
    return ImpactRow(
        impact_id=impact_id,
        ball=ball_key,
        trace=trace,
        gate_in_1_s=gates["gate_in_1_s"],
        gate_in_2_s=gates["gate_in_2_s"],
        gate_out_2_s=gates["gate_out_2_s"],
        gate_out_1_s=gates["gate_out_1_s"],
        mass_kg=mass_kg,
        note=cells.get("note", "").strip(),
        line=line,
        problems=problems,
    )


# ---------------------------------------------------------------------- public


def read_session(path) -> Session:
    """
    Read a raw session folder (session.yaml and impacts.csv), without writing anything.

    Parameters
    ----------
    path : str or Path
        The session folder ``raw/<session_id>``; its name must equal ``session_id``.

    Returns
    -------
    Session
        Metadata (rates in [Hz], ADC range in [V], gate spacing [m], resolution [s],
        ball masses [kg]) and one :class:`ImpactRow` per impact, gate times in [s].
        Impact-level faults (missing/bad gate times, bad mass override, missing or
        escaping trace path, trace file not found) are listed in ``ImpactRow.problems``,
        as :class:`ballimpact.problems.Problem` (a kind and a message).

    Raises
    ------
    SessionError
        Session-level faults: every one found (session.yaml and impacts.csv are both
        checked), one line each naming the file, the key or line, and what is wrong;
        the lines are also in ``SessionError.problems``.

    Warns
    -----
    SessionWarning
        Usable but suspect metadata (mass outside 40-70 g, unknown keys or columns).
    """
    session_dir = Path(path)
    if not session_dir.is_dir():
        raise SessionError(f"{session_dir}: session folder not found")
    yaml_path = session_dir / SESSION_FILE
    collect = _Collector()
    data = collect(_load_yaml, yaml_path, str(yaml_path))
    meta = None
    if data is not None:
        meta = _parse_meta(data, session_dir.resolve().name, str(yaml_path), collect)
    # impacts.csv is checked too when session.yaml has problems (its ball keys only
    # when the balls section could be read), so that every problem is reported at once
    if meta is None and collect.balls is not None:
        meta_for_rows = _BallsOnly(collect.balls)
    else:
        meta_for_rows = meta
    impacts = None
    if yaml_path.is_file():  # without any session.yaml the folder is hardly a session
        impacts = collect(_read_impacts, session_dir, meta_for_rows)
    _raise_collected(collect.problems)
    return Session(path=session_dir, meta=meta, impacts=impacts)


@dataclass(frozen=True)
class _BallsOnly:
    """Stand-in for SessionMeta while session.yaml has problems: its ball types only."""

    balls: dict


def file_sha256(path) -> str:
    """
    SHA-256 digest of a file's bytes, for provenance in the archive.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    str
        Hex digest (64 characters).
    """
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


@dataclass(frozen=True)
class SessionPlan:
    """What a workflow needs to plan one session's jobs, read without ever raising.

    Attributes
    ----------
    path : Path
        The session folder.
    fault : str or None
        The session-level fault (one line naming file, key or line), None when
        the session can be processed.
    metadata : dict
        session.yaml as parsed ({} when it could not be read).
    balls : tuple of str
        Ball types that have impacts, in session.yaml order.
    n_impacts : int
        Rows of impacts.csv [-].
    trace_files : tuple of (Path or None)
        Per row, the existing trace file inside the session folder, None when
        the row's trace is missing, unreadable or escapes the folder (an
        impact-level fault that processing reports).
    present_files : tuple of Path
        session.yaml and impacts.csv where they exist (what a faulty session's
        validation depends on).
    warnings : tuple of str
        Messages of the SessionWarnings the reader gave.
    """

    path: Path
    fault: str | None
    metadata: dict
    balls: tuple[str, ...]
    n_impacts: int
    trace_files: tuple[Path | None, ...]
    present_files: tuple[Path, ...]
    warnings: tuple[str, ...] = ()


def plan_session(path) -> SessionPlan:
    """
    Read a session folder for planning: the reader's own checks, never an exception.

    A workflow calls this once per session when it builds its job graph, so
    one bad session (or one bad cell of it) can never stop another: a
    session-level fault comes back as ``fault``, an impact-level one as a
    ``None`` trace file.

    Parameters
    ----------
    path : str or Path
        The session folder ``raw/<session_id>``.

    Returns
    -------
    SessionPlan
        Ball types, impact count and trace files, or the fault.
    """
    session_dir = Path(path)
    present = tuple(p for p in (session_dir / SESSION_FILE, session_dir / IMPACTS_FILE) if _is_file(p))
    metadata: dict = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SessionWarning)
        try:
            metadata = _load_yaml(session_dir / SESSION_FILE, str(session_dir / SESSION_FILE))
            session = read_session(session_dir)
        except SessionError as exc:
            return SessionPlan(session_dir, _one_line(exc), metadata, (), 0, (), present,
                               tuple(_one_line(w.message) for w in caught))
    messages = tuple(_one_line(w.message) for w in caught if issubclass(w.category, SessionWarning))
    used = {row.ball for row in session.impacts}
    balls = tuple(key for key in session.meta.balls if key in used)
    traces = tuple(_existing_trace(session, row) for row in session.impacts)
    return SessionPlan(session_dir, None, metadata, balls, len(session.impacts), traces, present, messages)


def _existing_trace(session: Session, row: ImpactRow) -> Path | None:
    """The row's trace file when it exists inside the session folder, else None."""
    problems: list[Problem] = []
    _check_trace(row.trace, session.path, problems)
    return None if problems else session.trace_path(row)


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False
