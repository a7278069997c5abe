"""Rule fit_session: fit every ball type of a small session in one process."""

from ballimpact.pipeline import fit_balls, log_to_file

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    fit_balls(
        impacts_nc=snakemake.input.impacts_nc,
        balls=list(snakemake.params.balls),
        session_dir=snakemake.params.session_dir,
        out_nc=snakemake.output.fits,
        n_bootstrap=int(snakemake.params.n_bootstrap),
        seed=int(snakemake.params.seed),
    )
