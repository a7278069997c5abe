"""One impact from raw gate times and voltage trace to calibrated force, TC and COR (section 2 of Goodwill & Haake 2004).

:func:`process_impact` composes the pure pieces: gate speeds
(:mod:`ballimpact.gates`), conditioning (:mod:`ballimpact.conditioning`),
contact detection (:mod:`ballimpact.contact`) and calibration
(:mod:`ballimpact.calibration`). It never raises for a fault of one impact:
the impact comes back ``excluded`` with its reason. :func:`iter_process`
streams a session, holding one trace in memory at a time;
:func:`flag_calibration_outliers` and :func:`flag_time_constant_outliers` apply the
session-level checks (kCAL, and the amplifier's time constant where it is estimated).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import Iterable, Iterator

import numpy as np

from .bandlimit import (  # noqa: F401  (re-exported where they were)
    ALIAS_SLOW_FRACTION, PEAK_WITHHOLD_MAX_ROUNDING, PLATE_IS_BANDWIDTH_TOLERANCE, alias_free, aliasing_problem,
    aliasing_ruled_out, front_rounding, peak_can_be_withheld)
from .checks import QUANTITIES, check_of
from .calibration import calibration_factor, contact_summary, force_from_voltage, integrate_motion
from .signal.baseline import baseline_integral_se
from .signal.conditioning import condition_voltage
from .signal.clipping import SATURATION_NEXT_SIGMA, SATURATION_TOP_SIGMA, detect_clipping, detect_saturation
from .signal.contact import contact_samples, end_standard_uncertainties
from .flight import BALL_DIAMETER_M, drag_constant, plate_speeds
from .gates import check_gate_times, coefficient_of_restitution, gate_speeds
from .model import BUCKLING_TIME_S, kelvin_voigt_parameters
from .problems import GATE_TIME_KINDS, PEAK_KINDS, TRACE_FILE_KINDS, Problem, ProblemKind, has_kind
from .session import ImpactRow, Session
from .traces import TraceError, read_trace
from .signal.cloth import cloth_phase_s, first_contact, hidden_cloth_phase, steep_edge
from .signal.effects import departure_before_start, end_slopes, finding_effects, window_effects
from .signal.end_checks import about_start
from .verdicts import gate_uncertainties, judge_quantities, random_uncertainties

__all__ = [
    "IMPACT_COLUMNS",
    "PHYSICAL_BOUNDS",
    "ImpactResult",
    "process_impact",
    "iter_process",
    "flag_calibration_outliers",
    "calibration_outlier_columns",
    "apply_calibration_check",
    "apply_time_constant_check",
    "time_constant_outlier_columns",
    "apply_session_flags",
    "VERDICT_COLUMNS",
    "flag_time_constant_outliers",
    "alias_free",
    "aliasing_ruled_out",
    "peak_can_be_withheld",
    "PEAK_WITHHOLD_MAX_ROUNDING",
]

#: kCAL's budget takes the force's largest step between two samples within this long of the contact's start as a
#: jump whose place within its sample interval is not known (the jump at first contact and the pre-buckling spike,
#: within the model's buckling time of 0.2 ms of it) [s]
INTEGRAL_JUMP_S = 0.3e-3

#: Columns of results/<session>/impacts.csv, in order (docs/outputs.md).
IMPACT_COLUMNS = [
    "impact_id", "ball", "status", "reason", "vin_m_s", "vout_m_s", "cor", "contact_time_ms",
    "kcal_N_per_V", "impulse_N_s", "peak_force_N", "time_to_peak_ms", "max_displacement_mm",
    "kv_stiffness_kN_m", "kv_damping_N_s_m",
    "vin_gate_m_s", "vout_gate_m_s",  # v1.1: speeds at the gates (= vin/vout without gates.distance_to_plate_m)
    "peak_note",  # v1.1: why peak_force_N and time_to_peak_ms are withheld on an ok impact, else empty
    # v1.2: per-quantity verdicts
    "contact_time_u_ms", "kcal_u_N_per_V", "peak_force_u_N", "cor_u",
    "contact_time_status", "kcal_status", "peak_status", "cor_status", "reason_code", "withheld_note",
]

#: Plausible ranges for a tennis ball fired at a force plate; outside = excluded.
PHYSICAL_BOUNDS = {
    "vin_m_s": (2.0, 80.0),  # inbound speed [m/s]
    "cor": (0.05, 1.0),  # coefficient of restitution [-]
    "contact_time_ms": (1.0, 12.0),  # contact time [ms]
}
#: Mains hum components removed: the fundamental and its harmonics up to the 5th.
HUM_HARMONICS = 5


@dataclass
class ImpactResult:
    """Everything measured of one impact; see IMPACT_COLUMNS for the scalar columns.

    Time series cover the contact, from its start (t = 0) to its end, at the
    trace's samples with the sub-sample ends interpolated: time [s], conditioned
    voltage [V], force [N], velocity [m/s] (towards the plate) and displacement
    [m]. ``raw_time_s`` / ``raw_voltage_V`` hold the whole trace (polarity
    applied), time from the contact start when it was found.
    """

    impact_id: str
    ball: str
    status: str = "ok"
    reason: str = ""  # the messages of ``problems``, "; "-separated (impacts.csv)
    problems: list = field(default_factory=list)  # ballimpact.problems.Problem, in the order found
    vin_m_s: float = math.nan
    vout_m_s: float = math.nan
    cor: float = math.nan
    contact_time_ms: float = math.nan
    kcal_N_per_V: float = math.nan
    impulse_N_s: float = math.nan
    peak_force_N: float = math.nan
    time_to_peak_ms: float = math.nan
    max_displacement_mm: float = math.nan
    kv_stiffness_kN_m: float = math.nan
    kv_damping_N_s_m: float = math.nan
    vin_gate_m_s: float = math.nan  # speeds from the gates; vin_m_s/vout_m_s are at the plate
    vout_gate_m_s: float = math.nan
    mass_kg: float = math.nan
    sample_rate_hz: float = math.nan
    trace_file: str = ""
    noise_rms_V: float = math.nan
    hum_amplitude_V: float = math.nan
    tau_s: float = math.nan  # charge-amplifier time constant [s] used (inf: no decay corrected)
    tau_se_s: float = math.nan  # its standard error [s] when estimated (_tau_standard_error), else NaN
    tau_source: str = ""  # "given" (plate.time_constant_s), "estimated" or "none"
    mains_hz: float = math.nan  # mains frequency [Hz] whose hum was removed (0: none)
    mains_source: str = ""  # "given" (daq.mains_hz), "detected" or "none"
    plate_resonance_hz: float = math.nan  # the plate resonance undone (ballimpact.plate); NaN when none was
    plate_damping_ratio: float = math.nan
    peak_note: str = ""  # v1.1: why the peak force is withheld on an ok impact
    peak_half_range_N: float = 0.0  # half the range the peak's top can take between two samples (its budget's)
    # v1.2 per-quantity verdicts (ballimpact.verdicts): standard uncertainty and ok / withheld of each quantity
    contact_time_u_ms: float = math.nan
    kcal_u_N_per_V: float = math.nan
    peak_force_u_N: float = math.nan
    cor_u: float = math.nan
    contact_time_status: str = "ok"
    kcal_status: str = "ok"
    peak_status: str = "ok"
    cor_status: str = "ok"
    reason_code: str = ""  # codes of the findings that withheld or excluded something, ";"-separated
    withheld_note: str = ""  # on an ok impact: why each withheld quantity is withheld ("kcal: ...; peak: ...")
    peak_is_spike: bool = False  # the peak is the pre-buckling spike (tolerance 5 %)
    u_random: dict = field(default_factory=dict, repr=False)  # relative random uncertainties, until settled
    time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    voltage_V: np.ndarray = field(default_factory=lambda: np.empty(0))
    force_N: np.ndarray = field(default_factory=lambda: np.empty(0))
    velocity_m_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    displacement_m: np.ndarray = field(default_factory=lambda: np.empty(0))
    raw_time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    raw_voltage_V: np.ndarray = field(default_factory=lambda: np.empty(0))

    def find(self, problem: Problem) -> "ImpactResult":
        """Record a finding of a check (a :class:`Problem`) and judge the quantities again.

        A fault excludes the impact; any other finding withholds the quantities its check can bias unless it
        estimated its effect on them (``problem.effects``), which then enters their budgets
        (:func:`ballimpact.verdicts.judge_quantities`). The impact is excluded when TC or COR is withheld.
        """
        if not isinstance(problem, Problem):
            raise TypeError(f"problem must be a ballimpact.problems.Problem, got {problem!r}")
        self.problems.append(problem)
        return self.judge()

    def judge(self) -> "ImpactResult":
        """Statuses, uncertainties, reason and codes from the findings so far and the random uncertainties."""
        u_random = {q: self.u_random.get(q, 0.0) for q in QUANTITIES}
        v = judge_quantities(self.problems, u_random, peak_is_spike=self.peak_is_spike)
        self.status = "excluded" if v.excluded else "ok"
        self.contact_time_status, self.kcal_status, self.peak_status, self.cor_status = (
            v.status[q] for q in QUANTITIES)
        self.reason_code = ";".join(v.codes)
        withheld = [q for q in QUANTITIES if v.status[q] != "ok"]
        if v.excluded:  # the faults; without one, every finding and what withheld TC or COR by its budget alone
            messages = [p.message for p in self.problems if check_of(p.kind).fault]
            messages = messages or [p.message for p in self.problems]
            messages += [m for q in ("contact_time", "cor") if q in withheld for m in v.why[q].split("; ") if m]
            self.reason, self.withheld_note, self.peak_note = "; ".join(dict.fromkeys(messages)), "", ""
        else:
            self.reason = ""
            self.withheld_note = "; ".join(f"{q}: {v.why[q]}" for q in withheld)
            self.peak_note = v.why["peak"] if "peak" in withheld else ""
        self._verdict = v
        return self

    def settle(self, u_random: dict) -> "ImpactResult":
        """The final verdict with the impact's random uncertainties (relative, COR absolute) [-], and the
        standard uncertainties in each quantity's unit."""
        self.u_random = dict(u_random)
        self.judge()
        u = self._verdict.u
        self.contact_time_u_ms = u["contact_time"] * self.contact_time_ms
        self.kcal_u_N_per_V = u["kcal"] * self.kcal_N_per_V
        self.peak_force_u_N = u["peak"] * self.peak_force_N
        self.cor_u = u["cor"]
        return self

    def row(self) -> dict:
        """The impacts.csv row of this impact."""
        return {c: getattr(self, c) for c in IMPACT_COLUMNS}


def _out_of_bounds(name, value):
    lo, hi = PHYSICAL_BOUNDS[name]
    return not (lo <= value <= hi)


#: The pulse is taken as of the other sign than plate.polarity when its largest excursion
#: that way is more than this many times the largest the declared way [-] (the amplifier's
#: undershoot after a contact stays well below the pulse for any time constant >= 0.01 s).
OPPOSITE_PULSE_RATIO = 2.0


def _opposite_pulse_reason(raw, polarity: int) -> Problem | None:
    """Why a trace cannot be processed when it is the polarity: the pulse has the other sign.

    Compares the largest excursion of the voltage [V] from its median in the declared
    direction (``plate.polarity`` [-]) and in the other, after a 3-sample running median
    so that a single-sample spike counts for nothing. Returns the POLARITY problem "pulse
    is negative: plate.polarity is +1" (or the converse), else None.
    """
    v = polarity * (np.asarray(raw, dtype=float) - np.median(raw))
    if v.size >= 3:
        a, b, c = v[:-2], v[1:-1], v[2:]  # the median of three, as np.median gives it (NaN where one is NaN)
        v = np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))
    if v.size == 0 or not np.max(-v) > OPPOSITE_PULSE_RATIO * max(np.max(v), 0.0):
        return None
    sign = "negative" if polarity == 1 else "positive"
    return Problem(ProblemKind.POLARITY, f"pulse is {sign}: plate.polarity is {polarity:+d}")


def _speeds_at_plate(vin_gate, vout_gate, row: ImpactRow, session: Session):
    """Gate speeds corrected to the plate (:func:`ballimpact.flight.plate_speeds`) for this impact's ball."""
    meta = session.meta
    ball = meta.balls.get(row.ball)
    mass = row.mass_kg if math.isfinite(row.mass_kg) and row.mass_kg > 0 else (ball.mass_kg if ball else math.nan)
    diameter = ball.diameter_m if ball is not None and ball.diameter_m is not None else BALL_DIAMETER_M
    if not math.isfinite(mass):
        return math.nan, math.nan
    k = drag_constant(mass, diameter, meta.air_density_kg_m3)
    return plate_speeds(vin_gate, vout_gate, meta.gate_spacing_m, meta.distance_to_plate_m, k,
                        orientation=meta.rig_orientation, diameter_m=diameter)


def process_impact(row: ImpactRow, session: Session) -> ImpactResult:
    """Process one impact: speeds, COR, kCAL, force, motion, TC and Kelvin-Voigt kB, cB.

    Implements section 2 of Goodwill & Haake 2004: COR = VB'/VB from the gates;
    kCAL = m (VB + VB') / integral of V dt over the contact; F = kCAL V; velocity
    and displacement by integrating -F/m from VB and 0; TC the time during which
    a force acts; Kelvin-Voigt kB and cB from Eqs. (2) and (3).

    Parameters
    ----------
    row : ImpactRow
        The impact's row of impacts.csv.
    session : Session
        Its session (metadata and folder).

    Returns
    -------
    ImpactResult
        Status ``ok``, or ``excluded`` with every reason found; never raises for
        a fault of this impact.
    """
    meta = session.meta
    res = ImpactResult(impact_id=row.impact_id, ball=row.ball, mass_kg=row.mass_kg, trace_file=row.trace)
    for problem in row.problems:
        res.find(problem)
    _gate_speeds(res, row, session)
    read = _conditioned_trace(res, row, session)
    if read is None:
        return res.settle(_random_uncertainties(res, row, meta))
    t, raw, cond = read
    aliasing = aliasing_problem(meta.bandwidth_hz, res.sample_rate_hz)
    if aliasing is not None:
        res.find(aliasing)
    contact = _contact(res, t, raw, cond, meta)
    if contact is not None:
        cond = replace(cond, contact=contact)  # its start completed by the cloth's phase, where it was
        _calibrated(res, row, t, cond, contact, meta)
    return res.settle(_random_uncertainties(res, row, meta, cond, float(t[0])))


def _gate_speeds(res: ImpactResult, row: ImpactRow, session: Session) -> None:
    """Speeds at the plate [m/s] and COR of the impact from its gate times, or the gate problems (section 2)."""
    meta = session.meta
    # Speeds from the gates (section 2): vin = spacing / (in_2 - in_1), vout = spacing / (out_1 - out_2).
    gate_problems = check_gate_times(row.gate_in_1_s, row.gate_in_2_s, row.gate_out_2_s, row.gate_out_1_s)
    # The reader already names every gate fault of its rows (missing, non-numeric, out of
    # order); these messages are for rows it did not check, and would only repeat it.
    if not has_kind(row.problems, GATE_TIME_KINDS):
        for p in gate_problems:
            res.find(p)
    if not gate_problems:
        vin, vout = gate_speeds(row.gate_in_1_s, row.gate_in_2_s, row.gate_out_2_s, row.gate_out_1_s,
                                meta.gate_spacing_m)
        res.vin_gate_m_s, res.vout_gate_m_s = float(vin), float(vout)
        if meta.distance_to_plate_m is not None:  # v1.1: from the gates to the plate (drag, gravity)
            vin, vout = _speeds_at_plate(vin, vout, row, session)
        res.vin_m_s, res.vout_m_s = float(vin), float(vout)
        res.cor = float(coefficient_of_restitution(vin, vout))
        if _out_of_bounds("vin_m_s", res.vin_m_s):
            res.find(Problem(ProblemKind.SPEED_OUT_OF_BOUNDS, f"inbound speed {res.vin_m_s:.2f} m/s outside "
                                f"physical bounds {PHYSICAL_BOUNDS['vin_m_s']}"))
        if _out_of_bounds("cor", res.cor):
            res.find(Problem(ProblemKind.COR_OUT_OF_BOUNDS,
                                f"COR {res.cor:.3f} outside physical bounds {PHYSICAL_BOUNDS['cor']}"))


def _conditioned_trace(res: ImpactResult, row: ImpactRow, session: Session):
    """Read and condition the trace: (time [s], raw voltage [V], ConditionedSignal), or None when excluded."""
    meta = session.meta
    # The trace.
    path = session.trace_path(row)
    try:
        is_file = path.is_file()
    except (OSError, ValueError):  # e.g. a file name too long for the OS: Path.is_file() re-raises ENAMETOOLONG
        is_file = False
    if not is_file:
        if not has_kind(res.problems, TRACE_FILE_KINDS):
            res.find(Problem(ProblemKind.TRACE_NOT_FOUND, f"trace file not found: {row.trace}"))
        return None
    try:
        trace = read_trace(path, meta.sample_rate_hz)
    except TraceError as exc:
        res.find(Problem(ProblemKind.TRACE_UNREADABLE, f"unreadable trace: {exc}"))
        return None
    fs = trace.sample_rate_hz
    res.sample_rate_hz = fs
    raw = trace.voltage_V
    t = trace.t0_s + np.arange(raw.size) / fs
    res.raw_time_s = t - t[0]
    res.raw_voltage_V = meta.polarity * raw

    if detect_clipping(raw, meta.adc_range_v):
        res.find(Problem(ProblemKind.CLIPPING, "clipping at the ADC rails"))
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        try:
            cond = condition_voltage(raw, fs, polarity=meta.polarity,
                                     mains_hz="auto" if meta.mains_hz is None else meta.mains_hz,
                                     n_harmonics=HUM_HARMONICS, tau_s=meta.time_constant_s, t0_s=trace.t0_s,
                                     plate=meta.plate_resonance, plate_uncertainty=meta.plate_uncertainty,
                                     cloth_phase_s=cloth_phase_s(res.vin_m_s),
                                     fit_own_plate=aliasing_ruled_out(meta.bandwidth_hz, fs))
        except ValueError as exc:
            res.find(Problem(ProblemKind.TRACE_UNUSABLE, f"unusable trace: {exc}"))
            return None
    # any sample at a rail that is not a replaced single-sample spike
    not_spikes = np.delete(raw, np.asarray(cond.spike_indices, dtype=int))
    if not has_kind(res.problems, ProblemKind.CLIPPING) and detect_clipping(not_spikes, meta.adc_range_v, min_run=1):
        res.find(Problem(ProblemKind.CLIPPING,
                            "clipping at the ADC rails (a sample at a rail that is not a single-sample spike)"))
    return t, raw, cond


def _saturation_problem(res: ImpactResult, raw, cond, polarity: int) -> None:
    """Exclude an impact whose contact has a flat top in the recorded voltage (contact.detect_saturation): a stage
    before the ADC saturated below its rails. Judged on the recorded voltage with single-sample spikes replaced,
    as it is (hum picked up before the amplifier is cut with it) and with the fitted hum removed (hum added after
    it rides on the flat top)."""
    c = cond.contact
    sigma = cond.noise_rms_V
    if not (c.found and math.isfinite(sigma) and sigma > 0):
        return
    i0, i1 = max(int(c.start_index), 0), min(int(c.end_index), raw.size - 1)
    if i1 - i0 < 2:
        return
    a, b = max(i0 - 1, 0), min(i1 + 2, raw.size)  # the contact and a neighbour each side, for its spikes
    x = polarity * np.asarray(raw[a:b], dtype=float)
    for i in cond.spike_indices:
        if a < i < b - 1:
            x[i - a] = 0.5 * (x[i - a - 1] + x[i - a + 1])
    for what, y in (("as recorded", x), ("with the hum removed", x - cond.baseline_V[a:b])):
        sat = detect_saturation(y[i0 - a:i1 + 1 - a], sigma)
        if sat.saturated:
            res.find(Problem(ProblemKind.CLIPPING, (
                f"clipping below the ADC rails: the recorded signal ({what}, polarity applied) is flat at the "
                f"contact's top, {sat.n_top} samples within {SATURATION_TOP_SIGMA:g} noise deviations of its top "
                f"against {sat.n_below} in the {SATURATION_NEXT_SIGMA - SATURATION_TOP_SIGMA:g} deviations below "
                f"(a smooth force's top holds about 1.4 times as many): the charge amplifier or another stage "
                f"before the ADC saturated, and the force above it is lost (use a less sensitive range)")))
            return


def _tau_standard_error(cond, fs: float, t0_s: float) -> float:
    """Standard error [s] of a time constant estimated from the trace (NaN when it was given or not estimated).

    The baseline fit's own (``kappa_se_per_s``, from the noise of the quiet samples) and, in quadrature, the
    contact integral's: kappa is the undershoot over the integral of the contact's voltage, summed by trapezia
    over the samples, and a jump of the force between two samples (the model's rise at the start: 30-57 % of the
    peak within 10 us) falls anywhere in its interval, which leaves the integral uncertain by the largest
    sample-to-sample rise [V] times 1 / (fs sqrt(12)) [s] (uniform over the interval). Without that term the
    estimates of 0.01-0.1 s scattered four times their standard error about the truth over the zoo's ok
    traces (``python bench/robustness.py --n 2000 --seed 0``, its time-constant table). Still not counted: the
    choice of hum model on a record of about one mains period (zoo trace 0:428).

    Parameters
    ----------
    cond : ballimpact.conditioning.ConditionedSignal
        The conditioned trace.
    fs : float
        Sample rate [Hz].
    t0_s : float
        Time of the trace's first sample [s].
    """
    kappa, kappa_se = (cond.baseline_coefficients.get(k, math.nan) for k in ("kappa_per_s", "kappa_se_per_s"))
    if not (cond.tau_source == "estimated" and math.isfinite(kappa_se) and kappa > 0):
        return math.nan
    se = kappa_se / kappa**2  # tau = 1 / kappa
    c = cond.contact
    if not (c.found and math.isfinite(c.start_s) and math.isfinite(c.end_s)):
        return se
    i0 = max(int(math.floor((c.start_s - t0_s) * fs)), 0)
    i1 = min(int(math.ceil((c.end_s - t0_s) * fs)) + 1, cond.voltage_V.size)
    seg = cond.voltage_V[i0:i1]
    integral = float(np.sum(seg)) / fs
    if not (seg.size > 2 and integral > 0):
        return se
    relative = float(np.max(np.abs(np.diff(seg)))) / (fs * math.sqrt(12.0)) / integral  # of kappa, so of tau
    return math.hypot(se, cond.tau_s * relative)


def _contact(res: ImpactResult, t, raw, cond, meta):
    """The contact of the conditioned trace with its problems and TC [ms]; None when there is no usable one."""
    res.noise_rms_V = cond.noise_rms_V
    res.hum_amplitude_V = cond.hum_amplitude_V
    res.tau_s = cond.tau_s
    res.tau_source = cond.tau_source
    res.tau_se_s = _tau_standard_error(cond, res.sample_rate_hz, float(t[0]))
    res.mains_hz = cond.baseline_coefficients.get("mains_hz", math.nan)
    res.mains_source = cond.baseline_coefficients.get("mains_source", "")
    if cond.plate is not None:
        res.plate_resonance_hz = cond.plate.frequency_hz
        res.plate_damping_ratio = cond.plate.damping_ratio
    contact = cond.contact
    wrong_sign = _opposite_pulse_reason(raw, meta.polarity)
    if wrong_sign is not None:
        res.find(wrong_sign)
        return None
    if not contact.found:
        res.find(Problem(ProblemKind.NO_CONTACT, "no contact found"))
        return None
    res.raw_time_s = t - contact.start_s
    if not has_kind(res.problems, ProblemKind.CLIPPING):  # a pulse of the right sign, found: is its top flat?
        _saturation_problem(res, raw, cond, meta.polarity)
    if contact.n_impacts > 1:
        seen = ", ".join(f"{'second' if k == 0 else 'another'} contact at {dt * 1e3:+.1f} ms, "
                         f"{100 * frac:.0f} % of the peak" for k, (dt, frac) in enumerate(contact.other_impacts))
        res.find(Problem(ProblemKind.MULTIPLE_IMPACTS,
                            f"more than one impact in the trace ({contact.n_impacts} found: {seen})"))
    if "contact_at_trace_start" in contact.flags or "contact_at_trace_end" in contact.flags:
        res.find(Problem(ProblemKind.CONTACT_TRUNCATED, "contact not entirely inside the trace (truncated trace?)"))
    # no alias, and no unseen rounding of the front, behind a peak problem
    peak_alone = peak_can_be_withheld(meta.bandwidth_hz, res.sample_rate_hz, contact.contact_time_s,
                                      None if cond.plate is None else cond.plate.frequency_hz)
    rounded = False  # the band limit's one rounding of the front is charged once, by the first peak problem
    for problem in cond.problems:
        # with daq.bandwidth_hz stated, a peak problem where that band limit may round the front unseen (or alias)
        # may hide a TC too long; without the key, an alias withholds kCAL and the peak (_aliasing_problem) and a
        # rounded front is judged by the ends' own checks, as at 60 kHz or faster; a problem of an undone force's
        # peak is one of its undoing or low-pass, no sign of that rounding (nor is a peak on the ringing of a plate
        # through which the ends were fitted: signal.sensed_ends)
        if problem.kind in PEAK_KINDS and meta.bandwidth_hz is not None and not peak_alone and not rounded \
                and not problem.data.get("undone_peak") and not problem.data.get("ends_fitted"):
            problem = front_rounding(problem, cond, meta.bandwidth_hz, res.sample_rate_hz, float(t[0]))
            rounded = True
        res.find(_with_effects(problem, cond, res.sample_rate_hz, float(t[0])))
    sensed = "ends_fitted_sensed" in contact.flags  # fitted through a known plate, the cloth's phase included
    completed = None if sensed else _cloth_completion(res, cond, float(t[0]))
    if completed is not None:
        contact = completed
        res.raw_time_s = t - contact.start_s  # (the same contact where its foot was read at the first contact)
    if cond.plate is None and not sensed:  # an undone plate's start is fitted through its chain, the low-pass's
        _departure_problem(res, cond, float(t[0]), contact)  # spread included
    if completed is None and not sensed and (cond.plate is not None or _JUMP_FLAGS & set(contact.flags)):
        # read at a jump, or on an undone force, and not completed from a steep edge
        _cloth_problem(res, cond, float(t[0]))
    tc_ms = contact.contact_time_s * 1e3
    res.contact_time_ms = tc_ms
    if _out_of_bounds("contact_time_ms", tc_ms):
        res.find(Problem(ProblemKind.CONTACT_TIME_OUT_OF_BOUNDS,
                            f"contact time {tc_ms:.2f} ms outside physical bounds {PHYSICAL_BOUNDS['contact_time_ms']}"))
    return contact


#: The contact's flags of a start read at the force's jump (signal.contact).
_JUMP_FLAGS = frozenset({"start_jump", "start_step"})


def _cloth_completion(res: ImpactResult, cond, t0_s: float):
    """The contact with its start at the first contact the force's jump gives (:func:`ballimpact.signal.cloth.
    first_contact`), where that is earlier than the start read by more than half a sample and twice the start's
    standard uncertainty; the contact as read where it is not so far from it either way (the foot read is the
    first contact) or is earlier still (a foot longer than the cloth's phase); None where the force shows no jump or
    the speed is not known.

    Where the start read is the first contact or is completed, it no longer rests on its foot alone: the findings
    about that foot (a CONTACT_END_UNDETERMINED of the start) are kept with the two starts' difference for their
    effect on TC (none where completed: the start's uncertainty is then the jump's)."""
    c, fs = cond.contact, res.sample_rate_hz
    if not (c.found and math.isfinite(fs) and res.vin_m_s > 0):
        return None
    start_u = (c.start_s - t0_s) * fs
    edge = steep_edge(cond.voltage_V, start_u, c.peak_index, cond.noise_rms_V, c.contact_time_s * fs)
    if edge is None:
        return None
    if start_u > edge.at_u + 1.0:  # a start read after the jump: the jump located is not the contact's (a spike)
        return None
    # a start read at a jump is the middle of the interval where the force left its foot: the jump is no later (a
    # steeper rise after it, the ball's ramp to its spike at a low sample rate, draws the steepest slope later)
    # ... where the signal is quiet before it (a filter's ringing ahead of the jump draws a start read early)
    at_jump = _JUMP_FLAGS & set(c.flags) and "cloth_foot" not in c.flags \
        and departure_before_start(cond.voltage_V, fs, start_u)[0] == 0.0
    jump_u = min(edge.at_u, start_u) if at_jump else edge.at_u
    first = first_contact(jump_u, fs, res.vin_m_s)
    read_se = c.start_se_s * fs if math.isfinite(c.start_se_s) else 0.0
    if not (0.0 <= first and start_u - first < c.contact_time_s * fs):  # a phase longer than TC: no ball's speed
        return None
    agree = max(0.5, 2.0 * read_se)
    if start_u - first < -agree:
        return c  # a foot longer than the cloth's phase: the start as read, what its checks found stands
    # the start no longer rests on the foot alone: the findings about it are bounded by the two starts' difference
    for k, p in enumerate(res.problems):
        if about_start(p):
            moot = abs(start_u - first) / (c.contact_time_s * fs) if start_u - first <= agree else 0.0
            res.problems[k] = replace(p, effects={**p.effects, "contact_time": moot},
                                      data={**p.data, "moot": "cloth_phase"})
    if start_u - first <= agree:
        return c  # the start read on the foot is the first contact: as read
    x = np.asarray(cond.voltage_V, dtype=float)
    a, b = int(math.ceil(first)), int(math.floor((c.end_s - t0_s) * fs))
    whole, before = float(np.sum(x[a:b + 1])), float(np.sum(x[a:int(math.ceil(start_u))]))
    phase = (jump_u - first) / fs
    # the jump located twice, read at the start and as the steep edge: where the two disagree beyond the edge's own
    # uncertainty, the jump is known only to within them, and TC with it
    apart = max(edge.at_u - jump_u - 2.0 * edge.se_u, 0.0)
    res.find(Problem(ProblemKind.CLOTH_PHASE_COMPLETED,
                     f"contact start completed from the force's jump by the cloth's phase: {1e3 * phase:.2g} ms (2 mm "
                     f"at {res.vin_m_s:.1f} m/s) before it, {1e3 * (start_u - first) / fs:.2g} ms before the start "
                     "read on its foot" + (f"; the jump read at the start {1e3 * (edge.at_u - jump_u) / fs:.2g} ms "
                                           "before the steepest rise" if apart > 0 else ""),
                     data={"cloth_phase_s": phase, "shift_s": (start_u - first) / fs, "jump_apart_s": apart / fs},
                     effects={"contact_time": apart / (c.contact_time_s * fs),
                              "kcal": abs(before) / whole if whole > 0 else math.nan}))
    flags = tuple(f for f in c.flags if f not in _JUMP_FLAGS) + ("cloth_completed",)
    return replace(c, start_s=t0_s + first / fs, start_index=int(math.ceil(first)), start_se_s=edge.se_u / fs,
                   start_spread_s=math.nan, flags=flags)


def _departure_problem(res: ImpactResult, cond, t0_s: float, contact) -> None:
    """A finding, with its effect on TC, where the signal departs from its noise before ``contact``'s start
    (:func:`ballimpact.signal.effects.departure_before_start`; above it only, where that start was completed from
    the force's jump)."""
    c, fs = cond.contact, res.sample_rate_hz
    if contact is c:
        span, noise = departure_before_start(cond.voltage_V, fs, (c.start_s - t0_s) * fs)
    else:  # completed from the jump: only a foot of force longer than the cloth's phase moves it
        span, noise = departure_before_start(cond.voltage_V, fs, (contact.start_s - t0_s) * fs, force_only=True)
    if not (math.isfinite(span) and span > 0 and contact.contact_time_s > 0):
        return
    res.find(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                     f"contact start not known to better than {1e3 * span:.3g} ms: the signal departs from its "
                     f"noise ({noise * 1e3:.2g} mV) that long before the start found (an anti-aliasing filter's "
                     "ringing ahead of a jump, or a foot of the force)",
                     data={"departure_s": span},
                     effects={"contact_time": span / contact.contact_time_s,
                              "kcal": window_effects(cond.voltage_V, fs, (contact.start_s - t0_s) * fs,
                                                     (contact.end_s - t0_s) * fs, cond.noise_rms_V, span,
                                                     at_start=True)}))


def _cloth_problem(res: ImpactResult, cond, t0_s: float) -> None:
    """A finding, with its effects on TC and kCAL, where a start read at the force's jump or on an undone plate's
    force, and not completed from a steep edge, may miss the cloth's phase
    (:func:`ballimpact.signal.cloth.hidden_cloth_phase`; kCAL: the signal before the start over that phase,
    :func:`ballimpact.signal.effects.window_effects`)."""
    c, fs = cond.contact, res.sample_rate_hz
    effect = hidden_cloth_phase(res.vin_m_s, c.contact_time_s)
    phase = effect * c.contact_time_s  # [s]; NaN where the speed is not known
    res.find(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                     "contact start may miss the cloth's phase: read at the force's jump or on a plate-undone "
                     "force, with no steep edge to complete it from, where the cloth's light load over the ball's "
                     "first 2 mm of compression may hide "
                     f"({1e3 * phase:.2g} ms at {res.vin_m_s:.1f} m/s)",
                     data={"cloth_phase_s": phase},
                     effects={"contact_time": effect,
                              "kcal": window_effects(cond.voltage_V, fs, (c.start_s - t0_s) * fs,
                                                     (c.end_s - t0_s) * fs, cond.noise_rms_V, phase, at_start=True)}))


def _with_effects(problem: Problem, cond, fs: float, t0_s: float) -> Problem:
    """A conditioning finding with its effects estimated where its check can (ballimpact.signal.effects)."""
    c = cond.contact
    if not (c.found and math.isfinite(fs)):
        return problem
    return finding_effects(problem, cond.problems, cond.voltage_V, fs, (c.start_s - t0_s) * fs,
                           (c.end_s - t0_s) * fs, cond.noise_rms_V)


def _end_standard_uncertainties(cond, fs: float, t0_s: float) -> tuple[float, float]:
    """Standard uncertainties of the contact's start and end [s]: from each end's fit (the force's curve where the
    end came from it), a uniform half sample where the force jumps, else the noise over the force's slope there."""
    c = cond.contact
    half = 1.0 / (fs * math.sqrt(12.0))
    fitted = dict(zip(("start", "end"), end_standard_uncertainties(c, jump_s=half)))
    slopes = dict(zip(("start", "end"), end_slopes(cond.voltage_V, fs, (c.start_s - t0_s) * fs,
                                                   (c.end_s - t0_s) * fs)))
    out = []
    for end in ("start", "end"):
        se = fitted[end]
        if not math.isfinite(se):
            se = max(cond.noise_rms_V / slopes[end], half) if slopes[end] > 0 else math.nan
        out.append(float(se))
    return out[0], out[1]


def _random_uncertainties(res: ImpactResult, row: ImpactRow, meta, cond=None, t0_s: float = 0.0) -> dict:
    """The impact's random uncertainties for :func:`ballimpact.verdicts.random_uncertainties` [-] (``t0_s``: the
    trace's first sample [s])."""
    u_vin, u_vout = gate_uncertainties(row.gate_in_2_s - row.gate_in_1_s, row.gate_out_1_s - row.gate_out_2_s,
                                       meta.gate_resolution_s)
    nan = {q: math.nan for q in QUANTITIES}
    nan["cor"] = res.cor * math.hypot(u_vin, u_vout) if math.isfinite(res.cor) else math.nan
    if cond is None or not cond.contact.found or res.voltage_V.size < 2:
        return nan
    fs, c = res.sample_rate_hz, cond.contact
    start_se, end_se = _end_standard_uncertainties(cond, fs, t0_s)
    kappa_se = cond.baseline_coefficients.get("kappa_se_per_s", 0.0) if cond.tau_source == "estimated" else 0.0
    baseline_se = baseline_integral_se(cond.baseline_coefficients, fs, (c.start_s - t0_s) * fs, (c.end_s - t0_s) * fs)
    # the force's jump at first contact and its spike: the largest step between two samples of the contact's start
    jump = float(np.max(np.abs(np.diff(res.voltage_V[:int(math.ceil(INTEGRAL_JUMP_S * fs)) + 2]))))
    # the range a spike's top cut by a drop between two samples can take, as _calibrated read the peak [V]
    top_half = res.peak_half_range_N / res.kcal_N_per_V if res.peak_half_range_N > 0 else 0.0
    return random_uncertainties(
        u_vin=u_vin, u_vout=u_vout, cor=res.cor, contact_time_s=c.contact_time_s, start_se_s=start_se,
        end_se_s=end_se, noise_V=cond.noise_rms_V, n_contact=res.voltage_V.size,
        integral_V_s=float(np.trapezoid(res.voltage_V, res.time_s)), peak_V=float(np.max(res.voltage_V)), fs=fs,
        kappa_se_per_s=kappa_se, baseline_se_V_s=baseline_se, jump_V=jump, peak_half_range_V=top_half)


def _calibrated(res: ImpactResult, row: ImpactRow, t, cond, contact, meta) -> ImpactResult:
    """kCAL from the impulse, force, velocity, displacement, peak and Kelvin-Voigt kB, cB (Eqs. 2, 3)."""
    jump = "start_jump" in contact.flags  # the force held back to the start over its jump's interval
    t_rel, v_contact = contact_samples(t, cond.voltage_V, contact.start_s, contact.end_s, start_jump=jump)
    res.time_s = t_rel
    res.voltage_V = v_contact
    # every contact series as long as time_s: NaN until the calibration gives a force
    res.force_N, res.velocity_m_s, res.displacement_m = (np.full(t_rel.size, np.nan) for _ in range(3))
    if not (math.isfinite(res.vin_m_s) and math.isfinite(res.vout_m_s) and math.isfinite(row.mass_kg)):
        return res  # excluded above: no calibration without speeds and mass
    try:
        kcal = calibration_factor(t, cond.voltage_V, contact.start_s, contact.end_s, row.mass_kg,
                                  res.vin_m_s, res.vout_m_s, start_jump=jump)
    except ValueError as exc:
        return res.find(Problem(ProblemKind.NO_CALIBRATION, f"no calibration: {exc}"))
    # A positive but vanishing (or overflowing) voltage integral gives kCAL = inf (or 0),
    # which force_from_voltage rejects with a ValueError: exclude instead of raising.
    if not (math.isfinite(kcal) and kcal > 0):
        return res.find(Problem(ProblemKind.NO_CALIBRATION,
                                   f"no calibration: calibration factor is {kcal!r} N/V (voltage integral over the "
                                   "contact too small or too large to calibrate)"))
    res.kcal_N_per_V = kcal
    if meta.kcal_range_N_per_V is not None:
        lo, hi = meta.kcal_range_N_per_V
        if not lo <= kcal <= hi:
            res.find(Problem(ProblemKind.KCAL_OUT_OF_RANGE,
                                f"calibration factor {kcal:.4g} N/V outside the plate's range [{lo:g}, {hi:g}] "
                                "N/V (plate.kcal_range_N_per_V)"))
    force = force_from_voltage(v_contact, kcal)
    velocity, displacement = integrate_motion(t_rel, force, row.mass_kg, res.vin_m_s)
    # the spike's top between two samples is judged on a force as sensed, not on one whose plate
    # resonance was undone (the inverse lifts the last ramp sample before a drop)
    noise_N = cond.noise_rms_V * kcal if cond.plate is None and math.isfinite(cond.noise_rms_V) else None
    summary = contact_summary(t_rel, force, row.mass_kg, res.vin_m_s, noise_N=noise_N)
    res.force_N, res.velocity_m_s, res.displacement_m = force, velocity, displacement
    res.impulse_N_s = row.mass_kg * (res.vin_m_s + res.vout_m_s)
    res.peak_force_N = summary.peak_force_N
    res.peak_half_range_N = summary.peak_half_range_N
    res.time_to_peak_ms = summary.time_to_peak_s * 1e3
    res.peak_is_spike = bool(summary.time_to_peak_s < BUCKLING_TIME_S)
    res.max_displacement_mm = summary.max_displacement_m * 1e3
    kb, cb = kelvin_voigt_parameters(row.mass_kg, res.contact_time_ms * 1e-3, res.cor)  # TC, as completed
    res.kv_stiffness_kN_m = float(kb) / 1e3
    res.kv_damping_N_s_m = float(cb)
    return res


def iter_process(session: Session, impact_ids: Iterable[str] | None = None) -> Iterator[ImpactResult]:
    """Process the impacts of a session one at a time, in raw order.

    Parameters
    ----------
    session : Session
        The session.
    impact_ids : iterable of str, optional
        Only these impacts (default all).

    Yields
    ------
    ImpactResult
        One per impact; only one trace is held in memory at a time.
    """
    wanted = None if impact_ids is None else set(impact_ids)
    for row in session.impacts:
        if wanted is None or row.impact_id in wanted:
            yield process_impact(row, session)


from .session_checks import (  # noqa: E402  (the session's checks, re-exported where they were)
    KCAL_MAX_RELATIVE, KCAL_MAX_ROBUST_Z, TAU_MAX_IMPULSE, TAU_MAX_Z, VERDICT_COLUMNS, apply_calibration_check,
    apply_session_flags, apply_time_constant_check, calibration_outlier_columns, flag_calibration_outliers,
    flag_time_constant_outliers, time_constant_outlier_columns)
