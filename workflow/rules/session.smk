# A small session in one job (small_session), or in stage-1 jobs and one more (session_outputs).
# A session of at most config fit_batch_impacts impacts (SMALL_SESSIONS, common.smk) runs
# rule session_outputs instead of fit_session + archive + figures + report, and, when it is
# processed as one chunk (ONE_JOB_SESSIONS), rule small_session instead of all of
# validate_session + process_chunk + collect_impacts + session_outputs: the same function
# calls in one process, so the same files, without the start-ups (Python, its imports and
# the compiled model's loading) of more processes. A changed fit setting (bootstrap, seed)
# then reruns the processing of such a session too (about a CPU second).
# Larger sessions, and every session with --config fit_batch_impacts=0, use the per-stage
# rules (workflow/rules/process.smk, fit.smk, report.smk), which also rerun one stage on its own.

# both produce the snapshot, impacts, fits, archive, figures and report of a small session
# processed as one chunk: this rule wins there
ruleorder: small_session > validate_session
ruleorder: small_session > collect_impacts
ruleorder: small_session > fit_session
ruleorder: small_session > archive
ruleorder: small_session > figures
ruleorder: small_session > report

# both produce the fits, archive, figures and report of a small session: this rule wins there
ruleorder: session_outputs > fit_session
ruleorder: session_outputs > archive
ruleorder: session_outputs > figures
ruleorder: session_outputs > report


rule small_session:
    """Snapshot, impacts, fits, archive, parameters.csv, figures and report.pdf of a small
    session processed as one chunk, in one job."""
    wildcard_constraints:
        session=ONE_JOB_SESSION_PATTERN,
    input:
        raw=session_raw_files,
    output:
        snapshot=result_path("work/session.json"),
        impacts_csv=result_path("impacts.csv"),
        impacts_nc=result_path("work/impacts.nc"),
        fits=result_path("work/fits.nc"),
        archive=result_path("{session}.nc"),
        parameters_csv=result_path("parameters.csv"),
        pdf=report_pdf_output(),
        **figure_outputs(),
    params:
        session_dir=session_dir,
        mains_hz=config.get("mains_hz"),
        balls=ball_keys,
        n_bootstrap=config["bootstrap"],
        seed=config["seed"],
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("small_session"),
    benchmark:
        benchmark_path("small_session")
    threads: 1
    script:
        "../scripts/small_session.py"


rule session_outputs:
    """Fits, archive, parameters.csv, figures and report.pdf of a small session, in one job."""
    wildcard_constraints:
        session=SPLIT_SMALL_SESSION_PATTERN,
    input:
        snapshot=result_path("work/session.json"),
        impacts_nc=result_path("work/impacts.nc"),
        session_yaml=raw_path("session.yaml"),
    output:
        fits=result_path("work/fits.nc"),
        archive=result_path("{session}.nc"),
        parameters_csv=result_path("parameters.csv"),
        pdf=report_pdf_output(),
        **figure_outputs(),
    params:
        session_dir=session_dir,
        balls=ball_keys,
        n_bootstrap=config["bootstrap"],
        seed=config["seed"],
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("session_outputs"),
    benchmark:
        benchmark_path("session_outputs")
    threads: 1
    script:
        "../scripts/session_outputs.py"
