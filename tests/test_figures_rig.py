"""The rig's figures: the plate's pooled free ringing and the time constant and kCAL per impact, drawn on an archive
with an identified plate, a stated one, none, and one written before the rig was archived."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.text import Text

from ballimpact import figures_rig
from ballimpact.figures_rig import NO_RIG, fig_rig_per_impact, fig_rig_ringing

from archive_fixture import make_archive
from rigkit import FN_HZ, KCAL, TAU_S, ringing_archive


def _texts(fig):
    return [t.get_text() for t in fig.findobj(match=Text) if t.get_visible() and t.get_text()]


def _without_rig(ds):
    return ds.drop_vars([v for v in ds.variables if str(v).startswith("rig_")])


def test_the_ringing_figure_draws_every_impact_on_the_plate_s_response():
    fig = fig_rig_ringing(ringing_archive(8))
    fig.canvas.draw()
    (ax,) = fig.axes
    grey = [line for line in ax.lines if line.get_color() == "0.55"]
    assert len(grey) == 8
    assert ax.get_title().startswith(f"fn = {FN_HZ / 1e3:.4g} kHz [")
    assert "identified" in ax.get_title() and "8 impacts" in ax.get_title()
    black = [line for line in ax.lines if line.get_color() == "k"]
    assert len(black) == 3  # the response and its envelope, above and below
    t, y = black[0].get_data()
    assert y[np.argmin(np.abs(t))] == pytest.approx(1.0, abs=0.01)  # the response's crest at the phase origin


@pytest.mark.parametrize("case", ["none", "no rig"])
def test_without_a_plate_the_ringing_panel_says_why(case):
    ds = ringing_archive(6, plate="none") if case == "none" else _without_rig(make_archive())
    fig = fig_rig_ringing(ds)
    fig.canvas.draw()
    text = " ".join(" ".join(_texts(fig)).split())
    assert not any(line.get_color() == "0.55" for ax in fig.axes for line in ax.lines)
    if case == "none":
        assert "no plate resonance identified: no free ringing above the noise after 6 contacts" in text
    else:
        assert " ".join(NO_RIG.split()) in text


def test_a_stated_plate_is_named_so():
    fig = fig_rig_ringing(ringing_archive(6, plate="stated"))
    assert "stated in session.yaml" in fig.axes[0].get_title()


def test_the_per_impact_figure_has_the_session_s_values_and_marks_the_excluded():
    ds = ringing_archive(8, excluded=(2, 5))
    fig = fig_rig_per_impact(ds)
    fig.canvas.draw()
    tau_ax, kcal_ax = fig.axes
    for ax, value in ((tau_ax, TAU_S), (kcal_ax, KCAL)):
        lines = [line for line in ax.lines if line.get_color() == "k"]
        assert len(lines) == 1 and np.allclose(lines[0].get_ydata(), value)  # the session's value
        bands = [p for p in ax.patches + [c for c in ax.collections if isinstance(c, PolyCollection)]]
        assert bands, "its 95 % interval"
        crosses = [line for line in ax.lines if line.get_marker() == "x"]
        assert sum(len(line.get_xdata()) for line in crosses) == 2
        assert sorted(np.concatenate([line.get_xdata() for line in crosses])) == [3, 6]  # impacts 3 and 6 (from 1)
    assert tau_ax.get_title().startswith(f"session {TAU_S:.4g} s [")
    assert any("excluded" in t for t in _texts(fig))


def test_the_per_impact_figure_draws_on_an_archive_without_the_rig():
    fig = fig_rig_per_impact(_without_rig(make_archive()))
    fig.canvas.draw()
    assert len(fig.axes) == 2
    assert all(NO_RIG in " ".join(ax.get_title().split()) for ax in fig.axes)  # each panel: no session value


def test_the_draw_functions_are_the_registry_s():
    from ballimpact.figure_registry import report_figure

    assert report_figure("rig_ringing").draw is figures_rig.draw_rig_ringing
    assert report_figure("rig_per_impact.png").draw is figures_rig.draw_rig_per_impact
