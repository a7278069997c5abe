"""The PDF report's page layout: A4 pages, footers, a text cursor, tables, figures placed or drawn, printable text."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from . import figures as _fig

__all__ = ["A4_PORTRAIT_IN"]

#: A4 portrait page size [in].
A4_PORTRAIT_IN = (8.27, 11.69)
_MARGIN_IN = 0.6  # page margin [in]

MAX_SHOWN_CHARS = 400  # longest text taken from the data onto a page (file names, reasons) [characters]


def _text(value, max_chars: int = MAX_SHOWN_CHARS) -> str:
    """Text from the archive as it can be printed: control characters escaped, at most
    ``max_chars`` (a 10 000-character trace path must not push a page's figure off it); a longer
    text keeps its start and end, cut between words where it has spaces."""
    if value is None:
        return ""
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    text = "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in str(value))
    if len(text) > max_chars:
        half = max_chars // 2 - 2
        head, tail = text[:half], text[-half:]
        if " " in head[half // 2:]:
            head = head[:head.rindex(" ")]
        if " " in tail[:half // 2]:
            tail = tail[tail.index(" ") + 1:]
        text = f"{head} ... {tail}"
    return text


def _page() -> Figure:
    fig = Figure(figsize=A4_PORTRAIT_IN)
    FigureCanvasAgg(fig)
    return fig


def _footer(fig, info, page_label):
    w, h = A4_PORTRAIT_IN
    fig.text(_MARGIN_IN / w, 0.35 / h, f"ballimpact {info['software_version']} - session {info['session_id']}",
             fontsize=7, color="0.4", ha="left")
    fig.text(1 - _MARGIN_IN / w, 0.35 / h, page_label, fontsize=7, color="0.4", ha="right")


class _Cursor:
    """Top-down text placement on a page, in inches from the top."""

    def __init__(self, fig, top_in=_MARGIN_IN):
        self.fig = fig
        self.y = top_in
        self.w, self.h = A4_PORTRAIT_IN

    def text(self, x_in, s, *, size=9.5, dy=None, **kw):
        self.fig.text(x_in / self.w, 1 - self.y / self.h, s, fontsize=size, va="top", ha="left", **kw)
        n_lines = s.count("\n") + 1
        self.y += dy if dy is not None else n_lines * size * 1.45 / 72.0

    def skip(self, dy_in):
        self.y += dy_in


def _fmt(value, fmt) -> str:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "-"
    if not np.isfinite(v):
        return "-"
    return format(v, fmt).replace(",", "\u2009")


def _table(ax, cells, col_widths, *, header_rows=1, font_size=8, row_height=None, bold_first_col=False,
           shade_rows=()):
    """A plain table filling ``ax`` (cells: list of rows of str)."""
    ax.set_axis_off()
    table = ax.table(cellText=cells, colWidths=col_widths, loc="upper center", cellLoc="center",
                     bbox=[0, 0, 1, 1])
    table.auto_set_font_size(False)
    table.set_fontsize(font_size)
    for (r, c), cell in table.get_celld().items():
        cell.set_edgecolor("0.75")
        cell.set_linewidth(0.5)
        if r < header_rows:
            cell.set_facecolor("0.88")
            cell.get_text().set_fontweight("bold")
        elif r in shade_rows:
            cell.set_facecolor("0.96")
        if c == 0 and r >= header_rows:
            cell.get_text().set_ha("left")
            cell.PAD = 0.03
            if bold_first_col:
                cell.get_text().set_fontweight("bold")
    return table


CELL_PAD_IN = 0.05  # room left and right of a table cell's text [in]


def _fit_columns(fig, ax, table, font_size: float, *, min_font: float = 5.0) -> float:
    """Widen each column of ``table`` to its widest text and shrink the font [pt] until the columns fit the
    axes' width; returns the font size used."""
    renderer = fig.canvas.get_renderer()
    width_px = ax.get_window_extent(renderer).width
    pad = 2 * CELL_PAD_IN * fig.dpi
    cells = table.get_celld()
    n_cols = 1 + max(c for _, c in cells)
    size = font_size
    while True:
        table.set_fontsize(size)
        need = [0.0] * n_cols
        for (_, c), cell in cells.items():
            text = cell.get_text()
            if text.get_text():
                need[c] = max(need[c], text.get_window_extent(renderer).width + pad)
        if sum(need) <= width_px or size <= min_font:
            break
        size = max(min_font, size * min(0.95, width_px / sum(need)))
    need = [max(n, pad) for n in need]
    spare = max(width_px - sum(need), 0.0)
    widths = [(n + spare * n / sum(need)) / width_px for n in need]
    for (_, c), cell in cells.items():
        cell.set_width(widths[c])
        if c == 0:
            cell.PAD = CELL_PAD_IN * fig.dpi / (widths[c] * width_px)
    return size


def _place_png(fig, png, top_in: float, max_h_in: float):
    """Put a PNG (a file, or its pixels as an array) on the page below top_in, as wide as the text, within max_h_in."""
    import matplotlib.image as mpimg

    img = png if isinstance(png, np.ndarray) else mpimg.imread(str(png))
    w, h = A4_PORTRAIT_IN
    avail_w = w - 2 * _MARGIN_IN
    aspect = img.shape[0] / img.shape[1]
    width = avail_w
    height = width * aspect
    if height > max_h_in:
        height, width = max_h_in, max_h_in / aspect
    left = (w - width) / 2
    ax = fig.add_axes([left / w, 1 - (top_in + height) / h, width / w, height / h])
    ax.imshow(img, interpolation="antialiased")
    ax.set_axis_off()
    return height


def _draw_into_page(fig, draw, top_in: float, height_in: float):
    """Draw a figure function's content into a region of the page (vector)."""
    w, h = A4_PORTRAIT_IN
    bottom = h - top_in - height_in
    side = _MARGIN_IN - 0.15  # constrained layout adds a little padding of its own
    # a constrained-layout subfigure spanning the region; the rest of the page is free text
    gs = fig.add_gridspec(
        3, 3, height_ratios=[top_in, height_in, max(bottom, 0.01)], width_ratios=[side, w - 2 * side, side],
        hspace=0, wspace=0,
    )
    sub = fig.add_subfigure(gs[1, 1])
    with _fig.figure_style():
        draw(sub)
    return sub


def _figure_file(figures_dir, name, images):
    """A figure file of figures_dir to place on a page: its pixels from ``images`` when there,
    else the file when it exists, else None (the figure is then drawn)."""
    if images is not None and name in images:
        return images[name]
    png = Path(figures_dir) / name if figures_dir is not None else None
    return png if png is not None and png.is_file() else None


def _hline(fig, y_in):
    from matplotlib.lines import Line2D

    w, h = A4_PORTRAIT_IN
    return Line2D([_MARGIN_IN / w, 1 - _MARGIN_IN / w], [1 - y_in / h] * 2, transform=fig.transFigure,
                  color="0.6", lw=0.6)
