"""Rule fit_ball: fit the ball model to the impacts of one ball type."""

from ballimpact.pipeline import fit_ball, log_to_file

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    fit_ball(
        impacts_nc=snakemake.input.impacts_nc,
        ball=snakemake.wildcards.ball,
        session_dir=snakemake.params.session_dir,
        out_nc=snakemake.output.fit,
        n_bootstrap=int(snakemake.params.n_bootstrap),
        seed=int(snakemake.params.seed),
    )
