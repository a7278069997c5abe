"""Rule collect_impacts: all impacts in raw order as impacts.csv and work/impacts.nc."""

from ballimpact.pipeline import collect_impacts, log_to_file

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    collect_impacts(
        session_dir=snakemake.params.session_dir,
        chunk_ncs=list(snakemake.input.chunks),
        out_csv=snakemake.output.impacts_csv,
        out_nc=snakemake.output.impacts_nc,
        mains_hz=snakemake.params.mains_hz,
    )
