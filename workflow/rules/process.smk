# Stage 1: check and snapshot the raw session, process the impacts in chunks, collect them.


rule validate_session:
    """Read session.yaml + impacts.csv (session-level faults stop the session here) and
    record the sha256 of every raw file."""
    input:
        raw=session_raw_files,
    output:
        snapshot=result_path("work/session.json"),
    params:
        session_dir=session_dir,
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("validate_session"),
    threads: 1
    script:
        "../scripts/validate_session.py"


rule process_chunk:
    """Process impacts chunk, chunk + n_chunks, ... of the session (one trace in memory at a time)."""
    input:
        # a new snapshot (any raw file of the session changed) re-runs every chunk. Do not
        # wrap it in ancient(): Snakemake then skips this job even when its own traces change.
        snapshot=result_path("work/session.json"),
        session_yaml=raw_path("session.yaml"),
        impacts_csv=raw_path("impacts.csv"),
        traces=chunk_trace_files,
    output:
        chunk=result_path("work/chunk_{chunk}.nc"),
    params:
        session_dir=session_dir,
        n_chunks=n_chunks,
        mains_hz=config.get("mains_hz"),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("process_chunk_{chunk}"),
    benchmark:
        benchmark_path("process_chunk_{chunk}")
    threads: 1
    script:
        "../scripts/process_chunk.py"


rule collect_impacts:
    """All impacts in raw order (impacts.csv, work/impacts.nc) and the session's kCAL QC."""
    input:
        snapshot=result_path("work/session.json"),
        chunks=chunk_files,
    output:
        impacts_csv=result_path("impacts.csv"),
        impacts_nc=result_path("work/impacts.nc"),
    params:
        session_dir=session_dir,
        mains_hz=config.get("mains_hz"),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("collect_impacts"),
    threads: 1
    script:
        "../scripts/collect_impacts.py"
