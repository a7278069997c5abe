"""Figures of the archive: every figure draws on complete and degenerate archives, save_all writes the files."""

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.figure import Figure

from ballimpact import figures
from ballimpact.archive import assemble_archive, impacts_dataset

from archive_fixture import make_archive

FIGURE_FUNCTIONS = [
    figures.fig_contact_time_cor,
    figures.fig_cor_speed_range,
    figures.fig_stiffness,
    figures.fig_force_curves,
    figures.fig_components,
    figures.fig_kelvin_voigt,
    figures.fig_kcal,
]
EXPECTED_FILES = [
    "fig7_contact_time_cor.png",
    "cor_speed_itf.png",
    "fig8_stiffness.png",
    "fig9_force_curves.png",
    "fig10_components.png",
    "fig2b_kelvin_voigt.png",
    "kcal.png",
    "rig_ringing.png",  # the rig's, placed on the report's rig page (tests/test_figures_rig.py)
    "rig_per_impact.png",
]


@pytest.fixture(scope="module")
def archives():
    return {
        "complete": make_archive(),
        # one ball with no good impact (its fit failed) and one custom ball whose fit failed
        "degenerate": make_archive(
            balls=("pressurised", "oversize", "club"), no_good_ball="oversize", failed_fit_ball="club",
            speeds_m_s=(18.0, 26.0),
        ),
        "single": make_archive(balls=("punctured",), speeds_m_s=(20.0,), with_exclusions=False),
        "impacts_only": assemble_archive(impacts_dataset([]), []),
    }


def _texts(fig):
    out = [t.get_text() for t in fig.findobj(match=lambda a: hasattr(a, "get_text"))]
    return " ".join(out)


@pytest.mark.parametrize("func", FIGURE_FUNCTIONS, ids=lambda f: f.__name__)
@pytest.mark.parametrize("which", ["degenerate", "single", "impacts_only"])
def test_figure_draws(archives, func, which):
    # the complete archive is rendered by test_save_all_writes_expected_files
    fig = func(archives[which])
    assert isinstance(fig, Figure)
    fig.canvas.draw()  # the whole figure renders
    drawn = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    if which == "impacts_only":
        assert "no impacts in this session" in _texts(fig)
        return
    assert drawn
    assert all(ax.get_ylabel() for ax in drawn if ax.has_data())
    assert any(ax.get_xlabel() for ax in drawn)
    assert all("[" in ax.get_ylabel() for ax in drawn if ax.get_ylabel())  # units in brackets


@pytest.mark.parametrize(
    "func", [figures.fig_contact_time_cor, figures.fig_force_curves, figures.fig_components], ids=lambda f: f.__name__
)
def test_degenerate_balls_say_no_fit(archives, func):
    text = _texts(func(archives["degenerate"]))
    assert "no fit" in text
    assert "Ball 3: oversize" in text  # labels come from ball_label


def test_stiffness_lists_balls_without_fit(archives):
    text = _texts(figures.fig_stiffness(archives["degenerate"]))
    assert "no fit: Ball 3: oversize, Custom: club" in text


def test_kelvin_voigt_shows_tensile_tail(archives):
    # the Kelvin-Voigt force goes negative before x returns to zero (paper Fig. 2b)
    text = _texts(figures.fig_kelvin_voigt(archives["complete"]))
    assert "tensile tail: min -" in text


def test_kcal_band_is_robust_median(archives):
    ds = archives["complete"]
    ok = ds["status"].values == "ok"
    k = ds["kcal_N_per_V"].values[ok]
    med, half = figures.kcal_band(ds)
    assert med == pytest.approx(np.median(k), rel=1e-12)
    mad = np.median(np.abs(k - np.median(k)))
    assert half == pytest.approx(3 * 1.4826 * mad, rel=1e-9)


@pytest.mark.parametrize("impact_id", ["clip01", "gate01", "trace01"])
def test_qc_figure_has_reason_in_title(archives, impact_id):
    ds = archives["complete"]
    i = int(np.flatnonzero(ds["impact_id"].values == impact_id)[0])
    fig = figures.fig_qc_impact(ds, impact_id)
    fig.canvas.draw()
    title = fig.get_suptitle().replace("\n", " ")
    assert impact_id in title
    assert ds["reason"].values[i].split(":")[0] in title


def test_qc_figure_marks_contact_when_known(archives):
    fig = figures.fig_qc_impact(archives["complete"], "clip01")
    assert "contact end (TC" in _texts(fig)
    fig = figures.fig_qc_impact(archives["complete"], "gate01")
    assert "contact end" not in _texts(fig)


def test_qc_unknown_impact(archives):
    with pytest.raises(KeyError, match="impact_id 'nope' is not in the archive"):
        figures.fig_qc_impact(archives["complete"], "nope")


def test_save_all_writes_expected_files(archives, tmp_path):
    ds = archives["complete"]
    paths = figures.save_all(ds, tmp_path / "figures")
    names = [p.relative_to(tmp_path / "figures").as_posix() for p in paths]
    assert names == EXPECTED_FILES + ["qc/clip01.png", "qc/gate01.png", "qc/trace01.png"]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # dpi 150 on a 7.5 in wide figure
    assert mpimg.imread(paths[1]).shape[1] == int(round(7.5 * 150))
    leftovers = [p for p in (tmp_path / "figures").rglob("*") if p.name.endswith(".tmp")]
    assert leftovers == []


def test_save_all_creates_empty_qc_folder(archives, tmp_path):
    paths = figures.save_all(archives["single"], tmp_path)
    assert (tmp_path / "qc").is_dir()
    assert list((tmp_path / "qc").iterdir()) == []
    assert [p.name for p in paths] == EXPECTED_FILES


def test_save_figure_is_atomic(archives, tmp_path, monkeypatch):
    target = tmp_path / "x.png"
    target.write_bytes(b"old")
    fig = figures.fig_kcal(archives["complete"])

    def broken(*args, **kwargs):
        raise RuntimeError("renderer crashed")

    monkeypatch.setattr(fig, "savefig", broken)
    with pytest.raises(RuntimeError, match="renderer crashed"):
        figures.save_figure(fig, target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["x.png"]


# --------------------------------------------------------- titles fit, synthetic mark (issue 14)


def _layout_problems(fig):
    """Titles wider than their panel, and overlaps between titles, the figure title and legends."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    problems = []
    titles = []
    for ax in fig.axes:
        box = ax.get_window_extent(renderer)
        for title in (ax.title, ax._left_title, ax._right_title):
            if title.get_visible() and title.get_text():
                extent = title.get_window_extent(renderer)
                titles.append((title.get_text(), extent))
                if extent.x0 < box.x0 - 1 or extent.x1 > box.x1 + 1:
                    problems.append(f"title wider than its panel: {title.get_text()!r}")
    if fig._suptitle is not None and fig._suptitle.get_text():
        titles.append((fig._suptitle.get_text(), fig._suptitle.get_window_extent(renderer)))
    boxes = titles + [("legend", legend.get_window_extent(renderer)) for legend in fig.legends]
    for i, (text_a, a) in enumerate(boxes):
        for text_b, b in boxes[i + 1:]:
            if a.overlaps(b):
                problems.append(f"overlap: {text_a[:40]!r} / {text_b[:40]!r}")
    return problems


def _long_labels(ds):
    """The archive with ball labels as long as a lab writes them."""
    long = ds.copy()
    long["ball_label"] = ("ball", np.array([f"Ball {k + 1}: {b} (club stock, batch 2026-11, re-pressurised)"
                                            for k, b in enumerate(ds["ball"].values)], dtype=object))
    return long


@pytest.mark.parametrize("func", FIGURE_FUNCTIONS, ids=lambda f: f.__name__)
@pytest.mark.parametrize("which", ["complete", "degenerate", "long labels"])
def test_titles_fit_and_do_not_overlap(archives, func, which):
    ds = _long_labels(archives["complete"]) if which == "long labels" else archives[which]
    assert _layout_problems(func(ds)) == []


def test_qc_page_titles_fit(archives):
    ds = archives["complete"]
    for impact_id, _, _ in figures.excluded_impacts(ds):
        assert _layout_problems(figures.fig_qc_impact(ds, impact_id)) == []


@pytest.mark.parametrize("synthetic", [True, False])
def test_every_figure_of_a_synthetic_session_is_marked(synthetic):
    ds = make_archive(balls=("pressurised",), speeds_m_s=(20.0, 25.0), synthetic=synthetic)
    figs = [func(ds) for func in FIGURE_FUNCTIONS]
    figs += [figures.fig_qc_impact(ds, impact_id) for impact_id, _, _ in figures.excluded_impacts(ds)]
    for fig in figs:
        marked = figures.SYNTHETIC_MARK in fig._suptitle.get_text()
        assert marked == synthetic


def test_fig7_legend_lies_below_its_panels_not_on_them():
    """Issue 49: Fig. 7's legends covered part of each panel; one legend now sits below them all."""
    from matplotlib.legend import Legend

    ds = make_archive(balls=("pressurised", "pressureless", "oversize", "punctured"))
    fig = figures.fig_contact_time_cor(ds)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    panels = [ax.get_window_extent(renderer) for ax in fig.get_axes() if ax.axison]
    legends = fig.findobj(match=Legend)
    assert len(legends) == 1
    box = legends[0].get_window_extent(renderer)
    assert box.y1 <= min(p.y0 for p in panels), (box, min(p.y0 for p in panels))
    assert {"measured", "fitted model", "95 % confidence (curve)"} <= {t.get_text() for t in legends[0].texts}
