"""The PDF report's summary page: the session, its impacts and conditioning, the fitted parameters and Table 2."""

from __future__ import annotations

import math
import textwrap

import numpy as np
from matplotlib.figure import Figure

from . import archive_read as ar
from . import summary as _summary
from .model_data import force_agreement
from .report_layout import _MARGIN_IN, A4_PORTRAIT_IN, _Cursor, _fit_columns, _fmt, _footer, _page, _table, _text

__all__ = ["conditioning_summary"]

_SOURCE_SHORT = {"extrapolated": "extrap.", "fitted": "fitted"}

DESCRIPTION_LINES = 10  # lines of the description on page 1; a longer one ends with " ..." between words [-]
MIN_DESCRIPTION_LINES = 3  # fewest lines of it when the parameter table needs the room [-]
LEGIBLE_TABLE_PT = 6.5  # smallest font [pt] of the parameter table before the description gives up lines
_NOTES_RESERVE_IN = 0.55  # room kept under the table and its fit warnings for the no-fit notes and the reference [in]
MAX_NOTE_LINES = 8  # lines of one fit warning under the parameter table [-]
MIN_NOTE_LINES = 2  # fewest lines of it when the parameter table needs the room [-]
NOTE_CHARS = 98  # characters of a line of a fit warning (8.5 pt bold, the text width) [-]


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


def _interval(value, lo, hi, fmt) -> str:
    main = _fmt(value, fmt)
    if main == "-":
        return "-"
    lo_s, hi_s = _fmt(lo, fmt), _fmt(hi, fmt)
    if lo_s == "-" or hi_s == "-":
        return main
    return f"{main}\n[{lo_s}, {hi_s}]"


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
