"""README.md: every code block runs, parses or names things that exist (issue 14).

* ```python blocks are executed, in the working folder of the demo run (they read
  results/demo-2004/...);
* ```yaml blocks are session.yaml examples: read with the session reader, no warning;
* ```sh blocks: every `ballimpact ...` line parses with the real argument parser, every
  `make X` names a Makefile target, every `python X.py` an existing script.
"""

from __future__ import annotations

import re
import shlex
import warnings

import matplotlib
import pytest

from ballimpact.cli import build_parser
from ballimpact.session import read_session
from workflow_helpers import REPO

README = REPO / "README.md"
BLOCK = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)


def _blocks(language: str) -> list[str]:
    return [body for lang, body in BLOCK.findall(README.read_text(encoding="utf-8")) if lang == language]


def test_readme_has_the_blocks_it_promises():
    assert len(_blocks("python")) >= 1
    assert len(_blocks("yaml")) >= 1
    assert len(_blocks("sh")) >= 1


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(_blocks("python"))))
def test_python_block_runs_on_the_demo_results(demo_run_output, index, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(demo_run_output["workdir"])  # holds results/demo-2004/
    code = _blocks("python")[index]
    exec(compile(code, f"README.md python block {index + 1}", "exec"), {"__name__": "readme"})  # noqa: S102


EXAMPLES = _blocks("yaml") + ([(REPO / "docs" / "example-session.yaml").read_text(encoding="utf-8")]
                              if (REPO / "docs" / "example-session.yaml").is_file() else [])


@pytest.mark.parametrize("index", range(len(EXAMPLES)))
def test_yaml_block_is_a_valid_session_yaml(tmp_path, index):
    """The README's session.yaml example (and docs/example-session.yaml, which it links)."""
    text = EXAMPLES[index]
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


def _sh_commands() -> list[str]:
    commands = []
    for body in _blocks("sh"):
        joined = re.sub(r"\\\n\s*", " ", body)
        for line in joined.splitlines():
            line = line.split("#", 1)[0].strip()
            if line:
                commands.append(line)
    return commands


@pytest.mark.parametrize("command", _sh_commands())
def test_sh_block_commands_exist(command):
    words = shlex.split(re.sub(r"\[([^\]]*)\]", r"\1", command))  # "[--json]": an optional argument
    if words[0] == "ballimpact":
        build_parser().parse_args(words[1:])  # SystemExit on an unknown option or sub-command
    elif words[0] == "make":
        targets = re.findall(r"^([\w-]+):", (REPO / "Makefile").read_text(encoding="utf-8"), re.M)
        assert set(words[1:]) <= set(targets), (command, targets)
    elif words[0] == "python":
        assert (REPO / words[1]).is_file(), command
    elif words[0] == ".venv/bin/python":
        assert words[1:3] == ["-m", "pytest"], command
    elif words[0] in ("snakemake", ".venv/bin/snakemake"):
        for word in words:
            if word.startswith("profiles/"):
                assert (REPO / word).is_dir(), command
    else:
        pytest.fail(f"README command not checked by this test: {command!r}")


def test_no_developer_wording():
    text = README.read_text(encoding="utf-8")
    for phrase in ("the issue's targets", "on this 2-core machine", "on this machine", "../shared", "shared/spec"):
        assert phrase not in text, phrase
    # one wording for the intervals: nominal 95 %, with the coverage measured by bench/coverage.py
    assert "nominal 95 %" in text and "read them as about 90 %" not in text
    assert "0.948-0.951 for AK, a, AC and kB(20 mm)" in text


@pytest.mark.slow
def test_run_summary_in_readme_is_the_demo_run_s(demo_run_output):
    """The summary shown under "What a run prints" is what the demo run prints."""
    text = README.read_text(encoding="utf-8").split("## What a run prints", 1)[1]
    shown = BLOCK.search(text).group(2).strip().splitlines()
    out = demo_run_output["stdout"]
    printed = out[out.rindex("ballimpact run summary"):].split("=" * 78)[0].strip().splitlines()
    assert shown[2:-1] == printed[1:]  # session lines; the header names the results folder
