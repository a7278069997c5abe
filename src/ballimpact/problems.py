"""Typed impact-level problems: a kind for every decision, a message for people.

A fault of one impact (a missing gate time, a trace that cannot be read, a pulse of
the wrong sign, ...) is a :class:`Problem`: its :class:`ProblemKind` is what code
tests, its ``message`` is what users read (impacts.csv ``reason``, the run summary,
``ballimpact validate``). Rewording a message never changes a decision.

impacts.csv holds messages only (docs/outputs.md); :func:`kind_of_message` gives the
kind of a message read back from it, the one place where message text is matched.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass, field
from typing import Iterable

__all__ = [
    "ProblemKind",
    "Problem",
    "GATE_TIME_KINDS",
    "TRACE_FILE_KINDS",
    "PEAK_KINDS",
    "has_kind",
    "kind_of_message",
]


class ProblemKind(enum.Enum):
    """The class of an impact-level problem; the value is a stable identifier."""

    # impacts.csv cells (ballimpact.session) and gate times (ballimpact.gates)
    GATE_TIME_MISSING = "gate_time_missing"
    GATE_TIME_INVALID = "gate_time_invalid"  # non-numeric, non-finite or negative
    GATE_ORDER = "gate_order"
    GATE_INTERVAL = "gate_interval"  # an interval between two gates is not positive
    MASS_INVALID = "mass_invalid"
    TRACE_PATH_MISSING = "trace_path_missing"
    TRACE_PATH_ESCAPES = "trace_path_escapes"
    TRACE_PATH_UNRESOLVABLE = "trace_path_unresolvable"
    TRACE_NOT_FOUND = "trace_not_found"
    TRACE_NOT_A_FILE = "trace_not_a_file"
    # the trace (ballimpact.processing)
    TRACE_UNREADABLE = "trace_unreadable"
    TRACE_UNUSABLE = "trace_unusable"
    CLIPPING = "clipping"
    POLARITY = "polarity"
    NO_CONTACT = "no_contact"
    MULTIPLE_IMPACTS = "multiple_impacts"
    CONTACT_TRUNCATED = "contact_truncated"
    # integrity checks of the conditioning (ballimpact.signal.conditioning)
    CONTACT_UNSTABLE = "contact_unstable"
    DECAY_NOT_CORRECTED = "decay_not_corrected"
    UNDERSHOOT_NOT_MEASURABLE = "undershoot_not_measurable"
    BASELINE_OFF_ZERO = "baseline_off_zero"
    BASELINE_RESIDUAL = "baseline_residual"
    BASELINE_STEP = "baseline_step"
    CONTACT_END_UNDETERMINED = "contact_end_undetermined"
    TOO_FEW_SAMPLES = "too_few_samples"
    PLATE_RINGING = "plate_ringing"
    MAINS_UNRESOLVED = "mains_unresolved"
    CONTACT_JUMP_UNRESOLVED = "contact_jump_unresolved"  # a force jump between samples costs > 0.7 % of TC
    NEGATIVE_FORCE = "negative_force"  # force below zero after the contact
    PEAK_ON_RINGING = "peak_on_ringing"  # the peak is a swing of plate ringing
    PEAK_BETWEEN_SAMPLES = "peak_between_samples"  # the force may rise above the largest sample by > 10 %
    ALIASING = "aliasing"  # daq.bandwidth_hz above half the sample rate: ringing sampled through its alias
    IMPULSE_UNRESOLVED = "impulse_unresolved"  # a single sample that may be an electrical spike moves the impulse
    CLOTH_PHASE_COMPLETED = "cloth_phase_completed"  # the start put the cloth's 2 mm before the force's jump
    # physical bounds and calibration (ballimpact.processing)
    SPEED_OUT_OF_BOUNDS = "speed_out_of_bounds"
    COR_OUT_OF_BOUNDS = "cor_out_of_bounds"
    CONTACT_TIME_OUT_OF_BOUNDS = "contact_time_out_of_bounds"
    NO_CALIBRATION = "no_calibration"
    KCAL_OUT_OF_RANGE = "kcal_out_of_range"  # outside plate.kcal_range_N_per_V
    KCAL_OUTLIER = "kcal_outlier"  # far from the session median
    TIME_CONSTANT_OUTLIER = "time_constant_outlier"  # estimated amplifier decay unlike the session's


#: Gate-time faults the session reader finds in a row (processing does not repeat them).
GATE_TIME_KINDS = frozenset({ProblemKind.GATE_TIME_MISSING, ProblemKind.GATE_TIME_INVALID, ProblemKind.GATE_ORDER})
#: No readable trace file inside the session folder: nothing to hash, read or process.
TRACE_FILE_KINDS = frozenset({
    ProblemKind.TRACE_PATH_MISSING, ProblemKind.TRACE_PATH_ESCAPES, ProblemKind.TRACE_PATH_UNRESOLVABLE,
    ProblemKind.TRACE_NOT_FOUND, ProblemKind.TRACE_NOT_A_FILE,
})

#: Problems of the peak force alone: where an alias and a rounded front are ruled out (processing.peak_can_be_withheld:
#: by daq.bandwidth_hz, or without it by a sample rate of twice v1.1's highest plate resonance) they withhold the
#: peak (impacts.csv ``peak_note``) instead of excluding the impact, whose TC and kCAL every other check judges.
PEAK_KINDS = frozenset({ProblemKind.PEAK_ON_RINGING, ProblemKind.PEAK_BETWEEN_SAMPLES})


@dataclass(frozen=True)
class Problem:
    """One finding of one impact: ``kind`` for decisions, ``message`` (one line) for people.

    ``data`` holds what the check measured, for the estimate of its effect (:mod:`ballimpact.verdicts`), e.g.
    ``line_hz`` [Hz] and ``amplitude_V`` [V] of a spectral line; ``effects``, where the check estimated them, the
    bounds of its relative effect on each quantity of :data:`ballimpact.checks.QUANTITIES` [-].
    """

    kind: ProblemKind
    message: str
    data: dict = field(default_factory=dict, compare=False, hash=False)
    effects: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self):
        if not isinstance(self.kind, ProblemKind):
            raise TypeError(f"kind must be a ProblemKind, got {self.kind!r}")
        if not isinstance(self.message, str) or not self.message:
            raise ValueError(f"message must be a non-empty string, got {self.message!r}")

    def __str__(self) -> str:
        return self.message


def has_kind(problems: Iterable[Problem], kinds) -> bool:
    """Whether any of ``problems`` is of ``kinds`` (one ProblemKind or a collection of them)."""
    wanted = {kinds} if isinstance(kinds, ProblemKind) else set(kinds)
    return any(p.kind in wanted for p in problems)


#: How each kind's messages begin (regular expressions), for messages read back from a file.
_MESSAGE_STARTS = {
    ProblemKind.GATE_TIME_MISSING: r"missing gate time ",
    ProblemKind.GATE_TIME_INVALID: r"(non-numeric|non-finite|negative) gate time ",
    ProblemKind.GATE_ORDER: r"gate times out of order",
    ProblemKind.GATE_INTERVAL: r"(inbound|rebound) gate interval not positive",
    ProblemKind.MASS_INVALID: r"(non-numeric|non-finite|non-positive|implausible) mass_g",
    ProblemKind.TRACE_PATH_MISSING: r"missing trace path",
    ProblemKind.TRACE_PATH_ESCAPES: r"trace path escapes the session folder",
    ProblemKind.TRACE_PATH_UNRESOLVABLE: r"trace path cannot be resolved",
    ProblemKind.TRACE_NOT_FOUND: r"trace file not found",
    ProblemKind.TRACE_NOT_A_FILE: r"trace path is not a file",
    ProblemKind.TRACE_UNREADABLE: r"unreadable trace",
    ProblemKind.TRACE_UNUSABLE: r"unusable trace",
    ProblemKind.CLIPPING: r"clipping (at|below) the ADC rails",
    ProblemKind.POLARITY: r"pulse is (negative|positive): plate\.polarity",
    ProblemKind.NO_CONTACT: r"no contact found",
    ProblemKind.MULTIPLE_IMPACTS: r"more than one impact",
    ProblemKind.CONTACT_TRUNCATED: r"contact not entirely inside the trace",
    ProblemKind.CONTACT_UNSTABLE: r"contact window not stable",
    ProblemKind.DECAY_NOT_CORRECTED: r"charge-amplifier decay not corrected",
    ProblemKind.UNDERSHOOT_NOT_MEASURABLE: r"charge-amplifier undershoot not measurable",
    ProblemKind.BASELINE_OFF_ZERO: r"corrected signal .* off zero",
    ProblemKind.BASELINE_RESIDUAL: r"quiet baseline not explained",
    ProblemKind.BASELINE_STEP: r"step in the baseline",
    ProblemKind.CONTACT_END_UNDETERMINED: r"contact (start|end) not determined",
    ProblemKind.TOO_FEW_SAMPLES: r"only \S+ samples in the contact",
    ProblemKind.PLATE_RINGING: r"plate ringing",
    ProblemKind.MAINS_UNRESOLVED: r"mains (frequency|hum) not resolved",
    ProblemKind.CONTACT_JUMP_UNRESOLVED: r"contact (start|end|start and end) between two samples",
    ProblemKind.NEGATIVE_FORCE: r"force below zero after the contact",
    ProblemKind.PEAK_ON_RINGING: r"peak force on plate ringing",
    ProblemKind.PEAK_BETWEEN_SAMPLES: r"peak force between samples",
    ProblemKind.ALIASING: r"signal bandwidth .* above half the sample rate",
    ProblemKind.IMPULSE_UNRESOLVED: r"impulse not known",
    ProblemKind.CLOTH_PHASE_COMPLETED: r"contact start completed",
    ProblemKind.SPEED_OUT_OF_BOUNDS: r"inbound speed \S+ m/s outside physical bounds",
    ProblemKind.COR_OUT_OF_BOUNDS: r"COR \S+ outside physical bounds",
    ProblemKind.CONTACT_TIME_OUT_OF_BOUNDS: r"contact time \S+ ms outside physical bounds",
    ProblemKind.NO_CALIBRATION: r"no calibration",
    ProblemKind.KCAL_OUT_OF_RANGE: r"calibration factor \S+ N/V outside the plate's range",
    ProblemKind.KCAL_OUTLIER: r"calibration factor \S+ N/V is \S+ % from the session median",
    ProblemKind.TIME_CONSTANT_OUTLIER: r"charge-amplifier time constant \S+ s estimated, unlike the session's",
}
_MESSAGE_PATTERNS = {kind: re.compile(start) for kind, start in _MESSAGE_STARTS.items()}


def kind_of_message(message: str) -> ProblemKind | None:
    """The kind of one problem message as written in a file (impacts.csv ``reason``), else None.

    Only for text read back from a file, which carries no kind; code that creates a
    problem keeps its :class:`Problem`. ``message`` is one message, not a "; "-joined reason.
    """
    text = str(message).strip()
    for kind, pattern in _MESSAGE_PATTERNS.items():
        if pattern.match(text):
            return kind
    return None
