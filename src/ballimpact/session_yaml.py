"""Reading session.yaml: the YAML loaded strictly, every key checked, into a SessionMeta."""

from __future__ import annotations

import datetime
import math
import re
import warnings
from pathlib import Path

import yaml

from .session_files import _decode_utf8, _one_line, _read_bytes
from .session_records import (
    DEFAULT_AIR_DENSITY_KG_M3,
    IMPACT_ID_PATTERN,
    MASS_MAX_G,
    MASS_MIN_G,
    MASS_TYPICAL_MAX_G,
    MASS_TYPICAL_MIN_G,
    BallType,
    SessionError,
    SessionMeta,
    SessionWarning,
    _Collector,
    _raise_collected,
)

__all__ = ["alias_risk"]

ISO_DATE_PATTERN = re.compile(r"\d{4}-\d{2}-\d{2}")

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

RIG_ORIENTATIONS = ("horizontal", "vertical")  # `rig.orientation` (v1.1); horizontal is the default

AIR_DENSITY_RANGE_KG_M3 = (0.5, 1.5)  # [kg/m^3] plausible air (sea level to ~5 km); outside = error
DEFAULT_BALL_DIAMETER_M = 0.0654  # [m] ball diameter when `balls.<key>.diameter_mm` is not given
ITF_REBOUND_MAX_CM = 254.0  # [cm] a rebound cannot exceed the 254 cm drop


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
