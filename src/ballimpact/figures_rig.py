"""Figures of the session's rig: the plate's pooled free ringing, and the time constant and kCAL of every impact."""

from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from . import archive_read as ar
from .figures_layout import _note, render
from .rig import COVERAGE
from .rig_archive import read_rig, ringing_overlay

__all__ = ["NO_RIG", "draw_rig_ringing", "draw_rig_per_impact", "fig_rig_ringing", "fig_rig_per_impact",
           "plate_panel_note"]

#: Said where an archive has no rig variables (written before they were, version 1.2).
NO_RIG = "this archive has no rig variables (written before ballimpact identified the rig)"
_GREY = "0.55"
_EXCLUDED = "tab:red"


def _interval_text(est, scale: float, fmt: str) -> str:
    """``[lo, hi]`` of an estimate's 95 % interval, scaled, or "" when it has none (or it is the value itself)."""
    lo, hi = est.low * scale, est.high * scale
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo == hi:
        return ""
    return f" [{lo:{fmt}}, {hi:{fmt}}]"


def plate_panel_note(ds) -> str:
    """Why the pooled-ringing panel has nothing to draw: no rig in the archive, or the plate's ``rig_note``."""
    rig = read_rig(ds)
    if not rig:
        return NO_RIG
    est = rig.get("plate_resonance_hz")
    if est is None:
        return NO_RIG
    if est.source == "none":
        return f"no plate resonance identified: {est.note}" if est.note else "no plate resonance identified"
    return "no impact's free ringing could be read again from the raw traces"


def draw_rig_ringing(fig, ds):
    """Draw the free ringing after every contact the plate's fit pooled, each on one curve, with the session's
    damped response (:func:`ballimpact.rig_archive.ringing_overlay`) into ``fig``, a matplotlib Figure or
    SubFigure; ``ds`` is the session archive. Without a plate (identified or stated) the panel says why."""
    ax = fig.subplots()
    overlay = ringing_overlay(ds)
    fig.suptitle("Free ringing of the plate after each contact, pooled over the session")
    if overlay is None:
        ax.set_axis_off()
        _note(ax, "\n".join(textwrap.wrap(plate_panel_note(ds), 70)))
        return
    fn, zeta = overlay.frequency_hz, overlay.damping_ratio
    wn = 2.0 * math.pi * fn
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    for t, y in overlay.curves:
        ax.plot(t * 1e3, y, color=_GREY, lw=0.5, alpha=0.6, zorder=1)
    t_lo = min(float(t[0]) for t, _ in overlay.curves)
    t_hi = max(float(t[-1]) for t, _ in overlay.curves)
    t = np.linspace(t_lo, t_hi, 2000)
    envelope = np.exp(-zeta * wn * t)
    ax.plot(t * 1e3, envelope * np.cos(wd * t), color="k", lw=1.3, zorder=3)
    ax.plot(t * 1e3, envelope, color="k", lw=0.8, ls="--", zorder=2)
    ax.plot(t * 1e3, -envelope, color="k", lw=0.8, ls="--", zorder=2)
    rig = read_rig(ds)
    f_est, z_est = rig["plate_resonance_hz"], rig["plate_damping_ratio"]
    how = "identified" if overlay.source == "identified" else "stated in session.yaml"
    ax.set_title(f"fn = {fn / 1e3:.4g} kHz{_interval_text(f_est, 1e-3, '.4g')}, "
                 f"\u03b6 = {zeta:.3g}{_interval_text(z_est, 1.0, '.3g')} (95 %, {how}); "
                 f"{len(overlay.curves)} impacts")
    ax.set_xlim(t_lo * 1e3, t_hi * 1e3)
    ax.set_ylim(-1.6, 1.6)
    ax.set_xlabel("Time from the ringing's phase origin [ms]")
    ax.set_ylabel("Ringing / its amplitude [-]")
    ax.legend(handles=[
        Line2D([], [], color=_GREY, lw=0.8, label=f"each impact ({len(overlay.curves)}), baseline removed"),
        Line2D([], [], color="k", lw=1.3, label="e^(-\u03b6 \u03c9n t) cos(\u03c9d t)"),
        Line2D([], [], color="k", lw=0.8, ls="--", label="envelope"),
    ], loc="upper right", fontsize=7)


def fig_rig_ringing(ds) -> Figure:
    """The plate's pooled free ringing (:func:`draw_rig_ringing`) as a figure of its own.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_rig_ringing, ds)


def _floats(ds, name: str) -> np.ndarray:
    n = ds.sizes.get("impact", 0)
    return np.asarray(ds[name].values, dtype=float) if name in ds else np.full(n, np.nan)


def _texts(ds, name: str) -> np.ndarray:
    n = ds.sizes.get("impact", 0)
    return ar.text_values(ds[name].values) if name in ds else np.array([""] * n, dtype=object)


def _session_line(ax, est, scale: float, unit: str, fmt: str) -> None:
    """The session's value as a line, its 95 % interval as a band, or a note of why there is none."""
    if est is None:
        ax.set_title("\n".join(textwrap.wrap(f"session: none ({NO_RIG})", 50)))
        return
    if not math.isfinite(est.value):
        ax.set_title("\n".join(textwrap.wrap(f"session: none ({est.note})" if est.note else "session: none", 50)))
        return
    ax.axhline(est.value * scale, color="k", lw=1.0, zorder=2)
    lo, hi = est.low * scale, est.high * scale
    if math.isfinite(lo) and lo < est.value * scale:
        hi = hi if math.isfinite(hi) else ax.get_ylim()[1]  # an interval open above (1/tau's reaches 0)
        ax.axhspan(lo, hi, color="0.5", alpha=0.18, lw=0, zorder=0)


def _per_impact_panel(ax, x, value, u, used, kept, excluded, est, scale, unit, fmt, label, other=""):
    """One quantity of every impact: used (filled, 95 % bar), kept but not pooled (open), excluded (red cross; one
    off the scale of the others is a red triangle at the edge). Returns the kinds of marks drawn."""
    v, bar = value * scale, COVERAGE * u * scale
    bar = np.where(np.isfinite(bar), bar, 0.0)
    finite = np.isfinite(v)
    drawn = set()
    for kind, mask, style in (("used", used, {"ms": 4}), ("kept", kept, {"ms": 5, "mfc": "none"})):
        if (mask & finite).any():
            ax.errorbar(x[mask & finite], v[mask & finite], yerr=bar[mask & finite], fmt="o", color="C0",
                        ecolor="C0", elinewidth=0.8, capsize=1.5, zorder=4, **style)
            drawn.add(kind)
    ref = []
    if est is not None and math.isfinite(est.value):
        ref = [est.value * scale] + [b * scale for b in (est.low, est.high) if math.isfinite(b)]
    scale_values = np.concatenate([v[finite & (used | kept)], np.asarray(ref, dtype=float)])
    if not scale_values.size:  # only excluded impacts: they set the scale
        scale_values = v[finite & excluded]
    if scale_values.size:
        lo, hi = float(scale_values.min()), float(scale_values.max())
        pad = 0.12 * (hi - lo) if hi > lo else 0.05 * abs(hi) or 1.0
        lo, hi = lo - pad, hi + pad
        ax.set_ylim(lo, hi)
        inside = excluded & finite & (v >= lo) & (v <= hi)
        if inside.any():
            ax.plot(x[inside], v[inside], "x", color=_EXCLUDED, ms=6, mew=1.3, zorder=5)
            drawn.add("excluded")
        for off, y, marker in ((excluded & finite & (v < lo), 0.0, "v"), (excluded & finite & (v > hi), 1.0, "^")):
            if off.any():
                ax.plot(x[off], np.full(off.sum(), y), marker, color=_EXCLUDED, ms=5, clip_on=False, zorder=5,
                        transform=ax.get_xaxis_transform())
                drawn.add("off scale")
    _session_line(ax, est, scale, unit, fmt)
    if not (finite & (used | kept | excluded)).any():
        ax.text(0.5, 0.8, "\n".join(textwrap.wrap(other or "no impact has a value", 38)), transform=ax.transAxes,
                ha="center", va="center", fontsize=8, color="0.35")
    ax.set_xlim(0.3, max(len(x), 1) + 0.7)
    ax.set_xlabel("Impact (raw order)")
    ax.set_ylabel(label)
    if est is not None and math.isfinite(est.value):
        source = "stated" if est.source == "stated" else f"{est.source}, {est.n_impacts} impacts"
        ax.set_title(f"session {est.value * scale:{fmt}} {unit}{_interval_text(est, scale, fmt)}\n({source})")
    return drawn


def draw_rig_per_impact(fig, ds):
    """Draw each impact's amplifier time constant [s] and kCAL [N/V] with their 95 % bars against the session's
    values (``rig_value``: line; ``rig_low``-``rig_high``: band) into ``fig``, a matplotlib Figure or SubFigure;
    ``ds`` is the session archive. Excluded impacts are red crosses."""
    axes = fig.subplots(1, 2)
    n = ds.sizes.get("impact", 0)
    x = np.arange(1, n + 1)
    rig = read_rig(ds)
    excluded = _texts(ds, "status") == "excluded"
    tau_estimated = _texts(ds, "amplifier_time_constant_source") == "estimated"
    n_given = int(np.sum(_texts(ds, "amplifier_time_constant_source") == "given"))
    tau_other = (f"the time constant of {n_given} impacts is the one stated (plate.time_constant_s)"
                 if n_given else "no impact's time constant was estimated")
    drawn = _per_impact_panel(axes[0], x, _floats(ds, "amplifier_time_constant_s"), _floats(ds, "amplifier_time_constant_se_s"),
                      tau_estimated & ~excluded, np.zeros(n, dtype=bool), tau_estimated & excluded,
                      rig.get("time_constant_s"), 1.0, "s", ".4g", "Amplifier time constant [s]", tau_other)
    kcal_ok = _texts(ds, "kcal_status") == "ok" if "kcal_status" in ds else np.ones(n, dtype=bool)
    drawn |= _per_impact_panel(axes[1], x, _floats(ds, "kcal_N_per_V"), _floats(ds, "kcal_u_N_per_V"),
                      kcal_ok & ~excluded, ~kcal_ok & ~excluded, excluded, rig.get("kcal_N_per_V"), 1.0, "N/V",
                      ".4g", "Calibration factor kCAL [N/V]")
    fig.suptitle("The rig per impact against the session's values")
    marks = {
        "used": Line2D([], [], color="C0", marker="o", ls="", ms=4, label="impact, 95 % bar"),
        "kept": Line2D([], [], color="C0", marker="o", mfc="none", ls="", ms=5, label="kept, kCAL withheld"),
        "excluded": Line2D([], [], color=_EXCLUDED, marker="x", ls="", ms=6, mew=1.3, label="excluded"),
        "off scale": Line2D([], [], color=_EXCLUDED, marker="^", ls="", ms=5, label="excluded, off the scale"),
    }
    handles = [h for kind, h in marks.items() if kind in drawn]
    handles += [Line2D([], [], color="k", lw=1.0, label="session value"),
                Patch(color="0.5", alpha=0.18, label="its 95 % interval")]
    fig.legend(handles=handles, ncols=len(handles), loc="outside lower center", fontsize=7)


def fig_rig_per_impact(ds) -> Figure:
    """The time constant and kCAL of every impact against the session's (:func:`draw_rig_per_impact`) as a figure.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_rig_per_impact, ds)
