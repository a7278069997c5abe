"""The plate's resonance undone in a trace, and the checks the undone force must pass to be used."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..model import BUCKLING_TIME_S
from ..problems import Problem, ProblemKind
from .baseline import BaselineFit
from .cloth import steep_edge
from .contact import ContactResult, detect_contact
from .end_checks import about_start, end_problems, end_uncertainty, foot_sigma
from .plate import (PlateResonance, identify_free_ringing, identify_plate_resonance, refine_plate_resonance,
                    stated_resonance)
from .ringing import NEGATIVE_SIGMA, PLATE_EVIDENCE, ringing_problems
from .undo import (lowpass_spread_samples, lowpass_zero_phase, plate_undoable, undo_plate_resonance,
                   undone_noise_gain)
from .undone_end import undone_end
from .undone_peak import PLATE_LOWPASS_PEAK, lowpass_hides_peak

__all__ = ["UNDONE_PEAK", "Refusal", "plate_undone", "stated_plate_undone", "undone_peak_spread", "lowpassed_spike"]


class Refusal(str):
    """Why a plate's resonance was not undone, in words, with the resonance refused [Hz] and its damping ratio [-]
    (NaN: none identified), and whether the samples could undo it at all (False: its sampled response has no
    inverse, :func:`ballimpact.signal.undo.plate_undoable`)."""

    resonance_hz: float = math.nan
    damping_ratio: float = math.nan
    undoable: bool = True


def _refused(message: str, resonance_hz: float, damping_ratio: float) -> Refusal:
    out = Refusal(message)
    out.resonance_hz, out.damping_ratio = float(resonance_hz), float(damping_ratio)
    return out

PLATE_ID_AFTER_S = 2.0e-3  # the plate's ringing is identified from the contact and this long after it [s]
PLATE_ID_LAGS = (5, 8)  # two identifications, instruments this many samples back [samples]
PLATE_FREE_AFTER_S = (0.02e-3, 0.1e-3)  # ... or, where they find nothing, fits of the free ringing from this long
#                                         after the contact end (at least a sample) to PLATE_ID_AFTER_S after it [s]
PLATE_REFINE_S = (0.2e-3, 1.0e-3)  # each refined on the undone force from this long before to after the contact [s]
PLATE_AGREE_TC = 3.0e-3  # the two undone forces agree on TC to this fraction ... [-]
PLATE_AGREE_PEAK = 0.01  # ... and on the peak to this fraction, or the plate is not known well enough [-]
PLATE_TC_FRACTION = 0.01  # twice the undone contact's end uncertainty at most this fraction of TC [-]
PLATE_START_LATE = 1.0  # the undone contact may start this much later than the sensed one at most [samples]
PLATE_FOOT_SIGMA = 3.5  # ... unless the sensed force before its fitted start stays within this many standard errors [-]
PLATE_NOISE_FRACTION = 5.0e-3  # the undone force's noise (amplified above the resonance) at most this of the peak [-]
PLATE_LOWPASS_NOISE = 5.0e-3  # a refused undone force is low-passed until its noise is at most this of the peak [-]
PLATE_LOWPASS_MIN_FN = 1.0  # ... at a cutoff no lower than this times the resonance [-]
PLATE_LOWPASS_STEPS = 10  # ... trying cutoffs from fs / 2 down in this many steps of sqrt(2) [-]
PLATE_LOWPASS_TRIES = 6  # ... at most this many of them, from the first quiet enough (until one hides the peak) [-]
PLATE_LOWPASS_END_INSIDE = (6, 12)  # a low-passed force's ends fitted with this many samples inside [samples]
PLATE_LOWPASS_MAX_SPREAD = 0.07  # a kernel spreading each end over more than this fraction of TC (2 W) is too long
#                                  for the ends' line and parabola: fitted through it, TC came out 0.4-1.1 % long [-]
PLATE_EXACT_END_REACH = 6  # an exact undone force's ends fitted this many samples either side of those found [samples]
PLATE_END_JUMP_SIGMA = 10.0  # a fitted end's jump above this many residuals locates it to half a sample [-]
PLATE_FN_UNCERTAINTY = 0.01  # the resonance is known to about this fraction: how far TC moves is charged ... [-]
PLATE_END_MARGIN = 64  # ... undone again over the contact and this many samples (and 4 W) around it [samples]
PLATE_ZETA_UNCERTAINTY = 0.25  # the identified damping ratio is off by more than this fraction on about one undone
#                                plate in eight (its error's median about 1 %, with long tails) [-]
PLATE_PEAK_SPREAD = 0.015  # the undone peak moving by more than this fraction with the damping ratio that far off, or
#                            fn PLATE_FN_UNCERTAINTY off, is not known: half the peak's 3 % tolerance [-]
LOWPASS_SPIKE_FRACTION = 0.9  # a low-passed undone force's maximum in the spike's phase above this of its peak: the
#                               peak may be the spike, lowered by the kernel (and the sampling) by up to 15 % [-]
#: The data of a problem of the undone force's peak (its undoing, its low-pass): no sign of a band limit rounding
#: the contact's jump unseen (ballimpact.processing judges those of the sensed force so).
UNDONE_PEAK = {"undone_peak": True}
#: Problems that plate ringing causes: checked again on the undone force.
PLATE_KINDS = frozenset({ProblemKind.PLATE_RINGING, ProblemKind.PEAK_ON_RINGING, ProblemKind.NEGATIVE_FORCE,
                         ProblemKind.PEAK_BETWEEN_SAMPLES, ProblemKind.CONTACT_END_UNDETERMINED,
                         ProblemKind.CONTACT_JUMP_UNRESOLVED,
                         ProblemKind.IMPULSE_UNRESOLVED})  # a plate's first overshoot is a single-sample top too
#: Problems of the amplifier's decay, which bias kCAL and the peak only and cannot fake a plate's ringing: beside
#: those of PLATE_KINDS they leave the plate's undoing to be tried, and they stay with the force undone.
DECAY_KINDS = frozenset({ProblemKind.UNDERSHOOT_NOT_MEASURABLE, ProblemKind.DECAY_NOT_CORRECTED})


def plate_undone(x, fs, fit: BaselineFit, contact: ContactResult, problems, t0_s, *, cloth_phase_s: float = 0.0):
    """The force with the plate's resonance undone, its contact, the resonance and the low-pass used [Hz]; None
    when it is not tried; why it was refused, in words (str), when it was; and, as :func:`stated_plate_undone`,
    the findings the force kept leaves (a list of Problems, with their effects where known).

    Tried only when every problem is one plate ringing causes (or one of the
    amplifier's decay, DECAY_KINDS, which stays with the force undone) and one shows the
    ringing itself, on one contact that ends PLATE_ID_AFTER_S before the
    record does (the inverse's backward pass starts from rest there). The
    resonance is identified twice, from the contact (less two samples after its
    start, the force's jump) and PLATE_ID_AFTER_S after it, with instruments
    PLATE_ID_LAGS samples back (where that finds nothing, from the free ringing alone: a fit of a damped
    sinusoid from PLATE_FREE_AFTER_S after the contact's end to PLATE_ID_AFTER_S after it,
    :func:`ballimpact.signal.plate.identify_free_ringing`); each undone force must
    pass the contact, end and ringing checks again, its noise (undoing the
    resonance amplifies the noise above it) must stay below
    PLATE_NOISE_FRACTION of the peak, twice its TC's uncertainty (noise over
    slope at each end) below PLATE_TC_FRACTION of TC, it must not pull on the
    plate (below -NEGATIVE_SIGMA noise deviations) in the contact, nor start
    more than PLATE_START_LATE samples after the sensed force (the plate
    delays the sensed force; an undone force that starts later has lost a
    low foot in its amplified noise), and the two must agree. When its ends,
    read off it, fail on their uncertainty or start late, they are fitted
    through the plate instead (:func:`ballimpact.signal.undone_end.undone_end` with no
    low-pass, candidates PLATE_EXACT_END_REACH samples either side of those
    found; their uncertainty as for the low-passed force below), and a fitted
    start (this one's or a low-passed force's) later than the sensed one is a
    lost foot only when the sensed
    samples before it (the plate is causal: zero before the force) stand out
    of their noise by PLATE_FOOT_SIGMA standard errors as a level or a ramp
    up to it (the sensed start is read early where the plate's first
    overshoot passes for a foot). A pull is what
    is left where the force departs from the first-order hold the inverse
    assumes (a jump between samples leaves an alternating tail decaying by the
    zeros of the sampled plate).

    When every undone force of an identification is refused, the resonance
    is refined (:func:`ballimpact.signal.plate.refine_plate_resonance`: the fn and
    zeta near it that leave the least ringing in the undone force; the
    instrumental-variable fit is off by a few per cent in fn on noisy traces,
    and the force undone with it still rings) and tried again, with the same
    checks.

    An undone force refused by these checks is tried again through a
    zero-phase low-pass on a compact kernel (``ballimpact.signal.undo.lowpass_zero_phase``,
    cutoffs from :func:`_plate_cutoffs`), which trades the noise amplified
    above the resonance against the force's sharp features: the same checks
    and the peak's loss to the kernel (from its curvature) at most
    PLATE_LOWPASS_PEAK. The kernel spreads each end by up to its half-width
    W, so the ends are fitted through the plate's undoing and the kernel
    (:func:`ballimpact.signal.undone_end.undone_end`: a jump, a line and a parabola at
    the start, a line and a parabola at the end), with windows of
    PLATE_LOWPASS_END_INSIDE samples inside; TC's uncertainty is twice the
    ends' in quadrature, plus how far TC moves with the window and with the
    plate PLATE_FN_UNCERTAINTY off in fn. Each end's is at least what the
    fit's profile allows and at least its standard uncertainty from the
    sensed noise as the inverse and the kernel colour it (``undone_end``'s
    ``noise_se``, raised by the fit's residual where that is more than the
    noise leaves): that noise is correlated over several samples and moves a
    whole stretch of an end together (an end fitted without it came out two
    samples early). The start, where the
    force jumps from zero (section 3.2.4: the damping term at first contact),
    is known to half a sample at best (to its noise, or the fit's residual,
    over its slope where the fit sees no jump of PLATE_END_JUMP_SIGMA
    residuals; without that floor an aliased plate's start came out 0.7
    samples early where the fit's noise said 0.14); the end,
    where the ball's force falls to zero continuously, is located by the fit
    of the line and the parabola to it over several samples, to no interval
    between two: no half-sample floor there (which refused ends known to a
    few tenths of a sample). The fitted TC must be 0 to 2 W (+-1 sample)
    shorter than the contact found on the low-passed force.
    The force's ends are then restored from their fits (the impulse the
    kernel spread outside them is back), so the low-passed force's own end
    checks (:func:`ballimpact.signal.end_checks.end_problems`) do not refuse
    it: the fits' spread is what TC is charged. A low-pass may hide a peak:
    the exact undone force's largest sample inside the contact more than
    PLATE_LOWPASS_PEAK and PLATE_PEAK_SIGMA of its noise above the low-passed
    peak, or that noise too high to show a loss of PLATE_LOWPASS_SPIKE.
    These checks are judged by their effect, for an identified plate as for a
    stated one (:func:`stated_plate_undone`): a low-passed force that may hide
    or flatten only its peak is kept, and a PEAK_ON_RINGING finding says why
    (the peak alone is withheld, not TC and kCAL, which the other checks
    judge); two identifications apart by more than PLATE_AGREE_TC on TC or
    PLATE_AGREE_PEAK on the peak leave a PLATE_RINGING finding whose effects
    are their differences on TC, kCAL (the integrals over the contact) and
    the peak, bounds in those budgets; fitted ends that the kernel's spread
    does not explain are charged to TC by the excess.
    """
    kinds = {p.kind for p in problems} - DECAY_KINDS
    if not kinds or not kinds <= PLATE_KINDS or not kinds & PLATE_EVIDENCE:
        return None, []
    if not _plate_can_be_undone(x, fs, contact, t0_s):
        return None, []
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    a = max(int(math.ceil(s_u)) + 2, 0)
    b = min(int(math.floor(e_u)) + int(round(PLATE_ID_AFTER_S * fs)), x.size)
    ra = max(int(s_u - PLATE_REFINE_S[0] * fs), 0)
    rb = min(int(e_u + PLATE_REFINE_S[1] * fs), x.size)
    found, findings = [], []
    for lag, after_s in zip(PLATE_ID_LAGS, PLATE_FREE_AFTER_S):
        plate = identify_plate_resonance(x[a:b], fs, lag=lag, noise_rms=fit.noise)
        if plate is None and fit.noise > 0:  # the force drowns a damped plate's recursion: its free ringing after
            free = int(math.floor(e_u)) + max(int(round(after_s * fs)), 1)
            plate = identify_free_ringing(x[free:b], fs, fit.noise)
        if plate is None:
            return ("plate resonance not undone: no decaying oscillation identified out of the noise in the "
                    "contact and the 2 ms after it"), []
        seen: list = []  # the findings of the force kept, of the first identification
        hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, plate, seen, cloth_phase_s=cloth_phase_s)
        if isinstance(hit, str):  # the undone force still rings or fails a check: refine the resonance, try again
            plate = refine_plate_resonance(x[ra:rb], fs, plate)
            seen = []
            hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, plate, seen, cloth_phase_s=cloth_phase_s)
        if isinstance(hit, str):
            return _refused(f"plate resonance at {plate.frequency_hz / 1e3:.3g} kHz (damping ratio "
                            f"{plate.damping_ratio:.2g}) not undone: {hit}", plate.frequency_hz,
                            plate.damping_ratio), []
        if not found:
            findings = seen
        found.append(hit)
    (y, c, plate, cutoff), (y2, c2, _, _) = found
    apart = _identifications_apart(y, c, y2, c2)
    if apart["contact_time"] > PLATE_AGREE_TC or apart["peak"] > PLATE_AGREE_PEAK:
        # their differences, bounds, go into the budgets of TC, kCAL and the peak
        findings.append(Problem(ProblemKind.PLATE_RINGING, "plate resonance undone, but two identifications of "
                                f"the plate's resonance at {plate.frequency_hz / 1e3:.3g} kHz disagree by "
                                f"{100 * apart['contact_time']:.2g} % on TC and {100 * apart['peak']:.2g} % on the "
                                "peak", data={"identifications_apart": 1.0}, effects=apart))
    return (y, c, plate, cutoff), findings


def _identifications_apart(y, c: ContactResult, y2, c2: ContactResult) -> dict:
    """How far two undone forces ``y``, ``y2`` [V] (their contacts ``c``, ``c2``) are apart on TC, kCAL (their
    integrals over the first's contact) and the peak, relative to the first's [-]."""
    a, b = max(c.start_index, 0), c.end_index + 1
    whole = float(np.sum(y[a:b]))
    return {"contact_time": abs(c.contact_time_s - c2.contact_time_s) / c.contact_time_s,
            "kcal": abs(whole - float(np.sum(y2[a:b]))) / whole if whole > 0 else math.nan,
            "peak": abs(c.peak_V - c2.peak_V) / c.peak_V}


def _plate_can_be_undone(x, fs, contact: ContactResult, t0_s) -> bool:
    """Whether a plate's resonance can be undone on this contact: one contact, inside the record, that ends
    PLATE_ID_AFTER_S before the record does (the inverse's backward pass starts from rest at the record's end: the
    ringing must be over). A cut or doubled contact is excluded whatever the plate."""
    if contact.n_impacts > 1 or {"contact_at_trace_start", "contact_at_trace_end"} & set(contact.flags):
        return False
    return (contact.end_s - t0_s) * fs + PLATE_ID_AFTER_S * fs <= x.size - 1


def stated_plate_undone(x, fs, fit: BaselineFit, contact: ContactResult, t0_s, plate: tuple, *,
                        cloth_phase_s: float = 0.0):
    """The force with a stated resonance (fn [Hz], zeta [-]) undone, as :func:`plate_undone` returns it (force,
    contact, resonance, cutoff [Hz]; why it was refused, str; None where the contact is cut or doubled, or the
    ringing is not over before the record ends), and the peak problems it leaves. The resonance is used exactly,
    neither identified nor refined; the undone force passes the same checks as an identified one
    (:func:`_undone_candidates`), except that a low-pass that may hide the peak withholds the peak alone (a
    PEAK_ON_RINGING problem) instead of refusing the force whose ends and impulse every other check passed."""
    if not _plate_can_be_undone(x, fs, contact, t0_s):
        return None, []
    if not plate_undoable(plate[0], plate[1], fs):
        out = _refused(f"stated plate resonance {plate[0] / 1e3:.3g} kHz (damping ratio {plate[1]:.2g}, "
                       f"plate.resonance_hz and plate.damping_ratio) not undone: sampled at {fs / 1e3:.3g} kHz, "
                       "its response has no inverse (too far above half the sample rate; its ringing aliases, and "
                       "what that does to the contact's ends is not known)", plate[0], plate[1])
        out.undoable = False
        return out, []
    s_u = (contact.start_s - t0_s) * fs
    resonance = stated_resonance(plate[0], plate[1], fs)
    peak_problems = []
    hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, resonance, peak_problems=peak_problems,
                             cloth_phase_s=cloth_phase_s)
    if isinstance(hit, str):
        return _refused(f"stated plate resonance {plate[0] / 1e3:.3g} kHz (damping ratio {plate[1]:.2g}, "
                        f"plate.resonance_hz and plate.damping_ratio) not undone: {hit}", plate[0], plate[1]), []
    return hit, peak_problems


def undone_peak_spread(x, fs, contact: ContactResult, plate: PlateResonance, cutoff: float, t0_s) -> list:
    """The undone peak's dependence on the identified plate: [a PEAK_ON_RINGING problem] when it moves by more than
    PLATE_PEAK_SPREAD with the damping ratio PLATE_ZETA_UNCERTAINTY off or fn PLATE_FN_UNCERTAINTY off, else [].

    The inverse of the plate, ``F = x + (2 zeta / wn) x' + x'' / wn^2`` in continuous time, builds a sharp peak
    (the pre-buckling spike, section 3.2.4 in Goodwill & Haake 2004) largely from the sensed force's slope and
    curvature, so the damping ratio the ringing gave weighs on it. That ratio is the least known of the plate's
    two numbers: a plate of 3.93 kHz and 0.267 identified at 3.85 kHz and 0.20 gave its spike's peak 9.2 % low,
    TC and kCAL right. The force is undone again from the sensed signal ``x`` [V] (low-passed at
    ``cutoff`` [Hz] as the force reported was) with each parameter off in turn, and the largest sample inside the
    contact compared with the one undone with the identified plate.
    """
    a = max(int(math.ceil((contact.start_s - t0_s) * fs)), 0)
    b = min(int(math.floor((contact.end_s - t0_s) * fs)) + 1, x.size)
    if b - a < 1:
        return []

    def peak(fn, zeta):
        u = undo_plate_resonance(x, fs, fn, zeta)
        if not math.isinf(cutoff):
            u = lowpass_zero_phase(u, fs, cutoff)
        return float(np.max(u[a:b]))

    fn, zeta = plate.frequency_hz, plate.damping_ratio
    ref = peak(fn, zeta)
    if not ref > 0:
        return []
    moved = {f"the damping ratio {100 * PLATE_ZETA_UNCERTAINTY:.2g} % off": max(
                 abs(peak(fn, zeta * (1 + d)) / ref - 1) for d in (-PLATE_ZETA_UNCERTAINTY, PLATE_ZETA_UNCERTAINTY)),
             f"fn {100 * PLATE_FN_UNCERTAINTY:.2g} % off": max(
                 abs(peak(fn * (1 + d), zeta) / ref - 1) for d in (-PLATE_FN_UNCERTAINTY, PLATE_FN_UNCERTAINTY))}
    what, spread = max(moved.items(), key=lambda kv: kv[1])
    if spread <= PLATE_PEAK_SPREAD:
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force not determined: undone from the plate's resonance at {fn / 1e3:.3g} kHz (damping "
                    f"ratio {zeta:.2g}), the peak moves by {100 * spread:.2g} % with {what}; the plate's undoing "
                    "builds it from the sensed force's slope and curvature", data=dict(UNDONE_PEAK))]


def lowpassed_spike(y, fs, contact: ContactResult, plate: PlateResonance, cutoff: float, t0_s) -> list:
    """[A PEAK_ON_RINGING problem] when the peak of a force undone from the plate and low-passed at ``cutoff``
    [Hz] may be the pre-buckling spike, else [] (``y`` the low-passed force [V]).

    The ball's force rises to a spike whose top is cut by a sudden drop at buckling (section 3.2.4 in Goodwill &
    Haake 2004; BUCKLING_TIME_S into the contact in the model), sharper than any kernel that quiets the noise the
    plate's inverse amplifies (the cutoffs run down to the resonance). The kernel lowers that top, and the exact
    undone force, noisy by construction there, cannot bound by how much (:func:`lowpass_hides_peak` reads it from
    fits that smooth a sharp top too): spike peaks reported from a low-passed undone force come out about 2 % low
    on average, and several per cent low at worst. So where the low-passed force's largest value within the
    spike's phase (BUCKLING_TIME_S and the kernel's half-width from the start) is a maximum above
    LOWPASS_SPIKE_FRACTION of its peak, the peak is not known: a spike lowered below a later maximum may still be
    the peak, the kernel and the sampling together taking up to about 15 % from its top. The same rule excludes
    forces whose spike, at 90-98 % of the later maximum, was not their peak (the price of the rule).
    """
    if math.isinf(cutoff):
        return []
    half, _ = lowpass_spread_samples(fs, cutoff)
    s_u = (contact.start_s - t0_s) * fs
    a = max(int(math.ceil(s_u)), 0)
    b = min(int(math.floor((contact.end_s - t0_s) * fs)) + 1, y.size)
    phase = min(int(math.floor(s_u + BUCKLING_TIME_S * fs + half)) + 1, b - 1)  # the spike's phase: y[a:phase]
    peak = float(np.max(y[a:b])) if b > a else math.nan
    if not (phase > a and peak > 0):
        return []
    k = a + int(np.argmax(y[a:phase]))
    top = float(y[k])
    if not (top >= LOWPASS_SPIKE_FRACTION * peak and top >= y[k + 1]):
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force not determined: undone from the plate's resonance at {plate.frequency_hz / 1e3:.3g} "
                    f"kHz and low-passed at {cutoff / 1e3:.3g} kHz, the force's maximum {1e3 * (k - s_u) / fs:.2g} ms "
                    f"into the contact ({100 * top / peak:.3g} % of the peak) may be the pre-buckling spike's top, "
                    "which the low-pass lowers by an amount the noisy exact undone force cannot bound (2 % on average "
                    "in the zoo, up to 15 % with the sampling's share)", data=dict(UNDONE_PEAK))]


def _undone_candidates(x, fs, fit: BaselineFit, contact: ContactResult, s_u, t0_s, plate: PlateResonance,
                       peak_problems: list, cloth_phase_s: float = 0.0):
    """The first undone force of one resonance, exact or low-passed, that passes :func:`_undone_contact`:
    (force, its contact, the resonance, the cutoff [Hz]); when none does, what the exact one and the last
    low-passed one failed, in words (str). The cutoffs (:func:`_plate_cutoffs`) are tried from the highest down.
    The findings of the force taken go into the list ``peak_problems``: a low-pass that flattens its peak
    (:func:`_fitted_ends`) or may hide it (:func:`lowpass_hides_peak`) is a PEAK_ON_RINGING problem."""
    exact = undo_plate_resonance(x, fs, plate.frequency_hz, plate.damping_ratio)
    why = []
    for cutoff in (math.inf, *_plate_cutoffs(fs, plate, fit.noise, float(contact.peak_V))):
        y = exact if math.isinf(cutoff) else lowpass_zero_phase(exact, fs, cutoff)
        notes: list = []
        c = _undone_contact(y, x, fs, fit, s_u, t0_s, cutoff, plate, notes, cloth_phase_s=cloth_phase_s)
        if isinstance(c, str):
            why.append(c if math.isinf(cutoff) else f"low-passed to {cutoff / 1e3:.3g} kHz, {c}")
            continue
        hides = None if math.isinf(cutoff) else lowpass_hides_peak(exact, fs, fit.noise, plate, c[0], t0_s)
        if hides:
            notes.append(Problem(ProblemKind.PEAK_ON_RINGING, f"peak force not known: low-passed to "
                                 f"{cutoff / 1e3:.3g} kHz after the plate was undone, {hides}",
                                 data=dict(UNDONE_PEAK)))
        peak_problems.extend(notes)
        return c[1], c[0], plate, cutoff
    return "; ".join(why[:1] + why[-1:] if len(why) > 1 else why)


def _plate_cutoffs(fs, plate: PlateResonance, noise, peak) -> list:
    """Low-passes to try on an undone force that was refused: their half-amplitude frequencies [Hz], highest first.

    From fs / 2 down in PLATE_LOWPASS_STEPS steps of sqrt(2), not below
    PLATE_LOWPASS_MIN_FN times the resonance (the force would lose what it
    holds there): the first that brings the undone force's noise (the sensed
    noise through the inverse and the low-pass) to PLATE_LOWPASS_NOISE of
    the peak, and the next PLATE_LOWPASS_TRIES - 1 below it (less noise,
    more smoothing: which one passes every check depends on the force).
    """
    if not (peak > 0 and noise >= 0):
        return []
    out = []
    cutoff = 0.5 * fs
    for _ in range(PLATE_LOWPASS_STEPS):
        cutoff /= math.sqrt(2.0)
        if cutoff < PLATE_LOWPASS_MIN_FN * plate.frequency_hz or len(out) >= PLATE_LOWPASS_TRIES:
            break
        if out or noise * undone_noise_gain(fs, plate.frequency_hz, plate.damping_ratio, cutoff) \
                <= PLATE_LOWPASS_NOISE * peak:
            out.append(cutoff)
    return out


def _smoothed_peak_loss(y, fs, sigma):
    """Fraction of its peak that a symmetric low-pass of deviation ``sigma`` samples took from a force [-].

    A unit-sum symmetric kernel of standard deviation sigma lowers a smooth
    peak by about ``sigma^2 |F''| / 2`` (F'' its second derivative there, per
    sample^2; Taylor to second order); read on the smoothed force over
    +-sigma samples (at least one), which underestimates it a little for a
    peak as sharp as the kernel.
    """
    k = int(np.argmax(y))
    h = max(int(round(sigma)), 1)
    if k - h < 0 or k + h >= y.size or not y[k] > 0:
        return math.inf
    curvature = (float(y[k + h]) - 2.0 * float(y[k]) + float(y[k - h])) / (h * h)
    return 0.5 * sigma * sigma * abs(curvature) / float(y[k])


def _undone_contact(y, x, fs, fit: BaselineFit, s_u, t0_s, cutoff, plate, notes: list, fit_ends=False,
                    cloth_phase_s=0.0):
    """The contact of an undone force ``y`` and the force (a low-passed one, or with ``fit_ends`` the exact one,
    with its ends restored from their fits) when it passes every check of :func:`plate_undone`; else what it
    failed, in words (str). The exact force whose ends read off it fail on their uncertainty or start late is
    tried again with its ends fitted through the plate. A low-pass that lowers the peak puts a PEAK_ON_RINGING
    problem into the list ``notes`` (:func:`_fitted_ends`)."""
    found = _undone_found(y, x, fs, fit, t0_s, cutoff)
    if isinstance(found, str):
        return found
    c, noise = found
    cs_u, ce_u = (c.start_s - t0_s) * fs, (c.end_s - t0_s) * fs
    bias = 0.0
    fitted = not math.isinf(cutoff) or (fit_ends and plate is not None)
    what = "low-passed force" if not math.isinf(cutoff) else "undone force"
    if fitted:  # for the exact force no kernel (W = 0): its ends fitted through the plate alone
        ends = _fitted_ends(y, x, fs, fit, c, cs_u, ce_u, noise, cutoff, plate, what, t0_s, notes)
        if isinstance(ends, str):
            return ends
        y, c, cs_u, ce_u, uncertainty, bias = ends
    else:
        uncertainty = 2.0 * end_uncertainty(y, fs, noise, c, cs_u, ce_u)
    late, tail = cs_u > s_u + PLATE_START_LATE, ""
    if not fitted and plate is not None and (late or uncertainty > PLATE_TC_FRACTION * (ce_u - cs_u)):
        # read off the exact force, its ends are its amplified noise over its slope and may lose a foot in it:
        # fitted through the plate instead (its step, ramp and parabola responses, undone)
        again = _undone_contact(y, x, fs, fit, s_u, t0_s, cutoff, plate, notes, fit_ends=True,
                                cloth_phase_s=cloth_phase_s)
        if not isinstance(again, str):
            return again
        tail = f"; its ends fitted through the plate: {again.removeprefix('the ')}"
    if uncertainty > PLATE_TC_FRACTION * (ce_u - cs_u):
        return (f"the undone TC is known to {100 * uncertainty / (ce_u - cs_u):.2g} % only ("
                + ("noise over slope at its ends" if not fitted else
                   f"{100 * bias / (ce_u - cs_u):.2g} % of it how far the ends move with the fit's window and with the "
                   f"plate {100 * PLATE_FN_UNCERTAINTY:g} % off in fn") + ")" + tail)
    inside = y[max(int(math.ceil(cs_u)), 0):max(int(math.floor(ce_u)) + 1, 0)]
    if inside.size and float(np.min(inside)) < -NEGATIVE_SIGMA * noise:
        # the force is not what this plate's inverse assumes
        return "the undone force pulls on the plate during the contact"
    if late and _lost_foot(x, fit.noise, s_u, cs_u, fitted) and not _cloth_foot(y, c, noise, s_u, cs_u, ce_u,
                                                                                 cloth_phase_s * fs):
        return "the undone force starts later than the sensed one (a foot lost in its noise)" + tail
    return c, y


def _undone_found(y, x, fs, fit: BaselineFit, t0_s, cutoff):
    """The single contact of an undone force ``y`` and its noise [V] when it is quiet enough and its ends and ringing
    pass their checks (:func:`ballimpact.signal.end_checks.end_problems`,
    :func:`ballimpact.signal.ringing.ringing_problems`); else what it failed, in words (str). The ends of a
    low-passed force (finite ``cutoff`` [Hz]) are fitted through the kernel next, and the fits' spread is charged
    to TC: the end checks' findings do not refuse it."""
    c = detect_contact(y, fs, t0_s=t0_s, spread=True)
    if not c.found or not c.peak_V > 0 or c.n_impacts > 1:
        return "the undone force holds no single contact"
    if (c.end_s - t0_s) * fs + PLATE_ID_AFTER_S * fs > x.size - 1:
        return "the undone contact ends too close to the record's end"
    noise = float(c.noise_rms_V)
    if noise > PLATE_NOISE_FRACTION * float(c.peak_V):  # the largest sample of so noisy a force is a biased peak
        return f"the undone force is too noisy (noise {100 * noise / float(c.peak_V):.2g} % of the peak)"
    checked = replace(fit, noise=noise)
    cs_u, ce_u = (c.start_s - t0_s) * fs, (c.end_s - t0_s) * fs
    seen = (end_problems(y, fs, checked, c, cs_u, ce_u, 1.0)
            + ringing_problems(y, fs, noise, float(c.peak_V), cs_u, ce_u, cs_u, ce_u, fall=math.isinf(cutoff)))
    if not math.isinf(cutoff):  # a low-passed force's ends are fitted through the kernel, their spread charged
        seen = [p for p in seen if p.kind is not ProblemKind.CONTACT_END_UNDETERMINED]
    if seen and _jumps(y, c, noise, cs_u, ce_u):  # its start is the jump's, less the cloth's phase, not the
        seen = [p for p in seen if not about_start(p)]  # foot's (a foot the sensed force shows: _lost_foot)
    if seen:
        return "the undone force still shows " + seen[0].message.split(":")[0]
    return c, noise


def _cloth_foot(y, c: ContactResult, noise, s_u, cs_u, ce_u, phase_u) -> bool:
    """Whether the sensed force's foot, from ``s_u`` [samples], is no longer than the cloth's phase (``phase_u``
    [samples], 0: not known) before the undone force's jump: the contact's start completed from that jump
    (:func:`ballimpact.signal.cloth.first_contact`) counts it, lost in the undone noise or not."""
    edge = steep_edge(y, cs_u, c.peak_index, noise, ce_u - cs_u) if phase_u > 0 else None
    return edge is not None and s_u >= edge.at_u - phase_u - 1.0


def _jumps(y, c: ContactResult, noise, cs_u, ce_u) -> bool:
    """Whether the undone force starts with the ball's jump (:func:`ballimpact.signal.cloth.steep_edge`): its
    contact's start is then completed from the jump by the cloth's phase, whatever its foot shows."""
    return steep_edge(y, cs_u, c.peak_index, noise, ce_u - cs_u) is not None


def _fitted_ends(y, x, fs, fit: BaselineFit, c, cs_u, ce_u, noise, cutoff, plate, what, t0_s, notes: list):
    """The ends of the ``what`` ``y`` (contact ``c`` from ``cs_u`` to ``ce_u`` [samples]) fitted through the plate's
    undoing and the low-pass's kernel (:func:`ballimpact.signal.undone_end.undone_end`): (the force with its ends'
    jump and spread impulse restored, its contact, its ends [samples], the expanded uncertainty of TC [samples],
    and how far the ends move with the fit's window and the plate's fn [samples]); else why not (str).

    A kernel that spreads each end over more than PLATE_LOWPASS_MAX_SPREAD of TC (twice its half-width W) is
    refused: over so long a stretch the force near its ends is no line and parabola, and the fitted TC comes out
    long by more than the fits' spread says (0.4-1.1 % at 7.5-11 % of TC, plates of 1.1-1.6 kHz). A low-pass that
    flattens the peak by more than PLATE_LOWPASS_PEAK (from its curvature) withholds the peak
    alone, a PEAK_ON_RINGING problem into the list ``notes``. The fitted TC
    0 to twice the kernel's half-width W (+-1 sample) shorter than the contact found on the low-passed force is
    what the kernel's spread explains; the fits and the contact found disagree by what lies beyond, and that is
    charged to TC with the fits' spread."""
    half_width, sigma = lowpass_spread_samples(fs, cutoff)
    if 2.0 * half_width > PLATE_LOWPASS_MAX_SPREAD * (ce_u - cs_u):
        return (f"the low-pass spreads each end over {100 * 2 * half_width / (ce_u - cs_u):.2g} % of TC, too long for "
                "the ends' fits")
    loss = _smoothed_peak_loss(y, fs, sigma)
    if loss > PLATE_LOWPASS_PEAK:  # the low-pass flattens a peak sharper than its kernel
        notes.append(Problem(ProblemKind.PEAK_ON_RINGING, f"peak force not known: low-passed to {cutoff / 1e3:.3g} "
                             f"kHz after the plate was undone, the low-pass lowers the peak by about "
                             f"{100 * loss:.2g} % (from its curvature)", data=dict(UNDONE_PEAK)))
    # the low-pass spreads the force by its kernel's half-width at each end: the ends are fitted through
    # the plate's undoing and the kernel (a line, or a jump from zero), twice, and the fits' difference
    # is charged to TC
    fn, zeta = plate.frequency_hz, plate.damping_ratio
    reach = 2 if not math.isinf(cutoff) else PLATE_EXACT_END_REACH
    ends = [(undone_end(y, fs, fn, zeta, cutoff, cs_u, "start", inside_samples=m, reach_samples=reach,
                        noise_rms=fit.noise),
             undone_end(y, fs, fn, zeta, cutoff, ce_u, "end", inside_samples=m, reach_samples=reach,
                        noise_rms=fit.noise))
            for m in PLATE_LOWPASS_END_INSIDE]
    if any(e is None for pair in ends for e in pair):
        return (f"the {what}'s ends fit no line or jump from zero through the plate and the kernel "
                f"(its {100 * 2 * half_width / (ce_u - cs_u):.2g} % spread of TC stays unknown)")
    (f_start, f_end) = ends[0]
    fs_u, fe_u = f_start.index, f_end.index
    bias = max(abs((e[1].index - e[0].index) - (fe_u - fs_u)) for e in ends[1:]) if len(ends) > 1 else 0.0
    bias = _fn_bias(x, fs, plate, cutoff, cs_u, ce_u, half_width, reach, fe_u - fs_u, bias, what)
    if isinstance(bias, str):
        return bias
    shorter = (ce_u - cs_u) - (fe_u - fs_u)  # the kernel lengthens the contact found by 0 to 2 W samples
    bias += max(-1.0 - shorter, shorter - (2.0 * half_width + 2.0), 0.0)  # the fits and the contact found disagree by this beyond the kernel's spread
    # the ends' jump and the impulse the kernel spread outside them restored from their fits
    y = y.copy()
    for f in (f_start, f_end):
        y[f.first:f.first + f.correction.size] += f.correction
    cs_u, ce_u = fs_u, fe_u
    inside = y[int(math.ceil(cs_u)):int(math.floor(ce_u)) + 1]
    se_start, se_end = _fitted_spread(f_start, f_end, noise)
    # the ends' standard uncertainties for TC's budget: the fits', the end's with how far TC moves with the window
    # and the plate's fn (a bound, as a uniform)
    c = replace(c, start_s=t0_s + fs_u / fs, end_s=t0_s + fe_u / fs, start_index=int(math.ceil(fs_u)),
                end_index=int(math.floor(fe_u)), peak_index=int(math.ceil(cs_u)) + int(np.argmax(inside)),
                peak_V=float(np.max(inside)), start_se_s=se_start / fs,
                end_se_s=math.hypot(se_end, bias / math.sqrt(3.0)) / fs)
    uncertainty = 2.0 * math.hypot(se_start, se_end) + bias
    return y, c, cs_u, ce_u, uncertainty, bias


def _fn_bias(x, fs, plate, cutoff, cs_u, ce_u, half_width, reach, tc_u, bias, what):
    """``bias`` [samples] raised to how far TC (``tc_u`` [samples] from the ends' fits) moves with the plate's fn
    PLATE_FN_UNCERTAINTY off either way; else why the ends fit nothing then (str)."""
    fn, zeta = plate.frequency_hz, plate.damping_ratio
    # the plate is known to about PLATE_FN_UNCERTAINTY in fn: what it leaves ringing moves the ends
    # (undone over the contact and a margin only: the undoing's passes forget their start within a few samples)
    a = max(int(cs_u) - PLATE_END_MARGIN - 4 * int(half_width), 0)
    b = min(int(ce_u) + PLATE_END_MARGIN + 4 * int(half_width), x.size)
    for scale in (1.0 - PLATE_FN_UNCERTAINTY, 1.0 + PLATE_FN_UNCERTAINTY):
        y2 = lowpass_zero_phase(undo_plate_resonance(x[a:b], fs, fn * scale, zeta), fs, cutoff)
        pair = (undone_end(y2, fs, fn * scale, zeta, cutoff, cs_u - a, "start",
                           inside_samples=PLATE_LOWPASS_END_INSIDE[0], reach_samples=reach),
                undone_end(y2, fs, fn * scale, zeta, cutoff, ce_u - a, "end",
                           inside_samples=PLATE_LOWPASS_END_INSIDE[0], reach_samples=reach))
        if pair[0] is None or pair[1] is None:
            return (f"the {what}'s ends fit no line or jump from zero through the kernel with the plate "
                    f"{100 * PLATE_FN_UNCERTAINTY:g} % off in fn")
        bias = max(bias, abs((pair[1].index - pair[0].index) - tc_u))
    return bias


def _fitted_spread(f_start, f_end, noise):
    """The standard uncertainties of the start and the end fitted through the plate [samples]."""
    # each end at least as far as the fit's residual lets it move (its profile) and at least its standard
    # uncertainty from the sensed noise as the chain colours it (correlated over several samples); the start
    # (the force jumps from zero there) to half a sample at best, to its noise over its slope (the noise there
    # the fit's residual when that is larger: what the undoing left, or a force no line fits) where the fit
    # sees no jump well out of the noise; the end (a line and a parabola falling to zero, no jump) as the
    # fit locates it
    return [max(0.5 if f_start.jump > PLATE_END_JUMP_SIGMA * max(noise, f_start.residual) else
                (max(max(noise, f_start.residual) / f_start.slope, 0.5) if f_start.slope > 0 else math.inf),
                f_start.uncertainty, f_start.noise_se),
            max(f_end.uncertainty, f_end.noise_se) if f_end.slope > 0 else math.inf]


def _lost_foot(x, noise, s_u, cs_u, fitted) -> bool:
    """An undone contact starting at ``cs_u``, later than the sensed one at ``s_u`` [samples], lost a foot: the
    sensed force ``x`` between them stands more than PLATE_FOOT_SIGMA standard errors (of its noise ``noise``) out
    (always, for ends not ``fitted`` through the plate)."""
    # the plate is causal: the sensed force is zero before the force starts, so a foot the undone force lost
    # stands out of the sensed noise before the undone start (from the sensed start on, back from the
    # sample before it: a level or a ramp up to it, over every length, in standard errors); a sensed start
    # early for no force there (its foot or edge fallback read into the plate's first overshoot) is no
    # lost foot when the ends are fitted through the plate
    seg = x[max(int(math.floor(s_u)) - 1, 0):max(int(math.floor(cs_u)), 0)][::-1]
    foot = foot_sigma(seg, noise) if seg.size else math.inf
    return not fitted or not foot <= PLATE_FOOT_SIGMA
