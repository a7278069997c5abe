"""Faint plate lines: a zoo trace on an ideal plate with a weak damped line added (tests and bench/faint_lines.py).

A plate with a weak mode at ``line_hz`` rings faintly from the impact on: the
recorded voltage gets ``fraction * peak_volts * sin(2 pi f (t - t0)) *
exp(-zeta 2 pi f (t - t0))`` from the contact's true start ``t0`` on. The line
is the plate's motion, not force on the ball, so the truth (TC, kCAL, peak) is
the zoo trace's. Independent of ``ballimpact.synth``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

import zoo

__all__ = ["faint_trace", "draw_faint"]


def faint_trace(base: "zoo.ZooTrace", line_hz: float, fraction: float, zeta: float = 0.02,
                phase: float = 0.0) -> "zoo.ZooTrace":
    """``base`` with a faint damped line added from its contact's start.

    Parameters
    ----------
    base : zoo.ZooTrace
        The trace (an ideal plate is what makes the line the only ringing).
    line_hz : float
        Frequency of the line [Hz].
    fraction : float
        Its amplitude as a fraction of the trace's peak voltage [-] (0.0005-0.01 for a faint line).
    zeta : float
        Its damping ratio [-].
    phase : float
        Its phase at the contact's start [rad].
    """
    fs = base.sample_rate_hz
    v = np.asarray(base.voltage_V, dtype=float)
    t = np.arange(v.size) / fs - base.truth.start_s
    w = 2 * math.pi * line_hz
    amp = fraction * base.rig.peak_volts
    line = np.where(t >= 0, amp * np.sin(w * t + phase) * np.exp(-zeta * w * np.clip(t, 0, None)), 0.0)
    return replace(base, voltage_V=v + base.rig.polarity * line, label=f"{base.label} line {line_hz:.0f} Hz "
                   f"{100 * fraction:.2g} %")


def draw_faint(seed: int, index: int) -> "zoo.ZooTrace":
    """Faint-line case ``index`` of ``seed``: a benign one-factor zoo rig (noise drawn), ideal plate, sampled at
    60-200 kHz (aliasing ruled out without daq.bandwidth_hz), with a line at 1-20 kHz (log-uniform) of 0.05-1 % of the peak and damping 0.01-0.05."""
    rng = np.random.default_rng([seed, index, 7])
    fs = float(math.exp(rng.uniform(math.log(60e3), math.log(200e3))))
    base = zoo.make_trace(np.random.default_rng([seed, index]), "noise", label=f"faint {seed}:{index}",
                          plate_hz=None, sample_rate_hz=fs)
    f = float(math.exp(rng.uniform(math.log(1e3), math.log(20e3))))
    frac = float(math.exp(rng.uniform(math.log(5e-4), math.log(1e-2))))
    zeta = float(rng.uniform(0.01, 0.05))
    return faint_trace(base, f, frac, zeta, float(rng.uniform(0, 2 * math.pi)))
