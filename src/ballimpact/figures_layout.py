"""The frame of every session figure: style, size, a fixed layout around its texts, the synthetic mark, notes."""

from __future__ import annotations

import textwrap
from contextlib import contextmanager

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator

from . import archive_read as ar
from .figure_registry import report_figure

__all__ = ["DPI", "figure_style", "render"]

#: Resolution of the PNG files [dots per inch].
DPI = 150

#: Width of the figures [in]; they are read on A4 paper.
FIGURE_WIDTH_IN = 7.5

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
