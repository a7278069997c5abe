"""Rule process_chunk: process impacts chunk, chunk + n_chunks, ... of a session."""

from ballimpact.pipeline import log_to_file, process_chunk

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    process_chunk(
        session_dir=snakemake.params.session_dir,
        chunk=int(snakemake.wildcards.chunk),
        n_chunks=int(snakemake.params.n_chunks),
        out_nc=snakemake.output.chunk,
        mains_hz=snakemake.params.mains_hz,
    )
