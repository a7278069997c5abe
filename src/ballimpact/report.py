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
from .atomic import atomic_path
from .figure_registry import QC_DIR_NAME, REPORT_FIGURES, report_figure
from .report_layout import (  # noqa: F401
    _MARGIN_IN,
    A4_PORTRAIT_IN,
    CELL_PAD_IN,
    MAX_SHOWN_CHARS,
    _Cursor,
    _draw_into_page,
    _figure_file,
    _fmt,
    _footer,
    _hline,
    _page,
    _place_png,
    _text,
)
from .report_summary import (  # noqa: F401
    DESCRIPTION_LINES,
    LEGIBLE_TABLE_PT,
    MAX_NOTE_LINES,
    MIN_DESCRIPTION_LINES,
    MIN_NOTE_LINES,
    NOTE_CHARS,
    _ball_values,
    _summary_page,
    conditioning_summary,
)

__all__ = ["A4_PORTRAIT_IN", "FIGURE_CAPTIONS", "conditioning_summary", "impact_conditioning", "itf_comparison",
           "session_warnings", "write_report", "report_pages", "report_page_count"]

#: Title and caption of each report figure with a page of its own by PNG file name, in report order
#: (from :data:`ballimpact.figure_registry.REPORT_FIGURES`; the rig's are on the rig page, :mod:`.report_rig`).
FIGURE_CAPTIONS = {f.file_name: (f.title, f.caption) for f in REPORT_FIGURES if f.page == "own"}

MAX_DESCRIPTION_CHARS = 1200  # longest session description shown on page 1 [characters]

MAX_WARNING_LINES = 24  # lines of session warnings before the list of excluded impacts; the rest are counted [-]


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


TITLE_CHARS = 80  # a figure page's title is wrapped to this many characters (11 pt bold, the text width) [-]


def _caption_block(fig, top_in, title, caption, *, width_chars=105):
    w, h = A4_PORTRAIT_IN
    title_lines = textwrap.wrap(title, TITLE_CHARS)
    fig.text(_MARGIN_IN / w, 1 - top_in / h, "\n".join(title_lines), fontsize=11, weight="bold", va="top")
    fig.text(_MARGIN_IN / w, 1 - (top_in + 0.28 + 0.2 * (len(title_lines) - 1)) / h,
             "\n".join(textwrap.wrap(caption, width_chars)), fontsize=8.8, va="top", linespacing=1.35)


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
