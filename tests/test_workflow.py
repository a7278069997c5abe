"""Tests of the Snakemake workflow (dry runs, config and session validation) and ballimpact.pipeline."""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import yaml

from ballimpact import pipeline
from shared_fixture import build_once
from workflow_helpers import (  # noqa: E402  (shared with test_run.py)
    BALLIMPACT, FINAL_FIGURES, IMPACTS_CSV_COLUMNS, REPO, run_snakemake,
)

SYNTH_IMPACTS_PER_BALL = 3
SYNTH_FAULTS_PER_KIND = 1


# --------------------------------------------------------------------------- helpers


def job_counts(output: str) -> dict[str, int]:
    """Rule -> number of jobs from the 'Job stats' table of a (dry) run."""
    match = re.search(r"Job stats:\n(.*?)\n\s*\n", output + "\n\n", re.S)
    if not match:
        return {}
    counts = {}
    for line in match.group(1).splitlines():
        row = re.fullmatch(r"\s*(\w+)\s+(\d+)\s*", line)
        if row and row.group(1) != "total":
            counts[row.group(1)] = int(row.group(2))
    return counts


def synth_session(raw_dir: Path, session_id: str) -> Path:
    """A small synthetic session raw_dir/session_id written by `ballimpact synth`."""
    out = raw_dir / session_id
    proc = subprocess.run(
        [
            str(BALLIMPACT), "synth", str(out),
            "--impacts-per-ball", str(SYNTH_IMPACTS_PER_BALL),
            "--faults-per-kind", str(SYNTH_FAULTS_PER_KIND),
        ],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stdout
    # the ground truth is written beside the session folder; keep raw_dir to session folders
    for truth in raw_dir.glob(f"{session_id}.truth.*"):
        truth.rename(raw_dir.parent / truth.name)
    return out


def copy_session(source: Path, raw_dir: Path, session_id: str) -> Path:
    """Copy a session folder under a new id (session_id in session.yaml updated)."""
    target = raw_dir / session_id
    shutil.copytree(source, target)
    yaml_path = target / "session.yaml"
    text = re.sub(r"(?m)^session_id:.*$", f"session_id: {session_id}", yaml_path.read_text(encoding="utf-8"))
    yaml_path.write_text(text, encoding="utf-8")
    return target


def raw_rows(session_dir: Path) -> list[dict]:
    with open(session_dir / "impacts.csv", encoding="utf-8", newline="") as fh:
        return list(csv.DictReader(fh))


def n_balls_used(session_dir: Path) -> int:
    return len({row["ball"] for row in raw_rows(session_dir)})


def config_args(raw_dir, results_dir, *extra):
    return ["--config", f"raw_dir={raw_dir}", f"results_dir={results_dir}", *extra]


@pytest.fixture(scope="module")
def synth_raw(tmp_path_factory) -> Path:
    """raw/ folder holding one synthetic session 's1' (shared by the dry-run tests; never written)."""
    raw = tmp_path_factory.mktemp("synth") / "raw"
    raw.mkdir()
    synth_session(raw, "s1")
    return raw


# ----------------------------------------------------------------------- dry runs


def test_dry_run_repo_raw_dir():
    """`snakemake -n --cores 2` in the repository parses and lists every rule for each session of raw/."""
    proc = run_snakemake("-n", "--cores", "2", check=True)
    raw = REPO / "raw"
    sessions = sorted(p.name for p in raw.iterdir() if (p / "session.yaml").is_file()) if raw.is_dir() else []
    if not sessions:
        assert "no session folder" in proc.stdout
        return
    counts = job_counts(proc.stdout)
    if not counts:  # results already up to date
        assert "Nothing to be done" in proc.stdout
        return
    assert set(counts) <= {
        "validate_session", "process_chunk", "collect_impacts", "fit_ball", "fit_session", "archive", "figures",
        "report", "session_impacts", "session_outputs", "catalogue", "all",
    }
    assert counts["all"] == 1


def test_dry_run_lists_every_rule(synth_raw, tmp_path):
    session = synth_raw / "s1"
    n_impacts = len(raw_rows(session))
    proc = run_snakemake("-n", "--cores", "2", *config_args(synth_raw, tmp_path / "results"), check=True)
    counts = job_counts(proc.stdout)
    n_chunks = min(n_impacts, max(yaml.safe_load((REPO / "config.yaml").read_text())["min_chunks"],
                                  math.ceil(n_impacts / 200)))
    # a small session processed as one chunk: validated, processed and collected in one job
    first = {"session_impacts": 1} if n_chunks == 1 else {
        "validate_session": 1, "process_chunk": n_chunks, "collect_impacts": 1}
    assert counts == {
        **first,
        # a small session (fit_batch_impacts): fits, archive, figures and report in one job
        "session_outputs": 1,
        "catalogue": 1,
        "all": 1,
    }
    for name in ("impacts.csv", "parameters.csv", "s1.nc", "report.pdf", "figures/qc",
                 *(f"figures/{stem}.png" for stem in FINAL_FIGURES)):
        assert f"{tmp_path / 'results' / 's1' / name}" in proc.stdout, name


@pytest.mark.parametrize(
    ("chunk_size", "min_chunks", "expected"),
    [
        pytest.param(5, 1, "ceil", marks=pytest.mark.slow),  # ceil(n / 5) chunks
        pytest.param(1000, 3, 3, marks=pytest.mark.slow),  # min_chunks wins
        pytest.param(1000, 1000, "n", marks=pytest.mark.slow),  # capped by the number of impacts
    ],
)
def test_number_of_chunks(synth_raw, tmp_path, chunk_size, min_chunks, expected):
    n_impacts = len(raw_rows(synth_raw / "s1"))
    expected = {"ceil": math.ceil(n_impacts / 5), "n": n_impacts}.get(expected, expected)
    proc = run_snakemake(
        "-n", "--cores", "1",
        *config_args(synth_raw, tmp_path / "results", f"chunk_size={chunk_size}", f"min_chunks={min_chunks}"),
        check=True,
    )
    assert job_counts(proc.stdout)["process_chunk"] == expected


def test_dry_run_slurm_profile(synth_raw, tmp_path):
    """The SLURM profile's dry run needs no sbatch (the dry-run executor runs nothing)."""
    proc = run_snakemake(
        "-n", "--profile", "profiles/slurm", "--quiet", "host",  # job details: profiles/default hides them
        *config_args(synth_raw, tmp_path / "results", "fit_batch_impacts=0"), check=True
    )
    assert "profiles/slurm" in proc.stdout
    assert job_counts(proc.stdout)["fit_ball"] == n_balls_used(synth_raw / "s1")
    # the profile's per-rule resources reached the jobs
    fit_block = proc.stdout[proc.stdout.index("rule fit_ball:"):]
    resources = re.search(r"resources: (.*)", fit_block).group(1)
    assert "mem_mb=4000" in resources and "runtime=120" in resources


def test_sessions_selects_only_those(synth_raw, tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    for name in ("alpha", "beta"):
        copy_session(synth_raw / "s1", raw, name)
    (raw / "not-a-session").mkdir()  # no session.yaml: ignored
    results = tmp_path / "results"

    proc = run_snakemake("-n", "--cores", "1", *config_args(raw, results, "sessions=[beta]"), check=True)
    assert f"{results / 'beta' / 'report.pdf'}" in proc.stdout
    assert f"{results / 'alpha'}" not in proc.stdout
    # the first job of a session: validate_session, or session_impacts for a small session
    first_jobs = ("validate_session", "session_impacts")
    assert sum(job_counts(proc.stdout).get(rule, 0) for rule in first_jobs) == 1

    proc = run_snakemake("-n", "--cores", "1", *config_args(raw, results), check=True)
    assert f"{results / 'alpha' / 'report.pdf'}" in proc.stdout
    assert f"{results / 'beta' / 'report.pdf'}" in proc.stdout
    assert sum(job_counts(proc.stdout).get(rule, 0) for rule in first_jobs) == 2


@pytest.mark.slow
def test_unknown_session_fails_naming_it(synth_raw, tmp_path):
    proc = run_snakemake("-n", "--cores", "1", *config_args(synth_raw, tmp_path / "results", "sessions=[gamma]"),
                         check=False)
    assert "config key 'sessions': session 'gamma' not found in raw_dir" in proc.stdout


# ------------------------------------------------------------------ config validation


@pytest.mark.parametrize(
    ("entry", "expected"),
    [
        ("chunk_size=-1", r"key 'chunk_size': -1 is less than the minimum of 1"),
        pytest.param("min_chunks=0", r"key 'min_chunks': 0 is less than the minimum of 1", marks=pytest.mark.slow),
        pytest.param("bootstrap=many", r"key 'bootstrap': 'many' is not of type 'integer'", marks=pytest.mark.slow),
        pytest.param(
            "mains_hz=-50", r"key 'mains_hz': -50 is less than or equal to the minimum of 0", marks=pytest.mark.slow
        ),
        ("chunksize=10", r"unknown key 'chunksize' \(known keys: raw_dir, results_dir, sessions, chunk_size"),
    ],
)
def test_bad_config_fails_naming_the_key(entry, expected):
    proc = run_snakemake("-n", "--cores", "1", "--config", entry, check=False)
    assert "invalid configuration" in proc.stdout
    assert re.search(expected, proc.stdout), proc.stdout


@pytest.mark.slow
def test_bad_configfile_fails_naming_the_key(tmp_path):
    config = tmp_path / "config.yaml"
    config.write_text("raw_dir: raw\nresults_dir: results\nchunk_size: -1\n", encoding="utf-8")
    proc = run_snakemake("-n", "--cores", "1", "--configfile", config, check=False)
    assert "key 'chunk_size': -1 is less than the minimum of 1" in proc.stdout


@pytest.mark.slow
def test_results_dir_must_differ_from_raw_dir(tmp_path):
    proc = run_snakemake("-n", "--cores", "1", *config_args(tmp_path, tmp_path), check=False)
    assert "results_dir" in proc.stdout and "must differ from raw_dir" in proc.stdout


@pytest.mark.parametrize(("raw", "results", "what"), [("raw", "raw/results", "inside"), ("data/raw", "data", "contains")])
def test_results_dir_inside_raw_dir_is_refused(tmp_path, raw, results, what):
    (tmp_path / raw).mkdir(parents=True)
    proc = run_snakemake("-n", "--cores", "1", *config_args(tmp_path / raw, tmp_path / results), check=False)
    assert f"results_dir ({tmp_path / results}) is {what} raw_dir ({tmp_path / raw})" in proc.stdout, proc.stdout
    assert not (tmp_path / raw / "results").exists()


# ----------------------------------------------------------- session schema (parse time)


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (("sample_rate_hz: 66964.3", "sample_rate_hz: -5"), "key 'daq.sample_rate_hz' must be a positive number, got -5"),
        (("session_id: bad", "session_id: other"), "key 'session_id' is 'other' but the session folder is named 'bad'"),
        pytest.param(
            ("  polarity: 1", "  polarity: 2"), "key 'plate.polarity' must be 1 or -1, got 2", marks=pytest.mark.slow
        ),
        pytest.param(
            ("mass_g: 57.7", "mass_g: 0.0577"), "key 'balls.pressurised.mass_g' must be in (1, 1000) g, got 0.0577", marks=pytest.mark.slow
        ),
        pytest.param(("gates:", "gate:"), "missing required key 'gates'", marks=pytest.mark.slow),
        pytest.param(("balls:", "balls: [\n"), "invalid YAML", marks=pytest.mark.slow),
    ],
)
def test_bad_session_yaml_fails_naming_the_file(synth_raw, tmp_path, edit, expected):
    raw = tmp_path / "raw"
    raw.mkdir()
    session = copy_session(synth_raw / "s1", raw, "bad")
    yaml_path = session / "session.yaml"
    text = yaml_path.read_text(encoding="utf-8")
    old, new = edit
    assert old in text
    yaml_path.write_text(text.replace(old, new, 1), encoding="utf-8")
    # the dry run names the file and the fault; the session is reduced to the rule
    # validate_session, which fails with that message (see the test below)
    proc = run_snakemake("-n", "--cores", "1", *config_args(raw, tmp_path / "results"))
    assert f"{yaml_path}: " in proc.stdout, proc.stdout
    assert expected in proc.stdout, proc.stdout
    assert "cannot be processed" in proc.stdout


def _lab_typo(text: str) -> str:
    """session.yaml with the lab's typo kb0_kn_m (for kb0_kN_m) under the first ball type."""
    return re.sub(r"(?m)^(\s+)kb0_kN_m: (.*)$", r"\1kb0_kn_m: \2", text, count=1)


HOSTILE_CELLS = ["traces/a\x00b.csv", "traces/\x07bell.csv", "traces/" + "x" * 10_000 + ".csv"]


@pytest.fixture(scope="module")
def mixed_run(synth_raw, tmp_path_factory):
    """One Snakemake run (bootstrap=10, keep-going) on three copies of s1, shared by the tests
    of what a bad session or a bad impact stops and of the run summary (one run instead of
    three; each test checks its own session):

    * 'lab': session.yaml with the typo kb0_kn_m under the first ball type (a warning);
    * 'hostile': a NUL byte, a control character and a 10 000-character path in the trace
      cells of its first three impacts;
    * 'bad': plate.polarity 2 (a session-level error).

    A dict: raw, results, proc (the CompletedProcess), hostile_ids, first_ball (of 'lab').
    Built once per test run and shared by the xdist workers (shared_fixture.build_once).
    """
    def run(tmp: Path) -> dict:
        raw = tmp / "raw"
        raw.mkdir()
        lab = copy_session(synth_raw / "s1", raw, "lab")
        original = (lab / "session.yaml").read_text(encoding="utf-8")
        (lab / "session.yaml").write_text(_lab_typo(original), encoding="utf-8")
        first_ball = next(iter(yaml.safe_load(original)["balls"]))

        bad = copy_session(synth_raw / "s1", raw, "bad")
        text = (bad / "session.yaml").read_text(encoding="utf-8")
        (bad / "session.yaml").write_text(text.replace("  polarity: 1", "  polarity: 2", 1), encoding="utf-8")

        hostile = copy_session(synth_raw / "s1", raw, "hostile")
        csv_path = hostile / "impacts.csv"
        lines = csv_path.read_text(encoding="utf-8").splitlines(keepends=True)
        header = lines[0].rstrip("\r\n").split(",")
        col = header.index("trace")
        hostile_ids = []
        for k, cell in enumerate(HOSTILE_CELLS, start=1):
            fields = lines[k].rstrip("\r\n").split(",")
            fields[col] = cell
            hostile_ids.append(fields[header.index("impact_id")])
            lines[k] = ",".join(fields) + "\n"
        csv_path.write_text("".join(lines), encoding="utf-8")

        results = tmp / "results"
        # the failed jobs' blocks ("Error in rule ...") are read: shown with every job's details
        proc = run_snakemake("--cores", "2", *config_args(raw, results, "bootstrap=10"), "--quiet", "host",
                             check=False)
        return {"raw": raw, "results": results, "proc": proc, "hostile_ids": hostile_ids, "first_ball": first_ball}

    return build_once(tmp_path_factory, "mixed-run", run)


def _summary_block(summary: str, session: str) -> str:
    """The lines of one session in the run summary (from '  <session>:' to the next session)."""
    start = summary.index(f"\n  {session}:")
    following = re.search(r"\n  \S", summary[start + 1:])
    return summary[start: start + 1 + following.start()] if following else summary[start:]


@pytest.mark.slow
def test_bad_session_stops_only_itself(mixed_run):
    """keep-going (profiles/default): the good sessions complete beside the bad one."""
    results, proc = mixed_run["results"], mixed_run["proc"]
    for good in ("lab", "hostile"):
        assert (results / good / "report.pdf").is_file(), proc.stdout[-3000:]
    assert not (results / "bad" / "work" / "session.json").exists()
    log = (results / "bad" / "logs" / "validate_session.log").read_text(encoding="utf-8")
    assert "session.yaml" in log and "polarity" in log


@pytest.mark.slow
def test_hostile_trace_cells_stop_only_their_impacts(mixed_run):
    """A NUL byte, a control character and a 10 000-character path in the trace cells of one
    session: the workflow plans and runs it; those impacts are excluded with a reason."""
    results, proc = mixed_run["results"], mixed_run["proc"]
    assert (results / "hostile" / "report.pdf").is_file(), proc.stdout[-3000:]
    # the run failed only because of the session 'bad': every failed job is of 'bad'
    blocks = re.findall(r"Error in rule \w+:\n((?:    .*\n)+)", proc.stdout)
    failed = {s for block in blocks for s in re.findall(rf"output: {re.escape(str(results))}/([^/\s]+)/", block)}
    assert blocks and failed == {"bad"}, proc.stdout[-3000:]
    rows = {r["impact_id"]: r for r in raw_rows(results / "hostile")}
    for impact_id in mixed_run["hostile_ids"]:
        assert rows[impact_id]["status"] == "excluded"
        assert "trace" in rows[impact_id]["reason"]


@pytest.mark.slow
def test_session_yaml_exponent_without_dot_is_a_number(synth_raw, tmp_path):
    """`resolution_s: 1e-6` (YAML 1.1 reads it as text) is accepted, as the library accepts it."""
    raw = tmp_path / "raw"
    raw.mkdir()
    session = copy_session(synth_raw / "s1", raw, "expo")
    yaml_path = session / "session.yaml"
    text = re.sub(r"resolution_s: .*", "resolution_s: 1e-6", yaml_path.read_text(encoding="utf-8"))
    yaml_path.write_text(text, encoding="utf-8")
    run_snakemake("-n", "--cores", "1", *config_args(raw, tmp_path / "results"), check=True)


@pytest.mark.slow
def test_impacts_csv_missing_column_fails_naming_the_file(synth_raw, tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    session = copy_session(synth_raw / "s1", raw, "nocol")
    csv_path = session / "impacts.csv"
    lines = csv_path.read_text(encoding="utf-8").splitlines(keepends=True)
    lines[0] = lines[0].replace("trace,", "trace_file,", 1)
    csv_path.write_text("".join(lines), encoding="utf-8")
    proc = run_snakemake("-n", "--cores", "1", *config_args(raw, tmp_path / "results"))
    assert f"{csv_path}: line 1: missing required column(s): trace" in proc.stdout


# ------------------------------------------------------------------ ballimpact.pipeline


def test_snapshot_session_hashes_every_raw_file(synth_raw, tmp_path):
    session = synth_raw / "s1"
    out = tmp_path / "work" / "session.json"
    pipeline.snapshot_session(session, out)
    snapshot = json.loads(out.read_text(encoding="utf-8"))
    rows = raw_rows(session)
    assert snapshot["session_id"] == "s1"
    assert snapshot["n_impacts"] == len(rows)
    expected = {
        name: hashlib.sha256((session / name).read_bytes()).hexdigest()
        for name in ["session.yaml", "impacts.csv"] + [r["trace"] for r in rows if (session / r["trace"]).is_file()]
    }
    assert snapshot["raw_sha256"] == expected
    # the missing trace planted by synth is reported, not hashed
    assert any("trace file not found" in p for ps in snapshot["impact_problems"].values() for p in ps)
    assert sum(snapshot["impacts_per_ball"].values()) == len(rows)
    assert not list(out.parent.glob(".*tmp*"))


def test_snapshot_session_fault_names_the_file(synth_raw, tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    session = copy_session(synth_raw / "s1", raw, "dup")
    csv_path = session / "impacts.csv"
    lines = csv_path.read_text(encoding="utf-8").splitlines(keepends=True)
    csv_path.write_text("".join(lines + [lines[1]]), encoding="utf-8")  # duplicate impact id
    from ballimpact.session import SessionError

    with pytest.raises(SessionError, match=r"impacts\.csv: line \d+: impact_id .* duplicates line 2"):
        pipeline.snapshot_session(session, tmp_path / "session.json")
    assert not (tmp_path / "session.json").exists()


def test_log_to_file_turns_session_error_into_one_line_exit(tmp_path):
    from ballimpact.session import SessionError

    log = tmp_path / "logs" / "rule.log"
    with pytest.raises(SystemExit, match=r"^error: raw/x/session.yaml: missing required key 'date'$"):
        with pipeline.log_to_file(log):
            raise SessionError("raw/x/session.yaml: missing required key 'date'")
    assert "missing required key 'date'" in log.read_text(encoding="utf-8")


@pytest.mark.parametrize("n_chunks", [1, 2, 3, 7, 16])
def test_chunks_partition_the_impacts(n_chunks):
    ids = [f"i{k:02d}" for k in range(16)]
    chunks = [pipeline.chunk_impact_ids(ids, c, n_chunks) for c in range(n_chunks)]
    assert sorted(i for chunk in chunks for i in chunk) == ids
    assert all(chunk for chunk in chunks)


@pytest.mark.parametrize(("chunk", "n_chunks", "match"), [(2, 2, "smaller than n_chunks"), (0, 0, "n_chunks must be")])
def test_chunk_impact_ids_rejects_bad_chunks(chunk, n_chunks, match):
    with pytest.raises(ValueError, match=match):
        pipeline.chunk_impact_ids(["a", "b"], chunk, n_chunks)


@dataclass
class _FakeResult:
    """Duck-typed ImpactResult: contact series of a given length, a raw trace."""

    impact_id: str
    ball: str
    n_samples: int
    status: str = "ok"
    reason: str = ""
    vin_m_s: float = 20.0
    mass_kg: float = 0.057
    sample_rate_hz: float = 1.0e5

    def __post_init__(self):
        self.time_s = np.arange(self.n_samples) * 1.0e-5
        for name in ("voltage_V", "force_N", "velocity_m_s", "displacement_m"):
            setattr(self, name, np.full(self.n_samples, float(self.n_samples)))
        self.raw_time_s = np.arange(2 * self.n_samples) * 1.0e-5
        self.raw_voltage_V = np.ones(2 * self.n_samples)


def _chunk_files(session: Path, out: Path, n_chunks: int, *, drop=None) -> list[Path]:
    from ballimpact import archive

    rows = raw_rows(session)
    results = [
        _FakeResult(r["impact_id"], r["ball"], n_samples=10 + 3 * k,
                    status="excluded" if k == 1 else "ok", reason="missing gate time gate_in_2_s" if k == 1 else "")
        for k, r in enumerate(rows)
        if r["impact_id"] != drop
    ]
    files = []
    for chunk in range(n_chunks):
        path = out / f"chunk_{chunk}.nc"
        archive.write_dataset(archive.impacts_dataset(results[chunk::n_chunks]), path)
        files.append(path)
    return files


def test_collect_impacts_restores_raw_order_and_pads(synth_raw, tmp_path):
    from ballimpact import archive

    session = synth_raw / "s1"
    rows = raw_rows(session)
    chunks = _chunk_files(session, tmp_path, 3)
    pipeline.collect_impacts(session, chunks[::-1], tmp_path / "impacts.csv", tmp_path / "impacts.nc")
    with open(tmp_path / "impacts.csv", encoding="utf-8", newline="") as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames[: len(IMPACTS_CSV_COLUMNS)] == IMPACTS_CSV_COLUMNS  # v1.1 adds columns after
        table = list(reader)
    assert [r["impact_id"] for r in table] == [r["impact_id"] for r in rows]
    assert [r["ball"] for r in table] == [r["ball"] for r in rows]
    assert table[1]["status"] == "excluded" and table[1]["reason"] == "missing gate time gate_in_2_s"
    ds = archive.open_dataset(tmp_path / "impacts.nc")
    longest = 10 + 3 * (len(rows) - 1)
    assert ds.sizes["sample"] == longest and ds.sizes["raw_sample"] == 2 * longest
    for k in range(len(rows)):  # each impact keeps its own samples, NaN after them
        force = ds["force_N"].values[k]
        assert np.all(force[: 10 + 3 * k] == 10 + 3 * k) and np.all(np.isnan(force[10 + 3 * k:]))


def test_collect_impacts_excludes_a_time_constant_unlike_the_sessions(synth_raw, tmp_path, caplog):
    from ballimpact import archive

    session = synth_raw / "s1"
    rows = raw_rows(session)
    results = [_FakeResult(r["impact_id"], r["ball"], n_samples=10) for r in rows]
    for k, r in enumerate(results):  # one amplifier of 0.8 s; the third impact took a step for its decay
        r.tau_s, r.tau_se_s, r.tau_source, r.contact_time_ms = (0.08, 1e-4, "estimated", 4.0) if k == 2 else \
            (0.8 * (1 + 0.002 * (k % 3 - 1)), 0.005, "estimated", 4.0)
    path = tmp_path / "chunk_0.nc"
    archive.write_dataset(archive.impacts_dataset(results), path)
    pipeline.collect_impacts(session, [path], tmp_path / "impacts.csv", tmp_path / "impacts.nc")
    ds = archive.open_dataset(tmp_path / "impacts.nc")
    status = [str(s) for s in ds["status"].values]
    assert status == ["ok"] * 2 + ["excluded"] + ["ok"] * (len(rows) - 3)
    assert str(ds["reason"].values[2]).startswith("charge-amplifier time constant 0.08 s estimated, unlike the session's")
    assert ds.attrs["time_constant_median_s"] == pytest.approx(0.8, rel=0.01)
    # chunk files written before the time constant was archived: the check is skipped, and says so
    old = tmp_path / "old_chunk_0.nc"
    archive.write_dataset(archive.open_dataset(path).drop_vars(["amplifier_time_constant_se_s"]), old)
    with caplog.at_level("WARNING"):
        pipeline.collect_impacts(session, [old], tmp_path / "old.csv", tmp_path / "old.nc")
    assert [str(s) for s in archive.open_dataset(tmp_path / "old.nc")["status"].values] == ["ok"] * len(rows)
    assert "the session time-constant check is skipped" in caplog.text


def test_collect_impacts_refuses_a_dropped_impact(synth_raw, tmp_path):
    session = synth_raw / "s1"
    dropped = raw_rows(session)[4]["impact_id"]
    chunks = _chunk_files(session, tmp_path, 2, drop=dropped)
    with pytest.raises(ValueError, match=rf"missing impacts \['{dropped}'\]"):
        pipeline.collect_impacts(session, chunks, tmp_path / "impacts.csv", tmp_path / "impacts.nc")
    assert not (tmp_path / "impacts.csv").exists() and not (tmp_path / "impacts.nc").exists()


@pytest.mark.slow
def test_archive_figures_and_report_from_pipeline(synth_raw, tmp_path):
    """write_archive on collected impacts + fits, then make_figures and make_report on a complete archive."""
    import xarray as xr

    from archive_fixture import make_archive
    from ballimpact import archive

    session = synth_raw / "s1"
    rows = raw_rows(session)
    pipeline.collect_impacts(session, _chunk_files(session, tmp_path, 2), tmp_path / "impacts.csv",
                             tmp_path / "impacts.nc")
    fits = []
    for ball in sorted({r["ball"] for r in rows}):
        fit = xr.Dataset(
            {"mass_kg": ("ball", [0.057]), "n_impacts": ("ball", [4]), "kb0_kN_m": ("ball", [21.0]),
             "ak_kN_m": ("ball", [16000.0]), "a": ("ball", [1.65]), "ac_kN_s_m3": ("ball", [3.5])},
            coords={"ball": np.array([ball], dtype=object)},
        )
        fits.append(archive.write_dataset(fit, tmp_path / f"fit_{ball}.nc"))
    pipeline.write_archive(session, tmp_path / "impacts.nc", fits, tmp_path / "s1.nc", tmp_path / "parameters.csv")
    ds = archive.open_dataset(tmp_path / "s1.nc")
    assert ds.attrs["session_id"] == "s1"
    raw_sha256 = json.loads(ds.attrs["raw_sha256"])
    assert raw_sha256["session.yaml"] == hashlib.sha256((session / "session.yaml").read_bytes()).hexdigest()
    with open(tmp_path / "parameters.csv", encoding="utf-8", newline="") as fh:
        params = list(csv.DictReader(fh))
    assert sorted(p["ball"] for p in params) == sorted({r["ball"] for r in rows})
    assert {float(p["a"]) for p in params} == {1.65}

    complete = tmp_path / "complete.nc"
    archive.write_dataset(make_archive(), complete)
    figures = tmp_path / "figures"
    (figures / ".figures.tmp").mkdir(parents=True)  # left by a run killed while drawing
    (figures / ".figures.tmp" / "fig_4.png").write_bytes(b"half a PNG")
    pipeline.make_figures(complete, figures)
    assert sorted(p.name for p in figures.glob("*.png")) == sorted(f"{stem}.png" for stem in FINAL_FIGURES)
    assert (figures / "qc").is_dir() and list((figures / "qc").glob("*.png"))
    assert not [p for p in figures.iterdir() if p.name.startswith(".")]
    pipeline.make_report(complete, figures, tmp_path / "report.pdf")
    assert (tmp_path / "report.pdf").read_bytes().startswith(b"%PDF")


# --------------------------------------------------------------------------- end to end

@pytest.mark.slow
def test_end_to_end_synthetic_session(tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    session = synth_session(raw, "e2e")
    results = tmp_path / "results"
    workdir = tmp_path / "work"  # .snakemake/ of this run stays out of the repository
    workdir.mkdir()
    common = [
        "--snakefile", REPO / "Snakefile", "--configfile", REPO / "config.yaml", "--directory", workdir,
        *config_args(raw, results, "bootstrap=10"),
    ]
    proc = run_snakemake("--cores", "2", *common, cwd=workdir)
    assert proc.returncode == 0, proc.stdout
    assert "steps (100%) done" not in proc.stdout[proc.stdout.index("ballimpact run summary"):]  # printed at the end

    out = results / "e2e"
    for name in ("impacts.csv", "parameters.csv", "e2e.nc", "report.pdf", "work/session.json",
                 *(f"figures/{stem}.png" for stem in FINAL_FIGURES)):
        assert (out / name).is_file(), name
        assert (out / name).stat().st_size > 0, name
    assert (out / "figures" / "qc").is_dir()

    rows = raw_rows(session)
    with open(out / "impacts.csv", encoding="utf-8", newline="") as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames[: len(IMPACTS_CSV_COLUMNS)] == IMPACTS_CSV_COLUMNS  # v1.1 adds columns after
        result_rows = list(reader)
    assert [r["impact_id"] for r in result_rows] == [r["impact_id"] for r in rows]
    assert {r["status"] for r in result_rows} <= {"ok", "excluded"}
    n_faults = sum(1 for r in rows if r["note"].startswith("synthetic "))
    assert sum(r["status"] == "excluded" for r in result_rows) >= n_faults
    with open(out / "parameters.csv", encoding="utf-8", newline="") as fh:
        assert sorted(r["ball"] for r in csv.DictReader(fh)) == sorted({r["ball"] for r in rows})
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]  # every write was atomic
    umask = os.umask(0o022)
    os.umask(umask)
    for name in ("impacts.csv", "parameters.csv", "e2e.nc", "report.pdf", "figures/kcal.png"):
        assert (out / name).stat().st_mode & 0o777 == 0o666 & ~umask, name  # readable as usual

    again = run_snakemake("--cores", "2", "-n", *common, cwd=workdir, check=True)
    assert "Nothing to be done" in again.stdout

    html = tmp_path / "report.html"
    run_snakemake("--report", html, *common, cwd=workdir, check=True)
    assert html.stat().st_size > 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"chunk": 0, "n_chunks": 2, "mains_hz": -50.0}, "mains_hz must be a positive number"),
        ({"chunk": 2, "n_chunks": 2}, "chunk must be smaller than n_chunks"),
        ({"chunk": -1, "n_chunks": 2}, "chunk must be an integer >= 0"),
    ],
)
def test_process_chunk_rejects_bad_arguments(synth_raw, tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        pipeline.process_chunk(synth_raw / "s1", out_nc=tmp_path / "chunk.nc", **kwargs)
    assert not (tmp_path / "chunk.nc").exists()


def test_snakemake_lint_is_clean():
    """`snakemake --lint` finds nothing: every rule has a log and a conda environment, no
    rule file mixes rules with functions."""
    proc = run_snakemake("--lint", check=True)
    assert "Lints for" not in proc.stdout, proc.stdout
    assert (REPO / "workflow" / "envs" / "ballimpact.yaml").is_file()


# ------------------------------------------------------------ run summary, stale results (issue 14)


@pytest.mark.slow
def test_run_summary_shows_warnings_errors_and_stale_results(mixed_run, tmp_path):
    raw, results, proc = mixed_run["raw"], mixed_run["results"], mixed_run["proc"]
    lab = raw / "lab"
    summary = proc.stdout[proc.stdout.index("ballimpact run summary"):]
    n_rows = len(raw_rows(lab))
    assert re.search(rf"\n  lab: {n_rows} impacts, \d+ ok, \d+ excluded\n", summary), summary
    block = _summary_block(summary, "lab")
    assert "    excluded   1 x clipping at the ADC rails" in block, summary
    assert (f"validate warning: {lab / 'session.yaml'}: unknown key(s) 'balls.{mixed_run['first_ball']}.kb0_kn_m'"
            in block), summary
    assert re.search(r"    fit \w+: (ok|WARNING: .+)\n", block)
    # the archive keeps the warning, for the report's summary page and later readers
    from ballimpact import archive, archive_read, report

    with archive.open_dataset(results / "lab" / "lab.nc") as ds:
        kept = archive_read.validate_warnings(ds)
        shown = report.session_warnings(ds)
    assert any(f"unknown key(s) 'balls.{mixed_run['first_ball']}.kb0_kn_m'" in w for w in kept), kept
    assert shown and "kb0_kn_m" in " ".join(shown), shown

    # three session-level mistakes at once: all reported, earlier results marked stale
    # (on copies of lab's raw folder and results, so that the shared run stays as it was)
    raw2, results2 = tmp_path / "raw", tmp_path / "results"
    raw2.mkdir()
    lab = copy_session(lab, raw2, "lab")
    shutil.copytree(results / "lab", results2 / "lab")
    yaml_path = lab / "session.yaml"
    typo = yaml_path.read_text(encoding="utf-8")
    yaml_path.write_text(typo.replace("date: ", "date: yesterday #", 1).replace("  polarity: 1", "  polarity: 2"),
                         encoding="utf-8")
    rows = (lab / "impacts.csv").read_text(encoding="utf-8").splitlines()
    rows[1] = rows[1].replace(f",{raw_rows(lab)[0]['ball']},", ",nosuchball,", 1)
    (lab / "impacts.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    proc = run_snakemake("--cores", "2", *config_args(raw2, results2, "bootstrap=10"), check=False)
    assert proc.returncode != 0
    summary = proc.stdout[proc.stdout.index("ballimpact run summary"):]
    assert "  lab: SESSION-LEVEL ERROR, not processed:" in summary, summary
    for fragment in ("key 'date'", "key 'plate.polarity'", "ball 'nosuchball' is not defined"):
        assert re.search(rf"    error: .*{re.escape(fragment)}", summary), (fragment, summary)
    assert f"    STALE: the results in {results2 / 'lab'} are from an earlier run" in summary
    stale = (results2 / "lab" / "STALE").read_text(encoding="utf-8")
    assert "report.pdf" in stale and "nosuchball" in stale


def test_snapshot_of_a_good_session_clears_the_stale_mark(synth_raw, tmp_path):
    out = tmp_path / "results" / "s1"
    (out / "work").mkdir(parents=True)
    (out / "STALE").write_text("STALE: ...")
    snapshot = pipeline.snapshot_session(synth_raw / "s1", out / "work" / "session.json")
    assert not (out / "STALE").exists()
    assert snapshot["warnings"] == []


@pytest.mark.slow
def test_misnamed_session_yaml_is_not_skipped_silently(synth_raw, tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    lab = copy_session(synth_raw / "s1", raw, "lab")
    (lab / "session.yaml").rename(lab / "session.yml")
    proc = run_snakemake("--cores", "1", *config_args(raw, tmp_path / "results"), check=False)
    assert proc.returncode != 0
    summary = proc.stdout[proc.stdout.index("ballimpact run summary"):]
    assert "  lab: SESSION-LEVEL ERROR, not processed:" in summary
    assert "session.yaml: file not found, but 'session.yml' is there: rename it to 'session.yaml'" in summary


@pytest.mark.slow
def test_fit_balls_in_one_process_gives_the_per_ball_fits(synth_raw, tmp_path):
    """Rule fit_session's file holds exactly what the fit_ball jobs write, ball by ball."""
    import xarray as xr

    from ballimpact import archive

    session = synth_raw / "s1"
    pipeline.process_chunk(session, 0, 1, tmp_path / "chunk_0.nc")
    pipeline.collect_impacts(session, [tmp_path / "chunk_0.nc"], tmp_path / "impacts.csv", tmp_path / "impacts.nc")
    balls = sorted({r["ball"] for r in raw_rows(session)})
    (tmp_path / ".fits.nc.fits.tmp").mkdir()  # left by a run killed while fitting
    (tmp_path / ".fits.nc.fits.tmp" / "fit_x.nc").write_bytes(b"half a file")
    pipeline.fit_balls(tmp_path / "impacts.nc", balls, session, tmp_path / "fits.nc", n_bootstrap=10, seed=3)
    joined = archive.open_dataset(tmp_path / "fits.nc")
    assert [str(b) for b in joined["ball"].values] == balls
    for ball in balls:
        pipeline.fit_ball(tmp_path / "impacts.nc", ball, session, tmp_path / f"fit_{ball}.nc", n_bootstrap=10, seed=3)
        single = archive.open_dataset(tmp_path / f"fit_{ball}.nc")
        xr.testing.assert_identical(joined.sel(ball=[ball]), single)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # staging folders removed, the stale one too
    with pytest.raises(ValueError, match="balls must name at least one ball type"):
        pipeline.fit_balls(tmp_path / "impacts.nc", [], session, tmp_path / "none.nc", n_bootstrap=0, seed=0)


@pytest.mark.slow
def test_session_impacts_writes_what_the_per_stage_rules_write(synth_raw, tmp_path):
    """Rule session_impacts (a small session validated, processed and collected in one job)
    writes the files of rules validate_session, process_chunk (one chunk) and collect_impacts."""
    import json

    import xarray as xr

    from ballimpact import archive

    session = synth_raw / "s1"
    one, staged = tmp_path / "one", tmp_path / "staged"
    one.mkdir()
    staged.mkdir()
    pipeline.session_impacts(session, one / "session.json", one / "impacts.csv", one / "impacts.nc")
    pipeline.snapshot_session(session, staged / "session.json")
    pipeline.process_chunk(session, 0, 1, staged / "chunk_0.nc")
    pipeline.collect_impacts(session, [staged / "chunk_0.nc"], staged / "impacts.csv", staged / "impacts.nc")
    assert json.loads((one / "session.json").read_text()) == json.loads((staged / "session.json").read_text())
    assert (one / "impacts.csv").read_text() == (staged / "impacts.csv").read_text()
    xr.testing.assert_identical(archive.open_dataset(one / "impacts.nc"), archive.open_dataset(staged / "impacts.nc"))
    assert sorted(p.name for p in one.iterdir()) == ["impacts.csv", "impacts.nc", "session.json"]  # no chunk left
    with pytest.raises(ValueError, match="mains_hz must be a positive number"):
        pipeline.session_impacts(session, one / "s.json", one / "i.csv", one / "i.nc", mains_hz=-50.0)


@pytest.mark.slow
def test_session_outputs_writes_what_the_per_stage_rules_write(synth_raw, tmp_path):
    """Rule session_outputs (a small session's fits, archive, figures and report in one job)
    writes the per-stage rules' files: its parameters.csv is the one rule archive writes
    from its fits, every figure of the registry and a QC page per excluded impact."""
    from ballimpact.figure_registry import FIGURE_STEMS

    session = synth_raw / "s1"
    pipeline.process_chunk(session, 0, 1, tmp_path / "chunk_0.nc")
    pipeline.collect_impacts(session, [tmp_path / "chunk_0.nc"], tmp_path / "impacts.csv", tmp_path / "impacts.nc")
    balls = sorted({r["ball"] for r in raw_rows(session)})
    out = tmp_path / "out"
    pipeline.session_outputs(session, tmp_path / "impacts.nc", balls, out / "work" / "fits.nc", out / "s1.nc",
                             out / "parameters.csv", out / "figures", out / "report.pdf", n_bootstrap=5, seed=3)
    pipeline.write_archive(session, tmp_path / "impacts.nc", [out / "work" / "fits.nc"], tmp_path / "s1.nc",
                           tmp_path / "parameters.csv")
    assert (out / "parameters.csv").read_text() == (tmp_path / "parameters.csv").read_text()
    assert sorted(p.stem for p in (out / "figures").glob("*.png")) == sorted(FIGURE_STEMS)
    with open(tmp_path / "impacts.csv", newline="", encoding="utf-8") as f:
        n_excluded = sum(1 for row in csv.DictReader(f) if row["status"] == "excluded")
    assert n_excluded > 0  # the synthetic session has faults: QC pages to write
    assert len(list((out / "figures" / "qc").glob("*.png"))) == n_excluded
    assert (out / "report.pdf").read_bytes()[:5] == b"%PDF-"
    with pytest.raises(ValueError, match="n_bootstrap must be an integer >= 0"):
        pipeline.session_outputs(session, tmp_path / "impacts.nc", balls, out / "f.nc", out / "x.nc", out / "p.csv",
                                 out / "figures", out / "r.pdf", n_bootstrap=-1, seed=0)
