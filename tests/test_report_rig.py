"""The rig page of the report: its table (values, 95 % intervals, units, sources, notes), its warnings and figures."""

from __future__ import annotations

import shutil
import subprocess

import pytest
from matplotlib.image import AxesImage
from matplotlib.table import Table
from matplotlib.text import Text

from ballimpact import figures, report
from ballimpact.report_rig import MAX_RIG_WARNING_LINES, RIG_ROWS, rig_page, rig_table_rows

from archive_fixture import make_archive
from rigkit import estimates, rig_dataset, ringing_archive
from test_report import _text_inside_page as _texts_outside


def _text_inside_page(fig):
    """The texts off the page (test_report's check), less the tick labels outside their axes' view, never drawn."""
    hidden = set()
    for ax in fig.axes:
        for axis, (lo, hi) in ((ax.xaxis, sorted(ax.get_xlim())), (ax.yaxis, sorted(ax.get_ylim()))):
            for tick in axis.get_major_ticks():
                if not lo - 1e-9 * (hi - lo) <= tick.get_loc() <= hi + 1e-9 * (hi - lo):
                    hidden.update(t.get_text()[:40] for t in (tick.label1, tick.label2))
    return [t for t in _texts_outside(fig) if t not in hidden]

DISAGREE = ("session.yaml states plate.resonance_hz = 3.5 kHz, but the session's 8 impacts give 3 kHz (95 % interval "
            "2.997-3.003): the stated value is used; check the tap test or the amplifier's setting")


def _with_rig(ds, plate="stated", warnings=(DISAGREE,)):
    ids = [str(i) for i in ds["impact_id"].values]
    return ds.merge(rig_dataset(ids, estimates(plate=plate, n=len(ids)), warnings=warnings))


@pytest.fixture(scope="module")
def archive():
    return _with_rig(make_archive())


def _all_texts(fig):
    fig.canvas.draw()
    texts = [t.get_text() for t in fig.findobj(match=Text) if t.get_visible() and t.get_text()]
    texts += [c.get_text().get_text() for table in fig.findobj(match=Table) for c in table.get_celld().values()]
    return texts


def test_the_table_shows_each_quantity_in_its_unit_with_interval_source_and_note():
    rows, notes = rig_table_rows(ringing_archive(8))
    assert [r[0] for r in rows] == [label for label, _, _ in RIG_ROWS.values()]
    fn = rows[0]
    assert fn[1:6] == ["3", "[2.997, 3.003]", "kHz", "identified", "8"]  # 3000 Hz [2997, 3003] in kHz
    assert rows[4][1:4] == ["0", "[0, 0]", "mV"] and rows[5][1:4] == ["1", "[0.95, 1.05]", "mV"]  # 1 mV noise
    assert rows[3][1:5] == ["50", "-", "Hz", "stated"]  # a stated value has no interval
    assert rows[7][1:5] == ["1", "-", "%", "identified"]  # kCAL's spread 0.01: 1 %
    assert notes == []
    rows, notes = rig_table_rows(ringing_archive(8, plate="none"))
    assert rows[0][1:5] == ["-", "-", "kHz", "none"] and rows[0][6] == rows[1][6] == "(1)"  # one note for both
    assert len(notes) == 1 and notes[0].startswith("no free ringing above the noise after 8 contacts")


def test_the_rig_page_has_its_table_note_warning_and_figures(archive):
    page = rig_page(archive, report._session_info(archive))
    texts = _all_texts(page)
    joined = " ".join(" ".join(texts).split())
    assert "The session's rig" in texts
    for label, _, _ in RIG_ROWS.values():
        assert label in texts
    assert "stated" in texts
    assert "(1) the session's traces give 3.1 kHz (95 % interval 3.09-3.11)" in joined  # beside the stated value
    assert "Warnings: 1 stated key(s) the traces disagree with" in texts
    assert " ".join(DISAGREE.split()) in joined
    assert "Free ringing of the plate after each contact, pooled over the session" in texts
    assert "The rig per impact against the session's values" in texts
    assert _text_inside_page(page) == []


@pytest.mark.parametrize("plate", ["identified", "none"])
def test_the_rig_page_of_a_plate_identified_or_not(plate):
    ds = ringing_archive(8, plate=plate, excluded=(1,))
    page = rig_page(ds, report._session_info(ds))
    joined = " ".join(" ".join(_all_texts(page)).split())
    if plate == "identified":
        assert "fn = 3 kHz [2.997, 3.003]" in joined and "The plate's free ringing was fitted over 8 impacts" in joined
    else:
        assert "no plate resonance identified: no free ringing above the noise" in joined
    assert "Warnings:" not in joined
    assert _text_inside_page(page) == []


def test_many_warnings_are_counted_not_listed():
    ds = _with_rig(make_archive(), warnings=[f"warning {k}: " + "the traces disagree " * 12 for k in range(10)])
    page = rig_page(ds, report._session_info(ds))
    joined = " ".join(" ".join(_all_texts(page)).split())
    assert "Warnings: 10 stated key(s)" in joined and "more (the archive's rig_value attribute rig_warnings)" in joined
    shown = [t for t in _all_texts(page) if t.startswith("- warning")]
    assert shown and sum(t.count("\n") + 1 for t in shown) <= MAX_RIG_WARNING_LINES
    assert _text_inside_page(page) == []


def test_an_archive_without_the_rig_gets_a_page_that_says_so():
    ds = make_archive()
    page = rig_page(ds, report._session_info(ds))
    assert any("This archive has no rig variables" in t for t in _all_texts(page))
    assert _text_inside_page(page) == []


def test_the_rig_page_places_the_figure_files(archive, tmp_path):
    figures.save_all(archive, tmp_path)
    assert (tmp_path / "rig_ringing.png").is_file() and (tmp_path / "rig_per_impact.png").is_file()
    page = rig_page(archive, report._session_info(archive), tmp_path)
    assert len(page.findobj(match=AxesImage)) == 2


def test_the_report_has_the_rig_page_after_the_figures(archive, tmp_path):
    pages = list(report.report_pages(archive))
    n_figures = len(report.FIGURE_CAPTIONS)
    assert "The session's rig" in _all_texts(pages[1 + n_figures])
    assert not any("The session's rig" in _all_texts(p) for p in pages[: 1 + n_figures])
    out = report.write_report(archive, tmp_path / "r.pdf")
    if shutil.which("pdftotext"):
        number = str(2 + n_figures)
        text = subprocess.run(["pdftotext", "-f", number, "-l", number, str(out), "-"], capture_output=True,
                              text=True, check=True).stdout
        assert "The session's rig" in text and "Plate resonance fn" in text and "disagree" in text
