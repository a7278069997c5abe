"""Rule validate_session: read the raw session and snapshot the sha256 of its files."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, snapshot_session
from ballimpact.session import SessionError
from ballimpact.summary import mark_stale

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    try:
        snapshot_session(session_dir=snakemake.params.session_dir, out_json=snakemake.output.snapshot)
    except SessionError as exc:
        # an earlier run's results stay, marked STALE (results/<session>/STALE), and the summary says so
        mark_stale(Path(snakemake.output.snapshot).parent.parent, str(exc))
        raise
