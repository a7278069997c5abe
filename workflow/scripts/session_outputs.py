"""Rule session_outputs: fits, archive, figures and report of a small session in one process."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, session_outputs

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    session_outputs(
        session_dir=snakemake.params.session_dir,
        impacts_nc=snakemake.input.impacts_nc,
        balls=list(snakemake.params.balls),
        out_fits_nc=snakemake.output.fits,
        out_nc=snakemake.output.archive,
        out_parameters_csv=snakemake.output.parameters_csv,
        figures_dir=Path(snakemake.output.qc).parent,  # figures/; writes <stem>.png and qc/
        out_pdf=snakemake.output.pdf,
        n_bootstrap=int(snakemake.params.n_bootstrap),
        seed=int(snakemake.params.seed),
        snapshot_json=snakemake.input.snapshot,
    )
