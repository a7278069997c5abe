"""A hand-made mutant for the interval tests: every interval of fit_ball_model scaled about its estimate.

    PYTHONPATH=bench WIDEN=2.0 python -m pytest -q -m "not slow" -p mutation_intervals
    PYTHONPATH=bench WIDEN=0.5 python -m pytest -q -m "not slow" -p mutation_intervals

A pytest plugin (loaded before the tests are collected, so their ``from ballimpact.fitting
import fit_ball_model`` gets the wrapped one): each ``<name>_lo``/``<name>_hi`` of the
returned BallFit becomes estimate -/+ WIDEN x its distance from the estimate. The fast suite
must fail for intervals twice as wide and for intervals half as wide (docs/physics-tests.md).
"""

from __future__ import annotations

import dataclasses
import os

import ballimpact.fitting as fitting

FACTOR = float(os.environ.get("WIDEN", "1.0"))
_fit_ball_model = fitting.fit_ball_model


def fit_ball_model(*args, **kwargs):
    """fitting.fit_ball_model with every interval's half-widths multiplied by WIDEN [-]."""
    fit = _fit_ball_model(*args, **kwargs)
    changes = {}
    for field in dataclasses.fields(fit):
        if field.name.endswith("_lo"):
            stem = field.name[:-3]
            estimate = getattr(fit, stem if hasattr(fit, stem) else stem + "_N_m")
            changes[field.name] = estimate - FACTOR * (estimate - getattr(fit, field.name))
            changes[stem + "_hi"] = estimate + FACTOR * (getattr(fit, stem + "_hi") - estimate)
    return dataclasses.replace(fit, **changes)


fitting.fit_ball_model = fit_ball_model
