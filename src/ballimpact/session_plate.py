"""The session's identified plate and mains, used in the impacts whose own trace could not tell them."""

from __future__ import annotations

import math

from .checks import CHECKS
from .problems import ProblemKind
from .rig import Rig
from .signal.ringing import PLATE_EVIDENCE
from .signal.sensed_ends import SENSED_FN_UNCERTAINTY
from .signal.undone import PLATE_KINDS

__all__ = ["SESSION_PLATE_MAX_SPREAD", "SESSION_ZETA_MAX_SPREAD", "SESSION_ZETA_CHARGE", "SESSION_MAINS_MIN_IMPACTS",
           "RETRY_KINDS", "session_plate", "session_plate_uncertainty", "session_mains", "retry_candidates"]

#: The session's plate is used in the impacts when its resonance's 95 % interval is this narrow or narrower, as a
#: fraction of the resonance on either side [-]: each impact measures it again in its own free ringing
#: (ballimpact.signal.sensed_ends), and where it cannot, its ends fitted through the plate charge TC for the
#: interval. It is undone as a stated plate only where the interval lies within the undoing's charge
#: (ballimpact.signal.undone.PLATE_FN_UNCERTAINTY, 1 %).
SESSION_PLATE_MAX_SPREAD = 0.05
#: ... and its damping ratio's this narrow or narrower [-]
SESSION_ZETA_MAX_SPREAD = 0.5
#: The contact's ends fitted through the session's plate charge TC for its damping ratio off by this many times its
#: interval's half-width, and by at least ... [-] (twice: an identified interval holds the truth less often than
#: its 95 % says; docs/rig.md)
SESSION_ZETA_CHARGE = (2.0, 0.10)
#: An impact whose TC its own processing withheld for these findings alone, one of them evidence of the plate,
#: is processed again with the session's plate, as if stated: the problems a plate's ringing causes, which the
#: undoing judges again (ballimpact.signal.undone.PLATE_KINDS), and the cloth's phase completed on them.
RETRY_KINDS = PLATE_KINDS | {ProblemKind.CLOTH_PHASE_COMPLETED}
_EVIDENCE = frozenset(k.value for k in PLATE_EVIDENCE)
#: The session's mains frequency is used in the impacts whose own quiet record could not tell 50 from 60 Hz when at
#: least this many impacts resolved their hum, all at that frequency [-]
SESSION_MAINS_MIN_IMPACTS = 3
_MAINS = ProblemKind.MAINS_UNRESOLVED.value
_FAULTS = frozenset(c.code for c in CHECKS.values() if c.fault)
#: The codes of checks that cannot bias TC and are no fault (an alias's, say: kCAL and the peak): beside the plate's,
#: they leave TC to the plate alone.
_NOT_TC = frozenset(c.code for c in CHECKS.values() if not c.fault and "contact_time" not in c.biases)


def session_plate(rig: Rig, *, max_spread: float = SESSION_PLATE_MAX_SPREAD,
                  max_zeta_spread: float = SESSION_ZETA_MAX_SPREAD) -> tuple[float, float] | None:
    """The plate the session identified from all its impacts, to undo in each: (resonance [Hz], damping ratio [-]),
    or None where the plate was stated (the impacts used it already), not identified, its resonance known no
    better than ``max_spread`` either side, or its damping ratio no better than ``max_zeta_spread``.

    Parameters
    ----------
    rig : ballimpact.rig.Rig
        The session's rig (:func:`ballimpact.rig_archive.session_rig`).
    max_spread : float
        Widest half-interval of the resonance accepted, as a fraction of it [-].
    max_zeta_spread : float
        Widest half-interval of the damping ratio accepted, as a fraction of it [-].

    Returns
    -------
    tuple of float or None
    """
    fn, zeta = rig["plate_resonance_hz"], rig["plate_damping_ratio"]
    if fn.source != "identified" or zeta.source != "identified":
        return None
    if not (fn.value > 0 and zeta.value > 0 and math.isfinite(fn.low) and math.isfinite(fn.high)):
        return None
    if max(fn.high - fn.value, fn.value - fn.low) > max_spread * fn.value:
        return None
    if not (math.isfinite(zeta.low) and math.isfinite(zeta.high)) \
            or max(zeta.high - zeta.value, zeta.value - zeta.low) > max_zeta_spread * zeta.value:
        return None
    return float(fn.value), float(zeta.value)


def session_plate_uncertainty(rig: Rig) -> tuple[float, float]:
    """How far the session's identified plate (:func:`session_plate`) is charged off in the impacts that use it,
    as fractions of its resonance and damping ratio [-], where an impact cannot measure it in its own free ringing:
    each :data:`SESSION_ZETA_CHARGE` times its interval's half-width, the resonance at least as far as a stated
    one's (:data:`ballimpact.signal.sensed_ends.SENSED_FN_UNCERTAINTY`), the damping ratio at least the floor.

    Parameters
    ----------
    rig : ballimpact.rig.Rig
        The session's rig, whose plate :func:`session_plate` gives.

    Returns
    -------
    tuple of float
    """
    fn, zeta = rig["plate_resonance_hz"], rig["plate_damping_ratio"]
    half = max(zeta.high - zeta.value, zeta.value - zeta.low) / zeta.value
    half_fn = max(fn.high - fn.value, fn.value - fn.low) / fn.value
    times, floor = SESSION_ZETA_CHARGE
    return max(times * half_fn, SENSED_FN_UNCERTAINTY), max(times * half, floor)


def session_mains(rig: Rig, *, min_impacts: int = SESSION_MAINS_MIN_IMPACTS) -> float | None:
    """The mains frequency the session identified from all its impacts [Hz], to use in each: or None where it was
    stated, found in fewer than ``min_impacts`` impacts that resolved their hum, or not at one frequency in all
    of them (``rig["mains_hz"]``'s interval spans the frequencies found).

    Parameters
    ----------
    rig : ballimpact.rig.Rig
        The session's rig (:func:`ballimpact.rig_archive.session_rig`).
    min_impacts : int
        Fewest impacts that resolved their hum [-].

    Returns
    -------
    float or None
    """
    mains = rig["mains_hz"]
    if mains.source != "identified" or not (mains.value > 0) or mains.n_impacts < min_impacts:
        return None
    return float(mains.value) if mains.low == mains.high == mains.value else None


def retry_candidates(impact_ids, contact_time_status, reason_code, *, plate: bool = True,
                     mains: bool = False) -> list[str]:
    """The impacts to process again with the session's plate (``plate``): TC withheld for problems a plate's
    ringing causes alone (:data:`RETRY_KINDS`, beside findings of checks that cannot bias TC and are no fault), one
    of them evidence of the plate (ringing, a peak on it, the force below zero); and with its mains (``mains``): TC
    withheld, among other findings that are no fault, for a hum the trace's quiet record could not resolve.

    Parameters
    ----------
    impact_ids, contact_time_status, reason_code : sequence of str
        Per impact, its id, TC's status and its ``;``-separated codes.
    plate, mains : bool
        Whether the session's plate, and its mains frequency, are there to use.

    Returns
    -------
    list of str
    """
    allowed = {k.value for k in RETRY_KINDS} | _NOT_TC | ({_MAINS} if mains else set())
    out = []
    for impact_id, status, codes in zip(impact_ids, contact_time_status, reason_code):
        found = {c for c in str(codes).split(";") if c}
        if str(status) == "ok" or not found:
            continue
        if (plate and found <= allowed and found & _EVIDENCE) or (mains and _MAINS in found and not found & _FAULTS):
            out.append(str(impact_id))
    return out

