"""Argument checks shared by the physics modules."""

from __future__ import annotations

import math


def positive_scalar(name: str, value) -> float:
    """``value`` as a float, or ValueError naming ``name`` when it is not a positive finite number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v
