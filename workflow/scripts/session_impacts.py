"""Rule session_impacts: validate, process and collect the impacts of a small session in one process."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, session_impacts
from ballimpact.session import SessionError
from ballimpact.summary import mark_stale

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    try:
        session_impacts(
            session_dir=snakemake.params.session_dir,
            out_json=snakemake.output.snapshot,
            out_csv=snakemake.output.impacts_csv,
            out_nc=snakemake.output.impacts_nc,
            mains_hz=snakemake.params.mains_hz,
        )
    except SessionError as exc:
        # as rule validate_session: an earlier run's results stay, marked STALE
        mark_stale(Path(snakemake.output.snapshot).parent.parent, str(exc))
        raise
