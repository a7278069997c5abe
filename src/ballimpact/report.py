"""The PDF session report: summary page, one page per figure, the exclusion list and the QC appendix (matplotlib PdfPages)."""

from __future__ import annotations

import datetime
import math
import re
import textwrap
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure

from . import archive_read as ar
from . import figures as _fig
from . import report_rig
from . import summary as _summary
from .atomic import atomic_path
from .figure_registry import QC_DIR_NAME, REPORT_FIGURES, report_figure
from .model_data import force_agreement

__all__ = ["A4_PORTRAIT_IN", "FIGURE_CAPTIONS", "conditioning_summary", "impact_conditioning", "itf_comparison",
           "session_warnings", "write_report", "report_pages", "report_page_count"]

#: A4 portrait page size [in].
A4_PORTRAIT_IN = (8.27, 11.69)
_MARGIN_IN = 0.6  # page margin [in]
_SOURCE_SHORT = {"extrapolated": "extrap.", "fitted": "fitted"}

#: Title and caption of each report figure with a page of its own by PNG file name, in report order
#: (from :data:`ballimpact.figure_registry.REPORT_FIGURES`; the rig's are on the rig page, :mod:`.report_rig`).
FIGURE_CAPTIONS = {f.file_name: (f.title, f.caption) for f in REPORT_FIGURES if f.page == "own"}


MAX_SHOWN_CHARS = 400  # longest text taken from the data onto a page (file names, reasons) [characters]
MAX_DESCRIPTION_CHARS = 1200  # longest session description shown on page 1 [characters]
DESCRIPTION_LINES = 10  # lines of the description on page 1; a longer one ends with " ..." between words [-]
MIN_DESCRIPTION_LINES = 3  # fewest lines of it when the parameter table needs the room [-]
LEGIBLE_TABLE_PT = 6.5  # smallest font [pt] of the parameter table before the description gives up lines
_NOTES_RESERVE_IN = 0.55  # room kept under the table and its fit warnings for the no-fit notes and the reference [in]
MAX_NOTE_LINES = 8  # lines of one fit warning under the parameter table [-]
MIN_NOTE_LINES = 2  # fewest lines of it when the parameter table needs the room [-]
NOTE_CHARS = 98  # characters of a line of a fit warning (8.5 pt bold, the text width) [-]
MAX_WARNING_LINES = 24  # lines of session warnings before the list of excluded impacts; the rest are counted [-]


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


def _session_info(ds) -> dict:
    """Session metadata from the archive attributes (falling back on the session YAML)."""
    attrs = ds.attrs
    info = {
        "session_id": _text(attrs.get("session_id", "")),
        "date": _text(attrs.get("session_date", "")),
        "operator": _text(attrs.get("operator", "")),
        "description": _text(attrs.get("session_description", ""), MAX_DESCRIPTION_CHARS),
        "software_version": _text(attrs.get("software_version", "")),
        "date_created": _text(attrs.get("date_created", "")),
        "synthetic": False,
    }
    yaml_text = attrs.get("session_yaml")
    if yaml_text and not (info["date"] and info["operator"] and info["description"]):
        try:
            import yaml

            meta = yaml.safe_load(_text(yaml_text)) or {}
        except Exception:  # the report still renders without the YAML fields
            meta = {}
        if isinstance(meta, dict):
            for key in ("date", "operator", "description", "session_id"):
                if not info[key] and meta.get(key) is not None:
                    info[key] = _text(meta[key])
            if "synthetic" not in attrs and meta.get("synthetic") is True:
                info["synthetic"] = True
    syn = attrs.get("synthetic", None)
    if syn is not None:
        if isinstance(syn, str):
            info["synthetic"] = syn.strip().lower() in ("1", "true", "yes")
        else:
            try:
                info["synthetic"] = bool(np.asarray(syn).ravel()[0])
            except (IndexError, TypeError, ValueError):
                info["synthetic"] = False
    return info


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


def _ball_values(ds, ball):
    get = lambda name: ar.ball_value(ds, name, ball)  # noqa: E731
    return get


def _counts(ds):
    balls = ar.balls(ds)
    rows = []
    for ball in balls:
        total = ar.impacts(ds, ball).size
        ok = ar.impacts(ds, ball, "ok").size
        used = ar.ball_value(ds, "n_impacts", ball)
        rows.append((ball, total, ok, total - ok, used))
    return rows


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


def _interval(value, lo, hi, fmt) -> str:
    main = _fmt(value, fmt)
    if main == "-":
        return "-"
    lo_s, hi_s = _fmt(lo, fmt), _fmt(hi, fmt)
    if lo_s == "-" or hi_s == "-":
        return main
    return f"{main}\n[{lo_s}, {hi_s}]"


def _force_curve_validation(ds) -> list[str]:
    """One line per ball: mean share of the contact after 0.2 ms where model and measured
    force agree within 10 % of the peak, and the mean RMS difference [N]."""
    needed = ("model_agreement_fraction", "model_rms_N", "ball_type", "status")
    if not all(name in ds for name in needed):
        return []
    balls = np.array([str(b) for b in ds["ball_type"].values])
    ok = np.array([str(v) == "ok" for v in ds["status"].values])
    share = np.asarray(ds["model_agreement_fraction"].values, dtype=float)
    rms = np.asarray(ds["model_rms_N"].values, dtype=float)
    lines = []
    for ball in ar.balls(ds):
        use = ok & (balls == ball) & np.isfinite(share) & np.isfinite(rms)
        if use.any():
            lines.append(
                f"{ar.ball_label(ds, ball)}: within 10 % of the peak for {100 * share[use].mean():.1f} % of the "
                f"contact after 0.2 ms (lowest {100 * share[use].min():.1f} %), RMS difference "
                f"{rms[use].mean():.0f} N, over {int(use.sum())} impacts"
            )
    return lines


def itf_comparison(ds) -> list[str]:
    """One sentence per ball on the ITF 254 cm drop test: the fitted model's predicted rebound (95 %
    interval) against the measured one when given, and how far the model's COR at the drop-test
    speed [m/s] is from the drop test's COR, computed from the archive's numbers."""
    needed = ("itf_rebound_pred_cm", "itf_impact_speed_m_s")
    if "ball" not in ds.coords or not all(n in ds for n in needed):
        return []
    from .itf import ITF_REBOUND_MAX_M, ITF_REBOUND_MIN_M

    lines = []
    for ball in ar.balls(ds):
        get = _ball_values(ds, ball)
        pred, lo, hi = (float(get(n)) for n in ("itf_rebound_pred_cm", "itf_rebound_pred_cm_lo",
                                                 "itf_rebound_pred_cm_hi"))
        meas = float(get("itf_rebound_cm")) if "itf_rebound_cm" in ds else math.nan
        v = float(get("itf_impact_speed_m_s"))
        if not math.isfinite(pred):
            if math.isfinite(meas):
                lines.append(f"{ar.ball_label(ds, ball)}: measured {meas:.1f} cm, no model prediction (no fit)")
            continue
        interval = f" [{lo:.1f}, {hi:.1f}]" if math.isfinite(lo) and math.isfinite(hi) else ""
        passes = ITF_REBOUND_MIN_M * 100 <= pred <= ITF_REBOUND_MAX_M * 100
        text = (f"{ar.ball_label(ds, ball)}: the model predicts a rebound of {pred:.1f} cm{interval} "
                f"({'inside' if passes else 'outside'} the 134.6-147.3 cm pass range)")
        cor_model = float(get("itf_model_cor")) if "itf_model_cor" in ds else math.nan
        cor_meas = float(get("itf_drop_test_cor")) if "itf_drop_test_cor" in ds else math.nan
        if math.isfinite(meas):
            text += f"; measured {meas:.1f} cm, {pred - meas:+.1f} cm"
            if math.isfinite(cor_model) and math.isfinite(cor_meas):
                text += (f"; at the drop-test speed of {v:.2f} m/s the model's COR {cor_model:.3f} is "
                         f"{abs(cor_model - cor_meas):.3f} {'above' if cor_model > cor_meas else 'below'} the "
                         f"drop test's {cor_meas:.3f}")
        lo_fit = float(get("fit_vin_min_m_s")) if "fit_vin_min_m_s" in ds else math.nan
        if math.isfinite(lo_fit) and v < lo_fit:
            text += f" (an extrapolation: the slowest impact fitted was {lo_fit:.1f} m/s)"
        lines.append(text)
    return lines


def _conditioned(ds, *, good_only: bool = False) -> np.ndarray:
    """Positions of the impacts whose trace was conditioned (a time-constant source recorded);
    with ``good_only`` those of the ok impacts when there are any (a faulty trace, clipped or
    with two contacts, can bias its own estimates)."""
    if "amplifier_time_constant_source" not in ds or not ds.sizes.get("impact", 0):
        return np.array([], dtype=int)
    done = ar.text_values(ds["amplifier_time_constant_source"].values) != ""
    ok = done & (ar.text_values(ds["status"].values) == "ok")
    return np.flatnonzero(ok if good_only and ok.any() else done)


def _range_text(values, fmt, unit) -> str:
    """``median X unit (lo-hi)`` of finite values; one value when they all round alike."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return f"- {unit}"
    med, lo, hi = (format(x, fmt) for x in (np.median(v), v.min(), v.max()))
    return f"{med} {unit}" if lo == hi else f"median {med} {unit} ({lo}-{hi} {unit})"


def conditioning_summary(ds) -> list[str]:
    """Sentences on how the session's traces were conditioned, for the summary page.

    Over the good impacts (all conditioned traces when none is good): says where
    the charge-amplifier time constant came from (``plate.time_constant_s``
    or estimated per trace, with its median and range [s]), which mains hum was removed
    (given or detected, its amplitude [mV]) and in how many traces a plate resonance
    was undone. When the time constant was estimated it recommends giving it: a
    step of the baseline inside a contact and the amplifier's own undershoot look
    alike to one trace's estimate (the session time-constant check sees it only where
    the other impacts disagree; a known time constant always).

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive (:mod:`ballimpact.archive`); an archive without the
        conditioning variables gives no sentences.

    Returns
    -------
    list of str
        One sentence per item; empty when no trace was conditioned.
    """
    idx = _conditioned(ds, good_only=True)
    if idx.size == 0:
        return []
    of = f"of {idx.size} {'good ' if (ar.text_values(ds['status'].values)[idx] == 'ok').all() else ''}impacts"
    tau = np.asarray(ds["amplifier_time_constant_s"].values, dtype=float)[idx]
    tau_source = ar.text_values(ds["amplifier_time_constant_source"].values)[idx]
    lines = []
    given = tau_source == "given"
    if given.all():
        lines.append(f"Charge-amplifier decay undone with plate.time_constant_s = {_range_text(tau[given], '.4g', 's')}.")
    else:
        estimated = tau_source == "estimated"
        parts = []
        if estimated.any():
            parts.append(f"estimated from the trace in {int(estimated.sum())} {of}, "
                         f"{_range_text(tau[estimated], '.3g', 's')}")
        if (tau_source == "none").any():
            parts.append(f"not corrected in {int((tau_source == 'none').sum())} (too slow to matter, or refused)")
        if given.any():
            parts.append(f"given for {int(given.sum())}")
        lines.append("Charge-amplifier time constant " + "; ".join(parts) + ". Give plate.time_constant_s in "
                     "session.yaml when it is known: with it the decay is undone exactly, and a step of the "
                     "baseline inside a contact is told from the amplifier's undershoot.")
    mains_source = ar.text_values(ds["mains_source"].values)[idx]
    mains = np.asarray(ds["mains_frequency_hz"].values, dtype=float)[idx]
    hum_mV = 1e3 * np.asarray(ds["hum_amplitude_V"].values, dtype=float)[idx]
    hummed = np.isfinite(mains) & (mains > 0)
    if hummed.any():
        freqs = ", ".join(f"{f:g} Hz" for f in np.unique(mains[hummed]))
        how = sorted(set(mains_source[hummed]))
        lines.append(f"Mains hum at {freqs} ({' and '.join(how)}) removed in {int(hummed.sum())} {of}, "
                     f"fundamental {_range_text(hum_mV[hummed], '.2g', 'mV')}.")
    else:
        lines.append("No mains hum removed" + (" (daq.mains_hz given, none fitted)." if (mains_source == "given").any()
                                               else ": none found in the traces."))
    plate = np.asarray(ds["plate_resonance_hz"].values, dtype=float)[idx]
    if np.isfinite(plate).any():
        lines.append(f"Plate resonance identified from its ringing and undone in {int(np.isfinite(plate).sum())} "
                     f"{of}, {_range_text(plate[np.isfinite(plate)] / 1e3, '.3g', 'kHz')}.")
    return lines


def session_warnings(ds) -> list[str]:
    """The warnings of reading and validating the session, as the report shows them.

    The archive's ``validate_warnings`` (usable but suspect input: a sample rate too slow
    to rule out an aliased plate without ``daq.bandwidth_hz``, a sample rate or polarity
    the traces disagree with, an unknown key, ...), each without the raw folder's path
    before ``session.yaml`` or ``impacts.csv``. The summary page counts them; the list of
    excluded impacts opens with them.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive (:mod:`ballimpact.archive`).

    Returns
    -------
    list of str
        One text per warning; empty when the session gave none (or the archive holds none).
    """
    return [re.sub(r"^.*?[/\\]((?:session\.ya?ml|impacts\.csv): )", r"\1", " ".join(w.split()))
            for w in ar.validate_warnings(ds)]


def impact_conditioning(ds, i: int) -> str:
    """How impact ``i``'s trace was conditioned, in one line for its QC page ('' when it was not).

    Noise [mV], hum [mV] at the mains frequency [Hz] and its source, the
    charge-amplifier time constant [s] and its source, and the plate resonance [kHz]
    undone. (No standard error of an estimated time constant: it does not count the
    choice of hum model on a short record; docs/accuracy.md.)
    """
    def num(name):
        return float(np.asarray(ds[name].values, dtype=float)[i])

    def text(name):
        return str(ar.text_values(ds[name].values)[i])

    if "amplifier_time_constant_source" not in ds or not text("amplifier_time_constant_source"):
        return ""  # not conditioned: excluded before, or an archive from before these variables

    parts = [f"noise {_fmt(1e3 * num('noise_rms_V'), '.2g')} mV"]
    mains = num("mains_frequency_hz")
    parts.append(f"hum {_fmt(1e3 * num('hum_amplitude_V'), '.2g')} mV at {mains:g} Hz ({text('mains_source')})"
                 if math.isfinite(mains) and mains > 0 else f"no hum removed ({text('mains_source') or 'none'})")
    tau, source = num("amplifier_time_constant_s"), text("amplifier_time_constant_source")
    parts.append(f"time constant {tau:.4g} s ({source})" if math.isfinite(tau) else "amplifier decay not corrected")
    plate = num("plate_resonance_hz")
    if math.isfinite(plate):
        parts.append(f"plate resonance {plate / 1e3:.3g} kHz (damping ratio {num('plate_damping_ratio'):.2g}) undone")
    return ", ".join(parts)


def _summary_page(ds, info, description_lines: int = DESCRIPTION_LINES, note_lines: int = MAX_NOTE_LINES,
                  compact: bool = False) -> Figure:
    """Page 1; when the parameter table would need a font below LEGIBLE_TABLE_PT, the page is laid out again with
    fewer lines of the session description (down to MIN_DESCRIPTION_LINES), then of each fit warning (down to
    MIN_NOTE_LINES; parameters.csv has them in full), then with the table's explanation in brief (``compact``)."""
    fig = _page()
    cur = _Cursor(fig)
    _summary_header(fig, cur, info, description_lines)
    _counts_block(fig, cur, ds)
    cur.text(_MARGIN_IN, "Fitted model parameters (95 % intervals) beside the paper's Table 2", size=12,
             weight="bold", dy=0.28)
    cur.text(_MARGIN_IN, _TABLE_BRIEF + _conditional_note(ds, brief=True) if compact else _TABLE_EXPLAINED
             + _conditional_note(ds), size=8, color="0.25")
    cur.skip(0.08)
    cells, shade, no_fit_notes, fit_notes = _parameter_cells(ds)
    # room for the fit warnings under the table (issue 14): they must stay visible
    notes_h = sum(min(note_lines, len(textwrap.wrap(note, NOTE_CHARS))) * 8.5 * 1.45 / 72 for note in fit_notes)
    missing = _parameter_table(fig, cur, cells, shade, notes_h)
    if missing > 0 and description_lines > MIN_DESCRIPTION_LINES:
        fewer = max(MIN_DESCRIPTION_LINES, description_lines - math.ceil(missing / (9.5 * 1.45 / 72)))
        return _summary_page(ds, info, fewer, note_lines)
    if missing > 0 and note_lines > MIN_NOTE_LINES and fit_notes:
        fewer = max(MIN_NOTE_LINES, note_lines - math.ceil(missing / (8.5 * 1.45 / 72) / len(fit_notes)))
        return _summary_page(ds, info, description_lines, fewer)
    if missing > 0 and not compact:
        return _summary_page(ds, info, description_lines, note_lines, compact=True)
    _summary_notes(fig, cur, ds, no_fit_notes, fit_notes, notes_h, note_lines)
    _footer(fig, info, "page 1: summary")
    return fig


def _summary_header(fig, cur, info, description_lines: int = DESCRIPTION_LINES) -> None:
    """Title, synthetic-data warning and the session's metadata."""
    w, h = A4_PORTRAIT_IN
    x0 = _MARGIN_IN
    cur.text(x0, "Tennis ball impacts on a rigid surface", size=17, weight="bold", dy=0.36)
    cur.text(x0, f"Session report: {info['session_id']}", size=13, dy=0.38)
    if info["synthetic"]:
        cur.text(
            x0 + 0.05, "SYNTHETIC DATA: generated by ballimpact.synth, not measured on the rig.",
            size=10.5, weight="bold", color="#c00000",
            bbox={"fc": "#fde8e8", "ec": "#c00000", "boxstyle": "round,pad=0.4"}, dy=0.45,
        )
    cur.skip(0.05)
    rows = [
        ("Session", info["session_id"] or "-"),
        ("Date", info["date"] or "-"),
        ("Operator", info["operator"] or "-"),
        ("Software", f"ballimpact {info['software_version'] or '?'}"),
        ("Archive created", info["date_created"] or "-"),
    ]
    for key, value in rows:
        fig.text(x0 / w, 1 - cur.y / h, key, fontsize=9.5, va="top", weight="bold")
        cur.text(x0 + 1.35, value, size=9.5)
    desc = info["description"] or "-"
    desc_lines = textwrap.wrap(" ".join(desc.split()), 84) or ["-"]
    if len(desc_lines) > description_lines:  # cut between words, and say so
        desc_lines = desc_lines[:description_lines]
        last = desc_lines[-1]
        desc_lines[-1] = (last.rsplit(" ", 1)[0] if len(last) > 80 else last) + " ..."
    fig.text(x0 / w, 1 - cur.y / h, "Description", fontsize=9.5, va="top", weight="bold")
    cur.text(x0 + 1.35, "\n".join(desc_lines), size=9.5)


def _counts_block(fig, cur, ds) -> None:
    """The impact counts: one sentence and a table by ball type."""
    w, h = A4_PORTRAIT_IN
    x0 = _MARGIN_IN
    cur.skip(0.15)
    n_total = ds.sizes.get("impact", 0)
    ok = ar.impacts(ds, status="ok") if n_total else np.empty(0, dtype=int)
    n_ok = ok.size
    cur.text(x0, "Impacts", size=12, weight="bold", dy=0.28)
    peaks = ""
    for q, what in (("kcal", "kCAL (and the force in newtons)"), ("peak", "peak force")):
        status = ar.text_values(ds[f"{q}_status"].values) if f"{q}_status" in ds else np.array([])
        n = int(sum(status[i] == "withheld" for i in ok)) if status.size else 0
        peaks += (f" The {what} of {n} good impact{'s' if n != 1 else ''} is withheld (impacts.csv withheld_note, "
                  "reason_code)." if n else "")
    n_warned = len(ar.validate_warnings(ds))
    warned = (f" Reading the session gave {n_warned} warning{'s' if n_warned != 1 else ''}: see the start of that "
              "list." if n_warned else "")
    cur.text(x0, "\n".join(textwrap.wrap(f"{n_total} impacts in the raw impacts.csv: {n_ok} good, "
                                         f"{n_total - n_ok} excluded (listed with their reasons after the figures)."
                                         + peaks + warned, 110)), size=9.5)
    cur.skip(0.08)
    cells = [["Ball type", "Impacts", "Good", "Excluded", "Used in fit"]]
    for ball, total, ok, excl, used in _counts(ds):
        cells.append([ar.ball_label(ds, ball), str(total), str(ok), str(excl), _fmt(used, ".0f")])
    cells.append(["All", str(n_total), str(n_ok), str(n_total - n_ok), ""])
    row_h = 0.22
    tab_h = row_h * len(cells)
    ax = fig.add_axes([x0 / w, 1 - (cur.y + tab_h) / h, (w - 2 * x0) / w, tab_h / h])
    table = _table(ax, cells, [0.4, 0.15, 0.15, 0.15, 0.15], font_size=8.5, shade_rows=(len(cells) - 1,))
    _fit_columns(fig, ax, table, 8.5)
    cur.skip(tab_h + 0.1)
    conditioning = conditioning_summary(ds)
    if conditioning:
        wrapped = "\n".join(textwrap.fill(line, 120) for line in conditioning)
        cur.text(x0, wrapped, size=8, color="0.25")
    cur.skip(0.2)


_PARAMETER_HEAD = ["Ball type", "Source", "n", "kB(0)\n[kN/m]", "AK\n[kN/m^(1+a)]", "a\n[-]", "AC\n[kN s/m\u00b3]",
                   "kB(10 mm)\n[kN/m]", "kB(20 mm)\n[kN/m]", "TC\nRMSE\n[%]", "COR\nRMSE\n[%]"]


def _parameter_cells(ds):
    """Rows of the parameter table (fitted, then Table 2 when the paper has the ball type), the
    rows to shade, and the no-fit and fit-warning notes."""
    cells, shade, no_fit_notes, fit_notes = [_PARAMETER_HEAD], [], [], []
    for ball in ar.balls(ds):
        cells.append(_fitted_row(ds, ball, no_fit_notes, fit_notes))
        get = _ball_values(ds, ball)
        paper = [get("paper_kb0_kN_m"), get("paper_ak_kN_m"), get("paper_a"), get("paper_ac_kN_s_m3")]
        if np.isfinite(np.asarray(paper, dtype=float)).any():
            shade.append(len(cells))
            # kB(10 mm), kB(20 mm) from Table 2's values by Eq. 4 (x in m)
            kb_paper = [paper[0] + paper[1] * x ** paper[2] for x in (0.010, 0.020)]
            cells.append(["", "paper Table 2", "", _fmt(paper[0], ".1f"), _fmt(paper[1], ",.0f"),
                          _fmt(paper[2], ".2f"), _fmt(paper[3], ".1f"), _fmt(kb_paper[0], ".1f"),
                          _fmt(kb_paper[1], ".1f"), "", ""])
    return cells, shade, no_fit_notes, fit_notes


def _fitted_row(ds, ball, no_fit_notes, fit_notes) -> list[str]:
    """The table row of one ball type's fit; appends its no-fit or fit-warning note."""
    get = _ball_values(ds, ball)
    src = _text(get("kb0_source")) if "kb0_source" in ds else ""
    src = "" if src == "nan" else src

    def interval(name, fmt):
        return _interval(*ar.parameter(ds, name, ball), fmt)

    # issue 14: a parameter on its search bound gets no interval; the fit's warnings are shown
    fit_message = _text(get("fit_message")) if "fit_message" in ds else ""
    undetermined = _summary.undetermined_parameters(
        {k: get(k) for k in ("ak_kN_m", "ak_lo", "ak_hi", "a", "a_lo", "a_hi", "ac_kN_s_m3", "ac_lo", "ac_hi")},
        fit_message)
    warn_text = _summary.fit_warnings(
        fit_message, undetermined, contact_time_rmse_pct=get("contact_time_rmse_pct"), cor_rmse_pct=get("cor_rmse_pct"),
        values={k: get(k) for k in ("ak_lo", "ak_hi", "ac_lo", "ac_hi")},
        force_agreement=force_agreement(ds).get(ball, math.nan))
    fitted = [
        "\n".join(textwrap.wrap(ar.ball_label(ds, ball), 24)),
        "this session" + (f"\nkB(0) {_SOURCE_SHORT.get(src, src)}" if src else ""),
        _fmt(get("n_impacts"), ".0f"),
        interval("kb0_kN_m", ".1f"), interval("ak_kN_m", ",.0f"), interval("a", ".3f"),
        interval("ac_kN_s_m3", ".2f"), interval("kb_10mm_kN_m", ".1f"), interval("kb_20mm_kN_m", ".1f"),
        _fmt(get("contact_time_rmse_pct"), ".2f"),
        _fmt(get("cor_rmse_pct"), ".2f"),
    ]
    for col, (key, fmt) in zip((4, 5, 6), (("ak_kN_m", ",.0f"), ("a", ".3f"), ("ac_kN_s_m3", ".2f"))):
        verdict = undetermined.get(key.split("_")[0])
        if verdict == _summary.NOT_DETERMINED and fitted[col] != "-":
            fitted[col] = f"{_fmt(get(key), fmt)}\nnot determined"
        elif verdict == _summary.OPEN_INTERVAL and fitted[col] != "-":
            fitted[col] = f"{_fmt(get(key), fmt)}\ninterval open"
    if warn_text and not all(c == "-" for c in fitted[3:7]):
        fitted[0] += f"\n(see fit warning {len(fit_notes) + 1})"
        fit_notes.append(f"Fit warning {len(fit_notes) + 1}, {ar.ball_label(ds, ball)}: {warn_text}")
    if all(c == "-" for c in fitted[3:7]):
        fitted[1] = "this session\nno fit"
        fitted[3:7] = ["no fit"] * 4
        no_fit_notes.append(
            f"{ar.ball_label(ds, ball)}: " + (fit_message if fit_message and fit_message != "nan" else "no fit")
        )
    return fitted


def _parameter_table(fig, cur, cells, shade, notes_h) -> float:
    """The parameter table, row heights by their lines of text, shrunk when the page is short; returns the height
    [in] it lacks for a font of LEGIBLE_TABLE_PT (0 when it has it)."""
    w, h = A4_PORTRAIT_IN
    x0 = _MARGIN_IN
    available = h - _MARGIN_IN - _NOTES_RESERVE_IN - cur.y - notes_h
    line_h = 0.17
    heights = [max(c.count("\n") + 1 for c in row) for row in cells]
    total_h = sum(heights) * line_h + 0.06 * len(cells)
    font = 8.0
    missing = max(0.0, total_h * LEGIBLE_TABLE_PT / font - available)
    available = max(available, 0.5)  # the first layout of a crowded page; it is laid out again (_summary_page)
    if total_h > available:  # many ball types: shrink the table to fit the page
        scale = available / total_h
        total_h, font = available, max(5.0, 8.0 * scale)
    ax = fig.add_axes([x0 / w, 1 - (cur.y + total_h) / h, (w - 2 * x0) / w, total_h / h])
    table = _table(ax, cells, [0.14, 0.1, 0.035, 0.085, 0.135, 0.1, 0.095, 0.095, 0.095, 0.06, 0.06], font_size=font,
                   shade_rows=tuple(shade))
    _fit_columns(fig, ax, table, font)
    # row heights proportional to the number of text lines
    units = [hh * line_h + 0.06 for hh in heights]
    total_units = sum(units)
    for (r, c), cell in table.get_celld().items():
        cell.set_height(units[r] / total_units)
    y_acc = 1.0
    tops = []
    for u in units:
        tops.append(y_acc - u / total_units)
        y_acc -= u / total_units
    for (r, c), cell in table.get_celld().items():
        cell.set_y(tops[r])
    cur.skip(total_h + 0.15)
    return missing


def _summary_notes(fig, cur, ds, no_fit_notes, fit_notes, notes_h, note_lines: int = MAX_NOTE_LINES) -> None:
    """The no-fit and fit-warning notes under the table, and the reference."""
    h = A4_PORTRAIT_IN[1]
    x0 = _MARGIN_IN
    for note in no_fit_notes:
        if cur.y < h - _MARGIN_IN - _NOTES_RESERVE_IN:
            cur.text(x0, "\n".join(textwrap.wrap("No fit for " + note, 110)[:2]), size=8.5, color="#8a4b00")
    for note in fit_notes:
        if cur.y < h - _MARGIN_IN - _NOTES_RESERVE_IN + notes_h:
            lines = textwrap.wrap(note, NOTE_CHARS)
            if len(lines) > note_lines:
                lines = lines[:note_lines - 1] + ["... (in full: parameters.csv, column fit_warnings)"]
            cur.text(x0, "\n".join(lines), size=8.5, color="#8a4b00", weight="bold")
    cur.skip(0.1)
    if cur.y < h - _MARGIN_IN - 0.35:
        ref = _text(ds.attrs.get("references", "")) or (
            "Goodwill S R, Haake S J (2004) Modelling of tennis ball impacts on a rigid surface. "
            "Proc. IMechE Part C 218:1139-1153"
        )
        cur.text(x0, "\n".join(textwrap.wrap("Reference: " + ref, 110)), size=7.5, color="0.3")


TITLE_CHARS = 80  # a figure page's title is wrapped to this many characters (11 pt bold, the text width) [-]


def _caption_block(fig, top_in, title, caption, *, width_chars=105):
    w, h = A4_PORTRAIT_IN
    title_lines = textwrap.wrap(title, TITLE_CHARS)
    fig.text(_MARGIN_IN / w, 1 - top_in / h, "\n".join(title_lines), fontsize=11, weight="bold", va="top")
    fig.text(_MARGIN_IN / w, 1 - (top_in + 0.28 + 0.2 * (len(title_lines) - 1)) / h,
             "\n".join(textwrap.wrap(caption, width_chars)), fontsize=8.8, va="top", linespacing=1.35)


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


def figure_label(name: str) -> str:
    """
    The report's name of a figure, taken from its PNG file name (which follows the paper's numbering).

    Parameters
    ----------
    name : str
        PNG file name of :data:`FIGURE_CAPTIONS`, e.g. ``fig<N>_<what>.png``.

    Returns
    -------
    str
        "Fig. <N>" for fig<N>_*.png (the paper's numbering, e.g. "Fig. 2b"); "<stem> figure"
        otherwise (kcal becomes kCAL: the paper has no such figure).
    """
    import re

    match = re.match(r"fig(\d+[a-z]?)_", name)
    if match:
        return f"Fig. {match.group(1)}"
    return f"{Path(name).stem.replace('kcal', 'kCAL')} figure"


def _caption_addition(ds, draw_name: str) -> str:
    """This session's numbers added to a figure's caption: the ITF drop test under the COR
    figure, the force-curve validation under the force curves (Fig. 9)."""
    if draw_name == _fig.draw_cor_speed_range.__name__:
        itf_lines = itf_comparison(ds)
        if itf_lines:
            return " ITF drop test of this session's balls: " + "; ".join(itf_lines) + "."
    if draw_name == _fig.draw_force_curves.__name__:
        validation = _force_curve_validation(ds)
        if validation:
            return (" Force-curve validation over every good impact (section 4 of the paper): "
                    + "; ".join(validation) + ".")
    return ""


def _figure_file(figures_dir, name, images):
    """A figure file of figures_dir to place on a page: its pixels from ``images`` when there,
    else the file when it exists, else None (the figure is then drawn)."""
    if images is not None and name in images:
        return images[name]
    png = Path(figures_dir) / name if figures_dir is not None else None
    return png if png is not None and png.is_file() else None


def _figure_page(ds, info, name, number, figures_dir, images=None) -> Figure:
    spec = report_figure(name)
    title, caption = spec.title, spec.caption + _caption_addition(ds, spec.draw_name)
    w, h = A4_PORTRAIT_IN
    top = _MARGIN_IN
    caption_lines = len(textwrap.wrap(caption, 105))
    title_lines = len(textwrap.wrap(f"{figure_label(name)} ({name}): {title}", TITLE_CHARS))
    caption_h = 0.28 + 0.2 * (title_lines - 1) + caption_lines * 8.8 * 1.35 / 72 + 0.25
    max_fig_h = h - top - caption_h - _MARGIN_IN - 0.2
    png = _figure_file(figures_dir, name, images)
    if png is not None:
        fig = _page()
        used = _place_png(fig, png, top, max_fig_h)
        fig_h = used
    else:
        fig_h = min(spec.figure_height_in(len(ar.balls(ds))), max_fig_h)
        fig = Figure(figsize=A4_PORTRAIT_IN, layout="constrained")
        FigureCanvasAgg(fig)
        fig.get_layout_engine().set(w_pad=0.04, h_pad=0.04)
        _draw_into_page(fig, lambda f: spec.draw(f, ds), top, fig_h)
    # issue 14: numbered as the PNG files and the paper (fig<N>_*.png is Fig. <N>), not 1-6
    label = figure_label(name)
    _caption_block(fig, top + fig_h + 0.2, f"{label} ({name}): {title}", caption)
    _footer(fig, info, label)
    return fig


_TABLE_EXPLAINED = (
    "kB = kB(0) + AK x^a (Eq. 4, x in m) and cB = AC dCONT\u00b2 (Eq. 7), in the units of Table 2 "
    "(the paper prints AK in kN/m\u00b2).\nBrackets: 95 % interval. kB(0) is fixed in session.yaml "
    "(config), fitted with AK, a, AC (impacts below 10 m/s) or\nextrapolated from the Kelvin-Voigt "
    "stiffness to zero speed (interval includes the extrapolation model). RMSE: relative\nRMS residual of "
    "TC and COR over the impacts used in the fit.")
_TABLE_BRIEF = ("kB = kB(0) + AK x^a (Eq. 4, x in m), cB = AC dCONT\u00b2 (Eq. 7), Table 2 units; brackets: 95 %\n"
                "interval; RMSE: relative RMS residual (docs/outputs.md).")


def _conditional_note(ds, *, brief: bool = False) -> str:
    """The sentence saying AK and a are conditional on kB(0) from the config, when one is (``brief``: without
    naming the balls)."""
    if "kb0_source" not in ds:
        return ""
    labels = [ar.ball_label(ds, b) for b in ar.balls(ds) if _text(ar.ball_value(ds, "kb0_source", b, "")) == "config"]
    if not labels:
        return ""
    text = ("AK and a are conditional on kB(0) from config (" + ", ".join(labels)
            + "): their intervals do not include kB(0)'s uncertainty.")
    if brief:
        text = "AK and a of a kB(0) from config leave its uncertainty out of their intervals."
    return "\n" + "\n".join(textwrap.wrap(text, 118))


def _fit_outlier_rows(ds) -> list[tuple[str, str, str]]:
    """(impact_id, ball, note) of every good impact left out of its ball type's fit."""
    if ds.sizes.get("impact", 0) == 0 or "used_in_fit" not in ds:
        return []
    ids, balls, status = (ar.text_values(ds[n].values) for n in ("impact_id", "ball_type", "status"))
    used = np.asarray(ds["used_in_fit"].values, dtype=float) > 0
    notes = ar.text_values(ds["fit_note"].values) if "fit_note" in ds else [""] * len(ids)
    return [(ids[i], balls[i], "left out of the fit (status ok): " + (notes[i] or "fit outlier"))
            for i in range(len(ids)) if status[i] == "ok" and not used[i]]


def _excluded_pages(ds, info) -> list[Figure]:
    rows = ar.excluded_impacts(ds) + _fit_outlier_rows(ds)
    w, h = A4_PORTRAIT_IN
    x_id, x_ball, x_reason = _MARGIN_IN, _MARGIN_IN + 1.15, _MARGIN_IN + 2.75
    reason_chars = 78
    line_in = 8.5 * 1.45 / 72
    pages, fig, cur = [], None, None

    def new_page(continued):
        nonlocal fig, cur
        fig = _page()
        pages.append(fig)
        cur = _Cursor(fig)
        title = "Excluded impacts" + (" (continued)" if continued else "")
        cur.text(_MARGIN_IN, title, size=14, weight="bold", dy=0.35)
        if not continued:
            n_total = ds.sizes.get("impact", 0)
            n_outl = len(_fit_outlier_rows(ds))
            cur.text(_MARGIN_IN, f"{len(rows)} of {n_total} impacts were left out of the fits. Each excluded "
                     "impact has a QC page with its raw trace\nin the appendix."
                     + (f" {n_outl} of them passed the per-impact checks but sit far off their ball type's "
                        "fit\n(fit outliers, listed last with their residuals)." if n_outl else ""),
                     size=9.5, dy=0.3 + (0.34 if n_outl else 0.17))
            _warnings_block(fig, cur, session_warnings(ds))
        for x, label in ((x_id, "Impact"), (x_ball, "Ball type"), (x_reason, "Reason")):
            fig.text(x / w, 1 - cur.y / h, label, fontsize=9, weight="bold", va="top")
        cur.skip(0.2)
        fig.add_artist(_hline(fig, cur.y - 0.04))

    new_page(False)
    if not rows:
        cur.text(_MARGIN_IN, "No impact was excluded.", size=10, style="italic")
    for impact_id, ball, reason in rows:
        lines = textwrap.wrap(reason or "(no reason given)", reason_chars) or [""]
        ball_lines = textwrap.wrap(ar.ball_label(ds, ball), 26) or [""]
        n = max(len(lines), len(ball_lines))
        if cur.y + n * line_in > h - _MARGIN_IN - 0.4:
            new_page(True)
        fig.text(x_id / w, 1 - cur.y / h, impact_id, fontsize=8.5, va="top", family="monospace")
        fig.text(x_ball / w, 1 - cur.y / h, "\n".join(ball_lines), fontsize=8.5, va="top")
        fig.text(x_reason / w, 1 - cur.y / h, "\n".join(lines), fontsize=8.5, va="top")
        cur.skip(n * line_in + 0.06)
    for k, page in enumerate(pages, 1):
        _footer(page, info, f"excluded impacts {k}/{len(pages)}")
    return pages


def _warnings_block(fig, cur, warned: list[str]) -> None:
    """The session's warnings, before the list of excluded impacts: MAX_WARNING_LINES lines at most."""
    if not warned:
        return
    cur.text(_MARGIN_IN, f"Warnings from reading the session: {len(warned)} (usable but suspect input)",
             size=9.5, weight="bold", color="#8a4b00")
    lines: list[str] = []
    for k, warning in enumerate(warned):
        wrapped = textwrap.wrap("- " + warning, 110, subsequent_indent="  ")
        if len(lines) + len(wrapped) > MAX_WARNING_LINES:
            lines.append(f"- and {len(warned) - k} more.")
            break
        lines.extend(wrapped)
    cur.text(_MARGIN_IN, "\n".join(lines), size=8.5, color="#8a4b00")
    cur.skip(0.2)


def _hline(fig, y_in):
    from matplotlib.lines import Line2D

    w, h = A4_PORTRAIT_IN
    return Line2D([_MARGIN_IN / w, 1 - _MARGIN_IN / w], [1 - y_in / h] * 2, transform=fig.transFigure,
                  color="0.6", lw=0.6)


def _qc_page(ds, info, impact_id, number, n_total, figures_dir, images=None) -> Figure:
    w, h = A4_PORTRAIT_IN
    i = ar.impact_position(ds, impact_id)
    ball = _text(ar.text_values(ds["ball_type"].values)[i])
    reason = _text(ar.text_values(ds["reason"].values)[i]) or "(no reason given)"
    png = _figure_file(figures_dir, f"{QC_DIR_NAME}/{_fig.qc_file_stem(impact_id)}.png", images)
    use_png = png is not None
    if use_png:
        fig = _page()
    else:
        fig = Figure(figsize=A4_PORTRAIT_IN, layout="constrained")
        FigureCanvasAgg(fig)
    cur = _Cursor(fig)
    cur.text(_MARGIN_IN, f"QC appendix {number}/{n_total}: impact {impact_id}", size=14, weight="bold", dy=0.36)
    def value(name, fmt, unit=""):
        text = _fmt(ds[name].values[i], fmt) if name in ds else "-"
        return "n/a" if text == "-" else f"{text}{unit}"

    trace = _text(ar.text_values(ds["trace_file"].values)[i]) if "trace_file" in ds else ""
    facts = [
        ("Ball type", ar.ball_label(ds, ball)),
        ("Reason", "\n".join(textwrap.wrap(reason, 85))),
        ("Trace file", "\n".join(textwrap.wrap(trace, 85)) or "-"),
        ("Gate speeds", f"VB = {value('vin_m_s', '.2f', ' m/s')}, VB' = {value('vout_m_s', '.2f', ' m/s')}, "
                        f"COR = {value('cor', '.3f')}"),
        ("Contact", f"TC = {value('contact_time_ms', '.3f', ' ms')}, "
                    f"peak force = {value('peak_force_N', '.0f', ' N')}, "
                    f"kCAL = {value('kcal_N_per_V', '.1f', ' N/V')}"),
        ("Conditioning", "\n".join(textwrap.wrap(impact_conditioning(ds, i), 85)) or "-"),
    ]
    for key, text in facts:
        fig.text(_MARGIN_IN / w, 1 - cur.y / h, key, fontsize=9, weight="bold", va="top")
        cur.text(_MARGIN_IN + 1.2, text, size=9)
    cur.skip(0.15)
    fig_h = min(6.0, h - cur.y - _MARGIN_IN - 0.5)
    if use_png:
        _place_png(fig, png, cur.y, fig_h)
    else:
        _draw_into_page(fig, lambda f: _fig.draw_qc(f, ds, impact_id), cur.y, fig_h)
    _footer(fig, info, f"QC {number}/{n_total}")
    return fig


def report_page_count(ds) -> int:
    """Number of pages :func:`write_report` produces for this archive.

    1 summary page + one page per figure + the rig page + the exclusion list (at least one page)
    + one QC page per excluded impact.
    """
    return 2 + len(FIGURE_CAPTIONS) + len(_excluded_pages(ds, _session_info(ds))) + len(ar.excluded_impacts(ds))


def write_report(ds, out_pdf, figures_dir=None, images=None) -> Path:
    """Write the session report as an A4 PDF, atomically.

    Pages: (1) title, session metadata (with a red warning for synthetic data),
    impact counts and the fitted parameters with 95 % intervals beside Table 2 of
    Goodwill & Haake 2004; (2-8) one page per figure with a caption (Figs 7, COR 3-40 m/s, 8, 9,
    10, 2b and kCAL); (9) the rig page (:func:`ballimpact.report_rig.rig_page`); then the list of excluded impacts with their reasons, opened
    by the session's warnings (:func:`session_warnings`); then the QC appendix, one
    page per excluded impact with its raw trace.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive (with the global attributes of
        :func:`ballimpact.archive.add_metadata`).
    out_pdf : str or Path
        Destination PDF; its folder must exist.
    figures_dir : str or Path, optional
        Folder written by :func:`ballimpact.figures.save_all`. When given, its PNG
        files are placed on the pages (identical to the figure files); figures
        missing there, or all when None, are drawn from ``ds`` as vector graphics.
    images : dict, optional
        The pixels of those files (RGBA, uint8) by path relative to ``figures_dir``, as
        :func:`ballimpact.figures.save_all` fills them: placed instead of reading the
        files again (the same pixels).

    Returns
    -------
    Path
        ``out_pdf``.
    """
    out_pdf = Path(out_pdf)
    if not out_pdf.parent.is_dir():
        raise FileNotFoundError(f"cannot write {out_pdf}: folder {out_pdf.parent} does not exist")
    if figures_dir is not None and not Path(figures_dir).is_dir():
        raise FileNotFoundError(f"figures_dir {figures_dir} does not exist")
    info = _session_info(ds)
    metadata = {
        "Title": f"Tennis ball impact session report: {info['session_id']}",
        "Author": "ballimpact",
        "Subject": (
            "Force-platform tennis ball impacts and the Goodwill & Haake (2004) ball model"
            + (" (SYNTHETIC DATA)" if info["synthetic"] else "")
        ),
        "Keywords": "tennis ball, impact, force platform, viscoelastic model",
        "Creator": f"ballimpact {info['software_version']}",
        "CreationDate": datetime.datetime.now(datetime.timezone.utc),
    }
    with atomic_path(out_pdf) as tmp:
        with PdfPages(tmp, metadata=metadata) as pdf:
            for page in report_pages(ds, figures_dir, images):
                pdf.savefig(page)
    return out_pdf


def report_pages(ds, figures_dir=None, images=None) -> Iterator[Figure]:
    """The pages of the session report, one A4 matplotlib figure each, in order.

    The pages :func:`write_report` writes to the PDF (the documentation site shows
    them as images): the summary page, one page per figure, the rig page, the list of excluded
    impacts and one QC page per excluded impact. Each page is made when the
    iteration reaches it.

    Parameters
    ----------
    ds : xarray.Dataset
        Session archive.
    figures_dir : str or Path, optional
        Folder of the figure files, as for :func:`write_report`.
    images : dict, optional
        The pixels of those files, as for :func:`write_report`.

    Yields
    ------
    matplotlib.figure.Figure
        One page of 8.27 x 11.69 in (A4 portrait).
    """
    info = _session_info(ds)
    yield _summary_page(ds, info)
    for number, name in enumerate(FIGURE_CAPTIONS, 1):
        yield _figure_page(ds, info, name, number, figures_dir, images)
    yield report_rig.rig_page(ds, info, figures_dir, images)
    yield from _excluded_pages(ds, info)
    excluded = ar.excluded_impacts(ds)
    for k, (impact_id, _, _) in enumerate(excluded, 1):
        yield _qc_page(ds, info, impact_id, k, len(excluded), figures_dir, images)
