"""Figures of the session archive: the paper's Figs 2b, 7, 8, 9, 10, the kCAL check and QC traces (matplotlib, Agg)."""

from __future__ import annotations

import re
import textwrap
from contextlib import contextmanager
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator

from . import archive_read as ar
from .archive_read import excluded_impacts
from .atomic import atomic_path
from .figure_registry import QC_DIR_NAME, REPORT_FIGURES, report_figure
from .model_data import COMPONENT_SPEED_M_S, impact_model_curve, kelvin_voigt_contact

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

#: Resolution of the PNG files [dots per inch].
DPI = 150
#: PNG file name of each report figure, in report order, with the function of this module that
#: draws it into a matplotlib figure (from :data:`ballimpact.figure_registry.REPORT_FIGURES`).
FIGURE_FILES = {f.file_name: f.draw_name for f in REPORT_FIGURES}
#: Half width of the kCAL band around the session median, in robust standard
#: deviations (1.4826 x median absolute deviation of the good impacts) [-].
KCAL_BAND_ROBUST_SD = 3.0
#: A measured impact is overlaid on Fig. 10 when its speed is this close to 20 m/s [m/s].
COMPONENT_SPEED_TOLERANCE_M_S = 2.5
#: Width of the figures [in]; they are read on A4 paper.
FIGURE_WIDTH_IN = 7.5

_MAD_TO_SD = 1.4826  # robust standard deviation per median absolute deviation (normal data)
_STYLE = {
    "font.size": 9,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9,
    "legend.fontsize": 7.5,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "figure.titlesize": 11,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.3,
}
_NO_FIT = "no fit"
_NO_GOOD = "no good impacts"


@contextmanager
def figure_style():
    """Context in which every figure of this module is drawn: font sizes [pt], grid and line widths."""
    with matplotlib.rc_context(_STYLE):
        yield


def render(draw, ds) -> Figure:
    """A report figure drawn by ``draw(fig, ds)``: :data:`FIGURE_WIDTH_IN` wide, as high as the
    registry (:mod:`ballimpact.figure_registry`) says for the archive's number of ball types."""
    with figure_style():
        fig = _new_figure(FIGURE_WIDTH_IN, report_figure(draw.__name__).figure_height_in(len(ar.balls(ds))))
        draw(fig, ds)
        _finish(fig, ds)
    return fig


def _new_figure(width_in: float, height_in: float) -> Figure:
    # no layout engine: _fixed_layout places the axes once, from the figure's size and its
    # texts (a constrained layout measures every tick label, twice, and cost as much as drawing)
    fig = Figure(figsize=(width_in, height_in), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


#: Mark drawn on every figure of a synthetic session (archive attribute ``synthetic``).
SYNTHETIC_MARK = "SYNTHETIC DATA (ballimpact synth), not measured"


def is_synthetic(ds) -> bool:
    """True when the archive says the session is synthetic (attribute ``synthetic``, 1 or true)."""
    value = ds.attrs.get("synthetic", 0)
    if isinstance(value, str):
        return value.strip().lower() in ("1", "true", "yes")
    try:
        return bool(int(np.asarray(value).ravel()[0])) if np.asarray(value).size else False
    except (TypeError, ValueError):
        return False


_PT_IN = 1.0 / 72.0  # inches per typographic point
_CHAR_EM = 0.62  # mean advance of a digit or letter of DejaVu Sans, in em (digits 0.636, minus 0.838)
_LINE = 1.2  # line height of a text, in font sizes


def _font_pt(key: str) -> float:
    """Size [pt] of an rcParams font-size entry (numbers or names such as "medium")."""
    from matplotlib.font_manager import FontProperties

    return float(FontProperties(size=matplotlib.rcParams[key]).get_size_in_points())


def _lines(text: str) -> int:
    return text.count("\n") + 1 if text else 0


def _ytick_width_in(ax) -> float:
    """Width [in] of the widest y tick label, from its characters (no text is laid out)."""
    lo, hi = sorted(ax.get_ylim())
    locator, formatter = ax.yaxis.get_major_locator(), ax.yaxis.get_major_formatter()
    locs = [v for v in locator.tick_values(lo, hi) if lo - 1e-9 * (hi - lo) <= v <= hi + 1e-9 * (hi - lo)]
    labels = formatter.format_ticks(locs) if locs else [""]
    chars = max((len(s) for s in labels), default=0)
    return chars * _CHAR_EM * _font_pt("ytick.labelsize") * _PT_IN


def _y_space_in(ax) -> float:
    """Room [in] left of an axes for its y tick labels and y label."""
    room = (matplotlib.rcParams["ytick.major.size"] + matplotlib.rcParams["ytick.major.pad"] + 3) * _PT_IN
    room += _ytick_width_in(ax)
    if ax.get_ylabel():
        room += (_LINE * _font_pt("axes.labelsize") + matplotlib.rcParams["axes.labelpad"]) * _PT_IN
    return room


def _below_in(ax) -> float:
    """Room [in] below an axes for its x tick labels and x label."""
    room = 2 * _PT_IN
    if ax.xaxis.get_tick_params(which="major").get("labelbottom", True):
        size = _font_pt("xtick.labelsize")
        fixed = isinstance(ax.xaxis.get_major_locator(), FixedLocator)  # ticks (and labels) set by set_xticks
        rotated = [t for t in ax.get_xticklabels() if abs(t.get_rotation() - 90) < 1] if fixed else []
        if rotated:  # impact ids written upwards (kCAL figure): as high as the longest id is wide
            size = max(t.get_fontsize() for t in rotated)
            height = max(len(t.get_text()) for t in rotated) * _CHAR_EM * size + 2
        else:
            height = _LINE * size
        room += (matplotlib.rcParams["xtick.major.size"] + matplotlib.rcParams["xtick.major.pad"] + height) * _PT_IN
    if ax.get_xlabel():
        room += (_LINE * _font_pt("axes.labelsize") + matplotlib.rcParams["axes.labelpad"] + 2) * _PT_IN
    return room


def _above_in(ax) -> float:
    """Room [in] above an axes for its (possibly wrapped) title."""
    lines = max(_lines(t.get_text()) for t in (ax.title, ax._left_title, ax._right_title) if t.get_visible())
    if not lines:
        return 4 * _PT_IN
    return (lines * _LINE * _font_pt("axes.titlesize") + matplotlib.rcParams["axes.titlepad"] + 4) * _PT_IN


def _wrap_titles(fig, renderer) -> None:
    """Wrap every axes title that is wider than its axes onto more lines (no title runs into
    the next panel); only the titles are measured."""
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        width = ax.get_window_extent(renderer).width
        for title in (ax.title, ax._left_title, ax._right_title):
            text = title.get_text()
            if not text or not title.get_visible():
                continue
            measured = title.get_window_extent(renderer).width
            if measured <= width:
                continue
            longest = max(len(line) for line in text.splitlines())
            chars = max(10, int(longest * width / measured * 0.95))
            title.set_text("\n".join(
                wrapped for line in text.splitlines() for wrapped in textwrap.wrap(line, chars) or [""]))


def _fixed_layout(fig) -> None:
    """Place the axes of a figure once, in inches, from what surrounds them.

    The grid of panels (one ``subplots`` call) gets margins for the figure title (its
    lines), each row's axes titles (wrapped to the panel width by :func:`_wrap_titles`),
    the y tick labels (their characters counted, not laid out), the axis labels and a
    legend of the figure below the panels (``fig.legend``, which this then puts at the
    bottom edge). No layout engine runs: a constrained layout measures every tick label
    twice, and cost as much as the drawing itself.
    """
    width_in, height_in = fig.get_size_inches()
    axes = [ax for ax in fig.axes if ax.get_subplotspec() is not None]
    if not axes:
        return
    grid = axes[0].get_subplotspec().get_gridspec()
    nrows, ncols = grid.get_geometry()
    shown = [ax for ax in axes if ax.get_visible()] or axes
    y_space = max(_y_space_in(ax) for ax in shown if ax.axison) if any(ax.axison for ax in shown) else 0.1
    left, right, gap_x = y_space + 0.08, 0.18, y_space + 0.3
    if left + right + (ncols - 1) * gap_x > 0.75 * width_in:  # tick labels wider than the figure
        scale = 0.75 * width_in / (left + right + (ncols - 1) * gap_x)
        left, right, gap_x = left * scale, right * scale, gap_x * scale
    grid.update(left=left / width_in, right=1 - right / width_in,
                wspace=gap_x / max((width_in - left - right - (ncols - 1) * gap_x) / ncols, 0.1))
    _place_axes(fig, axes)
    _wrap_titles(fig, fig.canvas.get_renderer())

    def rows(span):
        return range(span.rowspan.start, span.rowspan.stop)

    above, below = [4 * _PT_IN] * nrows, [2 * _PT_IN] * nrows
    for ax in shown:
        span = ax.get_subplotspec()
        above[span.rowspan.start] = max(above[span.rowspan.start], _above_in(ax))
        if ax.axison:
            below[span.rowspan.stop - 1] = max(below[span.rowspan.stop - 1], _below_in(ax))
    top = 0.08
    if fig._suptitle is not None and fig._suptitle.get_text():
        size = fig._suptitle.get_fontsize()
        top += (_lines(fig._suptitle.get_text()) * _LINE * size + 4) * _PT_IN
        fig._suptitle.set_y(1 - 0.06 / height_in)
        fig._suptitle.set_va("top")
    bottom = 0.06
    for legend in fig.legends:
        n = len(legend.texts)
        ncols_legend = max(1, legend._ncols)
        size = legend.prop.get_size_in_points()
        n_rows = -(-n // ncols_legend)
        # rows of text, the spacing between them and the frame's padding
        bottom += (n_rows * _LINE + (n_rows - 1) * 0.5 + 1.0) * size * _PT_IN + 0.06
        legend.set_bbox_to_anchor((0.5, 0.02 / height_in), transform=fig.transFigure)
        legend.set_loc("lower center")
    top += above[0]
    bottom += below[-1]
    gap_y = max([below[r] + above[r + 1] for r in range(nrows - 1)], default=0.0) + 0.06
    spare = height_in - top - bottom - (nrows - 1) * gap_y
    if spare < 0.25 * height_in:
        # texts taller than the figure (a title of thousands of characters): the panels keep a
        # quarter of the height and the margins shrink in proportion (texts may then overlap)
        scale = 0.75 * height_in / (top + bottom + (nrows - 1) * gap_y)
        top, bottom, gap_y = top * scale, bottom * scale, gap_y * scale
    axes_h = max((height_in - top - bottom - (nrows - 1) * gap_y) / nrows, 0.01)
    grid.update(top=1 - top / height_in, bottom=bottom / height_in, hspace=gap_y / axes_h)
    _place_axes(fig, axes)


def _place_axes(fig, axes) -> None:
    """Move every axes to its cell of the grid (GridSpec.update does not move existing axes)."""
    for ax in axes:
        ax.set_position(ax.get_subplotspec().get_position(fig))


def _finish(fig, ds) -> None:
    """Last touches of every figure: titles that fit their panels, and the synthetic mark."""
    if is_synthetic(ds):
        # first line of the figure title: _fixed_layout keeps it clear of everything else
        title = fig._suptitle.get_text() if fig._suptitle is not None else ""
        if SYNTHETIC_MARK not in title:
            size = fig._suptitle.get_fontsize() if fig._suptitle is not None else None
            fig.suptitle(f"[{SYNTHETIC_MARK}]" + (f"\n{title}" if title else ""), fontsize=size)
    _fixed_layout(fig)


# ----------------------------------------------------------------------------- notes and layout


def _colors(ds) -> dict[str, str]:
    """Matplotlib colour of each ball type, in archive order."""
    return {b: f"C{i % 10}" for i, b in enumerate(ar.balls(ds))}


def _note(ax, text, *, color="0.35"):
    ax.text(
        0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=10, color=color,
        bbox={"boxstyle": "round", "fc": "white", "ec": "0.7", "alpha": 0.9}, zorder=10,
    )


def _empty(fig):
    ax = fig.subplots()
    ax.set_axis_off()
    _note(ax, "no impacts in this session")


def _corner_note(ax, text):
    ax.text(0.98, 0.96, text, transform=ax.transAxes, ha="right", va="top", color="0.3", fontsize=9,
            bbox={"fc": "white", "ec": "0.7"}, zorder=10)


def _legend_with_headroom(ax, *, ncols=2, headroom=0.45, loc="upper left"):
    """Legend in a band added above the data so that it never hides a curve."""
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + headroom * (hi - lo))
    ax.legend(loc=loc, ncols=ncols, fontsize=7, handlelength=1.8, columnspacing=1.0, borderaxespad=0.3)


def _grid(fig, n, ncols):
    nrows = max(1, -(-n // ncols))
    axes = np.atleast_2d(fig.subplots(nrows, ncols, squeeze=False))
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return flat[:n]


# ----------------------------------------------------------------------------- Fig. 7


def draw_contact_time_cor(fig, ds):
    """Draw TC [ms] and COR [-] against inbound speed [m/s] with the fitted model, Eq. (14)
    (:func:`fig_contact_time_cor`) into ``fig``, a matplotlib Figure or SubFigure; ``ds`` is the session
    archive."""
    balls = ar.balls(ds)
    colors = _colors(ds)
    if not balls:
        _empty(fig)
        return
    axes = fig.subplots(len(balls), 2, squeeze=False, sharex=True)
    speed = np.asarray(ds["speed_m_s"].values, dtype=float) if "speed_m_s" in ds else None
    for row, ball in enumerate(balls):
        ax_tc, ax_cor = axes[row]
        good = ar.impacts(ds, ball, "ok")
        c = colors[ball]
        for ax, meas, model, unit_label in (
            (ax_tc, "contact_time_ms", "model_contact_time_ms", "Contact time TC [ms]"),
            (ax_cor, "cor", "model_cor", "COR [-]"),
        ):
            # fit outliers (used_in_fit 0) are drawn apart, as crosses
            outl = np.zeros(good.size, dtype=bool)
            if "used_in_fit" in ds and good.size:
                outl = np.asarray(ds["used_in_fit"].values[good], dtype=float) <= 0
            vin = ds["vin_m_s"].values[good] if good.size else np.empty(0)
            y = ds[meas].values[good] if good.size else np.empty(0)
            if good.size:
                ax.plot(vin[~outl], y[~outl], "o", color=c, ms=4.5, mfc="none", mew=1.2, label="measured")
            if outl.any():
                ax.plot(vin[outl], y[outl], "x", color="crimson", ms=7, mew=1.8, label="fit outlier (left out)")
            curve = ar.ball_array(ds, model, ball)
            lo, hi = ar.ball_array(ds, model + "_lo", ball), ar.ball_array(ds, model + "_hi", ball)
            plo, phi = ar.ball_array(ds, model + "_pred_lo", ball), ar.ball_array(ds, model + "_pred_hi", ball)
            if speed is not None and curve is not None and np.isfinite(curve).any():
                _plot_model_curve(ax, ds, ball, speed, curve, color="k")
                if lo is not None and hi is not None and np.isfinite(lo).any():
                    ax.fill_between(speed, lo, hi, color=c, alpha=0.25, lw=0, label="95 % confidence (curve)")
                if plo is not None and phi is not None and np.isfinite(plo).any():
                    ax.plot(speed, plo, "--", color=c, lw=0.9, label="95 % prediction (one impact)")
                    ax.plot(speed, phi, "--", color=c, lw=0.9)
            elif good.size:
                ax.plot([], [], ls="none", label=f"model: {_NO_FIT}")
            else:
                _note(ax, f"{_NO_GOOD}\n{_NO_FIT}")
            ax.set_ylabel(unit_label)
        n_used = ar.ball_value(ds, "n_impacts", ball)
        n_used = f", {int(n_used)} in fit" if np.isfinite(float(n_used)) else ""
        ax_tc.set_title(f"{ar.ball_label(ds, ball)}: TC ({good.size} good{n_used})", loc="left")
        ax_cor.set_title(f"{ar.ball_label(ds, ball)}: COR", loc="left")
    for ax in axes[-1]:
        ax.set_xlabel("Inbound speed VB [m/s]")
    _shared_legend(fig, axes.ravel())
    fig.suptitle("Contact time and COR against inbound speed (cf. Fig. 7 of Goodwill & Haake 2004)")


def _shared_legend(fig, axes) -> None:
    """One legend for every panel, below them (a legend inside a panel covers its data); each entry drawn in grey,
    as the colour is the ball type's, named by the panel titles."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    neutral = {
        "measured": Line2D([], [], ls="none", marker="o", ms=4.5, mfc="none", mew=1.2, color="0.35"),
        "fitted speeds": Patch(color="0.5", alpha=0.2),
        "95 % confidence (curve)": Patch(color="0.5", alpha=0.35, lw=0),
        "95 % prediction (one impact)": Line2D([], [], ls="--", lw=0.9, color="0.45"),
    }
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, neutral.get(label, handle))
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncols=min(4, len(handles)),
                   fontsize=8)


def _fitted_range(ds, ball) -> tuple[float, float]:
    """Slowest and fastest inbound speed fitted [m/s] (NaN when the archive predates v1.1 or there is no fit)."""
    return (float(ar.ball_value(ds, "fit_vin_min_m_s", ball)), float(ar.ball_value(ds, "fit_vin_max_m_s", ball)))


def _plot_model_curve(ax, ds, ball, speed, curve, *, color, label="fitted model"):
    """Model curve: solid over the fitted speeds (shaded), dashed where it extrapolates."""
    lo, hi = _fitted_range(ds, ball)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        ax.plot(speed, curve, "-", color=color, lw=1.2, label=label)
        return
    inside = (speed >= lo - 1e-9) & (speed <= hi + 1e-9)
    ax.axvspan(lo, hi, color="0.5", alpha=0.12, lw=0, zorder=0, label="fitted speeds")
    ax.plot(speed, curve, "--", color=color, lw=1.0, label="extrapolated")
    ax.plot(np.r_[lo, speed[inside], hi], np.interp(np.r_[lo, speed[inside], hi], speed, curve), "-",
            color=color, lw=1.4, label=label)


def fig_contact_time_cor(ds) -> Figure:
    """Measured contact time and COR against inbound speed with the fitted model (paper Fig. 7).

    One row per ball type: TC [ms] and COR [-] of the good impacts against VB
    [m/s], the fitted model curve (Eq. (14) in Goodwill & Haake 2004), its 95 %
    confidence band (shaded: where the curve lies) and its 95 % prediction band
    (dashed: where the next impact of this ball type will fall). Fit outliers (good
    impacts left out of the fit) are marked by red crosses. Panels of a ball without
    good impacts or fit say so.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_contact_time_cor, ds)


# ----------------------------------------------------------------------------- COR from 3 to 40 m/s, ITF


def draw_cor_speed_range(fig, ds):
    """Draw COR [-] from 3 to 40 m/s with the ITF drop test (:func:`fig_cor_speed_range`) into ``fig``, a
    matplotlib Figure or SubFigure; ``ds`` is the session archive."""
    from .itf import ITF_REBOUND_MAX_M, ITF_REBOUND_MIN_M, drop_test_cor

    balls = ar.balls(ds)
    colors = _colors(ds)
    if not balls:
        _empty(fig)
        return
    speed = np.asarray(ds["speed_m_s"].values, dtype=float) if "speed_m_s" in ds else None
    axes = _grid(fig, len(balls), 2 if len(balls) > 1 else 1)
    for ax, ball in zip(axes, balls):
        c = colors[ball]
        good = ar.impacts(ds, ball, "ok")
        if good.size:
            ax.plot(ds["vin_m_s"].values[good], ds["cor"].values[good], "o", color=c, ms=4, mfc="none", mew=1.1,
                    label="impacts (good)")
        curve = ar.ball_array(ds, "model_cor", ball)
        has_model = speed is not None and curve is not None and np.isfinite(curve).any()
        if has_model:
            _plot_model_curve(ax, ds, ball, speed, curve, color="k")
            lo, hi = ar.ball_array(ds, "model_cor_lo", ball), ar.ball_array(ds, "model_cor_hi", ball)
            if lo is not None and hi is not None and np.isfinite(lo).any():
                ax.fill_between(speed, lo, hi, color=c, alpha=0.25, lw=0, label="95 % band")
        v_itf = float(ar.ball_value(ds, "itf_impact_speed_m_s", ball))
        pred = float(ar.ball_value(ds, "itf_model_cor", ball))
        meas = float(ar.ball_value(ds, "itf_drop_test_cor", ball))
        mass = float(ar.ball_value(ds, "mass_kg", ball))
        if np.isfinite(v_itf) and np.isfinite(mass) and mass > 0:
            band = drop_test_cor(np.array([ITF_REBOUND_MIN_M, ITF_REBOUND_MAX_M]), mass)
            ax.plot([v_itf, v_itf], band, "-", color="tab:green", lw=5, alpha=0.45, solid_capstyle="butt",
                    label="ITF pass range")
        if np.isfinite(pred):
            ax.plot(v_itf, pred, "D", color="k", ms=5, mfc="white", label="model at ITF drop")
        if np.isfinite(meas):
            ax.plot(v_itf, meas, "*", color="tab:red", ms=10, label="ITF drop test (measured)")
        if not good.size and not has_model:
            _note(ax, f"{_NO_GOOD}\n{_NO_FIT}")
        ax.set_xlim(0, 42)
        ax.set_xlabel("Inbound speed VB [m/s]")
        ax.set_ylabel("COR [-]")
        ax.set_title(ar.ball_label(ds, ball), loc="left")
        if ax.get_legend_handles_labels()[0]:
            _legend_with_headroom(ax, ncols=2, headroom=0.55, loc="upper right")
    fig.suptitle("COR from 3 to 40 m/s: the fitted model, its extrapolation and the ITF drop test")


def fig_cor_speed_range(ds) -> Figure:
    """COR against inbound speed from 3 to 40 m/s with the fitted range, the impacts and the ITF drop test.

    One panel per ball type: the fitted model COR (Eq. (14), Goodwill & Haake 2004)
    solid over the fitted speeds (shaded) and dashed where it extrapolates, its 95 %
    band, the good impacts (COR [-] against VB [m/s]), the model at the ITF drop-test
    impact speed (about 6.9 m/s with drag), the measured drop test when session.yaml
    gives ``itf_rebound_cm`` and the ITF pass range (134.6-147.3 cm) as a COR range
    (:mod:`ballimpact.itf`).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_cor_speed_range, ds)


# ----------------------------------------------------------------------------- Fig. 8


def draw_stiffness(fig, ds):
    """Draw structural stiffness kB [kN/m] against displacement [mm], Eq. (4) (:func:`fig_stiffness`) into
    ``fig``, a matplotlib Figure or SubFigure; ``ds`` is the session archive."""
    from .model import structural_stiffness

    if not ar.balls(ds):
        _empty(fig)
        return
    ax = fig.subplots()
    colors = _colors(ds)
    x_m = np.asarray(ds["stiffness_x_m"].values, dtype=float) if "stiffness_x_m" in ds else np.linspace(0, 0.03, 61)
    no_fit = []
    any_line = False
    for ball in ar.balls(ds):
        c = colors[ball]
        label = ar.ball_label(ds, ball)
        curve = ar.ball_array(ds, "model_stiffness_kN_m", ball)
        params = ar.fitted_parameters(ds, ball)
        if (curve is None or not np.isfinite(curve).any()) and params is not None:
            curve = structural_stiffness(x_m, params[1], params[2], params[3]) / 1e3
        if curve is not None and np.isfinite(curve).any():
            ax.plot(x_m * 1e3, curve, "-", color=c, lw=2.4, alpha=0.55, label=f"{label}: fitted")
            any_line = True
        else:
            no_fit.append(label)
        paper = [float(ar.ball_value(ds, n, ball)) for n in ("paper_kb0_kN_m", "paper_ak_kN_m", "paper_a")]
        if all(np.isfinite(paper)):
            kb0, ak, a = paper
            ax.plot(x_m * 1e3, structural_stiffness(x_m, kb0, ak, a), "--", color=c, lw=1.2, zorder=3,
                    dashes=(4, 2.5), label=f"{label}: paper Table 2")
            any_line = True
    ax.set_xlabel("Centre-of-mass displacement x [mm]")
    ax.set_ylabel("Structural stiffness kB [kN/m]")
    ax.set_xlim(x_m[0] * 1e3, x_m[-1] * 1e3)
    ax.set_ylim(bottom=0)
    if any_line:
        ax.legend(loc="upper left", ncols=1)
    if no_fit:
        ax.text(0.98, 0.03, "no fit: " + ", ".join(no_fit), transform=ax.transAxes, ha="right", va="bottom",
                color="0.3", bbox={"fc": "white", "ec": "0.7"})
    # plain text, not mathtext: its parser costs a third of a second in every process
    ax.set_title("kB = kB(0) + AK x\u1d43 (Eq. 4); solid: fitted, dashed: paper Table 2", loc="left")
    fig.suptitle("Structural stiffness against displacement (cf. Fig. 8 of Goodwill & Haake 2004)")


def fig_stiffness(ds) -> Figure:
    """Structural stiffness kB against centre-of-mass displacement for every ball (paper Fig. 8).

    kB = kB(0) + AK x^a (Eq. (4) in Goodwill & Haake 2004) with the fitted
    parameters (solid) and Table 2 (dashed, Table 2 balls only); kB [kN/m] against
    x [mm].

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_stiffness, ds)


# ----------------------------------------------------------------------------- Fig. 9


def _extreme_good(ds, ball):
    """Good impacts of a ball at the lowest and the highest inbound speed (one if they coincide)."""
    good = [i for i in ar.impacts(ds, ball, "ok") if np.isfinite(ar.impact_value(ds, "vin_m_s", i))]
    good = [i for i in good if ar.contact_series(ds, i)[0].size >= 2]
    if not good:
        return []
    vin = np.array([ar.impact_value(ds, "vin_m_s", i) for i in good])
    lo, hi = good[int(np.argmin(vin))], good[int(np.argmax(vin))]
    return [lo] if lo == hi else [lo, hi]


def draw_force_curves(fig, ds):
    """Draw measured and modelled force [N] against time [ms] and displacement [mm]
    (:func:`fig_force_curves`) into ``fig``, a matplotlib Figure or SubFigure; ``ds`` is the session
    archive."""
    balls = ar.balls(ds)
    if not balls:
        _empty(fig)
        return
    axes = fig.subplots(len(balls), 2, squeeze=False)
    speed_colors = ("C0", "C3")
    for row, ball in enumerate(balls):
        ax_t, ax_x = axes[row]
        picks = _extreme_good(ds, ball)
        label = ar.ball_label(ds, ball)
        ax_t.set_title(f"{label}: force-time", loc="left")
        ax_x.set_title(f"{label}: force-displacement", loc="left")
        if not picks:
            for ax in (ax_t, ax_x):
                _note(ax, _NO_GOOD)
        fit_ok = ar.fitted_parameters(ds, ball) is not None
        for k, i in enumerate(picks):
            c = speed_colors[k]
            vin = ar.impact_value(ds, "vin_m_s", i)
            t, f, x = ar.contact_series(ds, i, "force_N", "displacement_m")
            ax_t.plot(t * 1e3, f, "-", color=c, lw=1.1, label=f"measured {vin:.1f} m/s")
            ax_x.plot(x * 1e3, f, "-", color=c, lw=1.1, label=f"measured {vin:.1f} m/s")
            sim = impact_model_curve(ar.fitted_parameters(ds, ball), vin, ar.impact_value(ds, "impact_mass_kg", i))
            if sim is not None:
                ts, fs, xs = sim
                ax_t.plot(ts * 1e3, fs, "--", color="k" if k == 0 else "0.45", lw=1.2, label=f"model {vin:.1f} m/s")
                ax_x.plot(xs * 1e3, fs, "--", color="k" if k == 0 else "0.45", lw=1.2, label=f"model {vin:.1f} m/s")
        for ax in (ax_t, ax_x):
            ax.set_ylabel("Force on the ball [N]")
            if picks:
                ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
                if not fit_ok:
                    ax.plot([], [], ls="none", label=f"model: {_NO_FIT}")
                _legend_with_headroom(ax)
        ax_t.set_xlabel("Time since first contact [ms]")
        ax_x.set_xlabel("Centre-of-mass displacement [mm]")
    fig.suptitle("Measured and modelled force at the lowest and highest good speed (cf. Fig. 9)")


def fig_force_curves(ds) -> Figure:
    """Measured against modelled force-time and force-displacement curves (paper Fig. 9).

    For each ball type, the good impacts at the lowest and the highest inbound
    speed: measured force [N] against time [ms] and against centre-of-mass
    displacement [mm], with the fitted model (Eq. (14) in Goodwill & Haake 2004,
    simulated at the same speed) dashed.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_force_curves, ds)


# ----------------------------------------------------------------------------- Fig. 10


def _nearest_good(ds, ball, speed, tol):
    good = [i for i in ar.impacts(ds, ball, "ok", quantity_ok="kcal") if ar.contact_series(ds, i)[0].size >= 2]
    if not good:
        return None
    d = np.array([abs(ar.impact_value(ds, "vin_m_s", i) - speed) for i in good])
    if not np.isfinite(d).any():
        return None
    j = int(np.nanargmin(d))
    return good[j] if d[j] <= tol else None


def draw_components(fig, ds):
    """Draw force components [N] of Eq. (14) at 20 m/s against time [ms] (:func:`fig_components`) into
    ``fig``, a matplotlib Figure or SubFigure; ``ds`` is the session archive."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    balls = ar.balls(ds)
    if not balls:
        _empty(fig)
        return
    ncols = 1 if len(balls) == 1 else 2
    axes = _grid(fig, len(balls), ncols)
    t_ms = np.asarray(ds["model_time_s"].values, dtype=float) * 1e3 if "model_time_s" in ds else None
    parts = (
        ("comp_total_force_N", "total model force", "k", 1.8),
        ("comp_stiffness_force_N", "structural stiffness kB x", "C0", 1.2),
        ("comp_damping_force_N", "material damping cB x'", "C2", 1.2),
        ("comp_momentum_flux_force_N", "momentum flux cM x'", "C3", 1.2),
    )
    for ax, ball in zip(axes, balls):
        drawn = False
        if t_ms is not None:
            for name, _, c, lw in parts:
                y = ar.ball_array(ds, name, ball)
                if y is not None and np.isfinite(y).any():
                    ax.plot(t_ms, y, "-", color=c, lw=lw)
                    drawn = True
        i = _nearest_good(ds, ball, COMPONENT_SPEED_M_S, COMPONENT_SPEED_TOLERANCE_M_S)
        title = ar.ball_label(ds, ball)
        if i is not None:
            t, f = ar.contact_series(ds, i, "force_N")
            ax.plot(t * 1e3, f, "-", color="0.6", lw=1.0, zorder=1)
            vin = ar.impact_value(ds, "vin_m_s", i)
            title += f" (measured: {ar.text_values(ds['impact_id'].values)[i]}, {vin:.1f} m/s)"
        ax.set_title(title, loc="left")
        if drawn or i is not None:
            ax.axhline(0.0, color="0.5", lw=0.6)
        if drawn:
            ax.axvspan(0, 0.6, color="C3", alpha=0.07, lw=0)
        elif i is not None:
            _corner_note(ax, _NO_FIT)
        else:
            _note(ax, f"{_NO_GOOD}\n{_NO_FIT}")
        ax.set_xlabel("Time since first contact [ms]")
        ax.set_ylabel("Force [N]")
    handles = [Line2D([], [], color=c, lw=lw, label=lab) for _, lab, c, lw in parts]
    handles.append(Line2D([], [], color="0.6", lw=1.0, label="measured, good impact nearest 20 m/s"))
    handles.append(Patch(color="C3", alpha=0.15, label="first 0.6 ms"))
    fig.legend(handles=handles, loc="outside lower center", ncols=3, fontsize=8)
    fig.suptitle(f"Force components of the fitted model at {COMPONENT_SPEED_M_S:.0f} m/s (cf. Fig. 10)")


def fig_components(ds) -> Figure:
    """Structural, damping and momentum-flux force components at 20 m/s (paper Fig. 10).

    One panel per ball type: the total model force and its three components
    kB x, cB x' and cM x' [N] (Eq. (14) in Goodwill & Haake 2004) against time
    [ms] with the fitted parameters, and the measured force of the good impact
    nearest 20 m/s (within 2.5 m/s) in grey.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_components, ds)


# ----------------------------------------------------------------------------- Fig. 2b


def _kelvin_voigt_curve(ds, i):
    """Kelvin-Voigt force of impact i up to its own end (x back to 0), else its stored ``kv_force_N``."""
    curve = kelvin_voigt_contact(ar.impact_value(ds, "vin_m_s", i), ar.impact_value(ds, "impact_mass_kg", i),
                                 ar.impact_value(ds, "kv_stiffness_kN_m", i) * 1e3,
                                 ar.impact_value(ds, "kv_damping_N_s_m", i))
    if curve is not None:
        return curve
    t, f = ar.contact_series(ds, i, "kv_force_N")
    keep = np.isfinite(f)
    return (t[keep], f[keep]) if keep.sum() >= 2 else None


def draw_kelvin_voigt(fig, ds):
    """Draw Kelvin-Voigt force of Eqs. (1)-(3) [N] against the measured one (:func:`fig_kelvin_voigt`) into
    ``fig``, a matplotlib Figure or SubFigure; ``ds`` is the session archive."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    balls = ar.balls(ds)
    if not balls:
        _empty(fig)
        return
    ncols = 1 if len(balls) == 1 else 2
    axes = _grid(fig, len(balls), ncols)
    colors = _colors(ds)
    for ax, ball in zip(axes, balls):
        ax.set_xlabel("Time since first contact [ms]")
        ax.set_ylabel("Force [N]")
        good = [i for i in ar.impacts(ds, ball, "ok", quantity_ok="kcal") if ar.contact_series(ds, i)[0].size >= 2]
        vins = [ar.impact_value(ds, "vin_m_s", i) for i in good]
        if not good or not np.isfinite(vins).any():
            ax.set_title(ar.ball_label(ds, ball), loc="left")
            _note(ax, _NO_GOOD)
            continue
        i = good[int(np.nanargmax(vins))]
        vin = ar.impact_value(ds, "vin_m_s", i)
        t, f = ar.contact_series(ds, i, "force_N")
        ax.plot(t * 1e3, f, "-", color=colors[ball], lw=1.4)
        kv = _kelvin_voigt_curve(ds, i)
        if kv is not None:
            tk, fk = kv
            ax.plot(tk * 1e3, fk, "--", color="C3", lw=1.4)
            neg = fk < 0
            if neg.any():
                ax.fill_between(tk * 1e3, fk, 0, where=neg, color="C3", alpha=0.25, lw=0)
                ax.text(0.03, 0.04, f"tensile tail: min {np.nanmin(fk):.0f} N", transform=ax.transAxes,
                        ha="left", va="bottom", color="C3", fontsize=8)
        sim = impact_model_curve(ar.fitted_parameters(ds, ball), vin, ar.impact_value(ds, "impact_mass_kg", i))
        if sim is not None:
            ax.plot(sim[0] * 1e3, sim[1], ":", color="k", lw=1.4)
        else:
            _corner_note(ax, f"improved model: {_NO_FIT}")
        ax.axhline(0.0, color="0.4", lw=0.7)
        ax.set_title(f"{ar.ball_label(ds, ball)}, VB = {vin:.1f} m/s ({ar.text_values(ds['impact_id'].values)[i]})", loc="left")
    handles = [
        Line2D([], [], color="0.25", lw=1.4, label="measured (ball colour)"),
        Line2D([], [], color="C3", ls="--", lw=1.4, label="Kelvin-Voigt, Eqs (1)-(3)"),
        Patch(color="C3", alpha=0.25, label="tensile (negative) force"),
        Line2D([], [], color="k", ls=":", lw=1.4, label="improved model, Eq. (14)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=8)
    fig.suptitle("Kelvin-Voigt model against measured force, fastest good impact of each ball (cf. Fig. 2b)")


def fig_kelvin_voigt(ds) -> Figure:
    """Kelvin-Voigt force against the measured force of each ball's fastest good impact (paper Fig. 2b).

    The Kelvin-Voigt force F = kB x + cB x' with kB and cB of Eqs. (2)-(3) in
    Goodwill & Haake 2004 (from the impact's TC and COR), up to the return of x to
    zero; its tensile (negative) tail is shaded. The improved model (Eq. (14)) is
    dotted. Force [N] against time [ms].

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return render(draw_kelvin_voigt, ds)


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
