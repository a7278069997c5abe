"""Rule figures: every report figure as a PNG, and the per-impact QC pages."""

from pathlib import Path

from ballimpact.pipeline import log_to_file, make_figures

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    make_figures(
        archive_nc=snakemake.input.archive,
        out_dir=Path(snakemake.output.qc).parent,  # figures/; writes <stem>.png and qc/
    )
