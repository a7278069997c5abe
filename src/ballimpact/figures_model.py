"""Figures of the fitted ball model and the impacts: the paper's Figs 2b, 7, 8, 9, 10 and COR from 3 to 40 m/s."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from . import archive_read as ar
from .figures_layout import _colors, _corner_note, _empty, _grid, _legend_with_headroom, _note, render
from .model_data import COMPONENT_SPEED_M_S, impact_model_curve, kelvin_voigt_contact

__all__ = [
    "fig_contact_time_cor",
    "fig_cor_speed_range",
    "fig_stiffness",
    "fig_force_curves",
    "fig_components",
    "fig_kelvin_voigt",
    "draw_contact_time_cor",
    "draw_cor_speed_range",
    "draw_stiffness",
    "draw_force_curves",
    "draw_components",
    "draw_kelvin_voigt",
]

#: A measured impact is overlaid on Fig. 10 when its speed is this close to 20 m/s [m/s].
COMPONENT_SPEED_TOLERANCE_M_S = 2.5

_NO_FIT = "no fit"
_NO_GOOD = "no good impacts"


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
