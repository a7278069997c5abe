"""The registry of checks: what each looks at, the quantities it can bias, its thresholds, and whether it is a fault.

Every problem the processing can find in an impact (a :class:`ballimpact.problems.ProblemKind`) is the finding of
one named :class:`Check`. A check is either a **fault**, which excludes the whole impact (a second contact, a
truncated contact, clipping, missing or impossible gate times, an unreadable trace), or a check of the signal that
can bias some of the impact's quantities (:data:`QUANTITIES`). A signal check's finding carries, where the check can
estimate it, the effect of what it saw on each quantity it can bias, in that quantity's relative unit; the effect
enters the quantity's error budget (:mod:`ballimpact.verdicts`). Where it cannot estimate the effect, the finding
withholds the quantities it can bias, never the impact.

``CHECKS`` lists them in the order they are judged and reported; :func:`get_check` looks one up by its code (the
ProblemKind's value, also impacts.csv ``reason_code``). ``docs/checks.md`` is generated from it
(``python docs/gen_checks.py``).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from .problems import ProblemKind

__all__ = [
    "QUANTITIES",
    "TOLERANCES",
    "Threshold",
    "Check",
    "CHECKS",
    "get_check",
    "check_of",
    "checks_markdown",
]

#: The quantities judged one by one: contact time TC, the calibration factor kCAL (and the force, velocity and
#: displacement that depend on it), the peak force and the coefficient of restitution.
QUANTITIES = ("contact_time", "kcal", "peak", "cor")

#: Tolerance of each quantity: relative for TC, kCAL and the peak [-] (``peak_spike``: the pre-buckling spike's),
#: absolute for COR [-]. A quantity whose expanded (k = 2) uncertainty exceeds its tolerance is withheld.
TOLERANCES = {"contact_time": 0.01, "kcal": 0.01, "peak": 0.03, "peak_spike": 0.05, "cor": 0.002}

_TC, _K, _P, _C = QUANTITIES
_ALL_SIGNAL = (_TC, _K, _P)


@dataclass(frozen=True)
class Threshold:
    """One threshold of a check: the module constant it is, its unit and what it bounds.

    The value is read from the module when asked (:attr:`value`), so that the registry never holds a copy that
    could drift from the code that uses it.
    """

    module: str
    name: str
    unit: str
    meaning: str

    @property
    def value(self):
        """The constant's current value (its unit in :attr:`unit`)."""
        return getattr(importlib.import_module(f"ballimpact.{self.module}"), self.name)


@dataclass(frozen=True)
class Check:
    """A named check of one impact.

    Attributes
    ----------
    kind : ProblemKind
        The problem it reports; ``kind.value`` is its code.
    title : str
        Short name for tables.
    looks_at : str
        What it looks at, in one sentence.
    biases : tuple of str
        The quantities (of :data:`QUANTITIES`) what it finds can bias; a fault's are all of them.
    fault : bool
        True when a finding excludes the impact (the right answer for a faulty trace).
    thresholds : tuple of Threshold
        Its thresholds, with units.
    test : str
        The test that shows what it catches (``tests/file.py::name`` or ``-k`` expression).
    effect : str
        How the effect of a finding on each quantity is estimated; empty when it is not (the finding then
        withholds every quantity in ``biases``).
    """

    kind: ProblemKind
    title: str
    looks_at: str
    biases: tuple
    fault: bool = False
    thresholds: tuple = ()
    test: str = ""
    effect: str = ""

    def __post_init__(self):
        unknown = set(self.biases) - set(QUANTITIES)
        if unknown:
            raise ValueError(f"check {self.kind.value}: unknown quantities {sorted(unknown)}; "
                             f"known: {', '.join(QUANTITIES)}")

    @property
    def code(self) -> str:
        """Stable machine-readable code (impacts.csv ``reason_code``)."""
        return self.kind.value


def _t(module, name, unit, meaning):
    return Threshold(module, name, unit, meaning)


_RING = "ballimpact.signal.effects.ringing_effects"
#: Every check, in the order they are judged and reported.
CHECKS: dict[str, Check] = {c.code: c for c in (
    # --- faults of the row and the file: nothing to measure
    Check(ProblemKind.GATE_TIME_MISSING, "gate time missing", "the four gate-time cells of the impact's row",
          (_TC, _K, _P, _C), fault=True, test="tests/test_session.py -k missing"),
    Check(ProblemKind.GATE_TIME_INVALID, "gate time invalid", "each gate time: numeric, finite, not negative",
          (_TC, _K, _P, _C), fault=True, test="tests/test_gates.py"),
    Check(ProblemKind.GATE_ORDER, "gate times out of order", "in 1 < in 2 <= out 2 < out 1",
          (_TC, _K, _P, _C), fault=True, test="tests/test_gates.py"),
    Check(ProblemKind.GATE_INTERVAL, "gate interval", "the inbound and rebound intervals are positive",
          (_TC, _K, _P, _C), fault=True, test="tests/test_gates.py"),
    Check(ProblemKind.MASS_INVALID, "mass invalid", "the row's mass_g: numeric, positive, plausible",
          (_TC, _K, _P, _C), fault=True, test="tests/test_session.py -k mass"),
    Check(ProblemKind.TRACE_PATH_MISSING, "trace path missing", "the row names a trace file", (_TC, _K, _P, _C),
          fault=True, test="tests/test_bad_input.py"),
    Check(ProblemKind.TRACE_PATH_ESCAPES, "trace path escapes", "the trace path stays inside the session folder",
          (_TC, _K, _P, _C), fault=True, test="tests/test_bad_input.py"),
    Check(ProblemKind.TRACE_PATH_UNRESOLVABLE, "trace path unresolvable", "the trace path can be resolved",
          (_TC, _K, _P, _C), fault=True, test="tests/test_bad_input.py"),
    Check(ProblemKind.TRACE_NOT_FOUND, "trace not found", "the trace file exists", (_TC, _K, _P, _C), fault=True,
          test="tests/test_bad_input.py"),
    Check(ProblemKind.TRACE_NOT_A_FILE, "trace not a file", "the trace path is a file", (_TC, _K, _P, _C),
          fault=True, test="tests/test_bad_input.py"),
    Check(ProblemKind.TRACE_UNREADABLE, "unreadable trace", "the trace file parses as CSV, TDMS or LVM",
          (_TC, _K, _P, _C), fault=True, test="tests/test_traces.py"),
    Check(ProblemKind.TRACE_UNUSABLE, "unusable trace", "the trace holds enough finite samples to condition",
          (_TC, _K, _P, _C), fault=True, test="tests/test_bad_input.py"),
    # --- gates: COR and the impulse
    Check(ProblemKind.SPEED_OUT_OF_BOUNDS, "inbound speed impossible", "the inbound speed from the gates",
          (_TC, _K, _P, _C), fault=True,
          thresholds=(_t("processing", "PHYSICAL_BOUNDS", "m/s (vin_m_s)", "plausible speeds, COR and TC"),),
          test="tests/test_processing.py -k bounds"),
    Check(ProblemKind.COR_OUT_OF_BOUNDS, "COR impossible", "the COR from the gates", (_TC, _K, _P, _C),
          fault=True, thresholds=(_t("processing", "PHYSICAL_BOUNDS", "- (cor)", "plausible COR"),),
          test="tests/test_processing.py -k bounds"),
    # --- faults of the trace
    Check(ProblemKind.CLIPPING, "clipping", "samples at an ADC rail, or a flat top of the contact below them",
          (_TC, _K, _P, _C), fault=True,
          thresholds=(_t("signal.clipping", "SATURATION_TOP_SIGMA", "noise sd", "a flat top's samples lie this close"),
                      _t("signal.clipping", "SATURATION_NEXT_SIGMA", "noise sd", "the band below a top")),
          test="tests/test_processing.py -k clipping"),
    Check(ProblemKind.POLARITY, "wrong polarity", "the sign of the pulse against plate.polarity", (_TC, _K, _P, _C),
          fault=True, thresholds=(_t("processing", "OPPOSITE_PULSE_RATIO", "-", "other sign's excursion ratio"),),
          test="tests/test_processing.py -k polarity"),
    Check(ProblemKind.NO_CONTACT, "no contact", "a run of the corrected signal above the contact threshold",
          (_TC, _K, _P, _C), fault=True,
          thresholds=(_t("signal.noise", "THRESHOLD_SIGMA", "noise sd", "contact threshold"),
                      _t("signal.noise", "THRESHOLD_FRACTION", "of the peak", "contact threshold")),
          test="tests/test_contact.py"),
    Check(ProblemKind.MULTIPLE_IMPACTS, "second contact", "other runs of force in the record", (_TC, _K, _P, _C),
          fault=True,
          thresholds=(_t("signal.contact", "SECOND_IMPACT_FRACTION", "of the peak", "a second contact from this on"),
                      _t("signal.contact", "SECOND_IMPACT_MIN_S", "s", "... lasting longer than this")),
          test="tests/test_contact.py -k impacts"),
    Check(ProblemKind.CONTACT_TRUNCATED, "truncated contact", "the contact lies inside the record",
          (_TC, _K, _P, _C), fault=True, test="tests/test_contact.py -k trace_start"),
    # --- the signal: each withholds what it can bias
    Check(ProblemKind.ALIASING, "aliasing", "daq.bandwidth_hz against half the sample rate", (_K, _P),
          thresholds=(_t("session", "PLATE_RESONANCE_MAX_HZ", "Hz", "highest plate resonance of the format"),
                      _t("bandlimit", "ALIAS_SLOW_FRACTION", "of the sample rate",
                         "a stated bandwidth aliasing below it biases TC too")),
          test="tests/test_verdicts.py -k alias; tests/test_robustness.py -k mended",
          effect="not estimated: where daq.bandwidth_hz lets a resonance alias below ALIAS_SLOW_FRACTION of the "
                 "sample rate, the end can be read on the alias's smooth tail, and TC is withheld with kCAL and the "
                 "peak (ballimpact.bandlimit.aliasing_problem)"),
    Check(ProblemKind.CONTACT_UNSTABLE, "contact window unstable",
          "the contact window and the baseline fitted around it converge", _ALL_SIGNAL,
          thresholds=(_t("signal.window", "UNSTABLE_SAMPLES", "samples", "still moving after the iterations"),),
          test="tests/test_conditioning.py -k unstable"),
    Check(ProblemKind.DECAY_NOT_CORRECTED, "decay not corrected",
          "the amplifier's decay could bias the impulse", (_K, _P),
          thresholds=(_t("signal.baseline", "BIAS_EXCLUDE_FRACTION", "of the impulse", "largest uncorrected bias"),),
          test="tests/test_conditioning.py -k decay"),
    Check(ProblemKind.UNDERSHOOT_NOT_MEASURABLE, "undershoot not measurable",
          "the amplifier's undershoot after the contact gives its time constant", (_K, _P),
          thresholds=(_t("signal.baseline", "UNDERSHOOT_SIGNIFICANCE", "standard errors", "significance of kappa"),),
          test="tests/test_conditioning.py -k undershoot"),
    Check(ProblemKind.BASELINE_OFF_ZERO, "baseline off zero", "the corrected signal's level away from the contact",
          _ALL_SIGNAL,
          thresholds=(_t("signal.integrity", "FLAT_FRACTION", "of the peak", "a level above this"),
                      _t("signal.integrity", "FLAT_SIGMA", "standard errors", "... and this significant")),
          test="tests/test_conditioning.py -k off_zero"),
    Check(ProblemKind.BASELINE_RESIDUAL, "baseline residual", "the quiet samples' residual from the baseline model",
          _ALL_SIGNAL, test="tests/test_conditioning.py -k residual"),
    Check(ProblemKind.BASELINE_STEP, "baseline step", "a step in the level of the quiet baseline", _ALL_SIGNAL,
          thresholds=(_t("signal.integrity", "BASELINE_STEP_SIGMA", "standard errors", "a step's significance"),
                      _t("signal.integrity", "BASELINE_STEP_FRACTION", "of the peak", "a step's size")),
          test="tests/test_conditioning.py -k step",
          effect="with the amplifier's time constant given, the step's size L as a level left under the contact "
                 "(ballimpact.signal.effects.level_effects): L over the force's slope at each end bounds each end's "
                 "shift (TC), L TC over the contact's integral bounds kCAL, L over the peak bounds the peak; with "
                 "the time constant estimated, the decay may take up a step next to the contact and the step found "
                 "is then a smaller one elsewhere: not estimated"),
    Check(ProblemKind.MAINS_UNRESOLVED, "mains unresolved", "50 and 60 Hz hum fits that differ under the contact",
          _ALL_SIGNAL, thresholds=(_t("signal.integrity", "MAINS_AMBIGUOUS_FRACTION", "of the peak", "difference"),),
          test="tests/test_conditioning_mains.py"),
    Check(ProblemKind.TOO_FEW_SAMPLES, "too few samples", "samples across the contact", _ALL_SIGNAL,
          thresholds=(_t("signal.end_checks", "MIN_CONTACT_SAMPLES", "samples", "fewest across the contact"),),
          test="tests/test_conditioning.py -k few"),
    Check(ProblemKind.CONTACT_END_UNDETERMINED, "contact end undetermined",
          "each end's fit: its spread, its standard uncertainty, the force's curve and what stands after it",
          (_TC, _K),
          thresholds=(_t("signal.end_checks", "END_SE_MAX_FRACTION", "of TC", "expanded uncertainty of the ends"),
                      _t("signal.end_checks", "SPREAD_MAX_FRACTION", "of TC", "an end's spread"),
                      _t("signal.end_checks", "END_CHECK_SIGMA", "standard errors", "force standing after an end"),
                      _t("signal.effects", "DEPARTURE_SIGMA", "noise deviations", "signal before the start"),
                      _t("signal.effects", "DEPARTURE_SWING", "of its height",
                         "a run before a completed start swinging below zero so far is ringing, not force")),
          test="tests/test_conditioning.py -k end",
          effect="signal departing from its noise before the start (ballimpact.signal.effects.departure_before_start): "
                 "the span from the earliest departure to the start as completed bounds the start's shift (TC); a "
                 "start read on a plate-undone force with no jump to complete it from (ballimpact.signal.cloth."
                 "hidden_cloth_phase): the cloth's 2 mm at the inbound speed; a finding about the start's foot where "
                 "the start is completed from the force's jump (ballimpact.signal.cloth.first_contact): none. kCAL: "
                 "the signal's integral over the span the end may move by (its refit's move, the curve's lateness, "
                 "twice its fit's standard uncertainty, the stretch checked beyond it, a departure or the cloth's "
                 "phase before the start; ballimpact.signal.effects.window_effects) against the contact's; where no "
                 "such span is known (an end in the noise, or no line pinning it) kCAL is withheld with TC"),
    Check(ProblemKind.CONTACT_JUMP_UNRESOLVED, "contact jump unresolved",
          "half a sample at an end where the force jumps, against TC", (_TC,),
          thresholds=(_t("signal.end_checks", "JUMP_MAX_FRACTION", "of TC", "half a sample at most this"),),
          test="tests/test_conditioning.py -k jump"),
    Check(ProblemKind.PLATE_RINGING, "plate ringing",
          "ringing after the contact, a spectral line in it, two humps, and the plate's identification",
          _ALL_SIGNAL,
          thresholds=(_t("signal.ringing", "RING_MAX_FRACTION", "of the peak", "rms ringing after the contact"),
                      _t("signal.ringing", "RING_LINE_PROMINENCE", "-", "a line over its neighbourhood"),
                      _t("signal.ringing", "RING_LINE_NOISE_FACTOR", "-", "a line over the noise in a bin"),
                      _t("signal.effects", "UNSEEN_RING_SIGMA", "noise deviations",
                         "a ringing no identification finds, at most"),
                      _t("signal.sensed_ends", "SENSED_FN_UNCERTAINTY", "-", "a known plate's resonance, charged"),
                      _t("signal.sensed_ends", "SENSED_ZETA_UNCERTAINTY", "-", "its damping ratio, charged"),
                      _t("signal.sensed_ends", "SENSED_OWN_FN_UNCERTAINTY", "-",
                         "the trace's own identification's resonance, charged where its ringing cannot measure it"),
                      _t("signal.sensed_ends", "SENSED_OWN_ZETA_UNCERTAINTY", "-", "its damping ratio, likewise"),
                      _t("signal.sensed_ends", "SENSED_MAX_RESIDUAL", "noise deviations",
                         "an end's fit through the plate, at most"),
                      _t("signal.sensed_ends", "SENSED_MAX_START_RESIDUAL", "of its jump",
                         "a start's fit through the plate, at most (rms)"),
                      _t("signal.sensed_ends", "SENSED_RING_MAX_RESIDUAL", "noise deviations",
                         "the free ringing's fit that measures the plate in the trace, at most"),
                      _t("signal.sensed_ends", "SENSED_RING_COVERAGE", "standard uncertainties",
                         "the plate so measured, charged"),
                      _t("signal.sensed_ends", "SENSED_MIN_END_SIGMA", "noise deviations",
                         "force inside an end's window, at least")),
          test="tests/test_verdicts.py -k faint; tests/test_sensed_ends.py; tests/test_stated_plate.py -k aliases",
          effect=f"a spectral line of amplitude A at f ({_RING}): the larger of A and the sinusoid fitted at f after "
                 "the contact, over the force's slope at each end, bounds each end's shift (TC); A over the peak "
                 "bounds the peak; A / (pi f) over the contact's integral bounds kCAL. A plate identified but not "
                 "undone carries the line's effects when the line is all the evidence and the plate's resonance lies "
                 "in the band the line check looks in; where a peak on ringing was all the evidence, or it and lines, "
                 "and no resonance stands out of the noise, TC gets the larger of the lines' bounds and "
                 "UNSEEN_RING_SIGMA noise deviations over the end's slope (kCAL and the peak not estimated). The "
                 "stated band limit's rounding of the front is charged once, by the first peak problem. A known "
                 "plate (stated, the session's, or one the trace identified itself "
                 "where aliasing is ruled out) that is not undone has the contact's ends fitted through it in the "
                 "sensed force, the plate measured in the trace's free ringing after the end where one mode explains "
                 "it: TC gets how far it moves with the fit's windows and the plate off by SENSED_RING_COVERAGE of "
                 "its standard uncertainties so measured (else by SENSED_FN_UNCERTAINTY and SENSED_ZETA_UNCERTAINTY, "
                 "the session's intervals, or for the trace's own identification SENSED_OWN_FN_UNCERTAINTY and "
                 "SENSED_OWN_ZETA_UNCERTAINTY), and the ringing's other findings then bias kCAL and the peak only. A "
                 "stated plate above what the samples resolve (its ringing aliases): TC gets half its period plus "
                 "what the jump's ringing leaves at the end over the slope there "
                 "(ballimpact.signal.effects.aliased_plate_effects); kCAL and the peak not estimated."),
    Check(ProblemKind.NEGATIVE_FORCE, "force below zero", "the corrected signal after the contact", _ALL_SIGNAL,
          thresholds=(_t("signal.ringing", "NEGATIVE_FRACTION", "of the peak", "depth"),
                      _t("signal.ringing", "NEGATIVE_SIGMA", "standard errors", "significance")),
          test="tests/test_conditioning.py -k negative"),
    Check(ProblemKind.CLOTH_PHASE_COMPLETED, "cloth's phase completed",
          "the force's steep edge (its jump) against the start read on its foot", (_TC, _K),
          thresholds=(_t("signal.cloth", "STEEP_MIN_RISE", "of the peak", "a jump's rise, and the foot's most"),
                      _t("signal.cloth", "STEEP_MAX_WIDTH", "of TC", "a jump's longest"),
                      _t("signal.cloth", "STEEP_MIN_SIGMA", "noise deviations", "a jump's least rise")),
          test="tests/test_cloth.py",
          effect="the start is the jump less the cloth's 2 mm at the inbound speed (ballimpact.signal.cloth."
                 "first_contact; section 3.2.4), uncertain by the jump's location (TC's random uncertainty); where "
                 "the jump read at the start lies before the steepest rise by more than twice that, the two "
                 "readings' distance bounds the start's shift (TC); what the signal holds between that start and "
                 "the start read, over the contact's integral, bounds kCAL"),
    Check(ProblemKind.IMPULSE_UNRESOLVED, "impulse unresolved",
          "single samples that may be electrical spikes at the contact's ends or top", (_K, _P),
          thresholds=(_t("signal.spikes", "SPIKE_END_IMPULSE", "of the impulse", "a kept sample's share"),),
          test="tests/test_spike_ends.py"),
    Check(ProblemKind.PEAK_ON_RINGING, "peak on ringing",
          "the peak against one period of ringing about it; and, once the session's plate is known (stated or "
          "identified from all its impacts), the largest sample against the force that plate's inverse gives",
          (_P,),
          thresholds=(_t("signal.peak", "PEAK_ON_RINGING_FRACTION", "of the peak", "drop over a period"),
                      _t("session_checks", "PLATE_PEAK_NOISE_SIGMA", "standard deviations",
                         "the noise's share added to the session plate's effect")),
          test="tests/test_processing.py -k withheld; tests/test_verdicts.py -k overshoot",
          effect="the session's plate (ballimpact.session_checks.plate_overshoot): the largest sample's distance "
                 "from the peak of the force undone through the plate, in the peak's budget. With daq.bandwidth_hz "
                 "stated where its band limit may round the contact's jump unseen, a peak problem of the sensed "
                 "force biases TC and kCAL too, by that rounding (ballimpact.signal.effects.rounding_effects: "
                 "1 / (2 B) over TC; the force's area within it at each end over the integral)"),
    Check(ProblemKind.PEAK_BETWEEN_SAMPLES, "peak between samples",
          "how far the force may rise above its largest sample", (_P,),
          thresholds=(_t("signal.peak", "PEAK_SAMPLING_FRACTION", "of the peak", "rise above the largest sample"),),
          test="tests/test_processing.py -k withheld",
          effect="with daq.bandwidth_hz stated where its band limit may round the contact's jump unseen, it biases "
                 "TC and kCAL too, by that rounding (ballimpact.signal.effects.rounding_effects); the peak itself: "
                 "not estimated"),
    # --- the physical bounds and the calibration
    Check(ProblemKind.CONTACT_TIME_OUT_OF_BOUNDS, "TC out of bounds", "TC against plausible contact times", (_TC,),
          thresholds=(_t("processing", "PHYSICAL_BOUNDS", "ms (contact_time_ms)", "plausible TC"),),
          test="tests/test_processing.py -k bounds"),
    Check(ProblemKind.NO_CALIBRATION, "no calibration", "a finite positive voltage integral over the contact",
          (_TC, _K, _P, _C), fault=True, test="tests/test_calibration.py"),
    # a kCAL unlike the plate's is a symptom: a gate time off (then COR too), a trace's sample rate or gain unlike
    # the session's (then TC too); which one the impact cannot tell, so it withholds every quantity
    Check(ProblemKind.KCAL_OUT_OF_RANGE, "kCAL out of range", "kCAL against plate.kcal_range_N_per_V",
          (_TC, _K, _P, _C), test="tests/test_processing.py -k kcal_range"),
    Check(ProblemKind.KCAL_OUTLIER, "kCAL outlier", "kCAL against the session's median", (_TC, _K, _P, _C),
          thresholds=(_t("session_checks", "KCAL_MAX_ROBUST_Z", "-", "robust z-score"),
                      _t("session_checks", "KCAL_MAX_RELATIVE", "-", "relative deviation")),
          test="tests/test_verdicts.py -k outlier"),
    Check(ProblemKind.TIME_CONSTANT_OUTLIER, "time constant outlier",
          "the estimated amplifier time constant against the session's", (_TC, _K, _P),
          thresholds=(_t("session_checks", "TAU_MAX_Z", "standard errors", "difference in kappa"),
                      _t("session_checks", "TAU_MAX_IMPULSE", "of the impulse", "its effect on the impulse")),
          test="tests/test_processing.py -k time_constant"),
)}

_missing = set(ProblemKind) - {c.kind for c in CHECKS.values()}
if _missing:  # every kind of problem is judged by one check
    raise RuntimeError(f"checks registry lacks {sorted(k.value for k in _missing)}")


def get_check(code: str) -> Check:
    """The check of ``code`` (a ProblemKind value, impacts.csv ``reason_code``).

    Raises
    ------
    KeyError
        For an unknown code, listing the valid ones.
    """
    try:
        return CHECKS[str(code)]
    except KeyError:
        raise KeyError(f"unknown check {code!r}; valid: {', '.join(CHECKS)}") from None


def check_of(kind: ProblemKind) -> Check:
    """The check that reports problems of ``kind``."""
    return CHECKS[kind.value]


def checks_markdown() -> str:
    """docs/checks.md: per check, what it looks at, what it can bias, its thresholds and its test (generated)."""
    lines = [
        "# The checks",
        "",
        "Generated from `ballimpact.checks.CHECKS` by `python docs/gen_checks.py`; do not edit by hand.",
        "",
        "A **fault** excludes the impact. Any other check's finding goes into the error budget of each quantity it",
        "can bias where it estimates its effect, and withholds those quantities where it does not; an impact enters",
        "its ball type's fit when TC and COR are `ok`. Tolerances (expanded, k = 2): "
        + ", ".join(f"{q} {v:g}" for q, v in TOLERANCES.items()) + " (relative, COR absolute).",
        "",
        "| code | check | looks at | fault | can bias | effect estimated |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for c in CHECKS.values():
        lines.append(f"| `{c.code}` | {c.title} | {c.looks_at} | {'yes' if c.fault else ''} | "
                     f"{', '.join(c.biases)} | {'yes' if c.effect else ''} |")
    lines.append("")
    for c in CHECKS.values():
        lines += [f"## `{c.code}`: {c.title}", "", f"Looks at {c.looks_at}.", ""]
        lines.append("A fault: the impact is excluded." if c.fault else
                     f"Can bias: {', '.join(c.biases)}.")
        if c.effect:
            lines += ["", f"Effect: {c.effect}"]
        if c.thresholds:
            lines += ["", "| threshold | value | unit | meaning |", "| --- | --- | --- | --- |"]
            lines += [f"| `{t.module}.{t.name}` | `{t.value!r}` | {t.unit} | {t.meaning} |" for t in c.thresholds]
        if c.test:
            lines += ["", f"Test: `{c.test}`"]
        lines.append("")
    return "\n".join(lines)
