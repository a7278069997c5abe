"""Per-quantity verdicts: each quantity's error budget against its tolerance, from the findings of every check.

An impact's findings (:class:`ballimpact.problems.Problem`, each judged by its check in
:data:`ballimpact.checks.CHECKS`) and the random uncertainties of its measurement give, for each quantity of
:data:`ballimpact.checks.QUANTITIES`, a standard uncertainty and a status: ``ok``, or ``withheld`` with the
findings that withheld it. A fault excludes the impact; otherwise the impact enters its ball type's fit when
contact time and COR are both ``ok``.

The budget of a quantity is the root sum of squares of its random standard uncertainty and, for every finding
that estimated its effect on it, that bound taken as a uniform distribution (bound / sqrt 3). The quantity is
withheld when twice its standard uncertainty (a 95 % interval) exceeds its tolerance, or when a finding that can
bias it did not estimate its effect.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .checks import QUANTITIES, TOLERANCES, check_of

__all__ = ["COVERAGE", "Verdict", "biased_quantities", "judge_quantities", "unestimated", "gate_uncertainties",
           "random_uncertainties"]

#: Coverage factor of the expanded uncertainty compared with the tolerance (a 95 % interval of a normal error) [-].
COVERAGE = 2.0


@dataclass
class Verdict:
    """What the findings and the budgets decide for one impact.

    Attributes
    ----------
    excluded : bool
        A fault was found, or TC or COR is withheld: the impact does not enter the fit.
    fault : bool
        A fault was found.
    status : dict
        Per quantity, ``ok`` or ``withheld``.
    u : dict
        Per quantity, its standard uncertainty [-]: relative for TC, kCAL and the peak, absolute for COR.
    why : dict
        Per quantity, the messages of the findings that withheld it ("" when ok).
    codes : list of str
        The codes of every finding that withheld or excluded something, in the registry's order, once each.
    """

    excluded: bool
    fault: bool
    status: dict = field(default_factory=dict)
    u: dict = field(default_factory=dict)
    why: dict = field(default_factory=dict)
    codes: list = field(default_factory=list)


def _tolerance(quantity: str, peak_is_spike: bool) -> float:
    return TOLERANCES["peak_spike" if quantity == "peak" and peak_is_spike else quantity]


def biased_quantities(finding) -> tuple:
    """The quantities of :data:`ballimpact.checks.QUANTITIES` a finding can bias: its check's, and those its data
    adds (``also_biases``).

    Parameters
    ----------
    finding : ballimpact.problems.Problem

    Returns
    -------
    tuple of str
    """
    return tuple(dict.fromkeys(tuple(check_of(finding.kind).biases) + tuple(finding.data.get("also_biases", ()))))


def unestimated(findings, quantity: str) -> list:
    """The codes of the findings (not faults) that can bias ``quantity`` and gave no finite estimate of their
    effect on it: each withholds it by itself, whatever the budget (:func:`judge_quantities`).

    Parameters
    ----------
    findings : iterable of ballimpact.problems.Problem
    quantity : str
        One of :data:`ballimpact.checks.QUANTITIES`.

    Returns
    -------
    list of str
        Check codes, in the findings' order, once each.
    """
    out = [check_of(p.kind).code for p in findings if not check_of(p.kind).fault
           and quantity in biased_quantities(p) and not math.isfinite(float(p.effects.get(quantity, math.nan)))]
    return list(dict.fromkeys(out))


def judge_quantities(findings, u_random: dict, *, peak_is_spike: bool = False) -> Verdict:
    """Per-quantity statuses and budgets of one impact.

    Parameters
    ----------
    findings : iterable of ballimpact.problems.Problem
        Every finding of the impact. A finding's ``effects`` (relative bounds [-] per quantity) enter the budget of
        each quantity its check can bias; a quantity it can bias but has no finite effect for is withheld.
    u_random : dict
        Random standard uncertainty of each quantity of :data:`ballimpact.checks.QUANTITIES` [-] (relative; COR
        absolute); NaN or absent: not known, withheld.
    peak_is_spike : bool
        The peak is the pre-buckling spike (its tolerance is ``TOLERANCES["peak_spike"]``).

    Returns
    -------
    Verdict
    """
    findings = list(findings)
    var = {q: float(u_random.get(q, math.nan)) ** 2 for q in QUANTITIES}
    why = {q: [] for q in QUANTITIES}
    used = []
    contributed = {q: [] for q in QUANTITIES}  # (effect, code, message) of the findings in each budget
    fault = False
    for p in findings:
        check = check_of(p.kind)
        if check.fault:  # excludes the impact, and nothing of it is known
            fault = True
            used.append(check.code)
            for q in check.biases:
                why[q].append(p.message)
            continue
        for q in biased_quantities(p):
            effect = float(p.effects.get(q, math.nan))
            if math.isfinite(effect):
                var[q] += (abs(effect) / math.sqrt(3.0)) ** 2
                contributed[q].append((abs(effect), check.code, p.message))
            else:
                why[q].append(p.message)
                used.append(check.code)
    status, u = {}, {}
    for q in QUANTITIES:
        u[q] = math.sqrt(var[q]) if math.isfinite(var[q]) else math.nan
        over = not (COVERAGE * u[q] <= _tolerance(q, peak_is_spike))
        if over and not why[q]:
            why[q].append(f"{q.replace('_', ' ')} uncertain: expanded uncertainty {COVERAGE * u[q]:.3g} above its "
                          f"tolerance {_tolerance(q, peak_is_spike):g}")
            if contributed[q]:  # the largest estimated effect in the budget, named by its check
                _, code, message = max(contributed[q])
                why[q].append(message)
                used.append(code)
        status[q] = "withheld" if why[q] else "ok"
    if status["kcal"] == "withheld" and status["peak"] == "ok":  # the peak in newtons is kCAL times volts
        status["peak"] = "withheld"
        why["peak"].append("kCAL withheld")
    codes = list(dict.fromkeys(used))
    excluded = fault or status["contact_time"] != "ok" or status["cor"] != "ok"
    return Verdict(excluded, fault, status, u, {q: "; ".join(dict.fromkeys(v)) for q, v in why.items()}, codes)


def gate_uncertainties(gate_interval_in_s: float, gate_interval_out_s: float, resolution_s: float) -> tuple:
    """Relative standard uncertainties of the inbound and rebound speeds from the gate timer's resolution [-].

    Each interval is the difference of two times each read to the timer's resolution r, uniform within +-r/2:
    its standard uncertainty is r / sqrt 6, and a speed spacing / interval has the same relative uncertainty.

    Parameters
    ----------
    gate_interval_in_s, gate_interval_out_s : float
        The inbound and rebound intervals between the two gates [s].
    resolution_s : float
        The timer's resolution [s].

    Returns
    -------
    (float, float)
        u(vin) / vin and u(vout) / vout [-]; NaN for an interval that is not positive.
    """
    u_dt = resolution_s / math.sqrt(6.0)
    return tuple(u_dt / dt if dt > 0 else math.nan for dt in (gate_interval_in_s, gate_interval_out_s))


def random_uncertainties(*, u_vin: float, u_vout: float, cor: float, contact_time_s: float, start_se_s: float,
                         end_se_s: float, noise_V: float, n_contact: int, integral_V_s: float, peak_V: float,
                         fs: float, kappa_se_per_s: float = 0.0, baseline_se_V_s: float = 0.0,
                         jump_V: float = 0.0, peak_half_range_V: float = 0.0) -> dict:
    """Random standard uncertainties of TC, kCAL, the peak and COR of one impact [-].

    TC: the root sum of squares of its ends' standard uncertainties (each from its fit, half a sample uniform
    where the force jumps). kCAL = m (vin + vout) / integral (section 2 of Goodwill & Haake 2004): the gates'
    timing in the impulse, white noise summed over the contact's samples in the integral, and the amplifier's
    decay constant's standard error, which moves the integral by kappa TC / 2, the baseline's under the
    contact (its fitted offset, drift and hum as the quiet samples pin them), and the trapezium rule across a jump
    of the force (its jump at first contact, section 3.2.4, and the pre-buckling spike): across a step of height J
    at a place within its sample interval that the samples do not tell, the rule errs by J (delta - 1/2) / fs for
    delta uniform in [0, 1), a standard deviation of J / (fs sqrt 12). The peak: kCAL's, one noise deviation
    against the peak voltage, and where a spike's top is cut by a drop between two samples, the range it can take
    there, uniform (its half over sqrt 3). COR = vout / vin: the two speeds' timing.

    Parameters
    ----------
    u_vin, u_vout : float
        Relative standard uncertainties of the speeds [-] (:func:`gate_uncertainties`).
    cor : float
        COR [-].
    contact_time_s : float
        TC [s].
    start_se_s, end_se_s : float
        Standard uncertainties of the contact's ends [s] (NaN: not known).
    noise_V : float
        Noise standard deviation of the conditioned trace [V].
    n_contact : int
        Samples in the contact [-].
    integral_V_s : float
        Integral of the voltage over the contact [V s].
    peak_V : float
        Largest voltage of the contact [V].
    fs : float
        Sample rate [Hz].
    kappa_se_per_s : float
        Standard error of the decay constant 1 / tau undone [1/s] (0 when given or none).
    baseline_se_V_s : float
        Standard error of the baseline's integral over the contact [V s]
        (:func:`ballimpact.signal.baseline.baseline_integral_se`; 0 or NaN when not known).
    jump_V : float
        Height of the force's largest jump between two samples [V] (0: none).
    peak_half_range_V : float
        Half the range the peak's top can take between two samples [V]
        (:func:`ballimpact.calibration.force_top`; 0: the largest sample).

    Returns
    -------
    dict
        ``contact_time``, ``kcal``, ``peak`` (relative) and ``cor`` (absolute) [-]; NaN where not known.
    """
    u_impulse = math.hypot(u_vin, u_vout * cor) / (1.0 + cor) if cor > 0 else math.nan
    u_integral = noise_V * math.sqrt(max(n_contact, 1)) / fs / integral_V_s if integral_V_s > 0 else math.nan
    u_decay = abs(kappa_se_per_s) * contact_time_s / 2.0 if math.isfinite(kappa_se_per_s) else 0.0
    u_baseline = baseline_se_V_s / integral_V_s if integral_V_s > 0 and math.isfinite(baseline_se_V_s) else 0.0
    u_jump = abs(jump_V) / fs / math.sqrt(12.0) / integral_V_s if integral_V_s > 0 and math.isfinite(jump_V) else 0.0
    u_kcal = math.sqrt(u_impulse**2 + u_integral**2 + u_decay**2 + u_baseline**2 + u_jump**2)
    u_tc = math.hypot(start_se_s, end_se_s) / contact_time_s if contact_time_s > 0 else math.nan
    return {
        "contact_time": u_tc,
        "kcal": u_kcal,
        "peak": math.sqrt(u_kcal**2 + (noise_V / peak_V)**2 + (peak_half_range_V / math.sqrt(3.0) / peak_V)**2)
        if peak_V > 0 else math.nan,
        "cor": cor * math.hypot(u_vin, u_vout),
    }
