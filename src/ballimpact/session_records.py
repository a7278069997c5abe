"""The raw session format's records and errors: file names, columns, ball types, metadata, impact rows."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .problems import Problem

__all__ = [
    "SessionError",
    "SessionWarning",
    "BallType",
    "SessionMeta",
    "ImpactRow",
    "Session",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "GATE_COLUMNS",
]

SESSION_FILE = "session.yaml"
IMPACTS_FILE = "impacts.csv"

GATE_COLUMNS = ("gate_in_1_s", "gate_in_2_s", "gate_out_2_s", "gate_out_1_s")
REQUIRED_COLUMNS = ("impact_id", "ball", "trace") + GATE_COLUMNS
OPTIONAL_COLUMNS = ("mass_g", "note")

IMPACT_ID_PATTERN = re.compile(r"[A-Za-z0-9_-]+")

MASS_MIN_G = 1.0  # [g] exclusive lower bound of a plausible ball mass
MASS_MAX_G = 1000.0  # [g] exclusive upper bound of a plausible ball mass
MASS_TYPICAL_MIN_G = 40.0  # [g] below this a warning (tennis balls are 56-59.4 g)
MASS_TYPICAL_MAX_G = 70.0  # [g] above this a warning

DEFAULT_AIR_DENSITY_KG_M3 = 1.2  # [kg/m^3] default `rig.air_density_kg_m3`


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
    # ([-], [-]) how far the plate's resonance and damping ratio are charged off either way, as fractions; None = the
    # defaults for a stated plate (ballimpact.signal.sensed_ends); the session's identified plate sets them
    plate_uncertainty: tuple[float, float] | None = None


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


def _normalise_trace(trace: str) -> str:
    return trace.replace("\\", "/")
