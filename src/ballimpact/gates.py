"""Ball speeds and coefficient of restitution from light-gate beam-break times."""

from __future__ import annotations

import math

import numpy as np

from ._checks import positive_scalar
from .problems import Problem, ProblemKind

__all__ = [
    "gate_speeds",
    "coefficient_of_restitution",
    "speed_uncertainty",
    "check_gate_times",
]


def _as_result(value: np.ndarray, scalar: bool):
    """Return a float for all-scalar input, else the array."""
    return float(value) if scalar else value


def gate_speeds(gate_in_1_s, gate_in_2_s, gate_out_2_s, gate_out_1_s, spacing_m):
    """Inbound and rebound ball speed from the four beam-break times.

    Inbound speed VB = spacing / (gate_in_2 - gate_in_1), rebound speed
    VB' = spacing / (gate_out_1 - gate_out_2) (section 2 in Goodwill & Haake 2004).
    Gate 1 is the far gate, gate 2 the one near the plate. Only differences of
    times matter, so the timer's clock origin is irrelevant.

    Parameters
    ----------
    gate_in_1_s, gate_in_2_s : float or array_like
        Times the inbound ball broke gate 1 and then gate 2 [s]. NaN = missed.
    gate_out_2_s, gate_out_1_s : float or array_like
        Times the rebounding ball broke gate 2 and then gate 1 [s]. NaN = missed.
    spacing_m : float
        Distance between the two gates [m].

    Returns
    -------
    vin_m_s, vout_m_s : float or numpy.ndarray
        Inbound speed VB and rebound speed VB' [m/s], both positive; NaN where a
        time is NaN or its interval is not positive. Floats when every time is a
        scalar, else arrays of the broadcast shape.

    Raises
    ------
    ValueError
        If spacing_m is not positive and finite, or the times do not broadcast.
    """
    spacing = positive_scalar("spacing_m", spacing_m)
    times = [gate_in_1_s, gate_in_2_s, gate_out_2_s, gate_out_1_s]
    scalar = all(np.ndim(t) == 0 for t in times)
    try:
        t_in1, t_in2, t_out2, t_out1 = np.broadcast_arrays(*[np.asarray(t, dtype=float) for t in times])
    except ValueError as exc:
        raise ValueError(f"gate time arrays do not have compatible shapes: {exc}") from None
    with np.errstate(invalid="ignore", divide="ignore"):
        dt_in = t_in2 - t_in1
        dt_out = t_out1 - t_out2
        vin = np.where(dt_in > 0, spacing / np.where(dt_in > 0, dt_in, 1.0), np.nan)
        vout = np.where(dt_out > 0, spacing / np.where(dt_out > 0, dt_out, 1.0), np.nan)
    return _as_result(vin, scalar), _as_result(vout, scalar)


def coefficient_of_restitution(vin_m_s, vout_m_s):
    """Coefficient of restitution COR = VB' / VB.

    Section 2 in Goodwill & Haake 2004.

    Parameters
    ----------
    vin_m_s : float or array_like
        Inbound speed VB [m/s], positive.
    vout_m_s : float or array_like
        Rebound speed VB' [m/s], positive.

    Returns
    -------
    float or numpy.ndarray
        COR [-]; NaN where either speed is NaN or vin is not positive.
    """
    scalar = np.ndim(vin_m_s) == 0 and np.ndim(vout_m_s) == 0
    vin, vout = np.broadcast_arrays(np.asarray(vin_m_s, dtype=float), np.asarray(vout_m_s, dtype=float))
    with np.errstate(invalid="ignore", divide="ignore"):
        cor = np.where(vin > 0, vout / np.where(vin > 0, vin, 1.0), np.nan)
    cor = np.where(np.isfinite(vout) & (vout >= 0), cor, np.nan)
    return _as_result(cor, scalar)


def speed_uncertainty(speed_m_s, spacing_m, resolution_s):
    """Standard uncertainty of a gate speed caused by the timer resolution.

    Each of the two beam-break times is rounded (or truncated) to the timer
    resolution r, an error uniform over one step (standard deviation
    r / sqrt(12)); taken as independent (the interval falls at a random
    position relative to the timer ticks), the interval has standard
    deviation r / sqrt(6). With v = s / dt, u(v) = v**2 / s * u(dt) =
    v**2 * r / (s * sqrt(6)). The worst case (both errors at their extremes) is
    v**2 * r / s, sqrt(6) = 2.45 times larger.

    Parameters
    ----------
    speed_m_s : float or array_like
        Measured speed [m/s].
    spacing_m : float
        Gate spacing [m].
    resolution_s : float
        Timer resolution [s]; 0 gives zero uncertainty.

    Returns
    -------
    float or numpy.ndarray
        Standard uncertainty of the speed [m/s]; NaN where the speed is NaN.
    """
    spacing = positive_scalar("spacing_m", spacing_m)
    try:
        res = float(resolution_s)
    except (TypeError, ValueError):
        raise ValueError(f"resolution_s must be a number, got {resolution_s!r}") from None
    if not math.isfinite(res) or res < 0:
        raise ValueError(f"resolution_s must be non-negative and finite, got {resolution_s!r}")
    scalar = np.ndim(speed_m_s) == 0
    v = np.abs(np.asarray(speed_m_s, dtype=float))
    u = v**2 * res / (spacing * math.sqrt(6.0))
    return _as_result(u, scalar)


def check_gate_times(gate_in_1_s, gate_in_2_s, gate_out_2_s, gate_out_1_s) -> list[Problem]:
    """Problems with the four gate times of one impact, each a kind and a short message.

    Parameters
    ----------
    gate_in_1_s, gate_in_2_s, gate_out_2_s, gate_out_1_s : float
        Beam-break times of one impact [s]; NaN = missed by the timer.

    Returns
    -------
    list of ballimpact.problems.Problem
        Empty when both speeds can be computed; otherwise e.g. GATE_TIME_MISSING
        ``"missing gate time gate_out_1_s"`` or GATE_INTERVAL
        ``"inbound gate interval not positive (gate_in_2_s - gate_in_1_s = -0.001 s)"``.
    """
    names = ("gate_in_1_s", "gate_in_2_s", "gate_out_2_s", "gate_out_1_s")
    values = {}
    problems = []
    for name, value in zip(names, (gate_in_1_s, gate_in_2_s, gate_out_2_s, gate_out_1_s)):
        try:
            v = float(value)
        except (TypeError, ValueError):
            v = math.nan
        values[name] = v
        if not math.isfinite(v):
            problems.append(Problem(ProblemKind.GATE_TIME_MISSING, f"missing gate time {name}"))
    if problems:
        return problems
    d_in = values["gate_in_2_s"] - values["gate_in_1_s"]
    d_out = values["gate_out_1_s"] - values["gate_out_2_s"]
    if d_in <= 0:
        problems.append(Problem(ProblemKind.GATE_INTERVAL,
                                f"inbound gate interval not positive (gate_in_2_s - gate_in_1_s = {d_in:.6g} s)"))
    if d_out <= 0:
        problems.append(Problem(ProblemKind.GATE_INTERVAL,
                                f"rebound gate interval not positive (gate_out_1_s - gate_out_2_s = {d_out:.6g} s)"))
    return problems
