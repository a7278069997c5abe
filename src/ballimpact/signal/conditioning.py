"""Plate-voltage conditioning: polarity, offset, mains hum and charge-amplifier decay, without biasing the impulse.

The charge amplifier acts as a first-order high-pass with time constant tau:
``dV_meas/dt = dV_true/dt - V_meas / tau``. Integrating from the contact start
(where both are zero) gives the exact inverse used here::

    V_true(t) = V_meas(t) + (1 / tau) * integral_{start}^{t} V_meas dt'

After the contact V_true = 0, so there the measured signal obeys
``V_meas(t) = -(1 / tau) * integral_{start}^{t} V_meas dt'``: the undershoot and
its exponential recovery, for any tau (0.01 s, where the signal decays visibly
during the contact, as well as 100 s). The baseline model is therefore linear in
``kappa = 1 / tau``:

* every quiet sample: ``V = B`` with B = offset + linear drift + sin/cos at the
  mains frequency and its harmonics (one phase-continuous model for the whole
  trace);
* quiet samples after the contact: ``(V - B) + kappa * integral_{start}^{t} (V - B) dt' = 0``,
  i.e. ``V + kappa * I_V = sum_j theta_j (phi_j + kappa * I_phi_j)`` with the
  running integrals of V and of each model column phi_j.

For a given kappa this is linear in the model coefficients theta; kappa (when
``tau_s`` is not given) is the value that minimises the residual sum of squares,
found on a grid and refined, from normal equations that are quadratic in kappa
and built once per fit. The fit uses the quiet samples only: up to 100 ms of
pre-trigger and up to 50 ms after a guard for plate ringing (2 ms; 0.5 ms when
the record ends too soon for 2 ms after it), minus every event found in the
record (second contacts, with guards), with one robust pass that drops
outliers. When kappa comes out too uncertain for the impulse, the fits with
fewer hum harmonics are tried too (the least BIC wins). Single-sample spikes are replaced by the mean of their
neighbours first (except, at a contact end, a sample whose neighbours straddle the force's jump: the force's own,
kept and judged). When ``tau_s`` is given it is used exactly.

Events before baseline: each iteration decay-corrects the whole record and
marks every run that stands out of the noise (above 6 noise deviations and 0.5 %
of the peak) besides the main contact, with its shoulders (while it stays 3 noise
deviations above zero); the next fit leaves them out, so a second contact can
never bend the baseline. The contact window and the event mask are
iterated until they no longer move.

Mains: when ``mains_hz="auto"``, the fit is done without hum, with 50 Hz and
with 60 Hz harmonics on the same quiet samples and the smallest Bayesian
information criterion wins; when 50 and 60 Hz fit about equally well and their
hum differs under the contact, the impact is flagged as a problem.

Integrity checks (``ConditionedSignal.problems``, each one a reason to exclude
the impact): decay not measurable or not an amplifier decay, corrected signal
before or after the contact not flat at zero, mains frequency not resolved (or
hum in a record shorter than one mains period), a quiet residual that is more
than white noise, a step in the quiet baseline's level (the fit would spread
it over the record as drift) or across the contact when the time constant is
given, a contact that ends on a flat shelf of force (a step just after it
taken for the amplifier's undershoot), plate ringing during the contact (a
spectral line) or after it, a peak that is one of the plate's swings (or
lifted by its ringing from the force's jump), a peak between samples (the
largest sample on a steep ramp, or the first of the contact), force
below zero after the contact (the plate swinging back), a contact end that
moves when fitted again from higher samples (a tail fading into the noise), a
force jump from zero that locates an end only to half a sample when that is
more than 0.7 % of TC, too few samples across the contact, a contact window
that does not settle, and (last, on a trace nothing else excludes) a force's
jump spread over several samples by a low-pass in the chain, which delays the
contact's end.

Plate resonance: when the only problems are the plate's (ringing in or after
the contact, a peak on the ringing, force below zero after it, and the end and
peak problems such ringing causes), the resonance is identified from the
ringing and undone (``ballimpact.signal.plate``) and every contact, end and ringing
check is done again on the undone force. It is used only when two
identifications from independent instruments both pass every check and agree
on TC and peak, and the undone force is quiet enough for its peak and ends
(see ``plate_undone`` for every condition); otherwise the impact keeps its
problems.

"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ..problems import Problem, ProblemKind
from .baseline import (BaselineFit, MAINS_CANDIDATES_HZ, MIN_QUIET_SAMPLES, POST_GUARD_S, PRE_GUARD_S, fit_baseline,
                       mains_frequencies, rough_trend)
from .contact import ContactResult, detect_contact
from .end_checks import adc_step_problems, curve_end_contact, end_problems, plateau_end_problems
from .integrity import (baseline_bend_problems, baseline_step_problems, edge_event_problems, end_event_problems,
                        level_problems, mains_problems, short_record_hum)
from .noise import finite_median, quantization_step, robust_noise
from .plate import PlateResonance
from .ringing import ringing_problems
from .shape import front_lowpass, peak_on_slow_fall
from .spikes import low_spikes_at_ends, replace_spikes, second_differences, spikes_at_ends
from .sensed_ends import (SENSED_OWN_FN_UNCERTAINTY, SENSED_OWN_ZETA_UNCERTAINTY, resonance_lowpassed_contact,
                           sensed_contact)
from .undone import (PLATE_FN_UNCERTAINTY, PLATE_KINDS, Refusal, lowpassed_spike, plate_undone,
                     stated_plate_undone, undone_peak_spread)
from .window import iterate

__all__ = ["ConditioningWarning", "ConditionedSignal", "condition_voltage"]


class ConditioningWarning(UserWarning):
    """Usable but suspect conditioning (e.g. the decay could not be estimated)."""


@dataclass(frozen=True)
class ConditionedSignal:
    """A plate voltage with baseline, hum and decay removed.

    Attributes
    ----------
    voltage_V : numpy.ndarray
        Corrected voltage, polarity applied: proportional to the force, zero
        baseline [V].
    noise_rms_V : float
        Noise standard deviation of the quiet baseline (robust) [V].
    hum_amplitude_V : float
        Peak amplitude of the mains hum fundamental [V] (0 when not fitted).
    hum_harmonic_amplitudes_V : tuple of float
        Peak amplitude of the fundamental and each harmonic fitted [V].
    tau_s : float
        Charge-amplifier time constant used for the decay correction [s]; inf
        when no correction was applied, NaN when no contact was found.
    tau_source : str
        ``"estimated"``, ``"given"`` or ``"none"``.
    undershoot_V : float
        Step of the baseline just after the contact, positive downwards
        (``kappa`` times the contact's integral) [V].
    undershoot_se_V : float
        Standard error of undershoot_V [V].
    offset_V : float
        DC offset of the pre-contact baseline (polarity applied) [V].
    baseline_V : numpy.ndarray
        Offset + hum model subtracted from every sample (polarity applied) [V].
    baseline_coefficients : dict
        The fitted model: ``offset_V``, ``hum_cos_V`` and ``hum_sin_V`` (one per
        harmonic), ``hum_frequencies_hz``, ``kappa_per_s`` (1 / tau),
        ``kappa_se_per_s``, ``mains_hz`` (the mains frequency used, 0 for
        none), ``mains_source`` (``"given"``, ``"detected"`` or ``"none"``).
    contact : ContactResult
        Contact found on the corrected voltage.
    n_iterations : int
        Window/baseline iterations done [-].
    warnings : tuple of str
        Messages of the ConditioningWarnings issued.
    problems : tuple of ballimpact.problems.Problem
        Reasons the impact cannot be trusted (each names what was seen);
        empty when the conditioning passed every integrity check.
    spike_indices : tuple of int
        Samples replaced as single-sample spikes [-].
    plate : ballimpact.signal.plate.PlateResonance or None
        The plate resonance undone in ``voltage_V`` (None when none was).
    """

    voltage_V: np.ndarray
    noise_rms_V: float
    hum_amplitude_V: float
    hum_harmonic_amplitudes_V: tuple[float, ...]
    tau_s: float
    tau_source: str
    undershoot_V: float
    undershoot_se_V: float
    offset_V: float
    baseline_V: np.ndarray
    baseline_coefficients: dict = field(repr=False)
    contact: ContactResult = field(repr=False)
    n_iterations: int = 0
    warnings: tuple[str, ...] = ()
    problems: tuple[Problem, ...] = ()
    spike_indices: tuple[int, ...] = ()
    plate: PlateResonance | None = None


def condition_voltage(voltage_V, sample_rate_hz: float, *, polarity: int = 1, mains_hz: float | str | None = "auto",
                      n_harmonics: int = 3, t0_s: float = 0.0, tau_s: float | None = None,
                      pre_guard_s: float = PRE_GUARD_S, post_guard_s: float = POST_GUARD_S,
                      undo_plate: bool = True, plate: tuple | None = None, plate_uncertainty: tuple | None = None,
                      cloth_phase_s: float = 0.0, fit_own_plate: bool = True,
                      _kept: tuple | None = None, _near_ends: tuple = ()) -> ConditionedSignal:
    """Remove polarity, offset, mains hum and charge-amplifier decay from a plate voltage.

    The force-plate voltage must be proportional to the force for kCAL to be
    found from the impulse (section 2 in Goodwill & Haake 2004); this removes
    what the sensor chain adds. See the module docstring for the method. The
    impulse is not biased by the amplifier's undershoot: the decay is undone
    with the time constant that returns the post-contact baseline to zero.

    Parameters
    ----------
    voltage_V : array_like
        Voltage as recorded, one sample per 1/sample_rate_hz [V].
    sample_rate_hz : float
        Sample rate [Hz].
    polarity : int
        +1 when compressive force gives positive voltage, -1 otherwise [-].
    mains_hz : float, "auto" or None
        Mains frequency [Hz], used exactly; ``"auto"`` (default) detects 50 Hz,
        60 Hz or no hum from the quiet samples; None or 0 fits no hum.
    n_harmonics : int
        Hum components fitted: the fundamental and its harmonics up to
        ``n_harmonics * mains_hz`` [-].
    t0_s : float
        Time of the first sample [s] (only for the times reported).
    tau_s : float, optional
        Known amplifier time constant [s], undone exactly; ``math.inf`` for a
        DC-coupled amplifier. Estimated from the post-contact baseline when
        omitted.
    pre_guard_s, post_guard_s : float
        Samples closer than this to the contact are left out of the baseline
        fit [s].
    undo_plate : bool
        Undo a plate resonance identified from its ringing when that ringing
        is the only problem (see the module docstring); False reports the
        ringing as a problem.
    plate : tuple of float, optional
        A stated resonance (frequency [Hz], damping ratio [-]), e.g. from a tap
        test (session.yaml ``plate.resonance_hz``, ``plate.damping_ratio``):
        undone exactly on every trace, neither identified nor refined; where the
        force so undone fails the undone force's checks, the trace is
        conditioned as without it (its plate identified where it rings).
    plate_uncertainty : tuple of float, optional
        How far ``plate``'s resonance and damping ratio may be off, as fractions of them [-]: what the contact's
        ends fitted through it charge TC for (the session's identified plate's own intervals); None charges
        :data:`ballimpact.signal.sensed_ends.SENSED_FN_UNCERTAINTY` and ``SENSED_ZETA_UNCERTAINTY``.
    cloth_phase_s : float
        The cloth's phase of this impact, 2 mm at its inbound speed [s]
        (``ballimpact.signal.cloth``): a foot of the sensed force no longer
        than it before an undone force's jump is the cloth's, which the
        contact's start completed from the jump counts; 0 (default) or NaN
        where the speed is not known.
    fit_own_plate : bool
        Where a plate this trace identified itself is not undone, fit the
        contact's ends through it (measured again in its free ringing, or
        charged at SENSED_OWN_FN_UNCERTAINTY and SENSED_OWN_ZETA_UNCERTAINTY
        where its ringing cannot measure it). Only
        where no resonance can alias into the samples
        (:func:`ballimpact.bandlimit.aliasing_ruled_out`): an alias's ringing
        fits the samples after the contact, but not the force's response.
    _kept, _near_ends : tuple of int
        Internal, set when this function calls itself again: samples at a
        contact end not to be replaced as spikes, and lower spikes near the
        ends to be replaced (see :func:`spikes_at_ends`); None at the first
        pass.

    Returns
    -------
    ConditionedSignal
        Corrected voltage [V] with the noise [V], hum [V], tau [s], baseline
        model, the contact found on it and the integrity problems found. When
        no contact is found, only offset and hum are removed and
        ``contact.found`` is False.

    Raises
    ------
    ValueError
        For non-finite samples, fewer than 3 samples, a non-positive sample rate,
        a polarity other than +1/-1, a negative mains_hz or a non-positive tau_s.

    Warns
    -----
    ConditioningWarning
        When the decay cannot be estimated (no measurable undershoot, baseline
        after the contact above the one before it, post-contact stretch too
        short, implausible tau) and could bias the impulse by more than 0.1 %.
    """
    fs = float(sample_rate_hz)
    raw = _checked_voltage(voltage_V, sample_rate_hz, polarity, mains_hz, n_harmonics, tau_s, pre_guard_s,
                           post_guard_s)
    v_spiky, scale = _scaled(raw, polarity)
    # an ADC step above the noise: the noise is taken as no less than the step's (its error's deviation)
    adc_step = quantization_step(v_spiky)
    noise_floor = adc_step / math.sqrt(12.0)
    d2_spiky, v, spikes = _despiked(v_spiky, _kept, _near_ends)
    candidates, mains_source = _mains_candidates(mains_hz, n_harmonics, fs)
    kappa_given = None if tau_s is None else (0.0 if math.isinf(tau_s) else 1.0 / float(tau_s))

    rough = _rough_contact(v, fs)
    if not rough.found:
        return _unchecked_result(v, fs, candidates, noise_floor, t0_s, scale, spikes, mains_source)
    it = iterate(v, fs, candidates, rough, pre_guard_s * fs, post_guard_s * fs, tau_s, kappa_given, scale, noise_floor)
    # detect_contact(it.x, fs, t0_s=t0_s, noise_rms_V=it.fit.noise, ...), sharing the last iteration's search
    contact = curve_end_contact(it.search.result(t0_s=t0_s, spread=True, curve=True, step=True), fs, t0_s)
    at_ends, keep = spikes_at_ends(v_spiky, d2_spiky, spikes, _kept, contact, it.x, it.fit.noise, fs, t0_s, scale)
    near_ends = low_spikes_at_ends(v_spiky, d2_spiky, spikes, contact, fs, t0_s) if _kept is None else ()
    if keep or near_ends:  # the force's own samples at its jump kept, lower spikes at the ends replaced: again
        return condition_voltage(voltage_V, sample_rate_hz, polarity=polarity, mains_hz=mains_hz,
                                 n_harmonics=n_harmonics, t0_s=t0_s, tau_s=tau_s, pre_guard_s=pre_guard_s,
                                 post_guard_s=post_guard_s, undo_plate=undo_plate, plate=plate,
                                 plate_uncertainty=plate_uncertainty, cloth_phase_s=cloth_phase_s,
                                 fit_own_plate=fit_own_plate, _kept=keep, _near_ends=near_ends)
    messages: list[str] = []
    for msg in it.pending:
        warnings.warn(msg, ConditioningWarning, stacklevel=2 if _kept is None else 3)
        messages.append(msg)
    problems = it.problems + it.tau_problems
    problems.extend(at_ends)
    if contact.found:
        found, staircase = _contact_problems(it, fs, contact, candidates, adc_step, t0_s, scale, tau_s is not None,
                                             post_guard_s)
        problems.extend(found)
        undone, findings, stated = _undone_plate(it, fs, contact, problems, t0_s, undo_plate, plate, cloth_phase_s,
                                                 plate_uncertainty)
        fitted = _through_plate(it, fs, contact, problems, stated, undone, plate, t0_s, cloth_phase_s,
                                plate_uncertainty, fit_own_plate)
        if fitted and not isinstance(fitted, str):
            return _result(it.x, it.fit, it.tau, it.source, fitted[0], it.n_iter, messages, fitted[1], t0_s,
                           scale, spikes, it.mains, mains_source, it.contact_integral)
        if isinstance(undone, str):  # tried and refused: the ringing problems stay, and why the undoing did not help
            hz = getattr(undone, "resonance_hz", math.nan)  # the resonance refused (signal.undone.Refusal)
            refused = {"refused_hz": hz, "refused_zeta": undone.damping_ratio} if math.isfinite(hz) else {}
            if not getattr(undone, "undoable", True):  # a known plate above what the samples resolve
                refused["aliases"] = 1.0
            why = str(undone) + (f"; nor its contact's ends fitted through the plate in the sensed force: {fitted}"
                                 if fitted else "")
            problems.append(Problem(ProblemKind.PLATE_RINGING, why, data={"undo_refused": 1.0, **refused}))
        elif undone is not None:  # what the undone force's checks do not judge again stays with it
            return _undone_result(it, fs, undone, findings, messages, _beside_undone(problems, at_ends + staircase),
                                  t0_s, scale, spikes, mains_source)
        problems.extend(plateau_end_problems(it.x, fs, it.fit.noise, contact, t0_s))
    problems = _last_problems(it.x, fs, it.fit.noise, contact, problems, t0_s)
    return _result(it.x, it.fit, it.tau, it.source, contact, it.n_iter, messages, problems, t0_s, scale, spikes,
                   it.mains, mains_source, it.contact_integral)


def _scaled(raw, polarity):
    """The voltage with its polarity applied, in units of its largest magnitude (no overflow for any finite
    input) [scaled V], and that unit [V]."""
    scale = float(np.max(np.abs(raw)))
    if not (scale > 0 and math.isfinite(scale)):
        scale = 1.0
    return polarity * (raw / scale), scale


def _despiked(v_spiky, kept, near_ends):
    """The record's second differences with their noise (also for the spikes at the ends), the record with its
    single-sample spikes replaced [scaled V] (but the samples ``kept``; and the lower spikes ``near_ends`` too, see
    :func:`ballimpact.signal.spikes.spikes_at_ends`), and the samples replaced."""
    d2_spiky = second_differences(v_spiky)
    v, spikes = replace_spikes(v_spiky.copy(), *d2_spiky, keep=kept or ())
    if near_ends:
        near = np.asarray(near_ends, dtype=int)
        v[near] = 0.5 * (v_spiky[near - 1] + v_spiky[near + 1])
        spikes = np.union1d(spikes, near)
    return d2_spiky, v, spikes


def _mains_candidates(mains_hz, n_harmonics, fs):
    """The hum frequencies fitted for each mains frequency tried [Hz] (0: no hum), and how the mains is known
    (``"detected"``, ``"given"`` or ``"none"``)."""
    auto_mains = isinstance(mains_hz, str)
    if auto_mains:
        candidates = {0.0: []}
        candidates.update({f: mains_frequencies(f, n_harmonics, fs) for f in MAINS_CANDIDATES_HZ})
    else:
        candidates = {float(mains_hz or 0.0): mains_frequencies(mains_hz, n_harmonics, fs) if mains_hz else []}
    return candidates, "detected" if auto_mains else ("given" if mains_hz else "none")


def _rough_contact(v, fs):
    """The contact found on the record less a rough level, before any baseline is fitted."""
    trend = rough_trend(v)
    # the record before the peak holds no undershoot: its median is the level under the contact
    k_peak = int(np.argmax(v - trend))
    if k_peak >= MIN_QUIET_SAMPLES:
        trend = np.full(v.size, finite_median(v[:k_peak]))
    return detect_contact(v - trend, fs)


def _unchecked_result(v, fs, candidates, noise_floor, t0_s, scale, spikes, mains_source):
    """The record with no contact standing out of it before a baseline is fitted: offset and hum removed (the mains
    frequency of least BIC), and a contact found only then reported as unchecked."""
    fits = {f: fit_baseline(v, fs, fr, -math.inf, -math.inf, 0.0, 0.0, noise_floor=noise_floor)
            for f, fr in candidates.items()}
    mains = min(fits, key=lambda f: fits[f].bic)
    fit = fits[mains]
    y = v - fit.baseline
    contact = detect_contact(y, fs, t0_s=t0_s, noise_rms_V=fit.noise)
    # A contact that shows only once a baseline is fitted through it (its own samples included: a flat top
    # under a short pre-trigger left the record's level before its largest sample at the top) has no baseline
    # known under it, and none of the checks below ran.
    unchecked = [Problem(ProblemKind.CONTACT_UNSTABLE,
                         "contact window not stable: no contact stands out of the record until a baseline is "
                         "fitted through the whole of it, the contact's own samples included, so the baseline "
                         "under the contact is unknown and the contact was not checked")] if contact.found else []
    return _result(y, fit, math.nan, "none", contact, 0, [], unchecked, t0_s, scale, spikes, mains,
                   mains_source)


def _contact_problems(it, fs, contact, candidates, adc_step, t0_s, scale, tau_given, post_guard_s):
    """Problems of the corrected signal around a contact found, in order (integrity, hum of a short record, the
    staircases), and the staircases' (an ADC's steps at the ends, steps of the baseline) alone."""
    problems = _integrity(it.x, fs, it.fit, contact, t0_s, scale, it.ambiguous, it.start_u, it.end_u, post_guard_s)
    problems.extend(short_record_hum(it.x, fs, it.fit, tuple(f for f in candidates if f > 0),
                                     float(contact.peak_V), scale))
    staircase = adc_step_problems(it.x, fs, it.fit.noise, adc_step, contact, t0_s, scale)
    staircase += baseline_step_problems(it.x, fs, it.fit, contact, t0_s, scale, tau_given=tau_given)
    problems.extend(staircase)
    return problems, staircase


def _undone_plate(it, fs, contact, problems, t0_s, undo_plate, plate, cloth_phase_s=0.0, uncertainty=None):
    """The plate undone (see :func:`ballimpact.signal.undone.plate_undone`): (y, contact, plate, cutoff), why it
    was refused (str) or None (not tried); the findings of the undone force kept (its peak withheld, or the
    effects of two identifications apart); and why a stated plate was refused (str), or None. A known plate whose
    resonance is ``uncertainty`` (relative fn, zeta) off by more than the undoing charges (PLATE_FN_UNCERTAINTY)
    is not undone: only its contact's ends are fitted through it."""
    findings = []
    undone = stated = None
    if plate is not None and uncertainty is not None and uncertainty[0] > PLATE_FN_UNCERTAINTY:
        stated = Refusal(f"the plate at {plate[0] / 1e3:.4g} kHz (damping ratio {plate[1]:.2g}) is known to "
                         f"{100 * uncertainty[0]:.2g} % in fn only, more than the undoing charges "
                         f"({100 * PLATE_FN_UNCERTAINTY:g} %): not undone")
        plate = None
    if undo_plate and plate is not None:  # stated (plate.resonance_hz, plate.damping_ratio): used exactly ...
        undone, findings = stated_plate_undone(it.x, fs, it.fit, contact, t0_s, plate, cloth_phase_s=cloth_phase_s)
        stated = undone if isinstance(undone, str) else None
    if undo_plate and (plate is None or isinstance(undone, str)):  # ... or, refused, identified from the trace
        refused = undone
        undone, findings = plate_undone(it.x, fs, it.fit, contact, problems, t0_s, cloth_phase_s=cloth_phase_s)
        if undone is None and not getattr(refused, "undoable", True):  # a stated plate the samples cannot undo
            undone = refused  # stands as a finding, though the sensed force shows no ringing (it aliases)
    return undone, findings, stated


def _beside_undone(problems, kept):
    """The findings that stay with a force whose plate was undone: ``kept`` (those of the spikes at the ends and the
    staircases) and every other finding whose kind the undone force's checks do not judge again (not in
    :data:`ballimpact.signal.undone.PLATE_KINDS`): the amplifier's decay's, the baseline's, the mains'. A plate's
    identification is tried only beside plate and decay findings; a stated plate, or the session's, is undone
    beside any, and a finding of the baseline under the contact (hum not resolved, a step, a level off zero) stands
    for the undone force as for the sensed one. An unstable window does not: the sensed force's ends move from fit
    to fit with the plate's ringing (a 24 kHz plate at 125 kHz, its ends 76 samples apart after 8 fits, TC right on
    the undone force), and the undone force's contact is found again."""
    ids = {id(p) for p in kept}
    return list(kept) + [p for p in problems if id(p) not in ids and p.kind not in PLATE_KINDS
                         and p.kind is not ProblemKind.CONTACT_UNSTABLE]


def _through_plate(it, fs, contact, problems, stated, undone, plate, t0_s, cloth_phase_s, uncertainty, own):
    """The contact with its ends fitted through a known plate not undone (:func:`_sensed_result`), or why not (str,
    "" where not tried): a stated or the session's plate whose undoing was refused (``stated``); or, with ``own``,
    the plate the trace identified itself and could not undo (``undone``), measured again in its free ringing or,
    where that fails, charged at SENSED_OWN_FN_UNCERTAINTY and SENSED_OWN_ZETA_UNCERTAINTY."""
    if isinstance(stated, str) and (undone is None or isinstance(undone, str)) and problems:
        return _sensed_result(it, fs, contact, problems, stated, plate, t0_s, cloth_phase_s, uncertainty)
    if own and stated is None and isinstance(undone, str) and problems \
            and math.isfinite(getattr(undone, "resonance_hz", math.nan)):
        return _sensed_result(it, fs, contact, problems, undone, (undone.resonance_hz, undone.damping_ratio), t0_s,
                              cloth_phase_s, (SENSED_OWN_FN_UNCERTAINTY, SENSED_OWN_ZETA_UNCERTAINTY))
    return ""


def _sensed_result(it, fs, contact, problems, refusal, plate, t0_s, cloth_phase_s, uncertainty=None):
    """A known plate (stated, or the session's) whose undoing was refused: the contact with its ends fitted through
    the plate in the sensed force (:func:`ballimpact.signal.sensed_ends.sensed_contact`) and the problems with what
    that fit judges, or why not (str: "" where the fit was not tried). ``uncertainty``: the plate's relative
    uncertainties in fn and the damping ratio charged to TC (None: the fit's defaults). The problems a plate's
    ringing causes (:data:`ballimpact.signal.undone.PLATE_KINDS`) no longer bias TC, whose ends the fit reads
    through the plate's response: their effect on TC is the fit's (its bound, in a PLATE_RINGING finding that says
    why the plate was not undone); kCAL and the peak, read on the force the plate still rings in, stay withheld
    (effects not known)."""
    if not getattr(refusal, "undoable", True):
        return ""
    if _second_contact_under_ringing(it.x, fs, plate, t0_s):
        return "the force undone and low-passed at the resonance holds a second contact"
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    charged = {} if uncertainty is None else {"fn_uncertainty": uncertainty[0], "zeta_uncertainty": uncertainty[1]}
    fit = sensed_contact(it.x, fs, plate[0], plate[1], s_u, e_u, noise_rms=it.fit.noise,
                         cloth_phase_samples=cloth_phase_s * fs, **charged)
    if isinstance(fit, str):
        return fit
    tc_u = fit.end - fit.start
    nan = math.nan
    kept = [p if p.kind not in PLATE_KINDS else replace(p, effects={"contact_time": 0.0, "kcal": nan, "peak": nan},
                                                        data={**p.data, "ends_fitted": 1.0})
            for p in problems]
    kept.append(Problem(ProblemKind.PLATE_RINGING, f"{refusal}; its contact's ends fitted through the plate in the "
                        f"sensed force instead (TC moves by up to {100 * fit.bias / tc_u:.2g} % with the fit's window "
                        "and the plate's resonance and damping off by their uncertainty): kCAL and the peak, read on "
                        "the force the plate rings in, not known",
                        data={"ends_fitted": 1.0, "residual_sigma": fit.residual},
                        effects={"contact_time": fit.bias / tc_u, "kcal": nan, "peak": nan}))
    inside = it.x[int(math.ceil(fit.start)):int(math.floor(fit.end)) + 1]
    fitted = replace(contact, start_s=t0_s + fit.start / fs, end_s=t0_s + fit.end / fs,
                     start_index=int(math.ceil(fit.start)), end_index=int(math.floor(fit.end)),
                     start_se_s=fit.start_se / fs, end_se_s=fit.end_se / fs,
                     flags=tuple(f for f in contact.flags if f not in ("start_jump", "end_jump", "start_step"))
                     + ("ends_fitted_sensed",),
                     peak_index=int(math.ceil(fit.start)) + int(np.argmax(inside)), peak_V=float(np.max(inside)))
    return fitted, kept


def _second_contact_under_ringing(x, fs, plate, t0_s) -> bool:
    """Whether the force undone from a known plate and low-passed at its resonance holds more than one contact: the
    sensed peak stands on the plate's swing, and a second contact of 5 % of the force's peak may be less of it,
    unseen by the contact search on the sensed force."""
    return resonance_lowpassed_contact(x, fs, plate[0], plate[1], t0_s=t0_s).n_impacts > 1


def _undone_result(it, fs, undone, findings, messages, kept_problems, t0_s, scale, spikes, mains_source):
    """The ConditionedSignal of a force whose plate was undone: its peak's problems and the plateau check on its
    final contact added to ``kept_problems`` (those of the spikes at the ends and the staircases)."""
    y, contact, plate, cutoff = undone
    peak_problems = (undone_peak_spread(it.x, fs, contact, plate, cutoff, t0_s)
                     + lowpassed_spike(y, fs, contact, plate, cutoff, t0_s) + findings)
    messages.append(f"plate resonance at {plate.frequency_hz / 1e3:.3g} kHz (damping ratio "
                    f"{plate.damping_ratio:.2g}) identified from its ringing and undone"
                    + ("" if math.isinf(cutoff) else f", low-passed at {cutoff / 1e3:.3g} kHz"))
    # the undone force's own noise: the ringing's plateau check on its final contact
    plateau = plateau_end_problems(y, fs, robust_noise(np.diff(y)) / math.sqrt(2.0), contact, t0_s)
    return _result(y, it.fit, it.tau, it.source, contact, it.n_iter, messages,
                   kept_problems + plateau + peak_problems, t0_s, scale, spikes, it.mains, mains_source,
                   it.contact_integral, plate)


def _last_problems(x, fs, noise, contact, problems, t0_s):
    """The checks made last, on a trace nothing else excludes: a low-pass in the chain where only the ends are in
    doubt, then a peak the force leaves slowly where nothing is."""
    # last, on a trace nothing else excludes or whose ends alone are in doubt (its fits cost a few ms): a low-pass
    # is then the cause to name (the spread check alone may see its slow front)
    if contact.found and all(p.kind is ProblemKind.CONTACT_END_UNDETERMINED for p in problems):
        problems = problems + front_lowpass(x, fs, noise, float(contact.peak_V),
                                            (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs,
                                            contact.contact_time_s)
    if contact.found and not problems:  # after the low-pass, which a slow fall may be too and which names TC's error
        s_u = (contact.start_s - t0_s) * fs
        xc = x[max(int(math.ceil(s_u)), 0):int(math.floor((contact.end_s - t0_s) * fs)) + 1]
        problems = peak_on_slow_fall(xc, fs, noise, float(contact.peak_V), math.ceil(s_u) - s_u)
    return problems


def _checked_voltage(voltage_V, sample_rate_hz, polarity, mains_hz, n_harmonics, tau_s, pre_guard_s, post_guard_s):
    """The arguments of :func:`condition_voltage` checked (ValueError naming the bad one); the voltage as floats."""
    fs = float(sample_rate_hz)
    if not math.isfinite(fs) or fs <= 0:
        raise ValueError(f"sample_rate_hz must be positive and finite, got {sample_rate_hz!r}")
    if polarity not in (1, -1):
        raise ValueError(f"polarity must be 1 or -1, got {polarity!r}")
    auto_mains = isinstance(mains_hz, str)
    if auto_mains and mains_hz != "auto":
        raise ValueError(f"mains_hz must be a number of Hz, 'auto' or None, got {mains_hz!r}")
    if not auto_mains and mains_hz is not None and (not math.isfinite(mains_hz) or mains_hz < 0):
        raise ValueError(f"mains_hz must be non-negative and finite, got {mains_hz!r}")
    if n_harmonics < 0:
        raise ValueError(f"n_harmonics must be non-negative, got {n_harmonics}")
    if tau_s is not None and not (tau_s > 0):
        raise ValueError(f"tau_s must be positive (math.inf for no decay), got {tau_s!r}")
    if pre_guard_s < 0 or post_guard_s < 0:
        raise ValueError(f"guards must be non-negative, got pre_guard_s={pre_guard_s}, post_guard_s={post_guard_s}")
    raw = np.asarray(voltage_V, dtype=float).ravel()
    if raw.size < 3:
        raise ValueError(f"voltage_V needs at least 3 samples, got {raw.size}")
    if not np.all(np.isfinite(raw)):
        bad = np.flatnonzero(~np.isfinite(raw))
        raise ValueError(f"voltage_V holds {bad.size} non-finite samples (first at index {bad[0]})")
    return raw


def _integrity(x, fs, fit: BaselineFit, contact: ContactResult, t0_s, scale, ambiguous, start_u, end_u,
               post_guard_s=POST_GUARD_S):
    """Problems of the corrected signal, in a fixed order: levels, contact ends, ringing, mains."""
    peak = float(contact.peak_V)
    if not peak > 0:
        return []
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    return (edge_event_problems(x, fs, fit.noise, peak, s_u, scale)
            + end_event_problems(x, fs, fit.noise, peak, e_u, e_u - s_u, scale, post_guard_s)
            + baseline_bend_problems(fit, peak, s_u, e_u, scale)
            + level_problems(x, fs, fit, peak, scale, e_u, post_guard_s)
            + end_problems(x, fs, fit, contact, s_u, e_u, scale, curve=True)
            + ringing_problems(x, fs, fit.noise, peak, s_u, e_u, start_u, end_u, front=True)
            + mains_problems(x, fs, fit, peak, scale, ambiguous, start_u, end_u))


def _result(x, fit: BaselineFit, tau, source, contact, n_iter, messages, problems, t0_s, scale, spikes, mains,
            mains_source, contact_integral=math.nan, plate=None):
    """Assemble the ConditionedSignal, back in volts."""
    coef = dict(fit.coef)
    coef["offset_V"] = coef["offset_V"] * scale
    coef["drift_V_per_s"] = coef["drift_V_per_s"] * scale
    for key in ("hum_cos_V", "hum_sin_V"):
        coef[key] = tuple(c * scale for c in coef[key])
    coef["coef_cov"] = None if fit.cov is None else fit.cov * scale * scale  # offset, drift, hum [V^2, ...]
    coef["t_mid_s"] = fit.t_mid
    has_hum = bool(fit.hum_amplitudes)
    coef["mains_hz"] = float(mains) if has_hum else 0.0
    coef["mains_source"] = mains_source if has_hum or mains_source == "given" else "none"
    contact = replace(contact, peak_V=contact.peak_V * scale, noise_rms_V=contact.noise_rms_V * scale,
                      threshold_V=contact.threshold_V * scale)
    estimated = fit.has_post and math.isfinite(fit.kappa) and math.isfinite(contact_integral)
    undershoot = fit.kappa * contact_integral * scale if estimated else math.nan
    undershoot_se = fit.kappa_se * abs(contact_integral) * scale if estimated else math.nan
    with np.errstate(over="ignore"):
        return ConditionedSignal(
            voltage_V=x * scale,
            noise_rms_V=float(fit.noise * scale),
            hum_amplitude_V=float(fit.hum_amplitudes[0] * scale) if fit.hum_amplitudes else 0.0,
            hum_harmonic_amplitudes_V=tuple(a * scale for a in fit.hum_amplitudes),
            tau_s=float(tau),
            tau_source=source,
            undershoot_V=float(undershoot),
            undershoot_se_V=float(undershoot_se),
            offset_V=float(coef["offset_V"]),
            baseline_V=fit.baseline * scale,
            baseline_coefficients=coef,
            contact=contact,
            n_iterations=int(n_iter),
            warnings=tuple(messages),
            problems=tuple(dict.fromkeys(problems)),
            spike_indices=tuple(int(i) for i in spikes),
            plate=plate,
        )
