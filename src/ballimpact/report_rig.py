"""The rig page of the PDF report: the session's rig with 95 % intervals and sources, its warnings and figures."""

from __future__ import annotations

import math
import textwrap

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .figure_registry import REPORT_FIGURES
from .rig import DETECT_Z, RIG_QUANTITIES
from .rig_archive import plate_impacts, read_rig, rig_warnings

__all__ = ["RIG_ROWS", "RIG_PAGE_FIGURES", "MAX_RIG_WARNING_LINES", "rig_table_rows", "rig_page"]

#: How each quantity of :data:`ballimpact.rig.RIG_QUANTITIES` is shown on the rig page: label, unit, and the factor
#: from the archive's unit (``rig_unit``) to it.
RIG_ROWS = {
    "plate_resonance_hz": ("Plate resonance fn", "kHz", 1e-3),
    "plate_damping_ratio": ("Plate damping ratio \u03b6", "-", 1.0),
    "time_constant_s": ("Amplifier time constant \u03c4", "s", 1.0),
    "mains_hz": ("Mains frequency", "Hz", 1.0),
    "hum_amplitude_V": ("Hum amplitude (median)", "mV", 1e3),
    "noise_rms_V": ("Noise RMS (median)", "mV", 1e3),
    "kcal_N_per_V": ("kCAL (median over the ok impacts)", "N/V", 1.0),
    "kcal_spread": ("kCAL spread between impacts", "%", 100.0),
}
#: The figures of the registry placed on the rig page, in order.
RIG_PAGE_FIGURES = tuple(f for f in REPORT_FIGURES if f.page == "rig")
#: Lines of the rig's warnings on the page; more are counted [-].
MAX_RIG_WARNING_LINES = 8
_CAPTION_PT = 7.3  # font size of a figure's caption on the rig page [pt]
_CAPTION_CHARS = 135  # characters of one of its lines [-]


def _number(value: float, fmt: str = ".4g") -> str:
    if not math.isfinite(value):
        return "\u221e" if value > 0 else "-"
    return format(value, fmt)


def rig_table_rows(ds) -> tuple[list[list[str]], list[str]]:
    """The rig page's table: one row per quantity (label, value, 95 % interval, unit, source, impacts, note mark),
    and the notes the marks refer to (each text once).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive with the rig variables (:func:`ballimpact.rig_archive.rig_variables`).

    Returns
    -------
    rows : list of list of str
        Empty when the archive has no rig.
    notes : list of str
        Note ``k`` is marked ``(k)`` (from 1) in the rows.
    """
    rig = read_rig(ds)
    rows, notes = [], []
    for name in list(RIG_QUANTITIES) + [n for n in rig if n not in RIG_QUANTITIES]:
        if name not in rig:
            continue
        est = rig[name]
        label, unit, scale = RIG_ROWS.get(name, (name, RIG_QUANTITIES.get(name, ("", ""))[0], 1.0))
        value = _number(est.value * scale)
        interval = "-"
        if est.source == "identified" and math.isfinite(est.low) and math.isfinite(est.value):
            interval = f"[{_number(est.low * scale)}, {_number(est.high * scale)}]"
        mark = ""
        if est.note:
            if est.note not in notes:
                notes.append(est.note)
            mark = f"({notes.index(est.note) + 1})"
        rows.append([label, value, interval, unit, est.source, str(est.n_impacts) if est.n_impacts else "-", mark])
    return rows, notes


def _plate_line(ds) -> str:
    """What the plate's fit rests on: impacts, detection statistic and ringing amplitude."""
    attrs = ds["rig_value"].attrs
    z = float(attrs.get("plate_detection_z", math.nan))
    fraction = float(attrs.get("plate_ringing_fraction", math.nan))
    n = len(plate_impacts(ds))
    if not n:
        return "The plate's free ringing: no impact had one long enough to fit."
    text = (f"The plate's free ringing was fitted over {n} impacts (pooled): it stands z = {_number(z, '.3g')} "
            f"deviations above chance ({DETECT_Z:g} needed for a plate)")
    if math.isfinite(fraction):
        text += f"; at each ringing's start it is {100 * fraction:.2g} % of its contact's peak (median)"
    return text + "."


def rig_page(ds, info, figures_dir=None, images=None) -> Figure:
    """The rig page of the session report (one A4 page).

    A table of the session's rig (:data:`ballimpact.rig.RIG_QUANTITIES`: value, 95 % interval, unit, source
    stated / identified / none, impacts it rests on, and the note of a quantity not known or beside a stated value),
    the warnings of its identification (stated keys the traces disagree with), and the figures of
    :data:`RIG_PAGE_FIGURES`, each with a short caption: their PNG files from ``figures_dir`` (or ``images``) when
    there, else drawn from ``ds``.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    info : dict
        The session's metadata for the footer (``ballimpact.report``'s).
    figures_dir : str or Path, optional
        Folder of the figure files (:func:`ballimpact.figures.save_all`).
    images : dict, optional
        Their pixels by path relative to ``figures_dir``.

    Returns
    -------
    matplotlib.figure.Figure
        A page of 8.27 x 11.69 in.
    """
    from . import report_layout as _r

    margin = _r._MARGIN_IN
    pngs = [_r._figure_file(figures_dir, spec.file_name, images) for spec in RIG_PAGE_FIGURES]
    if all(p is not None for p in pngs):
        fig = _r._page()
    else:
        fig = Figure(figsize=_r.A4_PORTRAIT_IN, layout="constrained")
        FigureCanvasAgg(fig)
        fig.get_layout_engine().set(w_pad=0.04, h_pad=0.04)
    cur = _r._Cursor(fig)
    cur.text(margin, "The session's rig", size=14, weight="bold", dy=0.34)
    intro = ("One plate, one charge amplifier and one mains supply serve every impact of a session: each quantity "
             "is identified once from all the impacts (pooled), or taken as session.yaml states it; the archive "
             "holds them as rig_value, rig_low, rig_high, rig_source on its rig_quantity dimension.")
    cur.text(margin, "\n".join(textwrap.wrap(intro, 120)), size=8.5)
    cur.skip(0.08)
    _rig_table(fig, cur, ds)
    _rig_warnings(cur, ds)
    cur.skip(0.12)
    _rig_figures(fig, cur, ds, pngs)
    _r._footer(fig, info, "Rig")
    return fig


def _rig_table(fig, cur, ds) -> None:
    """The rig's table, its numbered notes and the plate fit's line, at the cursor; or why there is none."""
    from . import report_layout as _r

    w, h = _r.A4_PORTRAIT_IN
    margin = _r._MARGIN_IN
    rows, notes = rig_table_rows(ds)
    if not rows:
        cur.text(margin, "This archive has no rig variables: it was written before ballimpact identified the rig "
                         "(re-run the session).", size=9)
        return
    head = ["Quantity", "Value", "95 % interval", "Unit", "Source", "Impacts", "Note"]
    row_h = 0.2
    table_h = row_h * (len(rows) + 1)
    ax = fig.add_axes([margin / w, 1 - (cur.y + table_h) / h, (w - 2 * margin) / w, table_h / h])
    table = _r._table(ax, [head] + rows, [0.3, 0.12, 0.2, 0.07, 0.11, 0.09, 0.06], font_size=8)
    _r._fit_columns(fig, ax, table, 8.0)
    cur.skip(table_h + 0.1)
    note_lines = []
    for k, note in enumerate(notes, 1):
        note_lines += textwrap.wrap(f"({k}) {_r._text(note)}", 112, subsequent_indent="     ")
    if note_lines:
        cur.text(margin, "\n".join(note_lines[:8]), size=7.8, color="0.25")
    cur.text(margin, "\n".join(textwrap.wrap(_plate_line(ds), 112)), size=7.8, color="0.25")


def _rig_warnings(cur, ds) -> None:
    """The warnings of the rig's identification (stated keys the traces disagree with), at most
    MAX_RIG_WARNING_LINES lines."""
    from . import report_layout as _r

    warned = rig_warnings(ds)
    if not warned:
        return
    margin = _r._MARGIN_IN
    cur.skip(0.05)
    cur.text(margin, f"Warnings: {len(warned)} stated key(s) the traces disagree with", size=9, weight="bold",
             color="#8a4b00")
    lines: list[str] = []
    for k, warning in enumerate(warned):
        wrapped = textwrap.wrap("- " + _r._text(warning), 120, subsequent_indent="  ")
        if len(lines) + len(wrapped) > MAX_RIG_WARNING_LINES:
            lines.append(f"- and {len(warned) - k} more (the archive's rig_value attribute rig_warnings).")
            break
        lines.extend(wrapped)
    cur.text(margin, "\n".join(lines), size=8, color="#8a4b00")


def _rig_figures(fig, cur, ds, pngs) -> None:
    """The figures of RIG_PAGE_FIGURES with their captions, shrunk to the room left on the page."""
    from . import report_layout as _r

    h = _r.A4_PORTRAIT_IN[1]
    margin = _r._MARGIN_IN
    captions = ["\n".join(textwrap.wrap(f"{spec.title}. {spec.caption}", _CAPTION_CHARS))
                for spec in RIG_PAGE_FIGURES]
    caption_h = [(c.count("\n") + 1) * _CAPTION_PT * 1.45 / 72 + 0.12 for c in captions]
    room = h - cur.y - margin - 0.15 - sum(caption_h)
    heights = [spec.height_in for spec in RIG_PAGE_FIGURES]
    shrink = min(1.0, room / sum(heights)) if sum(heights) > 0 else 1.0
    for spec, png, caption, height in zip(RIG_PAGE_FIGURES, pngs, captions, heights):
        height *= shrink
        if png is not None:
            used = _r._place_png(fig, png, cur.y, height)
        else:
            _r._draw_into_page(fig, lambda f, draw=spec.draw: draw(f, ds), cur.y, height)
            used = height
        cur.skip(used + 0.05)
        cur.text(margin, caption, size=_CAPTION_PT, color="0.2")
        cur.skip(0.07)
