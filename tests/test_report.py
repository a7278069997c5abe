"""The PDF report: page count and order, metadata, A4, text inside the page, atomic writing."""

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from ballimpact import archive_read, figures, report

from archive_fixture import make_archive

N_FIGURES = 7  # Figs 7, COR 3-40 m/s with the ITF drop test, 8, 9, 10, 2b and kCAL
RIG_PAGES = 1  # the rig page (ballimpact.report_rig), after the figures
A4_POINTS = (595.44, 841.68)  # 8.27 x 11.69 in at 72 pt/in


def _page_count(pdf_bytes: bytes) -> int:
    return len(re.findall(rb"/Type /Page\b", pdf_bytes))


@pytest.fixture(scope="module")
def ds():
    return make_archive()


@pytest.fixture(scope="module")
def pdf(ds, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "report.pdf"
    report.write_report(ds, out)
    return out


def test_page_count(ds, pdf):
    n_excluded = int((ds["status"].values == "excluded").sum())
    assert n_excluded == 3
    # summary + figures + the rig page + one exclusion-list page + one QC page per excluded impact
    assert _page_count(pdf.read_bytes()) == 1 + N_FIGURES + RIG_PAGES + 1 + n_excluded
    assert report.report_page_count(ds) == 1 + N_FIGURES + RIG_PAGES + 1 + n_excluded



def test_report_pages_are_the_pdf_pages(ds, pdf):
    """report_pages gives the PDF's pages one by one: as many, each A4, the first the summary."""
    pages = list(report.report_pages(ds))
    assert len(pages) == _page_count(pdf.read_bytes()) == report.report_page_count(ds)
    for page in pages:
        assert tuple(page.get_size_inches()) == pytest.approx(report.A4_PORTRAIT_IN, abs=1e-6)
    assert any("fixture-session-01" in text.get_text() for text in pages[0].texts)

def test_pdf_metadata_and_a4(pdf):
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF")
    assert b"/Author (ballimpact)" in data
    assert b"/Title (Tennis ball impact session report: fixture-session-01)" in data
    assert b"/Subject (" in data
    assert b"/CreationDate (D:" in data
    boxes = re.findall(rb"/MediaBox \[ *([\d.]+) +([\d.]+) +([\d.]+) +([\d.]+) *\]", data)
    assert boxes
    for box in boxes:
        w, h = float(box[2]), float(box[3])
        assert (w, h) == pytest.approx(A4_POINTS, abs=0.5)


@pytest.mark.skipif(shutil.which("pdftotext") is None, reason="pdftotext (poppler-utils) not installed")
def test_first_page_text(pdf, ds):
    text = subprocess.run(
        ["pdftotext", "-f", "1", "-l", "1", "-layout", str(pdf), "-"], capture_output=True, text=True, check=True
    ).stdout
    assert "fixture-session-01" in text
    assert "SYNTHETIC DATA" in text
    assert "Fixture Operator" in text
    assert "paper Table 2" in text
    exclusions = subprocess.run(
        ["pdftotext", "-f", "10", "-l", "10", str(pdf), "-"], capture_output=True, text=True, check=True
    ).stdout
    assert "Excluded impacts" in exclusions
    for impact_id in ("clip01", "gate01", "trace01"):
        assert impact_id in exclusions


def _text_inside_page(fig):
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    bad = []
    for t in fig.findobj(match=lambda a: hasattr(a, "get_window_extent") and hasattr(a, "get_text")):
        if not t.get_visible() or not t.get_text():
            continue
        bb = t.get_window_extent(renderer)
        if bb.x0 < -0.5 or bb.y0 < -0.5 or bb.x1 > width + 0.5 or bb.y1 > height + 0.5:
            bad.append(t.get_text()[:40])
    return bad


def test_summary_page_text_fits(ds):
    long = ds.copy()
    long.attrs = dict(ds.attrs)
    long.attrs["session_description"] = "A very long description of the session. " * 30
    fig = report._summary_page(long, report._session_info(long))
    assert _text_inside_page(fig) == []


def _page_texts(fig):
    from matplotlib.text import Text

    return [t.get_text() for t in fig.findobj(match=Text) if t.get_text()]


def test_summary_page_counts_the_good_impacts_whose_peak_is_withheld(ds):
    withheld = ds.copy()
    ok = np.flatnonzero(np.asarray(withheld["status"].values).astype(str) == "ok")
    status = np.array(["ok"] * withheld.sizes["impact"], dtype=object)
    status[ok[:2]] = "withheld"
    status[np.flatnonzero(np.asarray(withheld["status"].values).astype(str) != "ok")[:1]] = "withheld"  # not ok
    withheld["peak_status"] = ("impact", status)
    text = " ".join(_page_texts(report._summary_page(withheld, report._session_info(withheld))))
    assert re.search(r"The\s+peak\s+force\s+of\s+2\s+good\s+impacts\s+is\s+withheld", text), text
    plain = " ".join(_page_texts(report._summary_page(ds, report._session_info(ds))))
    assert "withheld" not in plain
    assert _text_inside_page(report._summary_page(withheld, report._session_info(withheld))) == []


def test_long_exclusion_list_paginates(ds):
    many = ds.copy()
    n = many.sizes["impact"]
    many["status"] = ("impact", np.array(["excluded"] * n, dtype=object))
    many["reason"] = ("impact", np.array(
        ["the trace shows something unusual that needs a long explanation, " * 3] * n, dtype=object))
    many = many.isel(impact=np.tile(np.arange(n), 6))
    many["impact_id"] = ("impact", np.array([f"x{k:03d}" for k in range(many.sizes["impact"])], dtype=object))
    pages = report._excluded_pages(many, report._session_info(many))
    assert len(pages) >= 2
    for page in pages:
        assert _text_inside_page(page) == []
    assert report.report_page_count(many) == 1 + N_FIGURES + RIG_PAGES + len(pages) + many.sizes["impact"]


def test_report_from_figure_files(ds, tmp_path):
    figures.save_all(ds, tmp_path / "figures")
    out = report.write_report(ds, tmp_path / "report.pdf", figures_dir=tmp_path / "figures")
    assert _page_count(out.read_bytes()) == 1 + N_FIGURES + RIG_PAGES + 1 + 3
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


def test_no_exclusions_and_real_session(tmp_path):
    ds = make_archive(balls=("pressurised",), speeds_m_s=(20.0,), with_exclusions=False, synthetic=False)
    info = report._session_info(ds)
    assert info["synthetic"] is False
    out = report.write_report(ds, tmp_path / "r.pdf")
    assert _page_count(out.read_bytes()) == 1 + N_FIGURES + RIG_PAGES + 1
    if shutil.which("pdftotext"):
        text = subprocess.run(["pdftotext", "-f", "1", "-l", "1", str(out), "-"], capture_output=True,
                              text=True, check=True).stdout
        assert "SYNTHETIC" not in text


def test_failed_write_leaves_nothing(ds, tmp_path, monkeypatch):
    target = tmp_path / "report.pdf"
    target.write_bytes(b"old report")

    def broken(*args, **kwargs):
        raise RuntimeError("page failed")

    monkeypatch.setattr(report, "_figure_page", broken)  # after the first page is written
    with pytest.raises(RuntimeError, match="page failed"):
        report.write_report(ds, target)
    assert target.read_bytes() == b"old report"
    assert [p.name for p in tmp_path.iterdir()] == ["report.pdf"]


def test_missing_output_folder(ds, tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        report.write_report(ds, tmp_path / "nope" / "r.pdf")


def test_force_curve_validation_lines_per_ball():
    ds = make_archive()
    lines = report._force_curve_validation(ds)
    balls = {str(b) for b in ds["ball"].values}
    assert len(lines) == len(balls)
    assert all("within 10 % of the peak for" in line and "RMS difference" in line for line in lines)


@pytest.mark.parametrize("n_balls", [2, 4])
def test_fit_warnings_and_undetermined_parameters_are_visible(ds, n_balls):
    """Issue 14: a parameter whose interval is the search range shows no interval, and the
    fit's warnings stand beside the ball's row (not only in the netCDF's fit_message)."""
    if n_balls != 2:  # four ball types and a long description: a full page
        ds = make_archive(balls=("pressurised", "pressureless", "oversize", "punctured"), speeds_m_s=(18.0, 26.0))
        ds.attrs["session_description"] = "A long description of the session. " * 20
    bad = ds.copy()
    ball = str(bad["ball"].values[0])
    a_lo = bad["a_lo"].values.copy()
    a_lo[0] = 0.3  # fitting.PARAMETER_BOUNDS["a"][0]
    bad["a_lo"] = ("ball", a_lo, bad["a_lo"].attrs)
    message = np.array(["ok"] * bad.sizes["ball"], dtype=object)
    message[0] = "ok; only 41 of 200 bootstrap refits converged; bands unreliable"
    bad["fit_message"] = ("ball", message, bad["fit_message"].attrs)
    fig = report._summary_page(bad, report._session_info(bad))
    fig.canvas.draw()
    from matplotlib.table import Table
    from matplotlib.text import Text

    texts = [t.get_text() for t in fig.findobj(match=Text) if t.get_visible() and t.get_text()]
    texts += [cell.get_text().get_text() for table in fig.findobj(match=Table) for cell in table.get_celld().values()]
    # a itself is inside its range (issue 49): its interval is open, the value not "not determined"
    assert any(t.endswith("\ninterval open") for t in texts), texts
    assert not any("[0.300," in t for t in texts)
    assert not any("not determined" in t for t in texts)
    label = archive_read.ball_label(bad, ball)
    assert any(" ".join(t.split()).startswith(f"Fit warning 1, {label}: a: 95 % interval reaches the search bound: "
                                              "the data bound it on one side only; only 41 of 200 bootstrap")
               for t in texts), texts
    assert any(t.endswith("(see fit warning 1)") for t in texts)
    assert _text_inside_page(fig) == []


@pytest.mark.parametrize(("name", "label"), [("fig7_contact_time_cor.png", "Fig. 7"), ("fig2b_kelvin_voigt.png",
                                                                                        "Fig. 2b"),
                                             ("fig10_components.png", "Fig. 10"), ("kcal.png", "kCAL figure")])
def test_figure_labels_follow_the_file_names(name, label):
    assert report.figure_label(name) == label


def test_figure_pages_are_numbered_as_their_files(ds):
    """Issue 14: the report called the figures 1-6 while the files are fig7/8/9/10/2b."""
    from matplotlib.text import Text

    for name in report.FIGURE_CAPTIONS:
        page = report._figure_page(ds, report._session_info(ds), name, 1, None)
        texts = [t.get_text() for t in page.findobj(match=Text)]
        number = re.match(r"fig(\w+?)_", name)
        if number:
            assert any(t.startswith(f"Fig. {number.group(1)} ({name}): ") for t in texts), (name, texts)
        assert not any(t.startswith("Figure 1") for t in texts)


def test_itf_comparison_states_prediction_measurement_and_cor_gap():
    # Table 2 ball 1 with Table 1's 138.9 cm: tests/test_itf.py measures +30.6 cm and a COR
    # 0.083 above the drop test's (both with drag), independently of this module
    import xarray as xr
    from types import SimpleNamespace

    from ballimpact import archive
    from ballimpact.balls import BALLS

    p = BALLS["pressurised"].params
    nan = float("nan")
    fit = SimpleNamespace(
        mass_kg=p.mass_kg, n_impacts=10, kb0_N_m=p.kb0_N_m, kb0_lo=nan, kb0_hi=nan, kb0_source="config",
        ak=p.ak, ak_lo=nan, ak_hi=nan, a=p.a, a_lo=nan, a_hi=nan, ac=p.ac, ac_lo=nan, ac_hi=nan,
        ak_a_correlation=nan, contact_time_rmse_pct=1.0, cor_rmse_pct=1.0, interval_method="test", messages=[],
        bootstrap=None,
    )
    with_measured = archive.fit_dataset("pressurised", fit, label="Ball 1", fit_vin_range_m_s=(14.0, 30.0),
                                        itf_rebound_cm=138.9)
    without = archive.fit_dataset("punctured", None, mass_kg=0.0575, itf_rebound_cm=103.8)
    lines = report.itf_comparison(xr.concat([with_measured, without], dim="ball", data_vars="minimal",
                                            coords="minimal", compat="override", join="exact"))
    assert len(lines) == 2
    assert "169.5 cm" in lines[0] and "outside the 134.6-147.3 cm pass range" in lines[0]
    assert "measured 138.9 cm, +30.6 cm" in lines[0]
    assert re.search(r"model's COR 0\.851 is 0\.083 above the drop test's 0\.768", lines[0])
    assert "extrapolation: the slowest impact fitted was 14.0 m/s" in lines[0]
    assert "measured 103.8 cm, no model prediction (no fit)" in lines[1]


# ------------------------------------------------------------ how the traces were conditioned


def _conditioned(ds, *, tau, tau_source, mains_hz, mains_source, hum_V=0.012, plate_hz=np.nan):
    """``ds`` with every impact's conditioning variables set to the given values."""
    out = ds.copy()
    n = out.sizes["impact"]
    for name, value in [("amplifier_time_constant_s", tau),
                        ("mains_frequency_hz", mains_hz), ("hum_amplitude_V", hum_V), ("noise_rms_V", 0.0015),
                        ("plate_resonance_hz", plate_hz), ("plate_damping_ratio", 0.1)]:
        out[name] = ("impact", np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy(), ds[name].attrs)
    for name, value in [("amplifier_time_constant_source", tau_source), ("mains_source", mains_source)]:
        out[name] = ("impact", np.array([value] * n, dtype=object), ds[name].attrs)
    return out


def test_conditioning_summary_of_the_fixture_says_no_decay_was_corrected(ds):
    n_good = int((ds["status"].values == "ok").sum())
    lines = report.conditioning_summary(ds)
    assert lines[0].startswith(f"Charge-amplifier time constant not corrected in {n_good} (")
    assert "Give plate.time_constant_s in session.yaml" in lines[0]
    assert lines[1] == "No mains hum removed: none found in the traces."
    assert len(lines) == 2  # no plate undone


def test_conditioning_summary_of_estimated_and_given_time_constants(ds):
    n = ds.sizes["impact"]
    n_good = int((ds["status"].values == "ok").sum())
    tau = np.linspace(0.78, 0.82, n)
    estimated = _conditioned(ds, tau=tau, tau_source="estimated", mains_hz=60.0,
                             mains_source="detected", plate_hz=18_500.0)
    good = estimated["status"].values == "ok"
    lines = report.conditioning_summary(estimated)
    med, lo, hi = np.median(tau[good]), tau[good].min(), tau[good].max()
    assert lines[0].startswith(f"Charge-amplifier time constant estimated from the trace in {n_good} of {n_good} "
                               f"good impacts, median {med:.3g} s ({lo:.3g}-{hi:.3g} s). Give plate.time_constant_s")
    assert lines[1] == f"Mains hum at 60 Hz (detected) removed in {n_good} of {n_good} good impacts, fundamental 12 mV."
    assert lines[2] == (f"Plate resonance identified from its ringing and undone in {n_good} of {n_good} good "
                        "impacts, 18.5 kHz.")
    given = _conditioned(ds, tau=2.5, tau_source="given", mains_hz=50.0, mains_source="given")
    lines = report.conditioning_summary(given)
    assert lines[0] == "Charge-amplifier decay undone with plate.time_constant_s = 2.5 s."
    assert "50 Hz (given)" in lines[1]


def test_conditioning_summary_needs_the_archive_variables(ds):
    old = ds.drop_vars(["amplifier_time_constant_source"])  # an archive written before they were added
    assert report.conditioning_summary(old) == []
    fig = report._summary_page(old, report._session_info(old))
    assert _text_inside_page(fig) == []


@pytest.mark.parametrize(("tau", "source", "expected"), [
    (0.80349, "estimated", "time constant 0.8035 s (estimated)"),
    (2.5, "given", "time constant 2.5 s (given)"),
    (np.nan, "none", "amplifier decay not corrected"),
])
def test_impact_conditioning_line(ds, tau, source, expected):
    c = _conditioned(ds, tau=tau, tau_source=source, mains_hz=50.0, mains_source="given",
                     plate_hz=18_500.0)
    assert report.impact_conditioning(c, 0) == (f"noise 1.5 mV, hum 12 mV at 50 Hz (given), {expected}, "
                                                "plate resonance 18.5 kHz (damping ratio 0.1) undone")
    early = _conditioned(ds, tau=tau, tau_source="", mains_hz=np.nan, mains_source="")
    assert report.impact_conditioning(early, 0) == ""  # excluded before its trace was conditioned


def _full_page_archive():
    """Four ball types, a long description and every conditioning sentence: a full summary page."""
    full = make_archive(balls=("pressurised", "pressureless", "oversize", "punctured"), speeds_m_s=(18.0, 26.0))
    full.attrs["session_description"] = "A long description of the session. " * 20
    n = full.sizes["impact"]
    return _conditioned(full, tau=np.linspace(0.5, 1.5, n), tau_source="estimated", mains_hz=50.0,
                        mains_source="detected", plate_hz=np.linspace(9e3, 20e3, n))


def test_summary_page_with_conditioning_sentences_fits():
    full = _full_page_archive()
    fig = report._summary_page(full, report._session_info(full))
    assert len(report.conditioning_summary(full)) == 3
    assert _text_inside_page(fig) == []


def _warned(ds, warnings):
    out = ds.copy()
    out.attrs = dict(ds.attrs)
    out.attrs["validate_warnings"] = json.dumps(warnings)
    return out


def test_session_warnings_lose_the_raw_folder_path(ds):
    assert report.session_warnings(ds) == []  # the fixture's session gave none
    warned = _warned(ds, ["/data/raw/rig 2/s1/session.yaml: key 'daq.bandwidth_hz' not given, and at 25 kHz ...",
                          "C:\\raw\\s1\\impacts.csv: column 'x' ignored", "daq.sample_rate_hz = 50000 Hz disagrees",
                          "p1: unreadable trace: traces/p1.csv: line 3"])
    assert report.session_warnings(warned) == [
        "session.yaml: key 'daq.bandwidth_hz' not given, and at 25 kHz ...",
        "impacts.csv: column 'x' ignored", "daq.sample_rate_hz = 50000 Hz disagrees",
        "p1: unreadable trace: traces/p1.csv: line 3"]  # only the path before session.yaml or impacts.csv goes


def test_session_warnings_are_counted_on_the_summary_page_and_open_the_exclusion_list(ds):
    long = "session.yaml: key 'daq.bandwidth_hz' not given, and at 25 kHz a plate resonance " + "between them " * 30
    warned = _warned(ds, [long, "short one"] + [f"warning {k}: " + "word " * 100 for k in range(8)])
    page1 = " ".join(_page_texts(report._summary_page(warned, report._session_info(warned))))
    assert re.search(r"Reading\s+the\s+session\s+gave\s+10\s+warnings", page1), page1
    assert "between them" not in page1  # counted there, listed with the exclusions
    pages = report._excluded_pages(warned, report._session_info(warned))
    first = " ".join(_page_texts(pages[0]))
    assert "Warnings from reading the session: 10 (usable but suspect input)" in first
    assert "- session.yaml: key 'daq.bandwidth_hz' not given" in first and "- short one" in first
    assert re.search(r"- and \d more\.", first)  # the rest counted
    assert "clip01" in " ".join(" ".join(_page_texts(p)) for p in pages)  # the exclusions still follow
    for page in pages:
        assert _text_inside_page(page) == []
    plain = " ".join(_page_texts(report._summary_page(ds, report._session_info(ds))))
    assert not re.search(r"Reading\s+the\s+session\s+gave", plain), plain  # no warning: no sentence
    assert "Warnings from reading" not in " ".join(_page_texts(report._excluded_pages(ds, report._session_info(ds))[0]))


def test_summary_page_with_warnings_fit_warnings_conditioning_and_four_balls_fits():
    full = _full_page_archive()
    message = ("ok; only 3 impacts: the intervals are rough; only 41 of 200 bootstrap refits converged; bands "
               "unreliable, and more words to fill a third line of the note")
    full["fit_message"] = ("ball", np.array([message] * full.sizes["ball"], dtype=object), full["fit_message"].attrs)
    full = _warned(full, ["a warning that needs every line it may take. " * 20] * 6)
    fig = report._summary_page(full, report._session_info(full))
    assert re.search(r"Reading\s+the\s+session\s+gave\s+6\s+warnings", " ".join(_page_texts(fig)))
    assert _text_inside_page(fig) == []


# ------------------------------------------------------------ layout: no clipped or overlapping text (issue 49)


def _layout_faults(fig) -> list[str]:
    """What a reader would see as broken on a page: a text beyond the page, a table cell's text beyond its cell,
    two texts of the page (its own texts and table cells) on top of each other."""
    from matplotlib.table import Table

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    faults = [f"outside the page: {t!r}" for t in _placed_texts_outside(fig, renderer)]
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in fig.texts if t.get_visible() and t.get_text()]
    for table in fig.findobj(match=Table):
        for cell in table.get_celld().values():
            text = cell.get_text()
            if not text.get_text():
                continue
            tb, cb = text.get_window_extent(renderer), cell.get_window_extent(renderer)
            if tb.x0 < cb.x0 - 0.5 or tb.x1 > cb.x1 + 0.5 or tb.y0 < cb.y0 - 0.5 or tb.y1 > cb.y1 + 0.5:
                faults.append(f"beyond its cell: {text.get_text()!r}")
            boxes.append((text.get_text(), tb))
    for i, (a, box_a) in enumerate(boxes):
        for b, box_b in boxes[i + 1:]:
            overlap_x = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)
            overlap_y = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
            if overlap_x > 1 and overlap_y > 1:
                faults.append(f"overlap: {a[:30]!r} / {b[:30]!r}")
    return faults


def legends_on_panels(fig) -> list[list[str]]:
    """The legends of a figure that lie on one of its panels (each as its first entries)."""
    from matplotlib.legend import Legend

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    panels = [ax.get_window_extent(renderer) for ax in fig.get_axes() if ax.axison and ax.get_visible()]
    found = []
    for legend in fig.findobj(match=Legend):
        lb = legend.get_window_extent(renderer)
        if any(min(lb.x1, p.x1) - max(lb.x0, p.x0) > 1 and min(lb.y1, p.y1) - max(lb.y0, p.y0) > 1 for p in panels):
            found.append([t.get_text() for t in legend.texts][:3])
    return found


def _placed_texts_outside(fig, renderer) -> list[str]:
    """The texts the report places (page texts, titles, axis labels, legends, table cells: not the tick labels,
    which matplotlib keeps for ticks outside the view) that reach beyond the page."""
    from matplotlib.axis import Tick

    ticks = {id(t) for tick in fig.findobj(match=Tick) for t in (tick.label1, tick.label2)}
    page = fig.bbox
    bad = []
    for t in fig.findobj(match=lambda a: hasattr(a, "get_window_extent") and hasattr(a, "get_text")):
        if id(t) in ticks or not t.get_visible() or not t.get_text():
            continue
        bb = t.get_window_extent(renderer)
        if bb.x0 < -0.5 or bb.y0 < -0.5 or bb.x1 > page.width + 0.5 or bb.y1 > page.height + 0.5:
            bad.append(t.get_text()[:40])
    return bad


def _four_balls_with_fit_warnings():
    """Four ball types with long labels, fit warnings, an undetermined parameter and an interval of four orders of
    magnitude, and the demo's long description: the session of issue 49."""
    ds = make_archive(balls=("pressurised", "pressureless", "oversize", "punctured"), speeds_m_s=(18.0, 26.0))
    ds.attrs["session_description"] = (
        "SYNTHETIC DATA, not a laboratory measurement. Made by `ballimpact synth` (seed 2004): impacts simulated "
        "with the Goodwill & Haake (2004) viscoelastic model and passed through a simulated sensor chain (plate "
        "resonance, per-impact kCAL spread, charge-amplifier high-pass decay, DC offset, mains hum, white noise, "
        "16-bit ADC with clipping, gate timer rounding). Faulty impacts are planted on purpose; see their note.")
    labels = np.array(["Ball 1: pressurised (new can, 2026 batch)", "Ball 2: pressureless practice ball",
                       "Ball 3: oversize (type 3)", "Ball 4: punctured with a 1 mm needle"], dtype=object)
    ds["ball_label"] = ("ball", labels)
    for name, value in (("ak_lo", 6602.0), ("ak_hi", 63_974_727.0), ("a_lo", 0.3)):
        values = ds[name].values.copy()
        values[0] = value
        ds[name] = ("ball", values, ds[name].attrs)
    rough = ("only 3 impacts: the intervals are rough; the ak interval reaches the end of its profile grid: the data "
             "barely constrain it; the a interval reaches the end of its profile grid: the data barely constrain it; "
             "the kb_10mm interval reaches the end of its profile grid: the data barely constrain it")
    message = np.array([f"ok; {rough}"] * ds.sizes["ball"], dtype=object)
    message[0] = f"ok; only 41 of 200 bootstrap refits converged; bands unreliable; {rough}"
    message[2] = f"ok; AC sits on its search bound; the data do not constrain it, treat it with care; {rough}"
    ds["fit_message"] = ("ball", message, ds["fit_message"].attrs)
    return ds


@pytest.mark.parametrize("which", ["demo-like", "four balls with fit warnings"])
def test_pages_1_to_3_have_no_clipped_or_overlapping_text(ds, which):
    """Issue 49: headings ran off the page, the parameter table's headers ran together, ball labels were cut, the AK
    interval overflowed its cell, and Fig. 7's legends covered its panels."""
    data = ds if which == "demo-like" else _four_balls_with_fit_warnings()
    info = report._session_info(data)
    pages = [report._summary_page(data, info)]
    pages += [report._figure_page(data, info, name, k + 1, None) for k, name in enumerate(report.FIGURE_CAPTIONS)
              if k < 2]
    for number, page in enumerate(pages, start=1):
        assert _layout_faults(page) == [], (which, number)
    assert legends_on_panels(pages[1]) == [], which  # Fig. 7: one legend, below its panels


def test_the_figure_titles_of_every_page_stay_on_it(ds):
    """Issue 49: "Fig. 7 (fig7_contact_time_cor.png): Contact time and coefficient of restitution against inb"."""
    info = report._session_info(ds)
    for k, name in enumerate(report.FIGURE_CAPTIONS):
        page = report._figure_page(ds, info, name, k + 1, None)
        page.canvas.draw()
        assert _placed_texts_outside(page, page.canvas.get_renderer()) == [], name


def test_the_description_is_never_cut_mid_word(ds):
    """Issue 49: the demo's description was cut mid-word ("simulated sensor chai ... e, per-impact")."""
    data = ds.copy()
    data.attrs = dict(ds.attrs)
    demo = _four_balls_with_fit_warnings().attrs["session_description"]
    words = set(demo.split())
    for description in (demo, "word " * 400 + "end"):
        data.attrs["session_description"] = description
        shown = [t for t in _page_texts(report._summary_page(data, report._session_info(data)))
                 if t.split()[:2] == description.split()[:2]]
        assert len(shown) == 1, shown
        text = " ".join(shown[0].split())
        if len(description) < 600:
            assert text == " ".join(description.split())  # all of it
        else:
            assert text.endswith(" ...") and set(text[:-4].split()) <= set(description.split()) | words | {"..."}
