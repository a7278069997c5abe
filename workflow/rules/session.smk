# Stages 2-3 of a small session in one job: its fits, archive, figures and report.
# A session of at most config fit_batch_impacts impacts (SMALL_SESSIONS, common.smk) runs
# rule session_outputs instead of fit_session + archive + figures + report: the same
# function calls in one process, so the same files, without three more process start-ups.
# Larger sessions, and every session with --config fit_batch_impacts=0, use the per-stage
# rules (workflow/rules/fit.smk, report.smk), which also rerun one stage on its own.

# both produce the fits, archive, figures and report of a small session: this rule wins there
ruleorder: session_outputs > fit_session
ruleorder: session_outputs > archive
ruleorder: session_outputs > figures
ruleorder: session_outputs > report


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
