"""Rule validate_session: read the raw session and snapshot the sha256 of its files."""

from ballimpact.pipeline import log_to_file, snapshot_session

snakemake = globals()["snakemake"]  # injected by Snakemake's `script:` directive

with log_to_file(snakemake.log[0]):
    snapshot_session(session_dir=snakemake.params.session_dir, out_json=snakemake.output.snapshot)
