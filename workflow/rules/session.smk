# A small session in two jobs: session_impacts (stage 1) and session_outputs (stages 2-3).
# A session of at most config fit_batch_impacts impacts (SMALL_SESSIONS, common.smk) runs
# rule session_outputs instead of fit_session + archive + figures + report, and, when it is
# processed as one chunk (ONE_JOB_SESSIONS), rule session_impacts instead of
# validate_session + process_chunk + collect_impacts: the same function calls in one
# process, so the same files, without five more process start-ups. Two jobs, not one, so
# that a changed fit setting (bootstrap, seed) reruns the fits but not the processing.
# Larger sessions, and every session with --config fit_batch_impacts=0, use the per-stage
# rules (workflow/rules/process.smk, fit.smk, report.smk), which also rerun one stage on its own.

# both produce the snapshot and the impacts of a small session: this rule wins there
ruleorder: session_impacts > validate_session
ruleorder: session_impacts > collect_impacts

# both produce the fits, archive, figures and report of a small session: this rule wins there
ruleorder: session_outputs > fit_session
ruleorder: session_outputs > archive
ruleorder: session_outputs > figures
ruleorder: session_outputs > report


rule session_impacts:
    """Snapshot, impacts.csv and work/impacts.nc of a small session, in one job."""
    wildcard_constraints:
        session=ONE_JOB_SESSION_PATTERN,
    input:
        raw=session_raw_files,
    output:
        snapshot=result_path("work/session.json"),
        impacts_csv=result_path("impacts.csv"),
        impacts_nc=result_path("work/impacts.nc"),
    params:
        session_dir=session_dir,
        mains_hz=config.get("mains_hz"),
    conda:
        "../envs/ballimpact.yaml"
    log:
        log_path("session_impacts"),
    benchmark:
        benchmark_path("session_impacts")
    threads: 1
    script:
        "../scripts/session_impacts.py"


rule session_outputs:
    """Fits, archive, parameters.csv, figures and report.pdf of a small session, in one job."""
    wildcard_constraints:
        session=SMALL_SESSION_PATTERN,
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
