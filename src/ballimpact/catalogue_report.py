"""The catalogue PDF for the lab head: every session x ball type, parameters against date, curves, changes, ranking."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .atomic import atomic_path

__all__ = ["write_catalogue_pdf"]

_A4 = (8.27, 11.69)  # portrait page [in]
_ROWS_PER_PAGE = 60
_MAX_LEGEND = 12  # most curves named in a legend
_PARAMS = (  # (catalogue column, interval columns, axis label)
    ("kb0_kN_m", ("kb0_lo", "kb0_hi"), "kB(0) [kN/m]"),
    ("ak_kN_m", ("ak_lo", "ak_hi"), "AK [kN/m^(1+a)]"),
    ("a", ("a_lo", "a_hi"), "a [-]"),
    ("ac_kN_s_m3", ("ac_lo", "ac_hi"), "AC [kN s/m^3]"),
)


def _fmt(value, fmt="{:.3g}") -> str:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not math.isfinite(v):
        return ""
    if fmt == "{:.3g}" and abs(v) >= 1000:  # AK: 23782 rather than 2.38e+04
        return f"{v:.0f}"
    return fmt.format(v)


def _interval(row, col, lo, hi) -> str:
    value = _fmt(row.get(col))
    if not value:
        return "-"
    a, b = _fmt(row.get(lo)), _fmt(row.get(hi))
    return f"{value} [{a}, {b}]" if a and b else value


def _page(title: str) -> Figure:
    fig = Figure(figsize=_A4)
    fig.text(0.07, 0.965, title, fontsize=13, weight="bold", va="top")
    return fig


def _table_pages(table: pd.DataFrame) -> list[Figure]:
    cols = ["session", "date", "ball", "n", "kB(0)", "AK [95 %]", "a [95 %]", "AC [95 %]", "rmse % TC/COR"]
    rows = []
    for _, r in table.iterrows():
        sid = str(r["session_id"])
        rows.append([
            sid if len(sid) <= 34 else sid[:32] + "..", str(r["session_date"]), str(r["ball"]),
            _fmt(r.get("n_impacts"), "{:.0f}"), _fmt(r.get("kb0_kN_m")),
            _interval(r, "ak_kN_m", "ak_lo", "ak_hi"), _interval(r, "a", "a_lo", "a_hi"),
            _interval(r, "ac_kN_s_m3", "ac_lo", "ac_hi"),
            f"{_fmt(r.get('contact_time_rmse_pct'), '{:.2g}')}/{_fmt(r.get('cor_rmse_pct'), '{:.2g}')}",
        ])
    pages = []
    for start in range(0, max(len(rows), 1), _ROWS_PER_PAGE):
        part = rows[start:start + _ROWS_PER_PAGE]
        fig = _page("Every session x ball type" + (" (continued)" if start else ""))
        fig.text(0.07, 0.93, "Fitted parameters in the units of Table 2 of Goodwill & Haake (2004): kB(0) [kN/m], "
                 "AK [kN/m^(1+a)], a [-], AC [kN s/m^3],\nwith 95 % intervals; pooled rows fit one parameter "
                 "set to the impacts of the sessions named.", fontsize=8, va="top")
        if part:
            _column_table(fig, part, cols, [0.2, 0.08, 0.09, 0.03, 0.05, 0.17, 0.12, 0.13, 0.1], top=0.89)
        else:
            fig.text(0.5, 0.8, "no session results", ha="center")
        pages.append(fig)
    return pages


def _column_table(fig: Figure, rows: list[list[str]], header: list[str], widths: list[float], *, top: float,
                  left: float = 0.03, width: float = 0.94, fontsize: float = 6.0, linespacing: float = 1.5) -> None:
    """A table drawn as one multi-line text per column (rows aligned by the common line
    spacing), a bold header and rules: a year of sessions is many pages of rows, which
    matplotlib's ``Axes.table`` lays out cell by cell at several times the cost."""
    row = fontsize * linespacing / 72 / fig.get_figheight()  # line pitch of the column texts [figure fraction]
    x = left
    for name, w, k in zip(header, widths, range(len(header))):
        fig.text(x + 0.004, top, name, fontsize=fontsize, weight="bold", va="top")
        fig.text(x + 0.004, top - 1.5 * row, "\n".join(r[k] for r in rows), fontsize=fontsize, va="top",
                 linespacing=linespacing)
        x += w * width / sum(widths)
    for y in (top + 0.4 * row, top - 1.2 * row, top - (len(rows) + 1.4) * row):
        fig.add_artist(Line2D([left, left + width], [y, y], lw=0.5, color="0.4"))


def _summary_page(tests, ranking: pd.DataFrame, speed: float, alpha: float) -> Figure:
    fig = _page("Did a ball type change between sessions?  Ranking of the ball types")
    text = (f"Test: one shared parameter set (AK, a, AC) for all sessions of a ball type against one set per session, "
            f"fitted to the impacts themselves (F test of nested least-squares fits on the relative TC and COR "
            f"residuals). A ball type is flagged CHANGED when p < {alpha:g}. The size of the change is the spread "
            f"(largest minus smallest) of the sessions' model contact time and COR at {speed:g} m/s.")
    fig.text(0.07, 0.93, "\n".join(textwrap.wrap(text, 120)), fontsize=8, va="top")
    ax = fig.add_axes([0.04, 0.50, 0.92, 0.36])
    ax.axis("off")
    cells = []
    for ball, t in tests.items():
        verdict = "untested" if not np.isfinite(t.p_value) else ("CHANGED" if t.changed else "unchanged")
        cells.append([ball, str(len(t.sessions)), str(t.n_impacts), _fmt(t.f_statistic, "{:.3g}"),
                      f"({t.df_num}, {t.df_den})", _fmt(t.p_value, "{:.2e}"), verdict,
                      _fmt(t.tc_change_ms, "{:.3f}"), _fmt(t.cor_change, "{:.3f}"),
                      "" if t.message == "ok" else t.message[:40]])
    if cells:
        table = ax.table(cellText=cells, loc="upper center", cellLoc="left",
                         colLabels=["ball", "sessions", "impacts", "F", "df", "p", "verdict",
                                    f"dTC@{speed:g} [ms]", f"dCOR@{speed:g}", "note"],
                         colWidths=[0.12, 0.07, 0.07, 0.07, 0.09, 0.09, 0.09, 0.1, 0.09, 0.21])
        table.auto_set_font_size(False)
        table.set_fontsize(7)
        table.scale(1, 1.4)
        for (r, _c), cell in table.get_celld().items():
            if r > 0 and cells[r - 1][6] == "CHANGED":
                cell.set_facecolor("#f8d0d0")
    fig.text(0.07, 0.47, f"Ranking at {speed:g} m/s (each ball type's latest session)", fontsize=11, weight="bold")
    fig.text(0.07, 0.45, "COR and contact time of the fitted model at this speed; stiffness is the Kelvin-Voigt "
             "equivalent kB = m pi^2 / TC^2 (Eq. 2).\nRank 1 = highest COR / stiffest.", fontsize=8, va="top")
    ax2 = fig.add_axes([0.04, 0.05, 0.92, 0.36])
    ax2.axis("off")
    rcells = [[str(r["ball"]), str(r["session_id"]), str(r["session_date"]), _fmt(r["cor"], "{:.3f}"),
               _fmt(r["contact_time_ms"], "{:.3f}"), _fmt(r["stiffness_kN_m"], "{:.1f}"),
               _fmt(r["cor_rank"], "{:.0f}"), _fmt(r["stiffness_rank"], "{:.0f}")] for _, r in ranking.iterrows()]
    if rcells:
        t2 = ax2.table(cellText=rcells, loc="upper center", cellLoc="left",
                       colLabels=["ball", "session", "date", "COR", "TC [ms]", "stiffness [kN/m]", "COR rank",
                                  "stiffness rank"])
        t2.auto_set_font_size(False)
        t2.set_fontsize(7)
        t2.scale(1, 1.4)
    return fig


def _date_axis(dates: list[str]):
    """x positions of ISO dates [days since the first]; text dates that do not parse are spread evenly."""
    parsed = pd.to_datetime(pd.Series(dates), errors="coerce")
    if parsed.notna().all() and len(parsed):
        return (parsed - parsed.min()).dt.days.to_numpy(dtype=float), True
    return np.arange(len(dates), dtype=float), False


def _ball_page(ds, table: pd.DataFrame, ball: str, test) -> Figure:
    fig = _page(f"Ball type {ball}")
    rows = table[table["ball"] == ball]
    verdict = ""
    if test is not None:
        verdict = ("untested: " + test.message if not np.isfinite(test.p_value) else
                   f"{'CHANGED' if test.changed else 'unchanged'} between sessions (p = {test.p_value:.2e}); "
                   f"spread at 20 m/s: TC {_fmt(test.tc_change_ms, '{:.3f}')} ms, COR {_fmt(test.cor_change, '{:.3f}')}")
    fig.text(0.07, 0.935, verdict, fontsize=9, va="top", color="#b00000" if test is not None and test.changed else "k")
    x_all, is_date = _date_axis(list(rows["session_date"]))
    pooled = (rows["pooled_sessions"].astype(str) != "").to_numpy()
    axes = [fig.add_axes([0.1 + 0.47 * (k % 2), 0.62 - 0.22 * (k // 2), 0.36, 0.17]) for k in range(4)]
    for ax, (col, (lo, hi), label) in zip(axes, _PARAMS):
        y = pd.to_numeric(rows.get(col), errors="coerce").to_numpy(dtype=float)
        ylo = pd.to_numeric(rows.get(lo), errors="coerce").to_numpy(dtype=float) if lo in rows else np.full(len(y), np.nan)
        yhi = pd.to_numeric(rows.get(hi), errors="coerce").to_numpy(dtype=float) if hi in rows else np.full(len(y), np.nan)
        for sel, style in ((~pooled, dict(fmt="o", color="C0", label="session")),
                           (pooled, dict(fmt="s", color="C3", mfc="none", label="pooled"))):
            if sel.any():
                err = np.vstack([np.where(np.isfinite(ylo[sel]), y[sel] - ylo[sel], 0),
                                 np.where(np.isfinite(yhi[sel]), yhi[sel] - y[sel], 0)])
                ax.errorbar(x_all[sel], y[sel], yerr=np.clip(err, 0, None), capsize=3, ms=4, **style)
        ax.set_ylabel(label, fontsize=8)
        ax.set_xlabel("days since first session" if is_date else "session (in order)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].legend(fontsize=7)
    speeds = np.asarray(ds["speed_m_s"].values, dtype=float)
    ax_tc = fig.add_axes([0.1, 0.06, 0.36, 0.22])
    ax_cor = fig.add_axes([0.57, 0.06, 0.36, 0.22])
    b = list(ds["ball"].values).index(ball)
    for k, sid in enumerate(ds["session"].values):
        tc = ds["model_contact_time_ms"].values[k, b]
        if not np.isfinite(tc).any():
            continue
        color = f"C{k % 10}"
        style = "--" if str(ds["pooled_sessions"].values[k]) else "-"
        ax_tc.plot(speeds, tc, style, color=color, lw=1.2, label=str(sid)[:24])
        ax_tc.fill_between(speeds, ds["model_contact_time_ms_lo"].values[k, b], ds["model_contact_time_ms_hi"].values[k, b],
                           color=color, alpha=0.15, lw=0)
        ax_cor.plot(speeds, ds["model_cor"].values[k, b], style, color=color, lw=1.2)
        ax_cor.fill_between(speeds, ds["model_cor_lo"].values[k, b], ds["model_cor_hi"].values[k, b],
                            color=color, alpha=0.15, lw=0)
    ax_tc.set_ylabel("model contact time [ms]", fontsize=8)
    ax_cor.set_ylabel("model COR [-]", fontsize=8)
    for ax in (ax_tc, ax_cor):
        ax.set_xlabel("inbound speed [m/s]", fontsize=8)
        ax.tick_params(labelsize=7)
    n_curves = len(ax_tc.get_lines())
    if n_curves <= _MAX_LEGEND:
        ax_tc.legend(fontsize=6, ncol=1 if n_curves < 7 else 2)
    else:  # a year of sessions: colours cycle in date order, no legend
        ax_tc.set_title(f"{n_curves} fits, in date order", fontsize=7)
    fig.text(0.07, 0.31, "Model TC and COR of every session's fit (lines) with 95 % bands (shaded); dashed: pooled fits.",
             fontsize=8)
    return fig


def write_catalogue_pdf(ds, table: pd.DataFrame, tests, ranking: pd.DataFrame, out_pdf) -> Path:
    """Write catalogue.pdf.

    Pages: the change tests and the ranking (COR and Kelvin-Voigt stiffness, Eq. (2)
    of Goodwill & Haake 2004, at the reference speed); the table of every session x
    ball type; one page per ball type with its parameters and 95 % intervals against
    session date and its model TC [ms] and COR [-] curves of every session overlaid
    with their bands.

    Parameters
    ----------
    ds : xarray.Dataset
        :func:`ballimpact.catalogue.catalogue_dataset`.
    table : pandas.DataFrame
        catalogue.csv.
    tests : mapping of str to ChangeTest
        Change test per ball type.
    ranking : pandas.DataFrame
        :func:`ballimpact.catalogue.ranking_table`.
    out_pdf : str or Path
        The PDF to write (atomically).

    Returns
    -------
    Path
    """
    from .catalogue import CHANGE_ALPHA, REFERENCE_SPEED_M_S

    out_pdf = Path(out_pdf)
    pages = [_summary_page(tests, ranking, REFERENCE_SPEED_M_S, CHANGE_ALPHA), *_table_pages(table)]
    pages += [_ball_page(ds, table, str(ball), tests.get(str(ball))) for ball in ds["ball"].values]
    with atomic_path(out_pdf) as tmp, PdfPages(tmp) as pdf:
        for fig in pages:
            pdf.savefig(fig)
        info = pdf.infodict()
        info["Title"] = "Catalogue of tennis ball impact sessions"
        info["Subject"] = "ballimpact catalogue across sessions"
    return out_pdf
