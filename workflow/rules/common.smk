# Configuration, session discovery and input functions shared by every rule.

import math
import os
import re
from pathlib import Path

from snakemake.exceptions import WorkflowError
from snakemake.logging import logger
from snakemake.utils import validate

from ballimpact.figure_registry import QC_DIR_NAME, REPORT_FIGURES
from ballimpact.session import IMPACTS_FILE, SESSION_FILE, plan_session


CONFIG_SCHEMA = "../schemas/config.schema.yaml"  # relative to this file
SESSION_SCHEMA = "../schemas/session.schema.yaml"


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
for _inner, _outer, _what in ((RESULTS_DIR, RAW_DIR, "inside"), (RAW_DIR, RESULTS_DIR, "contains")):
    if Path(os.path.abspath(_inner)).is_relative_to(os.path.abspath(_outer)):
        raise WorkflowError(
            f"invalid configuration: results_dir ({RESULTS_DIR}) is {_what} raw_dir ({RAW_DIR}); "
            "put them side by side, e.g. raw_dir=/data/rig2/raw results_dir=/data/rig2/results "
            "(the pipeline never writes into the raw data, and results must not be read as sessions)"
        )


def _list_sessions():
    """Session folder names: config `sessions`, or every folder of raw_dir holding a session.yaml."""
    raw = Path(RAW_DIR)
    selected = config.get("sessions")
    if selected is None:
        if not raw.is_dir():
            raise WorkflowError(f"raw_dir {RAW_DIR!r} is not a folder (set raw_dir in config.yaml or --config)")
        from ballimpact.session import near_miss_name

        # a folder whose session.yaml is misnamed (session.yml, ...) is a session too: its
        # validate_session job fails naming the file to rename, instead of a silent skip
        return sorted(
            p.name for p in raw.iterdir() if p.is_dir() and not p.name.startswith(".")
            and ((p / SESSION_FILE).is_file() or near_miss_name(p, SESSION_FILE) is not None)
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


def _session_info(session):
    """What the DAG needs of one session, read once at parse time by the library's own
    reader (ballimpact.session.plan_session, which never raises). A session-level fault,
    or session.yaml off the schema, reduces the session to rule validate_session, which
    fails with the reader's one-line message, while the other sessions go on
    (keep-going, profiles/default)."""
    plan = plan_session(Path(RAW_DIR) / session)
    fault = plan.fault
    if fault is None:
        try:
            validate(plan.metadata, SESSION_SCHEMA, set_default=False)
        except WorkflowError as exc:
            fault = (f"{plan.path / SESSION_FILE}: {_schema_error_message(exc)} "
                     "(see workflow/schemas/session.schema.yaml)")
    if fault is not None:
        logger.warning(f"ballimpact: session {session!r} cannot be processed: {fault}")
        return {"dir": plan.path.as_posix(), "fault": fault, "balls": [], "n_impacts": 0,
                "n_chunks": 0, "traces": [], "present": [p.as_posix() for p in plan.present_files]}
    for message in plan.warnings:
        logger.warning(f"ballimpact: session {session!r}: {message}")
    n_chunks = min(plan.n_impacts, max(MIN_CHUNKS, math.ceil(plan.n_impacts / CHUNK_SIZE)))
    return {
        "dir": plan.path.as_posix(),
        "balls": list(plan.balls),
        "n_impacts": plan.n_impacts,
        "n_chunks": n_chunks,
        # per row, None when missing or outside the session folder
        "traces": [None if t is None else t.as_posix() for t in plan.trace_files],
    }


SESSIONS = _list_sessions()
SESSION_INFO = {session: _session_info(session) for session in SESSIONS}
if not SESSIONS:
    logger.warning(f"ballimpact: no session folder with a {SESSION_FILE} in raw_dir {RAW_DIR!r}; nothing to do")



# Small sessions (at most config fit_batch_impacts impacts) get their fits, archive,
# figures and report from one job (rule session_outputs, workflow/rules/session.smk), or
# everything from one job (rule small_session) when processed as one chunk; the others
# from the per-stage rules fit_ball, archive, figures and report.
SMALL_SESSIONS = [
    s for s in SESSIONS
    if "fault" not in SESSION_INFO[s] and SESSION_INFO[s]["n_impacts"] <= int(config.get("fit_batch_impacts", 0))
]
# the session wildcard of session_outputs matches exactly these names ("(?!)" matches none)
SMALL_SESSION_PATTERN = "|".join(re.escape(s) for s in SMALL_SESSIONS) or "(?!)"
# Small sessions processed as one chunk (config chunk_size, min_chunks) are validated,
# processed, collected, fitted, archived, drawn and reported by one job (rule small_session)
# instead of validate_session, process_chunk, collect_impacts and session_outputs.
ONE_JOB_SESSIONS = [s for s in SMALL_SESSIONS if SESSION_INFO[s]["n_chunks"] == 1]
ONE_JOB_SESSION_PATTERN = "|".join(re.escape(s) for s in ONE_JOB_SESSIONS) or "(?!)"
# the session wildcard of session_outputs: the small sessions processed in several chunks
SPLIT_SMALL_SESSION_PATTERN = "|".join(re.escape(s) for s in SMALL_SESSIONS if s not in ONE_JOB_SESSIONS) or "(?!)"


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
        *(f"{base}/figures/{fig.file_name}" for fig in REPORT_FIGURES),
        f"{base}/figures/{QC_DIR_NAME}",
    ]


def figure_outputs():
    """The figures rule's outputs, also those of session_outputs. One PNG per figure of the registry
    (ballimpact.figure_registry), named by its stem, and the QC folder, each with its entry
    in the Snakemake report (captions in workflow/report/, relative to workflow/rules/)."""
    outputs = {
        fig.stem: report(
            result_path(f"figures/{fig.file_name}"),
            caption=f"../report/{fig.stem}.rst",
            category=fig.category,
            subcategory="{session}",
            labels={"session": "{session}", "figure": fig.report_label, "shows": fig.shows},
        )
        for fig in REPORT_FIGURES
    }
    outputs["qc"] = report(
        directory(result_path(f"figures/{QC_DIR_NAME}")),
        patterns=["{name}.png"],
        caption="../report/qc.rst",
        category="Quality control",
        subcategory="{session}",
        labels={"session": "{session}", "figure": "QC {name}", "shows": "raw trace of an excluded impact"},
    )
    return outputs


def report_pdf_output():
    """report.pdf with its entry in the Snakemake report (rules report and session_outputs)."""
    return report(
        result_path("report.pdf"),
        caption="../report/report_pdf.rst",
        category="Session report",
        subcategory="{session}",
        labels={"session": "{session}", "figure": "report.pdf", "shows": "the whole session report"},
    )


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


def _check_pools(pools):
    """Config `pool`: every named session selected and holding the ball type, else WorkflowError."""
    for k, pool in enumerate(pools or []):
        for session in pool["sessions"]:
            if session not in SESSION_INFO:
                raise WorkflowError(
                    f"config key 'pool' entry {k} (ball {pool['ball']!r}): session {session!r} is not selected "
                    f"(sessions: {', '.join(SESSIONS) or 'none'})"
                )
            info = SESSION_INFO[session]
            if "fault" not in info and pool["ball"] not in info["balls"]:
                raise WorkflowError(
                    f"config key 'pool' entry {k}: session {session!r} has no impacts of ball type "
                    f"{pool['ball']!r} (its ball types: {', '.join(info['balls']) or 'none'})"
                )
    return pools or []
