"""Argument checks shared by the physics modules."""

from __future__ import annotations

import math

import numpy as np


def positive_scalar(name: str, value) -> float:
    """``value`` as a float, or ValueError naming ``name`` when it is not a positive finite number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def positive_array(name: str, value) -> np.ndarray:
    """``value`` as a float array, or ValueError naming ``name`` and the first element that is
    not a positive finite number."""
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        bad = arr[~(np.isfinite(arr) & (arr > 0))].ravel()[0] if arr.ndim else arr
        raise ValueError(f"{name} must be positive and finite, got {float(bad)!r}")
    return arr


def nonnegative_array(name: str, value) -> np.ndarray:
    """``value`` as a float array, or ValueError naming ``name`` and the first element that is
    not a non-negative finite number."""
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        bad = arr[~(np.isfinite(arr) & (arr >= 0))].ravel()[0] if arr.ndim else arr
        raise ValueError(f"{name} must be non-negative and finite, got {float(bad)!r}")
    return arr


def finite_samples(name: str, value) -> np.ndarray:
    """``value`` as a flat float array, or ValueError naming ``name`` when a sample is not finite."""
    arr = np.asarray(value, dtype=float).ravel()
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds non-finite samples")
    return arr
