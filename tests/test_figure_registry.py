"""Tests of the figure registry: every figure has a unique stem, a draw function, a caption file and a height rule."""

from __future__ import annotations

import importlib

import pytest
from numpy.testing import assert_allclose

from ballimpact import figure_registry
from ballimpact.figure_registry import REPORT_FIGURES, ReportFigure, report_figure, rows_height_in

from workflow_helpers import REPO


def test_stems_and_draw_functions_are_unique():
    stems = [f.stem for f in REPORT_FIGURES]
    draws = [f.draw_name for f in REPORT_FIGURES]
    assert len(set(stems)) == len(stems) == len(set(draws))
    assert figure_registry.FIGURE_STEMS == tuple(stems)


@pytest.mark.parametrize("spec", REPORT_FIGURES, ids=lambda f: f.stem)
def test_every_figure_has_a_draw_function_and_a_report_caption(spec):
    assert spec.draw is getattr(importlib.import_module(f"ballimpact.{spec.module}"), spec.draw_name)
    assert callable(spec.draw)
    assert (REPO / "workflow" / "report" / f"{spec.stem}.rst").is_file()
    assert spec.title and spec.caption and spec.category and spec.report_label and spec.shows
    assert report_figure(spec.stem) is report_figure(spec.file_name) is report_figure(spec.draw_name) is spec


@pytest.mark.parametrize(("layout", "n_balls", "height_in"), [
    ("per_ball", 1, 2.0 + 0.7),  # one row of 2 in plus 0.7 in for the title
    ("per_ball", 3, 3 * 2.0 + 0.7),
    ("per_ball", 6, 10.0),  # 12.7 in capped at 10 in (an A4 page)
    ("two_columns", 1, 2.0 + 0.7),
    ("two_columns", 3, 2 * 2.0 + 0.7),  # 3 panels in 2 columns: 2 rows
    ("fixed", 5, 2.0),
])
def test_figure_height_follows_the_layout(layout, n_balls, height_in):
    spec = ReportFigure("x", "draw_kcal", "t", "c", layout, 2.0, "cat", "lab", "shows")
    assert_allclose(spec.figure_height_in(n_balls), height_in, rtol=1e-12)


def test_rows_height_has_room_for_at_least_one_row():
    assert_allclose(rows_height_in(0, 2.3), 2.3 + 0.7, rtol=1e-12)


def test_bad_layout_and_unknown_figure_are_named():
    with pytest.raises(ValueError, match="figure x: layout must be per_ball, two_columns or fixed, got 'grid'"):
        ReportFigure("x", "draw_kcal", "t", "c", "grid", 2.0, "cat", "lab", "shows")
    with pytest.raises(KeyError, match="no report figure 'fig99'"):
        report_figure("fig99")
    with pytest.raises(ValueError, match="figure x: page must be one of own, rig, got 'appendix'"):
        ReportFigure("x", "draw_kcal", "t", "c", "fixed", 2.0, "cat", "lab", "shows", page="appendix")


def test_the_rig_s_figures_stand_on_the_rig_page_and_the_others_on_their_own():
    pages = {f.stem: f.page for f in REPORT_FIGURES}
    assert [s for s, p in pages.items() if p == "rig"] == ["rig_ringing", "rig_per_impact"]
    assert all(p == "own" for s, p in pages.items() if not s.startswith("rig_"))
