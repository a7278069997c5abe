"""Checks of the contact's ends on the corrected signal: how well each end is known."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..problems import Problem, ProblemKind
from .baseline import BaselineFit
from .contact import ContactResult, end_standard_uncertainties

__all__ = [
    "about_start",
    "adc_step_problems",
    "end_uncertainty",
    "curve_end_contact",
    "plateau_end_problems",
    "foot_sigma",
    "end_problems",
]

MIN_CONTACT_SAMPLES = 20  # fewest samples across the contact [samples]
PLATEAU_END_FRACTION = 0.1  # the force over this fraction of TC before the end (PLATEAU_END_MIN samples or more) [-]
PLATEAU_END_MIN = 8  # fewest samples of that stretch [samples]
PLATEAU_END_FALL = 0.25  # ... that falls by less than this fraction of its level ... [-]
PLATEAU_END_LEVEL = 0.01  # ... at a level above this fraction of the peak and 10 standard errors: a plateau [-]
END_CHECK_S = 0.2e-3  # the samples this long inside each end of the contact ... [s]
END_CHECK_SIGMA = 3.0  # ... must average above this many standard errors [-]
FOOT_CHECK_S = 0.5e-3  # the corrected signal this long before the contact start (less a sample) ... [s]
FOOT_CHECK_SIGMA = 5.0  # ... holds no foot standing this many standard errors out of the noise [-]
SPREAD_MAX_FRACTION = 0.005  # an end that moves by more of TC when fitted from higher samples is not known [-]
CURVE_MIN_RATE_HZ = 33.0e3  # ... unless the force's curve pins it, at this sample rate or above [Hz]
CURVE_LATE_FRACTION = 2.5e-3  # the force's curve meets zero later than the end by more of TC: a convex fade [-]
JUMP_MAX_FRACTION = 0.007  # a force jump locates its contact end to half a sample; at most this fraction of TC [-]
ADC_STEP_DITHER = 0.5  # noise below this many ADC steps does not dither them: the trace moves in whole steps [-]
ADC_STEP_CROSSING = 3  # ... and each contact end is read off the force's crossing of this many steps above zero ...
ADC_STEP_MAX_FRACTION = 0.01  # ... which may take at most this fraction of TC per step (half of it: the 1 % budget) [-]
END_SE_MAX_FRACTION = 0.01  # END_SE_COVERAGE times the ends' standard uncertainty of TC at most this fraction of it [-]
END_SE_COVERAGE = 2.0  # ... the coverage factor of a 95 % interval of a normal error [-]
PLATE_SLOPE_S = 0.1e-3  # the force's slope at an end is read over this long inside it [s]


def adc_step_problems(x, fs, noise, step, contact: ContactResult, t0_s, scale) -> list[Problem]:
    """Contact ends read off the staircase of an ADC whose step the noise does not dither: not known to 1 %.

    An ADC records whole steps (:func:`ballimpact.signal.noise.quantization_step`).
    Noise of less than ADC_STEP_DITHER of a step does not dither them: where
    the force fades slowly to zero at an end, the recorded trace stays on one
    step for several samples and then drops to the next, and the line through
    the end's samples is fitted to a staircase whose errors are neither random
    nor independent: the end found can be more than a sample late, several of
    its standard errors. Each end is known to
    about the time the force takes to cross a step there (read over the
    samples from the end to where it first stands ADC_STEP_CROSSING steps
    above zero): the force meets zero within half a step's crossing of the
    staircase's last edge. Where a crossing takes more than
    ADC_STEP_MAX_FRACTION of TC, that half is more than half of the 1 %
    budget, and the end is not determined to 1 % (half that fraction excluded
    right traces). A jump crosses many steps within a sample and passes. Not
    in the paper.

    Parameters
    ----------
    x : numpy.ndarray
        Corrected signal [scaled V].
    fs : float
        Sample rate [Hz].
    noise : float
        Its noise, floored at the step's error [scaled V].
    step : float
        The ADC's step [scaled V] (0: none found).
    contact : ContactResult
        The contact found.
    t0_s : float
        Time of the first sample [s].
    scale : float
        Volts per scaled unit [V].

    Returns
    -------
    list of Problem
        A CONTACT_END_UNDETERMINED problem per end so read; empty otherwise.
    """
    tc = float(contact.contact_time_s)
    if not (step > 0 and noise < ADC_STEP_DITHER * step and tc > 0):
        return []
    out = []
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    for name, u, inward in (("start", s_u, 1), ("end", e_u, -1)):
        k = int(math.ceil(u)) if inward > 0 else int(math.floor(u))
        limit = int(math.floor(e_u)) if inward > 0 else int(math.ceil(s_u))
        while 0 <= k < x.size and (k - limit) * inward < 0 and x[k] <= ADC_STEP_CROSSING * step:
            k += inward
        per_step = abs(k - u) / ADC_STEP_CROSSING / fs  # [s]
        if per_step > ADC_STEP_MAX_FRACTION * tc:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {name} not determined to 1 %: the record's noise is under half its ADC step "
                               f"({1e3 * step * scale:.3g} mV) and does not dither it, and the force takes "
                               f"{1e6 * per_step:.3g} us ({100 * per_step / tc:.2g} % of TC) to cross a step at its "
                               f"{name}: the {name} is read off a staircase (record with a finer ADC range or more "
                               "bits)",
                               data={"end": name, "span_s": per_step}))
    return out


def end_uncertainty(y, fs, noise, contact: ContactResult, s_u, e_u) -> float:
    """Standard uncertainty of TC from its two ends [samples]: noise over the force's slope at each end.

    An end where the force jumps is located to half a sample; elsewhere a line
    through the force's last samples meets zero within noise / slope samples
    (the slope read over PLATE_SLOPE_S inside the end).
    """
    m = max(int(round(PLATE_SLOPE_S * fs)), 2)
    out = []
    for where, i0, i1 in (("start", int(math.ceil(s_u)), int(math.ceil(s_u)) + m),
                          ("end", int(math.floor(e_u)), int(math.floor(e_u)) - m)):
        if f"{where}_jump" in contact.flags:
            out.append(0.5)
            continue
        if not (0 <= i0 < y.size and 0 <= i1 < y.size):
            return math.inf
        slope = abs(float(y[i1] - y[i0])) / m
        out.append(max(noise / slope, 0.5) if slope > 0 else math.inf)
    return math.hypot(*out)


def curve_end_contact(contact: ContactResult, fs, t0_s) -> ContactResult:
    """The contact with its end from the force's curve where the hinge's end is not determined but the curve's is.

    The hinge's end moves by more than SPREAD_MAX_FRACTION of TC when fitted
    again from the samples above twice the noise threshold where the force
    fades into the noise with a bend (a line through the last samples of a
    curved fade meets zero late or early, by an amount that depends on the
    noise). The force's curve before the end (``contact.curve_end_s``, see
    :func:`ballimpact.signal.curve_end.end_from_curve`) is then the end when twice its
    standard uncertainty is within the same SPREAD_MAX_FRACTION of TC; the
    contact is flagged ``end_curve`` and its end is not refitted again.

    Only where the refit moves the end later: the force then steepens into
    its end (concave, a punctured ball's), and the lower samples are nearer
    the truth. Where it moves earlier the force flattens into its end
    (convex), its last part is below the noise, and every fit through the
    samples above it, the curve's too, ends early, its spread passing
    (tests/test_contact.py).

    Only at CURVE_MIN_RATE_HZ or faster: below it, a plate of up to 30 kHz
    (raw-format v1.1) can alias below RING_LINE_MIN_HZ, where no check sees
    its ringing, and the spread check is then what stands between such a
    plate's sensed force and a wrong ok (its end known, its peak off).
    """
    if not contact.found or not contact.end_spread_s > SPREAD_MAX_FRACTION * contact.contact_time_s \
            or fs < CURVE_MIN_RATE_HZ:
        return contact
    end_s = contact.curve_end_s
    if not (2.0 * contact.curve_end_se_s <= SPREAD_MAX_FRACTION * (end_s - contact.start_s)):  # NaN: not known
        return contact
    u_end = (end_s - t0_s) * fs
    return replace(contact, end_s=end_s, end_index=int(math.floor(u_end)), edge_end_s=min(contact.edge_end_s, end_s),
                   flags=contact.flags + ("end_curve",))


def plateau_end_problems(x, fs, noise, contact: ContactResult, t0_s) -> list[Problem]:
    """A contact that ends on a plateau: the force flat over its last PLATEAU_END_FRACTION of TC, then gone (on the
    final force: a plate's undone, whose ringing would make any end's stretch rise and fall).

    A ball's force falls into its end (a fade to zero, or the model's drop at 2 mm of compression after a steep
    fall). A flat stretch at a level of PLATEAU_END_LEVEL of the peak or more that falls by less than
    PLATEAU_END_FALL of its level is not a ball's: it is what a step down in the baseline shortly after the contact
    leaves when the amplifier's decay is estimated, kappa taking the step for the undershoot and the decay
    correction lifting the record between the contact and the step into a shelf of force (TC tens of per cent
    long)."""
    peak = float(contact.peak_V)
    tc = contact.contact_time_s
    if not (peak > 0 and noise > 0 and tc > 0):
        return []
    b = int(math.floor((contact.end_s - t0_s) * fs))  # the last sample inside the contact
    n = max(int(round(PLATEAU_END_FRACTION * tc * fs)), PLATEAU_END_MIN)
    a = max(b - n, int(math.ceil((contact.start_s - t0_s) * fs)))
    if b - a < PLATEAU_END_MIN or b >= x.size:
        return []
    y = x[a:b]  # less the last sample (a jump's)
    u = np.arange(y.size) - 0.5 * (y.size - 1)
    slope = float(np.dot(u, y) / np.dot(u, u))
    level, fall = float(np.mean(y)), -slope * y.size
    if level > PLATEAU_END_LEVEL * peak and level > 10.0 * noise / math.sqrt(y.size) \
            and abs(fall) < PLATEAU_END_FALL * level:
        return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                        f"contact end not determined: the force is flat over the last {1e3 * y.size / fs:.2g} ms "
                        f"before it, at {100 * level / peak:.2g} % of the peak, falling by {100 * fall / level:+.2g} % "
                        "of that: not a ball's fade; a step down in the baseline just after the contact taken for the "
                        "amplifier's undershoot? (give plate.time_constant_s)")]
    return []


def foot_sigma(seg, noise) -> float:
    """How far a foot stands out of white noise ``noise`` [V] in ``seg`` [V], the samples before a contact start
    nearest first: the largest, over every length n from the start back, of the level (the samples' sum over
    sqrt(n)) and of a ramp up to the start (weights n - i, over their norm), in standard errors [-]; inf with no
    noise, 0 with no samples."""
    if not seg.size:
        return 0.0
    if not noise > 0:
        return math.inf
    n = np.arange(1, seg.size + 1)
    level, ramp = np.cumsum(seg), n * np.cumsum(seg) - np.cumsum(np.arange(seg.size) * seg)  # weights 1; n - i
    return float(max(np.max(level / np.sqrt(n)), np.max(ramp / np.sqrt(n * (n + 1) * (2 * n + 1) / 6.0)))) / noise


def _beyond_problems(x, fs, noise, s_u, e_u, curve):
    """A foot before the start and force after the end (with ``curve`` only): the corrected signal ``x`` over
    FOOT_CHECK_S beyond either end (less a sample) standing FOOT_CHECK_SIGMA standard errors out of its noise
    ``noise`` as a level or a ramp (see :func:`foot_sigma`); the ends ``s_u``, ``e_u`` in samples."""
    out = []
    # a foot before the start (a cloth that carries a little load before the core does) is part of the contact:
    # the corrected signal before the start (less the sample before it, which a start found a fraction of a
    # sample late leaves some force in) must hold none that stands out of the noise as a level or a ramp; and
    # force after the end (the fade's rest beyond an end found early, e.g. where interference swung it to zero)
    n_beyond = int(round(FOOT_CHECK_S * fs))
    k0, k1 = int(math.floor(s_u)) - 1, int(math.ceil(e_u)) + 1
    beyond = (("start", x[max(k0 - n_beyond, 0):max(k0, 0)][::-1], "before", "a foot of force before the rise",
               "start earlier"),
              ("end", x[k1:k1 + n_beyond], "after", "force after the end found", "end later"))
    for where, seg, side, seen, may in beyond:
        sigma = foot_sigma(seg, noise) if curve else 0.0
        if sigma > FOOT_CHECK_SIGMA:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {where} not determined: the corrected signal in the "
                               f"{1e3 * FOOT_CHECK_S:.2g} ms {side} it stands {sigma:.3g} standard errors out of the "
                               f"noise ({seen}, or a baseline wrong there): the force may {may}",
                               data={"beyond": where, "span_s": FOOT_CHECK_S}))
    return out


def about_start(problem) -> bool:
    """Whether a CONTACT_END_UNDETERMINED finding of these checks is about the contact's start (its foot): its
    ``end`` (or, for a signal beyond an end, ``beyond``) is ``"start"``."""
    return problem.kind is ProblemKind.CONTACT_END_UNDETERMINED and "start" in (problem.data.get("end"),
                                                                                  problem.data.get("beyond"))


def end_problems(x, fs, fit: BaselineFit, contact: ContactResult, s_u, e_u, scale, curve=False):
    """Contact ends that hold no force, are located to half a sample only or move when fitted again; with
    ``curve``, also an end that the force's curve before it (``contact.curve_end_s``) puts more than
    CURVE_LATE_FRACTION of TC later than the straight line through the last samples (``contact.line_end_s``;
    the end itself is the bent hinge's, earlier where the force's slope eases into its end): the force flattens
    into its end (a convex fade), its last part is below
    the noise, and the line through the samples above it meets zero early (its refit from higher samples ending
    earlier still, by less than SPREAD_MAX_FRACTION of TC); not after an end
    flagged as a jump (located to half a sample, there is no line through a fade there: the curve meets zero up to
    a sample after the last sample of a true jump, and after a concave fade's end taken for one). With ``curve``,
    also a foot before the start and force after the end: the corrected signal over FOOT_CHECK_S beyond either
    (less a sample) standing FOOT_CHECK_SIGMA standard errors out of the noise as a level or a ramp. After the
    end it is the fade's rest beyond an end found early, where interference swung the fade to zero (TC tens of per
    cent short), or a baseline a little off there (right traces excluded, the price of the check)."""
    out = []
    # each end must be where force begins / ends: the samples just inside it hold force
    k_end = max(int(round(END_CHECK_S * fs)), 3)
    for where, sel in (("start", np.arange(int(math.ceil(s_u)), int(math.ceil(s_u)) + k_end)),
                       ("end", np.arange(int(math.floor(e_u)) - k_end + 1, int(math.floor(e_u)) + 1))):
        sel = sel[(sel >= 0) & (sel < x.size)]
        if sel.size >= 3:
            level = float(np.mean(x[sel]))
            if level < END_CHECK_SIGMA * fit.noise / math.sqrt(sel.size):
                out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                                   f"contact {where} not determined: the {1e3 * sel.size / fs:.2g} ms inside it hold "
                                   f"no force ({level * scale * 1e3:.3g} mV, noise {fit.noise * scale * 1e3:.2g} mV)",
                                   data={"end": where}))
    n_contact = (contact.end_s - contact.start_s) * fs
    if n_contact < MIN_CONTACT_SAMPLES:
        out.append(Problem(ProblemKind.TOO_FEW_SAMPLES,
                           f"only {n_contact:.1f} samples in the contact (fewer than {MIN_CONTACT_SAMPLES}): "
                           "sample rate too low for the contact time"))
    jumps = [w for w in ("start", "end") if f"{w}_jump" in contact.flags]
    if jumps and len(jumps) * 0.5 / fs > JUMP_MAX_FRACTION * contact.contact_time_s:
        out.append(Problem(ProblemKind.CONTACT_JUMP_UNRESOLVED,
                           f"contact {' and '.join(jumps)} between two samples: the force jumps from zero there, so "
                           f"TC is known to +-{len(jumps) * 0.5e6 / fs:.3g} us only, more than "
                           f"{100 * JUMP_MAX_FRACTION:.2g} % of {contact.contact_time_s * 1e3:.3g} ms (sample faster)"))
    out.extend(_hinge_problems(contact))
    for where, moved in (("start", contact.start_spread_s), ("end", contact.end_spread_s)):
        if where == "end" and "end_curve" in contact.flags:
            continue  # the end from the force's curve, known to SPREAD_MAX_FRACTION of TC: see curve_end_contact
        if abs(moved) > SPREAD_MAX_FRACTION * contact.contact_time_s:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {where} not determined to 1 %: fitted again from the samples above twice the "
                               f"noise threshold it moves by {moved * 1e6:+.3g} us "
                               f"({100 * moved / contact.contact_time_s:+.2g} % of TC); the force fades into the noise "
                               "there",
                               data={"end": where, "span_s": abs(moved)}))
    out.extend(_beyond_problems(x, fs, fit.noise, s_u, e_u, curve))
    # against the straight line's end (the bent hinge's sits earlier on an end whose slope eases; the threshold
    # was set on the line's)
    late = contact.curve_end_s - (contact.line_end_s if math.isfinite(contact.line_end_s) else contact.end_s)
    if "end_jump" in contact.flags:  # a jump's end is the middle of its interval: no line through a fade to judge
        late = math.nan
    if curve and late > CURVE_LATE_FRACTION * contact.contact_time_s:  # NaN: no curve, no problem
        out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                           f"contact end not determined to 1 %: the force's curve before it meets zero "
                           f"{late * 1e6:.3g} us later than the line through its last samples "
                           f"({100 * late / contact.contact_time_s:.2g} % of TC); the force flattens into the noise "
                           "there", data={"end": "end", "span_s": late}))
    return out


def _hinge_problems(contact: ContactResult) -> list:
    """TC not known to 1 % from its ends' fits: END_SE_COVERAGE times the root sum of squares of the ends' standard
    uncertainties (``contact.start_se_s`` / ``end_se_s``, each the hinge's three-sigma interval over three, with a
    step's uniform at a ``start_step``; an end from the force's curve, ``end_curve``, its own; a jump's half sample is
    judged by CONTACT_JUMP_UNRESOLVED) above END_SE_MAX_FRACTION of TC. A force that fades into the noise with about a
    noise deviation per sample leaves its end known to a few samples: on ideal plates at 20-60 kHz with noise of
    0.1-0.5 % of the peak (bench/ideal_plate_map.py), the line through the last samples met zero up to 1.8 % of TC
    late, and was ok."""
    tc = contact.contact_time_s
    ses = dict(zip(("start", "end"), end_standard_uncertainties(contact)))
    if any(math.isnan(v) for v in ses.values()) or not tc > 0:
        return []  # no fit to judge (the other checks judge such an end)
    spread = END_SE_COVERAGE * math.hypot(ses["start"], ses["end"])
    if spread <= END_SE_MAX_FRACTION * tc:
        return []
    worst = max(ses, key=lambda k: ses[k])
    edge = "first" if worst == "start" else "last"
    curve = worst == "end" and "end_curve" in contact.flags
    what = "the force's curve before it" if curve else f"the line through its {edge} samples"
    if math.isinf(ses[worst]):
        seen = ("the force's curve before it does not pin where it meets zero" if curve else
                f"no line through its {edge} samples pins where it meets zero (any corner in the hinge's window fits)")
    else:
        seen = (f"{what} meets zero within +-{END_SE_COVERAGE * 1e6 * ses[worst]:.3g} us only "
                f"({END_SE_COVERAGE:g} times its standard uncertainty; TC known to +-{100 * spread / tc:.2g} % with "
                "the other end's)")
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact {worst} not determined to 1 %: the force fades into the noise there, and {seen}",
                    data={"end": worst, "span_s": END_SE_COVERAGE * ses[worst]})]
