"""What the rig's stated band limit rules out: an alias of the plate, and an unseen rounding of the contact's jump."""

from __future__ import annotations

import math

from .problems import Problem, ProblemKind
from .session import PLATE_RESONANCE_MAX_HZ
from .signal.effects import rounding_effects

__all__ = ["PEAK_WITHHOLD_MAX_ROUNDING", "PLATE_IS_BANDWIDTH_TOLERANCE", "ALIAS_SLOW_FRACTION",
           "peak_can_be_withheld", "aliasing_ruled_out", "alias_free", "aliasing_problem", "front_rounding"]

#: A problem of the peak alone withholds the peak only where the stated band limit rounds the contact's jump over
#: at most this share of TC: half a period at ``daq.bandwidth_hz``, 1 / (2 bandwidth) [-]. A linear-phase
#: anti-aliasing filter rounds the jump unseen by the checks of the ends, and there a peak problem was the only sign
#: of a TC too long (``python bench/antialias_map.py --n 400 --seed 2`` trace 2:339: 9 kHz at 21.5 kHz, rounding
#: 1.7 % of TC, TC +1.5 %). Half the TC tolerance, as the ends' spread check (conditioning.SPREAD_MAX_FRACTION).
PEAK_WITHHOLD_MAX_ROUNDING = 0.005

#: The stated band limit is the plate's resonance, not a filter's cut-off, where the plate identified and undone
#: rings within this share of it [-]: the undoing restores the front the resonance rounded, and no rounding is left
#: for PEAK_WITHHOLD_MAX_ROUNDING to bound. On the keyed zoo traces of seeds 0-8 excluded for their peak alone the
#: plates undone were within 0.6 % of the key on most, 2-6 % on some; the ones further off (10-40 %: 0:180, 8:794)
#: are not taken for the key's plate.
PLATE_IS_BANDWIDTH_TOLERANCE = 0.1


def peak_can_be_withheld(bandwidth_hz: float | None, sample_rate_hz: float, contact_time_s: float,
                         plate_resonance_hz: float | None = None) -> bool:
    """Whether a problem of the peak alone withholds the peak instead of excluding the impact.

    Only where aliasing is ruled out (:func:`aliasing_ruled_out`) and nothing is left to round the contact's jump
    unseen: with ``daq.bandwidth_hz``, either it is the resonance of the plate identified and undone
    (within PLATE_IS_BANDWIDTH_TOLERANCE), or it rounds the jump over at most PEAK_WITHHOLD_MAX_ROUNDING of TC.
    Without the key (sampled at twice raw-format v1.1's highest plate resonance or faster) the ends' own checks are
    all that bound a low-pass's rounding, as on every impact with no problem of its peak (``python
    bench/lowpass_map.py`` and ``bench/antialias_map.py`` measure what they let through).

    Parameters
    ----------
    bandwidth_hz : float or None
        ``daq.bandwidth_hz`` [Hz]; None when not given.
    sample_rate_hz : float
        Sample rate of the trace [Hz].
    contact_time_s : float
        Contact time TC [s].
    plate_resonance_hz : float or None, optional
        Resonance of the plate identified and undone (ballimpact.plate) [Hz]; None or NaN when none was.

    Returns
    -------
    bool
    """
    if not aliasing_ruled_out(bandwidth_hz, sample_rate_hz) \
            or not (math.isfinite(contact_time_s) and contact_time_s > 0):
        return False
    if bandwidth_hz is None:
        return True
    if plate_resonance_hz is not None and math.isfinite(plate_resonance_hz) \
            and abs(plate_resonance_hz - bandwidth_hz) <= PLATE_IS_BANDWIDTH_TOLERANCE * bandwidth_hz:
        return True
    return 0.5 / bandwidth_hz <= PEAK_WITHHOLD_MAX_ROUNDING * contact_time_s


def aliasing_ruled_out(bandwidth_hz: float | None, sample_rate_hz: float) -> bool:
    """Whether no plate resonance can reach the samples through its alias.

    With ``daq.bandwidth_hz``, where it is at most half the sample rate (:func:`alias_free`); without it, where
    the trace is sampled at twice raw-format v1.1's highest plate resonance
    (session.PLATE_RESONANCE_MAX_HZ, 30 kHz) or faster.

    Parameters
    ----------
    bandwidth_hz : float or None
        ``daq.bandwidth_hz`` [Hz]; None when not given.
    sample_rate_hz : float
        Sample rate of the trace [Hz].

    Returns
    -------
    bool
    """
    if bandwidth_hz is None:
        return math.isfinite(sample_rate_hz) and sample_rate_hz >= 2.0 * PLATE_RESONANCE_MAX_HZ
    return alias_free(bandwidth_hz, sample_rate_hz)


def alias_free(bandwidth_hz: float | None, sample_rate_hz: float) -> bool:
    """Whether the rig rules out aliasing: the highest frequency reaching the ADC is at most half the sample rate.

    Parameters
    ----------
    bandwidth_hz : float or None
        ``daq.bandwidth_hz`` [Hz]: the anti-aliasing filter's cut-off, or without one the plate's highest
        resonance; None when not given (unknown: aliasing not ruled out).
    sample_rate_hz : float
        Sample rate of the trace [Hz].

    Returns
    -------
    bool
    """
    # (to a part in 1e9: a rate read back from a TDMS sample interval differs from the one written in its last bits)
    return bandwidth_hz is not None and bandwidth_hz <= 0.5 * sample_rate_hz * (1.0 + 1e-9)


#: An alias below this fraction of the sample rate is slow enough to pass for force at the contact's end [-]: its
#: period spans more than four samples, where a faster one swings sample to sample for the ringing checks to see.
ALIAS_SLOW_FRACTION = 0.25


def aliasing_problem(bandwidth_hz: float | None, sample_rate_hz: float) -> Problem | None:
    """The finding that withholds what an alias can bias, where the rig's stated bandwidth (``daq.bandwidth_hz``)
    is above half the sample rate, or where it is not stated and the sample rate does not rule aliasing out; else
    None.

    A plate resonance above fs / 2 reaches the samples as its alias: near fs (0.65-1.3 fs in the zoo) it folds
    near zero frequency, a slow swing no check can tell from the force, and it moves the impulse's sum of samples
    (so kCAL) and the ends and peak fitted through them. It is the zoo's last class of ok but wrong traces
    (``python bench/robustness.py --n 2000 --seed 0`` on 7a75a4b: 0:1236, kCAL -1.14 %); only the rig's bandwidth
    tells it. Where the stated bandwidth B lets a resonance alias below ALIAS_SLOW_FRACTION of the sample rate
    (B above fs - ALIAS_SLOW_FRACTION fs: the lowest alias of a resonance between fs / 2 and B is fs - B), the
    force's end rings through the alias as a smooth tail that the end can be read on (zoo 804:124, a 29.3 kHz
    plate at 29.2 kHz: TC 4.9 % long): TC is biased too, by an amount not known. A faster alias swings within a
    few samples, and TC stands on its own checks, which see the swings (zoo 0:74: 28.4 kHz at 54.4 kHz).

    Parameters
    ----------
    bandwidth_hz : float or None
        ``daq.bandwidth_hz`` [Hz]; None when not given.
    sample_rate_hz : float
        Sample rate of the trace [Hz].

    Returns
    -------
    ballimpact.problems.Problem or None
    """
    fs, bw = sample_rate_hz, bandwidth_hz
    if bw is None and math.isfinite(fs) and not aliasing_ruled_out(bw, fs):
        return Problem(ProblemKind.ALIASING, (
            f"kCAL and peak withheld: sampled at {fs / 1e3:.4g} kHz without daq.bandwidth_hz, a plate resonance "
            f"above {fs / 2e3:.4g} kHz would alias unseen (state daq.bandwidth_hz)"))
    if bw is None or not math.isfinite(fs) or alias_free(bw, fs):
        return None
    slow = fs - bw < ALIAS_SLOW_FRACTION * fs  # the slowest alias of a resonance up to bw [Hz] below that
    return Problem(ProblemKind.ALIASING, (
        f"signal bandwidth {bw / 1e3:.4g} kHz (daq.bandwidth_hz) above half the sample rate ({fs / 2e3:.4g} kHz): "
        f"the plate's ringing is sampled through its alias, which no check can tell from the force and which can "
        f"move TC, kCAL and the peak unseen (sample at {2 * bw / 1e3:.4g} kHz or faster, or low-pass below "
        f"{fs / 2e3:.4g} kHz before the ADC)"),
        data={"also_biases": ("contact_time",)} if slow else {})


def front_rounding(problem: Problem, cond, bandwidth_hz: float, fs: float, t0_s: float) -> Problem:
    """A problem of the peak that may also hide a TC and a kCAL off by the stated band limit's rounding of the
    contact's jump: those two added to the quantities it biases, with the rounding's effects on them
    (:func:`ballimpact.signal.effects.rounding_effects`) where aliasing is ruled out (an alias's are not known).

    Parameters
    ----------
    problem : ballimpact.problems.Problem
        A problem of the sensed force's peak (:data:`ballimpact.problems.PEAK_KINDS`).
    cond : ballimpact.signal.conditioning.ConditionedSignal
        The conditioned trace, its contact found.
    bandwidth_hz, fs : float
        ``daq.bandwidth_hz`` and the sample rate [Hz].
    t0_s : float
        Time of the trace's first sample [s].

    Returns
    -------
    ballimpact.problems.Problem
    """
    effects = dict(problem.effects)
    c = cond.contact
    if alias_free(bandwidth_hz, fs) and c.found:
        effects.update(rounding_effects(cond.voltage_V, fs, (c.start_s - t0_s) * fs, (c.end_s - t0_s) * fs,
                                        0.5 / bandwidth_hz))
    return Problem(problem.kind, problem.message, data={**problem.data, "also_biases": ("contact_time", "kcal")},
                   effects=effects)
