# Configuration, session discovery and input functions shared by every rule.

import csv
import math
import os
import re
from pathlib import Path, PurePosixPath, PureWindowsPath

import yaml
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate


CONFIG_SCHEMA = "../schemas/config.schema.yaml"  # relative to this file
SESSION_SCHEMA = "../schemas/session.schema.yaml"
SESSION_FILE = "session.yaml"
IMPACTS_FILE = "impacts.csv"
IMPACTS_REQUIRED_COLUMNS = ("impact_id", "ball", "trace")


def _schema_error_message(exc):
    """One line "key 'a.b': what is wrong" from snakemake.utils.validate's WorkflowError.

    The jsonschema ValidationError is the exception being handled when validate raised
    its WorkflowError, so it is found in ``__context__``.
    """
    import jsonschema

    inner = exc
    while inner is not None and not isinstance(inner, jsonschema.exceptions.ValidationError):
        inner = inner.__cause__ or inner.__context__
    if inner is None:
        return " ".join(str(exc).split())
    best = inner
    while best.context:  # oneOf/anyOf: the branch of the right type says what is wrong
        candidates = [e for e in best.context if e.validator != "type"] or list(best.context)
        best = jsonschema.exceptions.best_match(candidates)
    path = ".".join(str(p) for p in best.absolute_path)
    message = " ".join(best.message.split())
    if best.validator == "additionalProperties" and isinstance(best.instance, dict):
        known = list(best.schema.get("properties", {}))
        unknown = [repr(f"{path}.{k}" if path else k) for k in best.instance if k not in known]
        return f"unknown key {', '.join(unknown)} (known keys: {', '.join(known)})"
    if best.validator == "required" and isinstance(best.instance, dict):
        missing = [repr(f"{path}.{k}" if path else k) for k in best.validator_value if k not in best.instance]
        return f"missing required key {', '.join(missing)}"
    return f"key '{path}': {message}" if path else message


# ----------------------------------------------------------------------------- config

try:
    validate(config, CONFIG_SCHEMA)
except WorkflowError as exc:
    raise WorkflowError(
        f"invalid configuration (config.yaml or --config): {_schema_error_message(exc)} "
        "(see workflow/schemas/config.schema.yaml)"
    ) from None


def _resolve_dir(value):
    """A config folder: absolute, or relative to the workflow (repository) folder.

    Returned relative to the working directory when it lies below it (short paths in
    the job listing), else absolute.
    """
    path = Path(os.path.expanduser(str(value)))
    if not path.is_absolute():
        path = Path(workflow.basedir) / path
    path = Path(os.path.abspath(path))
    cwd = Path.cwd()
    if path.is_relative_to(cwd) and path != cwd:
        return path.relative_to(cwd).as_posix()
    return path.as_posix()


RAW_DIR = _resolve_dir(config["raw_dir"])
RESULTS_DIR = _resolve_dir(config["results_dir"])
CHUNK_SIZE = int(config["chunk_size"])
MIN_CHUNKS = int(config["min_chunks"])

if os.path.abspath(RAW_DIR) == os.path.abspath(RESULTS_DIR):
    raise WorkflowError(
        f"invalid configuration: results_dir ({RESULTS_DIR}) must differ from raw_dir "
        "(the pipeline never writes into the raw data)"
    )


def _list_sessions():
    """Session folder names: config `sessions`, or every folder of raw_dir holding a session.yaml."""
    raw = Path(RAW_DIR)
    selected = config.get("sessions")
    if selected is None:
        if not raw.is_dir():
            raise WorkflowError(f"raw_dir {RAW_DIR!r} is not a folder (set raw_dir in config.yaml or --config)")
        return sorted(
            p.name for p in raw.iterdir() if p.is_dir() and not p.name.startswith(".") and (p / SESSION_FILE).is_file()
        )
    if isinstance(selected, str):
        selected = [selected]
    for name in selected:
        if not (raw / name / SESSION_FILE).is_file():
            what = "folder not found" if not (raw / name).is_dir() else f"no {SESSION_FILE} in it"
            raise WorkflowError(
                f"config key 'sessions': session {name!r} not found in raw_dir {RAW_DIR!r} "
                f"({raw / name}: {what})"
            )
    return list(selected)


# ------------------------------------------------------------- session files at parse time


class _SessionYamlLoader(yaml.SafeLoader):
    """Safe loader as the library reads session.yaml: dates stay text, 1e-6 is a number."""


_SessionYamlLoader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:timestamp"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_SessionYamlLoader.add_implicit_resolver(  # YAML 1.2 floats without a dot, e.g. 1e-6
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def _read_session_yaml(path):
    """session.yaml as a dict, validated against the session schema; WorkflowError naming the file."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise WorkflowError(f"{path}: cannot read: {exc}") from None
    try:
        data = yaml.load(text, Loader=_SessionYamlLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise WorkflowError(f"{path}: {where}invalid YAML: {' '.join(str(problem).split())}") from None
    if not isinstance(data, dict):
        raise WorkflowError(f"{path}: top level must be a mapping of keys (session_id, date, plate, daq, gates, balls)")
    try:
        validate(data, SESSION_SCHEMA, set_default=False)
    except WorkflowError as exc:
        raise WorkflowError(
            f"{path}: {_schema_error_message(exc)} (see workflow/schemas/session.schema.yaml)"
        ) from None
    if str(data["session_id"]) != path.parent.name:
        raise WorkflowError(
            f"{path}: key 'session_id' is {data['session_id']!r} but the session folder is named "
            f"{path.parent.name!r}; they must be equal"
        )
    return data


def _trace_file(session_dir, trace):
    """Existing trace file of a row inside the session folder, else None (processing reports it)."""
    text = trace.strip().replace("\\", "/")
    if not text or PurePosixPath(text).is_absolute() or PureWindowsPath(trace.strip()).drive:
        return None
    path = session_dir / text
    try:
        inside = path.resolve().is_relative_to(session_dir.resolve())
    except (OSError, RuntimeError):
        return None
    return path.as_posix() if inside and path.is_file() else None


def _read_impact_rows(path):
    """Rows of impacts.csv as dicts, counted as ballimpact.session does; WorkflowError naming the file."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            records = list(csv.reader(fh, strict=True))
    except FileNotFoundError:
        raise WorkflowError(f"{path}: file not found (every session folder needs an {IMPACTS_FILE})") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise WorkflowError(f"{path}: cannot read: {' '.join(str(exc).split())}") from None
    # blank lines are skipped exactly as the library's reader skips them
    records = [r for r in records if r and not (len(r) <= 1 and all(not c.strip() for c in r))]
    if not records:
        raise WorkflowError(f"{path}: file is empty (expected a header row and one row per impact)")
    header = [c.strip() for c in records[0]]
    missing = [c for c in IMPACTS_REQUIRED_COLUMNS if c not in header]
    if missing:
        raise WorkflowError(
            f"{path}: missing required column(s) in the header: {', '.join(missing)}"
        )
    rows = [dict(zip(header, record)) for record in records[1:]]
    if not rows:
        raise WorkflowError(f"{path}: no impact rows (only the header)")
    return rows


def _session_info(session):
    """What the DAG needs of one session, read once at parse time."""
    session_dir = Path(RAW_DIR) / session
    data = _read_session_yaml(session_dir / SESSION_FILE)
    rows = _read_impact_rows(session_dir / IMPACTS_FILE)
    used = {row.get("ball", "").strip() for row in rows}
    # ball types with impacts, in session.yaml order; an undefined key is a session-level
    # fault that rule validate_session reports for this session
    balls = [str(key) for key in data["balls"] if str(key) in used]
    n_impacts = len(rows)
    n_chunks = min(n_impacts, max(MIN_CHUNKS, math.ceil(n_impacts / CHUNK_SIZE)))
    traces = [_trace_file(session_dir, row.get("trace", "")) for row in rows]
    return {
        "dir": session_dir.as_posix(),
        "balls": balls,
        "n_impacts": n_impacts,
        "n_chunks": n_chunks,
        "traces": traces,  # per row, None when missing or outside the session folder
    }


def _session_info_or_fault(session):
    """_session_info, or the session-level fault: such a session is reduced to rule
    validate_session, which fails with the reader's one-line message, while the other
    sessions go on (keep-going, profiles/default)."""
    try:
        return _session_info(session)
    except WorkflowError as exc:
        message = " ".join(str(exc).split())
        logger.warning(f"ballimpact: session {session!r} cannot be processed: {message}")
        session_dir = Path(RAW_DIR) / session
        present = [session_dir / name for name in (SESSION_FILE, IMPACTS_FILE) if (session_dir / name).is_file()]
        return {"dir": session_dir.as_posix(), "fault": message, "balls": [], "n_impacts": 0,
                "n_chunks": 0, "traces": [], "present": [p.as_posix() for p in present]}


SESSIONS = _list_sessions()
SESSION_INFO = {session: _session_info_or_fault(session) for session in SESSIONS}
if not SESSIONS:
    logger.warning(f"ballimpact: no session folder with a {SESSION_FILE} in raw_dir {RAW_DIR!r}; nothing to do")


wildcard_constraints:
    # "catalogue" is results/catalogue/ (workflow/rules/catalogue.smk), never a session
    session=r"(?!catalogue(?![A-Za-z0-9_.-]))[A-Za-z0-9][A-Za-z0-9_.-]*",
    chunk=r"[0-9]+",
    ball=r"[A-Za-z0-9_-]+",


# ------------------------------------------------------------------------ paths


def raw_path(name):
    """Pattern of a file in the raw session folder."""
    return f"{RAW_DIR}/{{session}}/{name}"


def result_path(name):
    """Pattern of a file in the session's results folder."""
    return f"{RESULTS_DIR}/{{session}}/{name}"


def log_path(name):
    return f"{RESULTS_DIR}/{{session}}/logs/{name}.log"


def benchmark_path(name):
    return f"{RESULTS_DIR}/{{session}}/benchmarks/{name}.tsv"


# PNG file stems written by rule figures (captions: workflow/report/<stem>.rst)
FIGURES = (
    "fig7_contact_time_cor",
    "fig8_stiffness",
    "fig9_force_curves",
    "fig10_components",
    "fig2b_kelvin_voigt",
    "kcal",
)


def session_targets(session):
    """Final outputs of one session (outputs.md); only the snapshot of a faulty session,
    whose rule then fails naming the fault."""
    base = f"{RESULTS_DIR}/{session}"
    if "fault" in SESSION_INFO[session]:
        return [f"{base}/work/session.json"]
    return [
        f"{base}/impacts.csv",
        f"{base}/parameters.csv",
        f"{base}/{session}.nc",
        f"{base}/report.pdf",
        *(f"{base}/figures/{stem}.png" for stem in FIGURES),
        f"{base}/figures/qc",
    ]


# ------------------------------------------------------------------ input functions


def _info(wildcards):
    try:
        return SESSION_INFO[wildcards.session]
    except KeyError:
        raise WorkflowError(
            f"session {wildcards.session!r} is not selected (sessions found or configured: "
            f"{', '.join(SESSIONS) or 'none'})"
        ) from None


def session_raw_files(wildcards):
    """session.yaml, impacts.csv and every existing trace: editing any of them re-runs the session."""
    info = _info(wildcards)
    if "fault" in info:
        return info["present"]
    traces = sorted({t for t in info["traces"] if t is not None})
    return [f"{info['dir']}/{SESSION_FILE}", f"{info['dir']}/{IMPACTS_FILE}", *traces]


def chunk_trace_files(wildcards):
    """Existing traces of chunk i (rows i, i + n_chunks, ... in raw order)."""
    info = _info(wildcards)
    chunk = int(wildcards.chunk)
    if chunk >= info["n_chunks"]:
        raise WorkflowError(
            f"session {wildcards.session!r} has {info['n_chunks']} chunks (0..{info['n_chunks'] - 1}), "
            f"no chunk {chunk}"
        )
    return sorted({t for t in info["traces"][chunk :: info["n_chunks"]] if t is not None})


def n_chunks(wildcards):
    return _info(wildcards)["n_chunks"]


def chunk_files(wildcards):
    """work/chunk_{i}.nc of every chunk of the session."""
    info = _info(wildcards)
    return [
        f"{RESULTS_DIR}/{wildcards.session}/work/chunk_{i}.nc" for i in range(info["n_chunks"])
    ]


def ball_keys(wildcards):
    return _info(wildcards)["balls"]


def fit_files(wildcards):
    """work/fit_{ball}.nc of every ball type with impacts in the session (one job each), or
    work/fits.nc of rule fit_session (all in one job) when the session has at most
    config fit_batch_impacts impacts."""
    if _info(wildcards)["n_impacts"] <= int(config.get("fit_batch_impacts", 0)):
        return [f"{RESULTS_DIR}/{wildcards.session}/work/fits.nc"]
    return [f"{RESULTS_DIR}/{wildcards.session}/work/fit_{ball}.nc" for ball in ball_keys(wildcards)]


def session_dir(wildcards):
    return _info(wildcards)["dir"]
