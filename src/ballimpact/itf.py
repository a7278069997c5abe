"""The ITF drop test (254 cm onto a rigid surface) predicted by the ball model, with air drag on the fall and the rise.

The ITF approves a ball by dropping it from 254 cm (100 in, measured to the bottom
of the ball) onto a rigid surface and measuring its rebound (bottom of the ball):
134.6-147.3 cm (53-58 in) passes (Goodwill & Haake 2004, section 2 and Table 1).
The prediction chains three steps:

1. the fall: impact speed VB = speed after falling 2.54 m from rest with drag
   (:func:`ballimpact.flight.speed_after`; 6.89 m/s for a 57.7 g ball, 7.06 m/s
   without drag);
2. the impact: VB' = COR(VB) VB with the model of Eq. (14)
   (:func:`ballimpact.model.simulate_impact`);
3. the rise: rebound height h = ln(1 + k VB'^2 / g) / (2 k)
   (:func:`ballimpact.flight.rise_height`).

The drop-test COR of a measured rebound is the same chain backwards
(:func:`drop_test_cor`). Both are far below the speeds (14-30 m/s) at which the
paper fitted the model: this is an extrapolation, and the tests measure how far
it is off for the paper's own balls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .flight import (
    AIR_DENSITY_KG_M3,
    BALL_DIAMETER_M,
    DRAG_COEFFICIENT,
    G_M_S2,
    drag_constant,
    rise_height,
    speed_after,
    speed_to_rise,
)
from .model import simulate_impact

__all__ = [
    "ITF_DROP_HEIGHT_M",
    "ITF_REBOUND_MIN_M",
    "ITF_REBOUND_MAX_M",
    "ItfPrediction",
    "drop_impact_speed",
    "drop_test_cor",
    "predict_itf_rebound",
    "predict_itf_rebound_interval",
]

#: ITF drop height, bottom of the ball above the surface [m] (100 in).
ITF_DROP_HEIGHT_M = 2.54
#: ITF rebound pass range, bottom of the ball [m] (53 in and 58 in; the paper: 134.6-147.3 cm).
ITF_REBOUND_MIN_M = 1.346
ITF_REBOUND_MAX_M = 1.473


@dataclass
class ItfPrediction:
    """Result of :func:`predict_itf_rebound`; arrays broadcast like the parameters.

    Attributes
    ----------
    impact_speed_m_s : numpy.ndarray
        Speed at the surface after the 254 cm fall [m/s].
    cor : numpy.ndarray
        Model COR at that speed [-].
    rebound_speed_m_s : numpy.ndarray
        Speed leaving the surface [m/s].
    rebound_height_m : numpy.ndarray
        Predicted rebound height [m] (bottom of the ball).
    """

    impact_speed_m_s: np.ndarray
    cor: np.ndarray
    rebound_speed_m_s: np.ndarray
    rebound_height_m: np.ndarray


def _k(mass_kg, diameter_m, air_density_kg_m3, drag_coefficient):
    return drag_constant(mass_kg, diameter_m, air_density_kg_m3, drag_coefficient)


def drop_impact_speed(mass_kg, *, diameter_m=BALL_DIAMETER_M, air_density_kg_m3=AIR_DENSITY_KG_M3,
                      drag_coefficient=DRAG_COEFFICIENT, drop_height_m=ITF_DROP_HEIGHT_M, g_m_s2=G_M_S2):
    """Impact speed of a ball dropped from rest: VB^2 = (g/k) (1 - exp(-2 k H)).

    Parameters
    ----------
    mass_kg : float or array_like
        Ball mass [kg].
    diameter_m : float
        Ball diameter [m].
    air_density_kg_m3 : float
        Air density [kg/m^3]; 0 gives the drag-free sqrt(2 g H).
    drag_coefficient : float
        Drag coefficient Cd [-].
    drop_height_m : float
        Drop height H of the bottom of the ball [m], > 0.
    g_m_s2 : float
        Gravity [m/s^2].

    Returns
    -------
    float or numpy.ndarray
        Impact speed [m/s].
    """
    if not drop_height_m > 0:
        raise ValueError(f"drop_height_m must be positive, got {drop_height_m!r}")
    k = _k(mass_kg, diameter_m, air_density_kg_m3, drag_coefficient)
    return speed_after(0.0, drop_height_m, k, g_m_s2)


def drop_test_cor(rebound_height_m, mass_kg, *, diameter_m=BALL_DIAMETER_M,
                  air_density_kg_m3=AIR_DENSITY_KG_M3, drag_coefficient=DRAG_COEFFICIENT,
                  drop_height_m=ITF_DROP_HEIGHT_M, g_m_s2=G_M_S2):
    """COR of the drop-test impact from a measured rebound height, with drag on the fall and the rise.

    COR = speed_to_rise(h) / drop_impact_speed(H); without drag this is sqrt(h / H).

    Parameters
    ----------
    rebound_height_m : float or array_like
        Measured rebound, bottom of the ball [m], >= 0.
    mass_kg : float
        Ball mass [kg].
    diameter_m, air_density_kg_m3, drag_coefficient, drop_height_m, g_m_s2 : float
        As in :func:`drop_impact_speed` ([m], [kg/m^3], [-], [m], [m/s^2]).

    Returns
    -------
    float or numpy.ndarray
        COR [-] at the drop-test impact speed.
    """
    k = _k(mass_kg, diameter_m, air_density_kg_m3, drag_coefficient)
    vb = drop_impact_speed(mass_kg, diameter_m=diameter_m, air_density_kg_m3=air_density_kg_m3,
                           drag_coefficient=drag_coefficient, drop_height_m=drop_height_m, g_m_s2=g_m_s2)
    return speed_to_rise(rebound_height_m, k, g_m_s2) / vb


def predict_itf_rebound(mass_kg, kb0_N_m, ak, a, ac, *, diameter_m=BALL_DIAMETER_M,
                        air_density_kg_m3=AIR_DENSITY_KG_M3, drag_coefficient=DRAG_COEFFICIENT,
                        drop_height_m=ITF_DROP_HEIGHT_M, g_m_s2=G_M_S2) -> ItfPrediction:
    """The ITF drop test predicted by the improved model (Eq. (14), Goodwill & Haake 2004) with drag.

    Parameters
    ----------
    mass_kg : float
        Ball mass m [kg].
    kb0_N_m, ak, a, ac : float or array_like
        Model parameters kB(0) [N/m], AK [N/m^(1+a)], a [-], AC [N s/m^3] (Eqs. (4), (7));
        arrays (e.g. bootstrap resamples) give one prediction each.
    diameter_m : float
        Ball diameter [m] (drag area).
    air_density_kg_m3 : float
        Air density [kg/m^3].
    drag_coefficient : float
        Drag coefficient Cd [-].
    drop_height_m : float
        Drop height [m] (ITF: 2.54 m).
    g_m_s2 : float
        Gravity [m/s^2].

    Returns
    -------
    ItfPrediction
    """
    k = _k(mass_kg, diameter_m, air_density_kg_m3, drag_coefficient)
    vb = drop_impact_speed(mass_kg, diameter_m=diameter_m, air_density_kg_m3=air_density_kg_m3,
                           drag_coefficient=drag_coefficient, drop_height_m=drop_height_m, g_m_s2=g_m_s2)
    sim = simulate_impact(vb, mass_kg, kb0_N_m, ak, a, ac)
    vout = np.asarray(sim.rebound_speed_m_s, dtype=float)
    h = np.full(vout.shape, np.nan)
    ok = np.isfinite(vout)
    h[ok] = rise_height(vout[ok], k, g_m_s2)
    return ItfPrediction(
        impact_speed_m_s=np.full(vout.shape, vb),
        cor=np.asarray(sim.cor, dtype=float),
        rebound_speed_m_s=vout,
        rebound_height_m=h,
    )


def predict_itf_rebound_interval(mass_kg, params, bootstrap=None, *, confidence=0.95, **flight_kw):
    """Predicted ITF rebound and its interval over bootstrap parameter sets.

    Parameters
    ----------
    mass_kg : float
        Ball mass [kg].
    params : sequence of float
        kB(0) [N/m], AK [N/m^(1+a)], a [-], AC [N s/m^3] of the fit.
    bootstrap : numpy.ndarray, optional
        Resampled parameter sets, shape (n, 4), columns as ``params`` (the fit's
        bootstrap over impacts); fewer than 10 rows give a NaN interval.
    confidence : float
        Interval level [-], in (0, 1).
    **flight_kw
        ``diameter_m``, ``air_density_kg_m3``, ``drag_coefficient``, ``drop_height_m``,
        ``g_m_s2`` for :func:`predict_itf_rebound`.

    Returns
    -------
    rebound_m, lo_m, hi_m : float
        Prediction and the percentile interval of the resamples [m]. The interval
        reflects the scatter of the fitted impacts only, not the model's error at
        this speed, far below the fitted range.
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    if len(params) != 4:
        raise ValueError(f"params must be (kb0_N_m, ak, a, ac), got {len(params)} values")
    pred = predict_itf_rebound(mass_kg, *params, **flight_kw)
    best = float(pred.rebound_height_m)
    lo = hi = float("nan")
    if bootstrap is not None:
        b = np.asarray(bootstrap, dtype=float)
        if b.ndim != 2 or b.shape[1] != 4:
            raise ValueError(f"bootstrap must have shape (n, 4), got {b.shape}")
        b = b[np.all(np.isfinite(b), axis=1)]
        if b.shape[0] >= 10:
            hb = predict_itf_rebound(mass_kg, b[:, 0], b[:, 1], b[:, 2], b[:, 3], **flight_kw).rebound_height_m
            q = 100 * np.array([0.5 - confidence / 2, 0.5 + confidence / 2])
            lo, hi = (float(x) for x in np.nanpercentile(hb, q))
    return best, lo, hi
