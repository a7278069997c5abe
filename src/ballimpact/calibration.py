"""Per-impact force-plate calibration from the impulse, and the ball's motion from the force."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid

from ._checks import positive_scalar
from .signal.contact import contact_samples

__all__ = [
    "ContactSummary",
    "calibration_factor",
    "contact_summary",
    "force_from_voltage",
    "force_top",
    "integrate_motion",
    "voltage_impulse",
]


#: The largest sample ends a ramp cut by a drop between it and the next sample (the ball's
#: pre-buckling spike, section 3.2.4 in Goodwill & Haake 2004) when the next sample falls
#: below the ramp's quadratic continuation through the three samples up to it by
#: more than this many standard errors of that third difference [-].
RAMP_DROP_SIGMA = 4.0
#: ... and the ramp's last rise is within these fractions of the rise before it (a straight or
#: gently bending ramp: a swing of plate ringing or a jump smoothed by a plate is neither) [-].
RAMP_RISE_RATIO = (0.5, 1.25)
#: ... from a sample above this fraction of the largest sample (the force's jump from zero,
#: at the contact start, is no ramp) [-].
RAMP_FLOOR_FRACTION = 0.1


def _time_and_values(time_s, values, name: str):
    t = np.asarray(time_s, dtype=float).ravel()
    y = np.asarray(values, dtype=float).ravel()
    if t.shape != y.shape:
        raise ValueError(f"time_s and {name} must have the same length, got {t.size} and {y.size}")
    if t.size < 2:
        raise ValueError(f"need at least 2 samples of {name}, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError(f"time_s and {name} must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("time_s must be strictly increasing")
    return t, y


def voltage_impulse(time_s, voltage_V, start_s: float, end_s: float, *, start_jump: bool = False) -> float:
    """Trapezium integral of the voltage over the contact [start, end].

    The pieces between the sub-sample start (end) and the neighbouring sample
    use the linearly interpolated voltage at the start (end); after a jump at
    the start, the first sample's voltage held back to it
    (:func:`ballimpact.signal.contact.contact_samples`). The paper's integral of V dt
    from 0 to TC (section 2 in Goodwill & Haake 2004).

    Parameters
    ----------
    time_s : array_like
        Sample times, strictly increasing [s].
    voltage_V : array_like
        Conditioned voltage [V].
    start_s, end_s : float
        Contact start and end, inside the trace [s].
    start_jump : bool
        The force jumps from zero between two samples at the start (the
        contact's ``start_jump`` flag).

    Returns
    -------
    float
        Integral of V over the contact [V s].
    """
    t, v = _time_and_values(time_s, voltage_V, "voltage_V")
    t_rel, v_in = contact_samples(t, v, float(start_s), float(end_s), include_ends=True, start_jump=start_jump)
    return float(trapezoid(v_in, t_rel))


def calibration_factor(time_s, voltage_V, start_s: float, end_s: float, mass_kg: float,
                       vin_m_s: float, vout_m_s: float, *, start_jump: bool = False) -> float:
    """Calibration factor kCAL of one impact from its impulse.

    kCAL = m (VB + VB') / integral of V dt over the contact, trapezium rule with
    sub-sample end pieces (section 2 in Goodwill & Haake 2004). The ball's
    momentum changes by m (VB + VB') because the rebound is opposite to the
    inbound direction.

    Parameters
    ----------
    time_s : array_like
        Sample times, strictly increasing [s].
    voltage_V : array_like
        Conditioned voltage (positive for compression) [V].
    start_s, end_s : float
        Contact start and end [s].
    mass_kg : float
        Ball mass [kg].
    vin_m_s, vout_m_s : float
        Inbound speed VB and rebound speed VB' (both positive) [m/s].
    start_jump : bool
        The force jumps from zero between two samples at the start (the
        contact's ``start_jump`` flag; see :func:`voltage_impulse`).

    Returns
    -------
    float
        kCAL [N/V].

    Raises
    ------
    ValueError
        For a non-positive mass or inbound speed, a negative rebound speed, or
        a voltage integral that is not positive.
    """
    m = positive_scalar("mass_kg", mass_kg)
    vin = positive_scalar("vin_m_s", vin_m_s)
    vout = float(vout_m_s)
    if not math.isfinite(vout) or vout < 0:
        raise ValueError(f"vout_m_s must be non-negative and finite, got {vout_m_s!r}")
    integral = voltage_impulse(time_s, voltage_V, start_s, end_s, start_jump=start_jump)
    if not integral > 0:
        raise ValueError(f"the voltage integral over the contact is not positive ({integral:.3g} V s)")
    return m * (vin + vout) / integral


def force_from_voltage(voltage_V, kcal_N_per_V: float):
    """Force on the plate from the conditioned voltage, F = kCAL * V.

    Section 2 in Goodwill & Haake 2004.

    Parameters
    ----------
    voltage_V : float or array_like
        Conditioned voltage [V].
    kcal_N_per_V : float
        Calibration factor [N/V].

    Returns
    -------
    float or numpy.ndarray
        Force [N].
    """
    k = positive_scalar("kcal_N_per_V", kcal_N_per_V)
    if np.ndim(voltage_V) == 0:
        return float(voltage_V) * k
    return np.asarray(voltage_V, dtype=float) * k


def integrate_motion(time_s, force_N, mass_kg: float, vin_m_s: float):
    """Velocity and displacement of the ball's centre of mass during contact.

    Integrates m dv/dt = -F once from v(0) = VB and again from x(0) = 0,
    trapezium rule (section 2 in Goodwill & Haake 2004). Velocity and
    displacement are positive towards the plate, so x is the compression.

    Parameters
    ----------
    time_s : array_like
        Sample times, strictly increasing; the first is the contact start [s].
    force_N : array_like
        Force on the ball, positive pushing it away from the plate [N].
    mass_kg : float
        Ball mass [kg].
    vin_m_s : float
        Inbound speed VB at the first sample [m/s].

    Returns
    -------
    velocity_m_s : numpy.ndarray
        Centre-of-mass velocity towards the plate [m/s]; -VB' at the end.
    displacement_m : numpy.ndarray
        Centre-of-mass displacement towards the plate [m].
    """
    m = positive_scalar("mass_kg", mass_kg)
    vin = float(vin_m_s)
    if not math.isfinite(vin):
        raise ValueError(f"vin_m_s must be finite, got {vin_m_s!r}")
    t, f = _time_and_values(time_s, force_N, "force_N")
    velocity = vin - cumulative_trapezoid(f, t, initial=0.0) / m
    displacement = cumulative_trapezoid(velocity, t, initial=0.0)
    return velocity, displacement


@dataclass(frozen=True)
class ContactSummary:
    """Scalar results of one contact.

    Attributes
    ----------
    peak_force_N : float
        Top of the force [N]: the largest sample, or the middle of the range a
        spike's top cut by a drop between two samples can take (:func:`force_top`).
    time_to_peak_s : float
        Time of that top after the first sample [s].
    max_displacement_m : float
        Largest centre-of-mass displacement [m].
    impulse_N_s : float
        Trapezium integral of the force [N s].
    final_velocity_m_s : float
        Velocity at the last sample, positive towards the plate [m/s]
        (-VB' when kCAL came from the same impulse).
    peak_half_range_N : float
        Half the range the top can take between two samples [N] (:func:`force_top`'s; 0 at the largest sample).
    """

    peak_force_N: float
    time_to_peak_s: float
    max_displacement_m: float
    impulse_N_s: float
    final_velocity_m_s: float
    peak_half_range_N: float = 0.0


def force_top(time_s, force_N, noise_N: float):
    """The top of a sampled contact force: the largest sample, or where a ramp cut by a drop can peak.

    The ball's pre-buckling spike is a ramp that ends in a sudden drop (section
    3.2.4 in Goodwill & Haake 2004, Eq. (14) with kB = kCONST for the first
    0.2 ms). Its top falls anywhere between the last sample of the ramp and the
    next one, so the largest sample misses it by up to the ramp's rise over one
    sample, and by half of it on average. The largest sample k is such a ramp when
    the next sample falls below the quadratic continuation of the three samples
    up to it, ``R = 3 F[k] - 3 F[k-1] + F[k-2]``, by more than RAMP_DROP_SIGMA
    standard errors of that difference (``sqrt(20) noise_N``: a smooth top is
    continued to within its third difference), its last two rises agree within
    RAMP_RISE_RATIO, and they start above RAMP_FLOOR_FRACTION of the largest
    sample and after no fall (a fall before the ramp's two rises, ``F[k-3] >
    F[k-2]``, makes it a swing of plate ringing: a 12.9 kHz plate at 35.5 kHz lifted
    to +8.2 % of the spike's top, bench/spike_top_map.py). The ramp bends ever
    less towards its top (the model's rises fall by less and less), so it lies
    below its last chord continued, ``F[k] + rise``, and above the quadratic
    ``R``, which falls short of the top (a spike at 24 kHz: the middle of
    ``[F[k], R]`` 5.6 % low). The top then lies between ``F[k]`` and
    ``F[k] + rise``, and its middle is taken, at the middle of the interval: its
    error is at most half that range, against a whole range for the sample
    itself. Elsewhere the top is the largest sample: a smooth top
    sampled at tens of kHz is within 0.1 %, and a parabola through three samples
    overshoots the spike's corner. A lower sampled maximum is not lifted above the
    largest sample: where the smooth part of the contact holds the peak, its
    middle could stand up to half its range (5 % of the peak where the check
    lets it pass) above the true peak, which is read to 3 %.

    Whether the top is known to a tolerance is not judged here
    (``conditioning``'s "peak force between samples" excludes a ramp whose
    range exceeds it). Use it on a force the samples show as it is, not on one
    whose plate resonance was undone: the inverse lifts the last ramp sample
    before a drop.

    Parameters
    ----------
    time_s : array_like
        Sample times [s], strictly increasing.
    force_N : array_like
        Contact force [N].
    noise_N : float
        Standard deviation of the force's noise [N] (>= 0).

    Returns
    -------
    peak_N : float
        Top of the force [N].
    time_s : float
        Its time [s] (a sample's, or the middle between two).
    half_range_N : float
        Half the range the top can take [N]; 0 at the largest sample.
    """
    t, f = _time_and_values(time_s, force_N, "force_N")
    noise = float(noise_N)
    if not (math.isfinite(noise) and noise >= 0):
        raise ValueError(f"noise_N must be finite and >= 0, got {noise_N!r}")
    k = int(np.argmax(f))
    top = (float(f[k]), float(t[k]), 0.0)
    if not 2 <= k < f.size - 1 or f[k - 2] < RAMP_FLOOR_FRACTION * f[k]:
        return top
    if k >= 3 and f[k - 3] > f[k - 2]:
        return top  # a fall before the ramp: a swing of plate ringing, no ball's ramp
    rise, before = float(f[k] - f[k - 1]), float(f[k - 1] - f[k - 2])
    ramp_next = float(3.0 * f[k] - 3.0 * f[k - 1] + f[k - 2])
    lo, hi = RAMP_RISE_RATIO
    if not (before > 0 and lo * before <= rise <= hi * before
            and ramp_next - f[k + 1] > RAMP_DROP_SIGMA * math.sqrt(20.0) * noise):
        return top
    half = 0.5 * rise
    return float(f[k]) + half, 0.5 * float(t[k] + t[k + 1]), half


def contact_summary(time_s, force_N, mass_kg: float, vin_m_s: float, *,
                    noise_N: float | None = None) -> ContactSummary:
    """Peak force, time to peak, largest displacement and impulse of a contact.

    Parameters
    ----------
    time_s : array_like
        Sample times from the contact start (e.g. from
        :func:`ballimpact.signal.contact.contact_samples`) [s].
    force_N : array_like
        Force on the ball [N].
    mass_kg : float
        Ball mass [kg].
    vin_m_s : float
        Inbound speed VB [m/s].
    noise_N : float, optional
        Standard deviation of the force's noise [N]. Given, the peak is
        :func:`force_top`'s (a spike's top cut by a drop between two samples
        taken at the middle of its range); None, the largest sample.

    Returns
    -------
    ContactSummary
        Peak force [N], time to peak from the first sample [s], largest
        displacement [m], impulse [N s] and final velocity [m/s].
    """
    t, f = _time_and_values(time_s, force_N, "force_N")
    velocity, displacement = integrate_motion(t, f, mass_kg, vin_m_s)
    if noise_N is None:
        k = int(np.argmax(f))
        peak, t_peak, half = float(f[k]), float(t[k]), 0.0
    else:
        peak, t_peak, half = force_top(t, f, noise_N)
    return ContactSummary(
        peak_force_N=peak,
        time_to_peak_s=t_peak - float(t[0]),
        max_displacement_m=float(np.max(displacement)),
        impulse_N_s=float(trapezoid(f, t)),
        final_velocity_m_s=float(velocity[-1]),
        peak_half_range_N=half,
    )
