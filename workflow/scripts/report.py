"""Rule report: the session's PDF report."""

from ballimpact.pipeline import log_to_file, make_report

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    make_report(
        archive_nc=snakemake.input.archive,
        figures_dir=snakemake.params.figures_dir,
        out_pdf=snakemake.output.pdf,
    )
