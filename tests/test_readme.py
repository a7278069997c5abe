"""README.md and the documentation site's pages: every code block runs, parses or names things
that exist; the README stays a short page for users.

* ```python blocks are executed, in the working folder of the demo run (they read
  results/demo-2004/... and raw/demo-2004);
* ```yaml blocks that are a session.yaml (they hold `session_id:`) are read with the
  session reader, without a warning;
* ```sh blocks: every `ballimpact ...` command parses with the real argument parser, every
  `make X` names a Makefile target, every `python X.py` an existing script.

The pages are README.md and docs/*.md, less the history pages (docs/changelog.md,
docs/robustness-history.md), whose commands are those of their day. Blocks indented under
an admonition count too.
"""

from __future__ import annotations

import re
import shlex
import textwrap
import warnings

import matplotlib
import pytest

from ballimpact.cli import build_parser
from ballimpact.session import read_session
from workflow_helpers import REPO

README = REPO / "README.md"
HISTORY_PAGES = {"changelog.md", "robustness-history.md"}
PAGES = [README] + sorted(p for p in (REPO / "docs").glob("*.md") if p.name not in HISTORY_PAGES)
#: a fenced block, at the start of a line or indented (under an admonition), with its info string
BLOCK = re.compile(r"^( *)```(\w*)[^\n]*\n(.*?)^\1```", re.S | re.M)
README_MAX_LINES = 300


def _page_blocks(page, language: str) -> list[str]:
    return [textwrap.dedent(body) for indent, lang, body in BLOCK.findall(page.read_text(encoding="utf-8"))
            if lang == language]


def _blocks(language: str) -> list[tuple[str, str]]:
    """(page name, block text) of every block in that language on every page."""
    return [(page.name, body) for page in PAGES for body in _page_blocks(page, language)]


def test_readme_has_the_blocks_it_promises():
    assert len(_page_blocks(README, "python")) >= 1
    assert len(_page_blocks(README, "yaml")) >= 1
    assert len(_page_blocks(README, "sh")) >= 1


PYTHON = _blocks("python")


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(PYTHON)), ids=[f"{name}-{k}" for k, (name, _) in enumerate(PYTHON)])
def test_python_block_runs_on_the_demo_results(demo_run_output, index, monkeypatch):
    matplotlib.use("Agg")
    workdir = demo_run_output["workdir"]  # holds results/demo-2004/
    try:
        (workdir / "raw").symlink_to(REPO / "raw", target_is_directory=True)  # and raw/demo-2004
    except FileExistsError:
        pass
    monkeypatch.chdir(workdir)
    name, code = PYTHON[index]
    exec(compile(code, f"{name} python block {index + 1}", "exec"), {"__name__": "readme"})  # noqa: S102


EXAMPLES = [(name, body) for name, body in _blocks("yaml") if re.search(r"^session_id:", body, re.M)]
EXAMPLES.append(("example-session.yaml", (REPO / "docs" / "example-session.yaml").read_text(encoding="utf-8")))


@pytest.mark.parametrize("index", range(len(EXAMPLES)), ids=[f"{name}-{k}" for k, (name, _) in enumerate(EXAMPLES)])
def test_yaml_block_is_a_valid_session_yaml(tmp_path, index):
    """The session.yaml examples of the pages (and docs/example-session.yaml)."""
    text = EXAMPLES[index][1]
    session_id = re.search(r"^session_id: *(\S+)", text, re.M).group(1).strip('"')
    folder = tmp_path / session_id
    (folder / "traces").mkdir(parents=True)
    (folder / "session.yaml").write_text(text, encoding="utf-8")
    balls = re.findall(r"^  (\w[\w-]*):\s*(?:#.*)?$", text.split("\nballs:", 1)[1], re.M)
    rows = [f"i{k},{ball},traces/t.csv,0.0,0.004,0.010,0.0145,," for k, ball in enumerate(balls)]
    (folder / "impacts.csv").write_text(
        "impact_id,ball,trace,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s,mass_g,note\n" + "\n".join(rows) + "\n")
    (folder / "traces" / "t.csv").write_text("voltage_V\n" + "0.0\n" * 200)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every key of the example is known: no warning
        session = read_session(folder)
    assert session.meta.session_id == session_id
    assert list(session.meta.balls) == balls
    # the units the comments state: mass in g is read as kg, the spacing in m
    mass_g = float(re.search(r"mass_g: *([\d.]+)", text).group(1))
    assert session.meta.balls[balls[0]].mass_kg == pytest.approx(mass_g / 1000.0, rel=1e-12)


def _sh_commands() -> list[tuple[str, str]]:
    commands = []
    for name, body in _blocks("sh"):
        joined = re.sub(r"\\\n\s*", " ", body)
        for line in joined.splitlines():
            for command in line.split("#", 1)[0].split("&&"):
                if command.strip():
                    commands.append((name, command.strip()))
    return commands


@pytest.mark.parametrize("name, command", _sh_commands())
def test_sh_block_commands_exist(name, command):
    words = shlex.split(re.sub(r"\[([^\]]*)\]", r"\1", command))  # "[--json]": an optional argument
    program = words[0].removeprefix(".venv/bin/")
    if program == "ballimpact":
        build_parser().parse_args(words[1:])  # SystemExit on an unknown option or sub-command
    elif program == "make":
        targets = re.findall(r"^([\w-]+):", (REPO / "Makefile").read_text(encoding="utf-8"), re.M)
        assert set(words[1:]) <= set(targets), (name, command, targets)
    elif program == "python" and words[1:3] != ["-m", "pytest"]:
        assert (REPO / words[1]).is_file(), (name, command)
    elif program == "python":
        assert words[0] == ".venv/bin/python", (name, command)  # the project's interpreter runs the suite
    elif program == "snakemake":
        for word in words:
            if word.startswith("profiles/"):
                assert (REPO / word).is_dir(), (name, command)
    else:
        pytest.fail(f"{name}: command not checked by this test: {command!r}")


def test_no_developer_wording():
    text = README.read_text(encoding="utf-8")
    for phrase in ("the issue's targets", "on this 2-core machine", "on this machine", "../shared", "shared/spec"):
        assert phrase not in text, phrase
    # one wording for the intervals: nominal 95 %, with the coverage measured by bench/coverage.py
    assert "nominal 95 %" in text and "read them as about 90 %" not in text
    assert "0.948-0.951 for AK, a, AC and kB(20 mm)" in text


def test_readme_is_short_and_has_no_history():
    """At most 300 lines, no commit hash, no issue number: the history is docs/changelog.md's."""
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= README_MAX_LINES
    hashes = re.findall(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b", text)
    assert hashes == [], hashes
    issues = re.findall(r"(?i)\bissues?\s*#?\d+|(?<![\w&])#\d+\b|\bPR\s*#?\d+", text)
    assert issues == [], issues


def test_readme_links_lead_to_files_of_the_repository():
    for target in re.findall(r"\]\(([^)#]+)\)", README.read_text(encoding="utf-8")):
        if not target.startswith("http"):
            assert (REPO / target).exists(), target


@pytest.mark.slow
def test_run_summary_in_the_docs_is_the_demo_run_s(demo_run_output):
    """The summary shown under "What a run prints" (docs/getting-started.md) is what the demo run prints."""
    page = REPO / "docs" / "getting-started.md"
    text = page.read_text(encoding="utf-8").split("## What a run prints", 1)[1]
    shown = BLOCK.search(text).group(3).strip().splitlines()
    out = demo_run_output["stdout"]
    printed = out[out.rindex("ballimpact run summary"):].split("=" * 78)[0].strip().splitlines()
    assert shown[2:-1] == printed[1:]  # session lines; the header names the results folder
