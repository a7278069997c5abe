"""Rule catalogue: the lab's catalogue across sessions (results/catalogue/)."""

from ballimpact.catalogue import write_catalogue
from ballimpact.pipeline import log_to_file

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    write_catalogue(
        list(snakemake.params.session_dirs),
        out_csv=snakemake.output.csv,
        out_nc=snakemake.output.nc,
        out_pdf=snakemake.output.pdf,
        pools=[dict(p) for p in snakemake.params.pool],
        n_bootstrap=int(snakemake.params.n_bootstrap),
        seed=int(snakemake.params.seed),
    )
