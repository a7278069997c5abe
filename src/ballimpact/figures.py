"""Figures of the session archive: the paper's Figs 2b, 7, 8, 9, 10, the kCAL check and QC traces (matplotlib, Agg)."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from . import archive_read as ar
from .archive_read import excluded_impacts
from .atomic import atomic_path
from .figure_registry import QC_DIR_NAME, REPORT_FIGURES
from .figures_layout import (  # noqa: F401
    DPI,
    FIGURE_WIDTH_IN,
    SYNTHETIC_MARK,
    _colors,
    _empty,
    _finish,
    _new_figure,
    _note,
    figure_style,
    is_synthetic,
    render,
)
from .figures_model import (  # noqa: F401
    COMPONENT_SPEED_TOLERANCE_M_S,
    draw_components,
    draw_contact_time_cor,
    draw_cor_speed_range,
    draw_force_curves,
    draw_kelvin_voigt,
    draw_stiffness,
    fig_components,
    fig_contact_time_cor,
    fig_cor_speed_range,
    fig_force_curves,
    fig_kelvin_voigt,
    fig_stiffness,
)
from .model_data import COMPONENT_SPEED_M_S

__all__ = [
    "DPI",
    "FIGURE_FILES",
    "KCAL_BAND_ROBUST_SD",
    "COMPONENT_SPEED_M_S",
    "fig_contact_time_cor",
    "fig_cor_speed_range",
    "fig_stiffness",
    "fig_force_curves",
    "fig_components",
    "fig_kelvin_voigt",
    "fig_kcal",
    "fig_qc_impact",
    "excluded_impacts",
    "kcal_band",
    "save_figure",
    "save_all",
    "figure_style",
    "render",
    "qc_file_stem",
    "draw_contact_time_cor",
    "draw_cor_speed_range",
    "draw_stiffness",
    "draw_force_curves",
    "draw_components",
    "draw_kelvin_voigt",
    "draw_kcal",
    "draw_qc",
]

#: PNG file name of each report figure, in report order, with the function of this module that
#: draws it into a matplotlib figure (from :data:`ballimpact.figure_registry.REPORT_FIGURES`).
FIGURE_FILES = {f.file_name: f.draw_name for f in REPORT_FIGURES}
#: Half width of the kCAL band around the session median, in robust standard
#: deviations (1.4826 x median absolute deviation of the good impacts) [-].
KCAL_BAND_ROBUST_SD = 3.0

_MAD_TO_SD = 1.4826  # robust standard deviation per median absolute deviation (normal data)


# ----------------------------------------------------------------------------- kCAL


def kcal_band(ds) -> tuple[float, float]:
    """Session median of kCAL over the good impacts and the band half width [N/V].

    The half width is :data:`KCAL_BAND_ROBUST_SD` robust standard deviations
    (1.4826 x median absolute deviation). NaN when there is no good impact.
    """
    good = ar.impacts(ds, status="ok", quantity_ok="kcal")
    k = np.asarray(ds["kcal_N_per_V"].values[good], dtype=float) if good.size else np.empty(0)
    k = k[np.isfinite(k)]
    if not k.size:
        return np.nan, np.nan
    med = float(np.median(k))
    return med, KCAL_BAND_ROBUST_SD * _MAD_TO_SD * float(np.median(np.abs(k - med)))


def draw_kcal(fig, ds):
    """Draw kCAL [N/V] of every impact with the session band (:func:`fig_kcal`) into ``fig``, a matplotlib
    Figure or SubFigure; ``ds`` is the session archive."""
    n = ds.sizes.get("impact", 0)
    if n == 0:
        _empty(fig)
        return
    ax = fig.subplots()
    colors = _colors(ds)
    ids = ar.text_values(ds["impact_id"].values)
    kcal = np.asarray(ds["kcal_N_per_V"].values, dtype=float)
    x = np.arange(n)
    med, half = kcal_band(ds)
    if np.isfinite(med):
        ax.axhline(med, color="k", lw=1.0, label=f"session median {med:.1f} N/V")
        if np.isfinite(half) and half > 0:
            ax.axhspan(med - half, med + half, color="0.5", alpha=0.15, lw=0,
                       label=f"median \u00b1 {KCAL_BAND_ROBUST_SD:g} robust SD (\u00b1{half:.1f} N/V)")
    for ball in ar.balls(ds):
        ok = ar.impacts(ds, ball, "ok", quantity_ok="kcal")
        if ok.size:
            ax.plot(x[ok], kcal[ok], "o", color=colors[ball], ms=5, label=ar.ball_label(ds, ball))
        ex = np.setdiff1d(ar.impacts(ds, ball), ok)  # excluded, or its kCAL withheld
        ex_f = ex[np.isfinite(kcal[ex])]
        if ex_f.size:
            ax.plot(x[ex_f], kcal[ex_f], "o", color=colors[ball], ms=7, mfc="none", mew=1.2)
    ex = np.setdiff1d(ar.impacts(ds), ar.impacts(ds, status="ok", quantity_ok="kcal"))
    ex_f = ex[np.isfinite(kcal[ex])]
    if ex_f.size:
        ax.plot(x[ex_f], kcal[ex_f], "x", color="k", ms=6, mew=1.3, label="excluded (kCAL known)")
    ex_n = ex[~np.isfinite(kcal[ex])]
    if ex_n.size:
        ax.plot(x[ex_n], np.full(ex_n.size, 0.02), "v", color="0.35", ms=6,
                transform=ax.get_xaxis_transform(), clip_on=False, label="excluded (no kCAL)")
    for i in ex:
        ax.axvline(x[i], color="0.6", lw=0.6, ls=":", zorder=0)
    finite = kcal[np.isfinite(kcal)]
    if finite.size:
        lo, hi = finite.min(), finite.max()
        if np.isfinite(med) and np.isfinite(half):
            lo, hi = min(lo, med - half), max(hi, med + half)
        pad = 0.15 * (hi - lo) if hi > lo else 0.05 * abs(hi) + 1.0
        ax.set_ylim(lo - pad, hi + 2.2 * pad)
    else:
        _note(ax, "no impact has a kCAL")
    if n <= 40:
        ax.set_xticks(x, ids, rotation=90, fontsize=7 if n > 20 else 8)
    ax.set_xlim(-0.7, n - 0.3)
    ax.set_xlabel("Impact (raw order)")
    ax.set_ylabel("Calibration factor kCAL [N/V]")
    ax.legend(loc="upper left", ncols=2)
    fig.suptitle("Per-impact force-plate calibration kCAL = m (VB + VB') / \u222bV dt")


def fig_kcal(ds) -> Figure:
    """kCAL of every impact in raw order, coloured by ball, with the session median and band.

    kCAL = m (VB + VB') / integral of V dt (section 2 of Goodwill & Haake 2004)
    [N/V]; band = median +- :data:`KCAL_BAND_ROBUST_SD` robust SD over the good
    impacts; excluded impacts are crossed (or marked on the axis when they have no
    kCAL).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_kcal, ds)


# ----------------------------------------------------------------------------- QC


def draw_qc(fig, ds, impact_id, *, wrap=90):
    """Draw the raw voltage [V] against time [ms] of one impact (:func:`fig_qc_impact`) into ``fig``;
    the title is wrapped at ``wrap`` characters."""
    i = ar.impact_position(ds, impact_id)
    ball = ar.text_values(ds["ball_type"].values)[i]
    status = ar.text_values(ds["status"].values)[i]
    reason = ar.text_values(ds["reason"].values)[i] or "(no reason given)"
    rt = np.asarray(ds["raw_time_s"].values[i], dtype=float) if "raw_time_s" in ds else np.empty(0)
    rv = np.asarray(ds["raw_voltage_V"].values[i], dtype=float) if "raw_voltage_V" in ds else np.empty(0)
    keep = np.isfinite(rt) & np.isfinite(rv)
    rt, rv = rt[keep], rv[keep]
    t_contact = ar.contact_series(ds, i)[0]
    contact_known = t_contact.size >= 2
    tc_ms = ar.impact_value(ds, "contact_time_ms", i)
    if contact_known and not np.isfinite(tc_ms):
        tc_ms = float(t_contact[-1]) * 1e3
    title = f"{impact_id} ({ar.ball_label(ds, ball)}), {status}: {reason}"
    fig.suptitle("\n".join(textwrap.wrap(title, wrap)), fontsize=10)
    if not rt.size:
        ax = fig.subplots()
        _note(ax, "no raw trace stored for this impact")
        ax.set_xlabel("Time [ms]")
        ax.set_ylabel("Voltage [V]")
        return
    zoom = contact_known and np.isfinite(tc_ms)
    axes = fig.subplots(2 if zoom else 1, 1, squeeze=False)[:, 0]
    xlabel = "Time since contact start [ms]" if contact_known else "Time since first sample [ms]"
    for k, ax in enumerate(axes):
        ax.plot(rt * 1e3, rv, "-", color="C0", lw=0.8, label="raw voltage (polarity applied)")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("Voltage [V]")
        if zoom:
            ax.axvline(0.0, color="C2", lw=1.0, ls="--", label="contact start")
            ax.axvline(tc_ms, color="C3", lw=1.0, ls="--", label=f"contact end (TC {tc_ms:.2f} ms)")
        if k == 1:
            margin = max(0.3 * tc_ms, 0.3)
            ax.set_xlim(-margin, tc_ms + margin)
            sel = (rt * 1e3 >= -margin) & (rt * 1e3 <= tc_ms + margin)
            if sel.any():
                lo, hi = rv[sel].min(), rv[sel].max()
                pad = 0.08 * (hi - lo) if hi > lo else 0.1
                ax.set_ylim(lo - pad, hi + pad)
            ax.set_title("zoom on the contact", loc="left")
        else:
            ax.set_title("whole trace" + ("" if contact_known else " (contact not found)"), loc="left")
        ax.legend(loc="upper right")


def fig_qc_impact(ds, impact_id) -> Figure:
    """Raw trace of one (excluded) impact with the exclusion reason in the title.

    Raw voltage [V] (polarity applied) against time [ms]; when the contact was
    found, its start and end (contact time) are marked and a second panel zooms
    on it.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    impact_id : str
        The impact to show.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    KeyError
        If the impact is not in the archive.
    """
    ar.impact_position(ds, impact_id)
    with figure_style():
        fig = _new_figure(FIGURE_WIDTH_IN, 5.0)
        draw_qc(fig, ds, impact_id)
        _finish(fig, ds)
    return fig


# ----------------------------------------------------------------------------- files


def save_figure(fig: Figure, path, dpi: int = DPI) -> Path:
    """Save a figure as PNG atomically (temporary file in the same folder, then os.replace).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        Destination PNG.
    dpi : int
        Resolution [dots per inch].

    Returns
    -------
    Path
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        # zlib level 1: as small a file as the default level 6 for these figures (flat
        # colours), in less time; the pixels are the same (PNG is lossless)
        fig.savefig(tmp, format="png", dpi=dpi, pil_kwargs={"compress_level": 1})
    return path


def qc_file_stem(impact_id: str) -> str:
    """File stem of an impact's QC page: the impact_id with every character outside
    ``A-Za-z0-9_.-`` replaced by ``_`` ("impact" when empty)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", str(impact_id)) or "impact"


def _keep_pixels(images, key: str, fig: Figure) -> None:
    """Store the pixels just saved (RGBA, uint8) of a figure under ``key`` when ``images`` is a dict."""
    if images is not None:
        images[key] = np.array(fig.canvas.buffer_rgba(), dtype=np.uint8, copy=True)


def save_all(ds, out_dir, images: dict | None = None) -> list[Path]:
    """Write every report figure as PNG (dpi 150) into ``out_dir``, QC traces into ``out_dir/qc``.

    Files: ``<stem>.png`` for each figure of
    :data:`ballimpact.figure_registry.REPORT_FIGURES`, in its order, and
    ``qc/<impact_id>.png`` for each excluded impact (the qc folder is always
    created). Each file is written atomically.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    out_dir : str or Path
        Output folder (created if needed).
    images : dict, optional
        When given, filled with the pixels of every file written (RGBA, uint8, the PNG's
        own pixels) under its path relative to ``out_dir`` (``<stem>.png``,
        ``qc/<impact>.png``), so that :func:`ballimpact.report.write_report` places them
        without decoding the files again.

    Returns
    -------
    list of Path
        The files written, report figures first, then the QC pages in raw order.
    """
    out_dir = Path(out_dir)
    qc_dir = out_dir / QC_DIR_NAME
    qc_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for spec in REPORT_FIGURES:
        fig = render(spec.draw, ds)
        written.append(save_figure(fig, out_dir / spec.file_name))
        _keep_pixels(images, spec.file_name, fig)
    for impact_id, _, _ in excluded_impacts(ds):
        fig = fig_qc_impact(ds, impact_id)
        name = f"{qc_file_stem(impact_id)}.png"
        written.append(save_figure(fig, qc_dir / name))
        _keep_pixels(images, f"{QC_DIR_NAME}/{name}", fig)
    return written
