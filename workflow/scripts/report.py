"""Rule report: the session's PDF report."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, make_report

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    make_report(
        archive_nc=snakemake.input.archive,
        figures_dir=Path(snakemake.input.qc).parent,  # figures/, holding the PNGs and qc/
        out_pdf=snakemake.output.pdf,
    )
