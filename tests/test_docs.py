"""The documentation site's pages (docs/): a session written from the user guide alone, the
API reference's coverage of the library, and the links between the pages and the repository.

The code blocks of the pages are run by tests/test_readme.py, with the README's.
"""

from __future__ import annotations

import ast
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from ballimpact.cli import main as cli_main
from ballimpact.processing import iter_process
from ballimpact.session import read_session
from ballimpact.validation import format_validation, validate_session
from tracekit import make_trace, shape_integral
from workflow_helpers import REPO

DOCS = REPO / "docs"
GUIDE = DOCS / "writing-a-session.md"
#: a fenced block with its info string: ```lang title="..."
FENCE = re.compile(r'^```(\w*)[ \t]*(?:title="([^"]*)")?[^\n]*\n(.*?)^```', re.S | re.M)


def _titled_blocks(page: Path) -> dict[str, tuple[str, str]]:
    """Blocks of a page that carry a title, as title -> (language, text)."""
    return {title: (lang, body) for lang, title, body in FENCE.findall(page.read_text(encoding="utf-8")) if title}


def _block(title: str) -> str:
    blocks = _titled_blocks(GUIDE)
    assert title in blocks, f"{GUIDE.name} has no block titled {title!r}: {sorted(blocks)}"
    return blocks[title][1]


def _session_from_the_guide(root: Path) -> Path:
    """The session of docs/writing-a-session.md, made from its blocks alone.

    session.yaml and impacts.csv are the page's blocks as they are. Each trace file is the
    page's trace block up to its column name, then samples of an impact recorded as the page
    says (quiet record before and after the contact), from tests/tracekit.py's independent
    sensor chain: an amplifier decay, an offset, 50 Hz hum and noise, at the sample rate the
    trace's header gives, its impulse matching the row's gate speeds at one calibration
    factor.
    """
    yaml_title = next(t for t in _titled_blocks(GUIDE) if t.endswith("/session.yaml"))
    folder = root / Path(yaml_title).parent.relative_to("raw")
    (folder / "traces").mkdir(parents=True)
    (folder / "session.yaml").write_text(_block(yaml_title), encoding="utf-8")
    impacts_csv = _block(f"raw/{folder.name}/impacts.csv")
    (folder / "impacts.csv").write_text(impacts_csv, encoding="utf-8")
    trace_title = next(t for t in _titled_blocks(GUIDE) if "/traces/" in t)
    trace_lines = _block(trace_title).splitlines()
    header = trace_lines[: trace_lines.index("voltage_V") + 1]
    rate = float(re.search(r"^# sample_rate_hz: *(\S+)", "\n".join(header), re.M).group(1))
    spacing, mass_kg, kcal = 0.100, 0.0577, 180.0
    rows = [line.split(",") for line in impacts_csv.strip().splitlines()[1:]]
    for k, (_, _, trace, in1, in2, out2, out1) in enumerate(rows):
        vin = spacing / (float(in2) - float(in1))
        cor = (spacing / (float(out1) - float(out2))) / vin
        half_sine = 4.0e-3
        peak_v = mass_kg * vin * (1.0 + cor) / (kcal * shape_integral(half_sine))
        voltage, _, _ = make_trace(sample_rate_hz=rate, half_sine_s=half_sine, peak_V=peak_v,
                                   pre_s=0.015, post_s=0.030, tau_s=0.8, offset_V=0.02, hum_V=0.005,
                                   noise_V=0.001, mass_kg=mass_kg, vin_m_s=vin, cor=cor, seed=k)
        samples = "\n".join(f"{v:.5f}" for v in voltage)
        (folder / trace).write_text("\n".join(header) + "\n" + samples + "\n", encoding="utf-8")
    return folder


@pytest.fixture(scope="module")
def guide_session(tmp_path_factory) -> Path:
    return _session_from_the_guide(tmp_path_factory.mktemp("guide"))


def test_guide_session_validates_without_a_problem_or_a_warning(guide_session, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every key of the guide's session.yaml is known
        report = validate_session(guide_session)
    assert report.ok and report.warnings == [], (report.problems, report.warnings)
    assert cli_main(["validate", "--strict", str(guide_session)]) == 0
    assert "Verdict: OK" in capsys.readouterr().out


def test_guide_shows_what_validate_prints(guide_session):
    """The validate output on the page is the real one, line for line."""
    shown = _block(f"ballimpact validate raw/{guide_session.name}").strip().splitlines()
    assert shown == format_validation(validate_session(guide_session)).strip().splitlines()


def test_guide_session_is_processed_every_impact_ok(guide_session):
    session = read_session(guide_session)
    results = list(iter_process(session))
    assert [r.impact_id for r in results] == ["p-001", "p-002", "p-003"]
    for r in results:
        assert r.status == "ok", (r.impact_id, r.reason)
    # the speeds the page states for p-001 (20 m/s in, 12.6 m/s out), from its gate times
    first = results[0]
    np.testing.assert_allclose([first.vin_m_s, first.vout_m_s], [20.0, 12.6], rtol=1e-3)
    # one calibration factor for the session, as made
    kcal = np.array([r.kcal_N_per_V for r in results])
    np.testing.assert_allclose(kcal, 180.0, rtol=0.01)


def test_guide_blocks_are_the_files_the_folder_layout_names():
    layout = next(body for lang, title, body in FENCE.findall(GUIDE.read_text(encoding="utf-8"))
                  if body.startswith("raw/"))
    named = re.findall(r"^  (\S+)", layout, re.M)
    titles = _titled_blocks(GUIDE)
    folder = layout.splitlines()[0].rstrip("/")
    for name in ("session.yaml", "impacts.csv"):
        assert name in named and f"{folder}/{name}" in titles
    traces = [t for t in titles if "/traces/" in t]
    assert traces and all(t.split(f"{folder}/", 1)[1] in named for t in traces)


# --- the API reference --------------------------------------------------------------------

def _hooks():
    import runpy
    return runpy.run_path(str(DOCS / "hooks.py"), run_name="hooks")


def _public_modules() -> list[str]:
    """Every public module as its path under src/ballimpact without .py (``signal/contact``; ``signal`` for the
    subpackage itself), as the docs hook lists them."""
    return _hooks()["public_modules"]()


def test_every_public_module_has_an_api_page_in_the_nav():
    nav = (REPO / "mkdocs.yml").read_text(encoding="utf-8")
    api_page = _hooks()["api_page"]
    index = (DOCS / "api" / "index.md").read_text(encoding="utf-8")
    for module in _public_modules():
        page = DOCS / "api" / api_page(module)
        assert page.is_file(), page
        assert f"::: ballimpact.{module.replace('/', '.')}" in page.read_text(encoding="utf-8"), page
        assert f"api/{api_page(module)}" in nav, module
        assert f"({api_page(module)})" in index, module


def test_the_docs_hook_sees_the_signal_subpackage():
    modules = _public_modules()
    assert "signal" in modules and "signal/contact" in modules and "checks" in modules
    assert not any(m.startswith("_") or "/_" in m for m in modules)


def test_every_public_module_has_a_one_line_docstring():
    """The API index lists each module by the first line of its docstring."""
    api_page = _hooks()["api_page"]
    for module in _public_modules():
        source = REPO / "src" / "ballimpact" / (f"{module}/__init__.py" if api_page(module).endswith("index.md")
                                                else f"{module}.py")
        doc = ast.get_docstring(ast.parse(source.read_text(encoding="utf-8")))
        assert doc and doc.splitlines()[0].endswith("."), module


# --- the site's pages ---------------------------------------------------------------------

def _nav_pages() -> list[str]:
    nav = (REPO / "mkdocs.yml").read_text(encoding="utf-8").split("\nnav:", 1)[1]
    return re.findall(r"([\w./-]+\.md)\s*$", nav, re.M)


def test_every_page_of_the_docs_folder_is_in_the_nav():
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md") if "generated" not in p.parts}
    in_nav = set(_nav_pages())
    assert in_nav <= pages, sorted(in_nav - pages)
    # a page written by a generator may exist before it is added to the nav
    assert pages == in_nav or pages - in_nav == set(), sorted(pages - in_nav)


@pytest.mark.parametrize("page", ["accuracy.md", "coverage.md", "robustness.md", "rigs.md"])
def test_each_validation_page_names_the_command_that_regenerates_it(page):
    text = (DOCS / page).read_text(encoding="utf-8")
    note = text.split('!!! note "Regenerate these numbers"', 1)
    assert len(note) == 2, f"{page}: no 'Regenerate these numbers' note"
    commands = re.findall(r"python (bench/\w+\.py)", note[1].split("\n## ", 1)[0])
    assert commands, page
    for script in commands:
        assert (REPO / script).is_file(), (page, script)


def test_repository_paths_named_on_the_pages_exist():
    """`bench/x.py`, `tests/test_x.py` and `src/ballimpact/x.py` named on a page are there."""
    missing = []
    for page in DOCS.rglob("*.md"):
        if page.name in ("robustness-history.md", "changelog.md"):  # history names what was there then
            continue
        for path in re.findall(r"\b((?:bench|tests|src/ballimpact|workflow)/[\w/.-]+\.(?:py|c|txt|smk|yaml))\b",
                               page.read_text(encoding="utf-8")):
            if not (REPO / path).exists():
                missing.append((page.name, path))
    assert not missing, missing
