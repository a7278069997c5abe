"""Rule small_session: every output of a small session processed as one chunk, in one process."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, session_impacts, session_outputs
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
    session_outputs(
        session_dir=snakemake.params.session_dir,
        impacts_nc=snakemake.output.impacts_nc,
        balls=list(snakemake.params.balls),
        out_fits_nc=snakemake.output.fits,
        out_nc=snakemake.output.archive,
        out_parameters_csv=snakemake.output.parameters_csv,
        figures_dir=Path(snakemake.output.qc).parent,  # figures/; writes <stem>.png and qc/
        out_pdf=snakemake.output.pdf,
        n_bootstrap=int(snakemake.params.n_bootstrap),
        seed=int(snakemake.params.seed),
        snapshot_json=snakemake.output.snapshot,
    )
