"""Rule archive: the session's netCDF archive and parameters.csv."""

from ballimpact.pipeline import log_to_file, write_archive

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    write_archive(
        session_dir=snakemake.params.session_dir,
        impacts_nc=snakemake.input.impacts_nc,
        fit_ncs=list(snakemake.input.fits),
        out_nc=snakemake.output.archive,
        out_parameters_csv=snakemake.output.parameters_csv,
        snapshot_json=snakemake.input.snapshot,
    )
